"""PDF report through typst: valid PDF, readable text, escaped user strings."""

from __future__ import annotations

import io
import re

import pypdf  # a declared test dependency: fail, never skip
import pytest

from toolbox.report import write_pdf
from toolbox.report.pdf import escape_markup, render_typst, typst_string

#: slow: typesets PDFs
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def pdf_text(full_pdf):
    data = full_pdf
    reader = pypdf.PdfReader(io.BytesIO(data))
    text = "\n".join(page.extract_text() for page in reader.pages)
    return data, reader, text


def test_pdf_is_valid(pdf_text):
    data, reader, _ = pdf_text
    assert data.startswith(b"%PDF-")
    # the fixture's content (tables, 5 loop figures, robustness, 1 trace figure)
    # fills 6 to 12 A4 pages; fewer means content was dropped, more a layout blow-up
    assert 6 <= len(reader.pages) <= 12


def _squash(s: str) -> str:
    return re.sub(r"\s+", "", s)


def test_pdf_text(pdf_text, hostile):
    _, _, text = pdf_text
    flat = _squash(text)
    assert _squash(hostile) in flat  # shown literally, markup characters included
    for needle in ("PI in dq", "Gain margin", "Phase margin", "Bode diagram",
                   "Nyquist plot", "Provenance", "Verification", "Robustness"):
        assert _squash(needle) in flat, needle


def test_pdf_minimal(minimal_data, tmp_path):
    path = tmp_path / "report.pdf"
    data = write_pdf(minimal_data, path)
    assert path.read_bytes() == data
    assert [p.name for p in tmp_path.iterdir()] == ["report.pdf"]  # no temporary left
    text = _squash("\n".join(p.extract_text() for p in pypdf.PdfReader(io.BytesIO(data)).pages))
    assert _squash("Margins: not computed") in text
    assert _squash("Verification: not computed") in text


def test_typst_string_escapes():
    assert typst_string('a"b\\c\nd') == '"a\\"b\\\\c\\nd"'
    assert typst_string("\x01") == '"\\u{1}"'
    assert escape_markup("#set *x*") == "\\#set \\*x\\*"


def test_pdf_deterministic(full_context, full_pdf):
    """Same content, same PDF bytes (document date unset)."""
    import typst

    source, images = render_typst(full_context)
    assert typst.compile(source.encode("utf-8"), format="pdf", sys_inputs=images) == full_pdf


def test_hostile_only_in_string_literals(full_context, hostile):
    """The raw hostile text never appears in the typst source outside a literal."""
    source, images = render_typst(full_context)
    assert hostile not in source  # it contains a quote and a backslash: always escaped
    assert typst_string(hostile) in source
    assert all(v.lstrip().startswith("<svg") for v in images.values())
