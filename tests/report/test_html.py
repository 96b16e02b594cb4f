"""HTML report: self-contained, escaped, well-formed SVG, deterministic, honest about gaps."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from toolbox.report import write_html




@pytest.fixture(scope="module")
def html(full_html) -> str:
    return full_html


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


def test_sections_and_values(html, full_data, full_context):
    for heading in ("Specification and motor", "Derived plant", "Controller",
                    "Margins and requirements", "Bode diagram", "Nyquist plot",
                    "Closed-loop functions", "Step response", "Pole-zero map",
                    "Robustness", "Verification", "Provenance"):
        assert heading in html
    m = full_data.analysis["margins"]["discrete"]["q"]
    assert f"{m['phase_margin_deg']:.4g}" in html
    assert "PI in dq" in html and "000 sect. 2" in html
    assert "bounds gamma/|W_i|" in full_context["figures"][2]["caption"]


def test_deterministic(full_data, full_html):
    """A fresh render (new figures, new content model) gives the same bytes."""
    assert write_html(full_data) == full_html


def test_minimal_says_not_computed(minimal_data):
    out = write_html(minimal_data)
    for what in ("Margins: not computed", "Requirement checks: not computed",
                 "Robustness sweep: not computed", "Certificate: not computed",
                 "Verification: not computed",
                 "Frequency and time responses: not computed"):
        assert what in out


def test_marked_margins_match_python_control(full_data, python_control_margins):
    """The margins the Bode figure marks (analysis.json's) agree with
    control.stability_margins on the same sampled loop.

    Tolerance 0.05 deg / 0.05 dB / 0.1 %: both refine the crossings on the
    exact frequency response (brentq to 1e-13 here, polynomial roots in
    python-control), so they agree far better; the slack covers
    python-control's root conditioning on a loop with a pole at z = 1.
    """
    for ax in ("d", "q"):
        got = full_data.analysis["margins"]["discrete"][ax]
        ref = python_control_margins[ax]
        assert got["phase_margin_deg"] == pytest.approx(ref["phase_margin_deg"], abs=0.05)
        assert got["gain_margin_db"] == pytest.approx(ref["gain_margin_db"], abs=0.05)
        assert got["gain_crossover_rad_s"] == pytest.approx(ref["gain_crossover_rad_s"],
                                                            rel=1e-3)


def test_figures_hold_no_user_text(full_context):
    svgs = [f["svg"] for f in full_context["figures"]]
    svgs += [s["svg"] for s in full_context["scenarios"] if s["svg"]]
    assert svgs and all("script" not in s and "rm -rf" not in s for s in svgs)
    # the figures' texts (SVG <text>, toolbox/report/_svgplot.py) are labels, tick
    # values and margins: no scenario name (the fixture's are user strings) is among them
    texts = {t for s in svgs for t in _svg_texts(s)}
    assert "q step 10 A" not in texts and "frequency (rad/s)" in texts


def _svg_texts(svg: str) -> list[str]:
    """The character data of every <text> of an SVG (tspans joined)."""
    root = ET.fromstring(svg)
    return ["".join(e.itertext()) for e in root.iter() if e.tag.endswith("}text")]


def test_zpk_text_paper_003_controller():
    """K_q of paper 003 (reference numbers of tests/papers/test_003_hinf.py) prints as its factors."""
    import control

    from toolbox.artifact import Zpk
    from toolbox.report import zpk_text

    num = 49.70 * np.polymul(np.polymul([1, 2.714e6], [1, 5e4]), [1, 214.3])
    den = np.polymul(np.polymul([1, 2.717e6], [1, 0.01174]), [1, 4793, 6.104e6])
    text = zpk_text(Zpk.from_statespace(control.ss(control.tf(num, den))))
    for factor in ("49.7 ", "(s + 2.714e+06)", "(s + 5e+04)", "(s + 214.3)",
                   "(s + 2.717e+06)", "(s + 0.01174)", "(s^2 + 4793 s + 6.104e+06)"):
        assert factor in text, text


def test_reduced_controller_and_simresult(full_data):
    """Reduced axes are listed; a SimResult-like object is accepted as traces."""
    import dataclasses
    import types

    import control

    from toolbox.artifact import AxisController
    from toolbox.report import _controller, _scenarios
    from toolbox.report.plots import _simulated_steps, traces_dict

    art = full_data.artifact
    red = AxisController.from_error_controller(control.tf([4.0], [1.0, 0.0]), art.sample_time)
    axes = {k: dataclasses.replace(v, reduced=red) for k, v in art.axes.items()}
    ctl = _controller(dataclasses.replace(art, axes=axes))
    assert [a["alt"] for a in ctl["axes"]] == ["K(s) = 4 / s"] * 2
    assert [a["alt_order"] for a in ctl["axes"]] == [1, 1]
    assert [a["alt_label"] for a in ctl["axes"]] == ["reduced, not executed"] * 2
    # the executed law runs the reduced controller: the full order is listed apart
    axes = {k: dataclasses.replace(red, full_order=v) for k, v in art.axes.items()}
    ctl = _controller(dataclasses.replace(art, axes=axes))
    assert [(a["order"], a["alt_order"]) for a in ctl["axes"]] == [(1, 1)] * 2
    assert [a["alt_label"] for a in ctl["axes"]] == ["full order, not executed"] * 2
    t = np.arange(50) * 1e-4
    sim = types.SimpleNamespace(metrics={"overshoot_pct": 1.0}, t=t, iq=np.ones(50),
                                iq_ref=np.r_[0.0, np.full(49, 5.0)], id=None)
    rows = _scenarios({"scenarios": [{"name": "x", "metrics": sim.metrics}]},
                      [traces_dict(sim)])
    assert rows[0]["metrics"] == [("overshoot_pct", "1", "%")] and rows[0]["svg"].startswith("<svg")
    (axis, k, ts, y), = _simulated_steps([traces_dict(sim)])
    assert (axis, k) == ("q", 1) and ts[0] == 0.0 and y[0] == pytest.approx(0.2)


def test_step_overlay_in_caption(full_context):
    assert "dashed: simulated responses" in full_context["figures"][3]["caption"]


def test_discrete_only_axis_prints_in_z(full_data):
    """An axis designed natively in discrete time (no continuous twin) prints K(z)."""
    import dataclasses

    import control

    from toolbox.artifact import AxisController
    from toolbox.report import _controller

    ts = full_data.artifact.sample_time
    law = control.ss([[1.0]], [[ts, -ts]], [[900.0]], [[4.2, -4.2]], ts)
    axis = AxisController.from_law(law, sample_time=ts, method="native")
    assert axis.continuous is None
    art = dataclasses.replace(full_data.artifact, axes={"d": axis, "q": axis})
    rows = _controller(art)["axes"]
    assert all(r["zpk"].startswith("K(z) = 4.2 (z - ") and r["zpk"].endswith("/ (z - 1)")
               for r in rows), rows


def test_zpk_text_snaps_roundoff_integrator():
    """A pole at -1e-13 rad/s (round-off of an exact integrator, 003 eq (71)-(72))
    prints as ``s``; 1e-12 relative to the largest root is far below any
    physical pole of a current loop (> 1e-3 rad/s against < 1e8 rad/s)."""
    from toolbox.artifact import Zpk
    from toolbox.report import zpk_text

    zpk = Zpk(np.array([-214.3 + 0j]), np.array([-1.025e-13 + 0j, -2397 - 600.5j, -2397 + 600.5j]),
              49.64)
    assert zpk_text(zpk) == "49.64 (s + 214.3) / s(s^2 + 4794 s + 6.106e+06)"  # 2397^2 + 600.5^2
