"""PDF report through typst (the ``typst`` PyPI package).

Why typst
---------
The PDF route must install from PyPI alone. The ``typst`` wheel embeds the
typst compiler (a mature typesetting engine with proper tables, page layout,
math and native SVG import) and its default fonts, so ``pip install typst`` is
all a user needs: no LaTeX distribution, no browser, no system library.
Alternatives were rejected: WeasyPrint needs the system Pango/HarfBuzz
libraries, ReportLab has no math typesetting and a low-level layout model, and
printing the HTML through a headless browser needs a browser.

Content equals the HTML report's (:func:`toolbox.report.build_context`):
tables are typst tables, figures and equations are the same SVG images passed
to the compiler through ``sys.inputs`` (so no temporary files).

Escaping: every string is inserted as a typst *string literal* (quotes,
backslashes and control characters escaped by :func:`typst_string`) in code
position, so user text is shown literally and never parsed as markup or code.
"""

from __future__ import annotations

import re
from pathlib import Path
import os
import tempfile

import jinja2

from .._cache import template_bytecode_cache
from . import build_context

__all__ = ["write_pdf", "render_typst", "typst_string", "escape_markup"]

TEMPLATES = Path(__file__).parent / "templates"

#: Figure widths in the PDF (square plots narrower so two fit a page).
PDF_FIGURE_WIDTH = {"bode": "100%", "nyquist": "62%", "sensitivity": "92%", "step": "100%",
                    "pzmap": "58%"}
EQUATION_SCALE = 0.62

_MARKUP_SPECIAL = set('\\#*_`$<>@[]=-+/~\'"{}')


def typst_string(value: object) -> str:
    """A typst string literal that evaluates to ``str(value)`` exactly.

    Backslash and double quote are backslash-escaped; newline, carriage
    return and tab use their escapes; other control characters become
    ``\\u{..}`` escapes.
    """
    out = []
    for ch in str(value):
        if ch == "\\":
            out.append("\\\\")
        elif ch == '"':
            out.append('\\"')
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\r":
            out.append("\\r")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 32 or ord(ch) == 127:
            out.append(f"\\u{{{ord(ch):x}}}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def escape_markup(value: object) -> str:
    """Escape text for typst *markup* position (backslash before special characters)."""
    return "".join("\\" + ch if ch in _MARKUP_SPECIAL else ch for ch in str(value))


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        bytecode_cache=template_bytecode_cache(__file__),
        autoescape=False,  # typst, not HTML: strings go through the ``ts`` filter
        undefined=jinja2.StrictUndefined,
        block_start_string="<%", block_end_string="%>",
        variable_start_string="<<", variable_end_string=">>",
        comment_start_string="<#", comment_end_string="#>",
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
    )
    env.filters["ts"] = typst_string
    return env


def render_typst(context: dict) -> tuple[str, dict[str, str]]:
    """Typst source and its ``sys.inputs`` (SVG images by key) for a content model."""
    images: dict[str, str] = {}
    ctx = dict(context)
    figs = []
    for k, f in enumerate(ctx["figures"]):
        images[f"fig{k}"] = f["svg"]
        width = PDF_FIGURE_WIDTH.get(f["id"], "100%")
        figs.append({**f, "key": f"fig{k}", "width": width})
    ctx["figures"] = figs
    eqs = []
    for k, e in enumerate(ctx["equations"]):
        key = None
        width = "auto"
        if e.get("svg"):
            key = f"eq{k}"
            images[key] = e["svg"]
            m = re.search(r'width="([0-9.]+)pt"', e["svg"])
            if m:  # mathtext at 17 pt, shown at about 10.5 pt in the PDF
                width = f"{EQUATION_SCALE * float(m.group(1)):.1f}pt"
        eqs.append({**e, "key": key, "width": width})
    ctx["equations"] = eqs
    if ctx.get("scenarios"):
        scs = []
        for k, s in enumerate(ctx["scenarios"]):
            key = None
            if s.get("svg"):
                key = f"sc{k}"
                images[key] = s["svg"]
            scs.append({**s, "key": key})
        ctx["scenarios"] = scs
    if ctx.get("robustness") and ctx["robustness"].get("svg"):
        images["rob"] = ctx["robustness"]["svg"]
        ctx["robustness"] = {**ctx["robustness"], "key": "rob"}
    elif ctx.get("robustness"):
        ctx["robustness"] = {**ctx["robustness"], "key": None}
    if ctx.get("envelope") and ctx["envelope"].get("svg"):
        images["env"] = ctx["envelope"]["svg"]
        ctx["envelope"] = {**ctx["envelope"], "key": "env"}
    source = _environment().get_template("report.typ.j2").render(**ctx)
    return source, images


def write_pdf(data, path: str | Path | None = None) -> bytes:
    """The PDF report of ``data``.

    Parameters
    ----------
    data : toolbox.report.ReportData or dict
        The report's data, or its content model from
        :func:`toolbox.report.build_context` (to share figures with the HTML).
    path : str or Path, optional
        Where to write the PDF as well (written to a temporary file in the
        same directory, then renamed: atomic).

    Returns
    -------
    bytes
        The PDF document.
    """
    import typst  # lazy: the typst compiler, PDF only

    source, images = render_typst(data if isinstance(data, dict) else build_context(data))
    pdf = typst.compile(source.encode("utf-8"), format="pdf", sys_inputs=images)
    if path is not None:
        target = Path(path)
        fd, tmp = tempfile.mkstemp(prefix=".report-", suffix=".pdf.tmp", dir=target.parent)
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(pdf)
            os.replace(tmp, target)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    return pdf
