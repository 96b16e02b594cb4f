"""HTML report: self-contained, escaped, well-formed SVG, deterministic, honest about gaps."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from toolbox.report import build_context, write_html
from toolbox.report.plots import crossings




@pytest.fixture(scope="module")
def html(full_data) -> str:
    return write_html(full_data)


def test_no_external_resources(html):
    """No attribute or CSS loads anything over the network (namespaces are not loads)."""
    text = re.sub(r'xmlns(:\w+)?="[^"]*"', "", html)
    assert not re.search(r'(src|href|action|poster|data)\s*=\s*["\']?\s*(https?:)?//', text, re.I)
    assert not re.search(r"url\(\s*['\"]?\s*(https?:)?//", text, re.I)
    assert "@import" not in text
    assert "<link" not in text.lower() and "<script" not in text.lower()
    assert "http://" not in text and "https://" not in text


def test_hostile_title_is_escaped(html, hostile):
    assert "<script>alert(1)</script>" not in html
    escaped = "&lt;script&gt;alert(1)&lt;/script&gt; &amp; &#34;quotes&#34; &#39; ; rm -rf /"
    assert html.count(escaped) >= 3  # <title>, <h1>, scenario table/heading, certificate


def test_every_svg_parses_and_has_size(html):
    svgs = re.findall(r"<svg\b.*?</svg>", html, flags=re.S)
    # 6 equations + 5 loop figures + robustness + 1 scenario with traces
    assert len(svgs) == 13
    for svg in svgs:
        root = ET.fromstring(svg)
        assert root.tag.endswith("svg")
        assert float(root.get("width").removesuffix("pt")) > 10
        assert float(root.get("height").removesuffix("pt")) > 10


def test_svg_ids_unique(html):
    ids = re.findall(r'\bid="([^"]+)"', html)
    assert len(ids) == len(set(ids))


def test_sections_and_values(html, full_data):
    for heading in ("Specification and motor", "Derived plant", "Controller",
                    "Margins and requirements", "Bode diagram", "Nyquist plot",
                    "Closed-loop functions", "Step response", "Pole-zero map",
                    "Robustness", "Verification", "Provenance"):
        assert heading in html
    m = full_data.margins["q"]
    assert f"{m['phase_margin_deg']:.4g}" in html
    assert "PI in dq" in html and "000 sect. 2" in html
    assert "gamma/|W1|" in html or "gamma/|W" in build_context(full_data)["figures"][2]["caption"]


def test_deterministic(full_data):
    assert write_html(full_data) == write_html(full_data)


def test_minimal_says_not_computed(minimal_data):
    out = write_html(minimal_data)
    for what in ("Margins: not computed", "Requirement checks: not computed",
                 "Robustness sweep: not computed", "Certificate: not computed",
                 "Verification: not computed", "Weight bounds: not computed"):
        assert what in out


def test_curve_margins_match_python_control(full_data):
    """Margins read off the plotted curve agree with control.stability_margins.

    Tolerance 0.2 deg / 0.1 dB: the 500-point log grid with linear interpolation
    (grid ratio 1.02 per step) bounds the interpolation error well below that.
    """
    from toolbox.report.plots import loop_data

    loops = loop_data(full_data.artifact, full_data.spec.motor)
    for ax in ("d", "q"):
        cr = crossings(loops[ax]["omega"], loops[ax]["L"])
        ref = full_data.margins[ax]
        assert cr["pm_deg"] == pytest.approx(ref["phase_margin_deg"], abs=0.2)
        assert cr["gm_db"] == pytest.approx(ref["gain_margin_db"], abs=0.1)
        assert cr["w_pm"] == pytest.approx(ref["gain_crossover_rad_s"], rel=0.01)


def test_figures_hold_no_user_text(full_data):
    ctx = build_context(full_data)
    for f in ctx["figures"]:
        assert "script" not in f["svg"]
    assert not np.isnan(len(ctx["figures"]))
