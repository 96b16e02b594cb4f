"""The verdict at a glance: banner, units and resolution, robustness counted as
the sweep counts, failing sets drawn red, baseline PI margins labelled.

The browser test (test_browser.py) checks the banner's rendered colour; these
check the content model and the HTML text.
"""

from __future__ import annotations

import copy
import dataclasses
import re

import pytest

from toolbox.report import BASELINE_LABEL, build_context, fmt_q
from toolbox.report.html import render_html


def test_failing_design_opens_with_a_red_fail_banner(full_context, full_html):
    b = full_context["banner"]
    assert b["status"] == "fail" and b["headline"] == "FAIL"
    n = len(full_context["checks"])
    n_fail = sum(c["status"] == "fail" for c in full_context["checks"])
    assert n_fail and b["count"] == f"{n_fail} / {n} checks fail"
    # one sentence naming the first failing check
    assert b["reason"].endswith(".") and b["reason"].count(". ") == 0, b["reason"]
    first = next(c for c in full_context["checks"] if c["status"] == "fail")
    assert first["key"] in b["reason"]
    # the banner comes first, above the cards; the requirement card is red, not grey
    assert full_html.index('id="verdict"') < full_html.index('class="summary"')
    assert '<div class="banner fail" id="verdict"' in full_html
    assert 'class="card fail" id="requirements-card"' in full_html
    assert f"{n_fail} / {n} fail" in full_html
    assert 'id="robustness-card"' in full_html or full_context["verdict_card"] is None


def test_passing_design_banner_is_green(passing_data):
    ctx = build_context(passing_data)
    assert ctx["banner"]["status"] == "pass" and ctx["banner"]["headline"] == "PASS"
    html = render_html(ctx)
    assert '<div class="banner pass" id="verdict"' in html
    assert 'class="card pass" id="requirements-card"' in html


def test_unverified_report_says_so(minimal_data):
    ctx = build_context(minimal_data)
    assert ctx["banner"]["status"] == "none" and ctx["banner"]["headline"] == "NOT VERIFIED"


def test_margin_failure_reads_as_a_sentence(full_data, passing_data):
    data = copy.deepcopy(full_data.analysis)
    data["requirements"] = {"min_phase_margin_deg": {
        "quantity": "phase_margin_deg", "bound": 45.0, "value": 25.71552343534306,
        "unit": "deg", "pass": False}}
    ctx = build_context(dataclasses.replace(passing_data, analysis=data))
    assert ctx["banner"]["reason"] == ("Phase margin 25.72 deg is below the required 45 deg "
                                       "(min_phase_margin_deg).")


@pytest.mark.parametrize("value, unit, text", [
    (4.441e-14, "1", "0"), (-4.441e-14, "A", "0"), (3e-8, "s", "0"), (2.5e-7, "s", "2.5e-07"),
    (0.0004, "dB", "0"), (25.71552, "deg", "25.72"), (None, "s", "not computed"),
    (float("nan"), "A", "not computed"), (1e-13, "", "1e-13")])
def test_values_below_the_resolution_read_zero(value, unit, text):
    assert fmt_q(value, unit) == text


def test_every_metric_table_has_units(full_context, full_html):
    assert all(r["unit"] for r in full_context["margins"])
    for sc in full_context["scenarios"]:
        assert all(len(m) == 3 and m[2] for m in sc["metrics"]), sc["metrics"]
    assert "<th>Unit</th>" in full_html
    assert "below the resolution of their unit" in full_html
    assert not re.search(r"\de-1[0-9]<", full_html)  # no round-off noise shown


def test_robustness_counts_as_the_sweep_and_prints_no_reprs(full_data, full_context,
                                                            full_html):
    sweep = full_data.analysis["sweep"]
    rob = full_context["robustness"]
    assert rob["count"] == f"{sweep['n_unstable']} / {sweep['n_sets']} sets unstable"
    section = full_html[full_html.index('<section id="robustness">'):
                        full_html.index('<section id="verification">')]
    text = re.sub(r"<svg.*?</svg>", "", section, flags=re.S)
    for repr_mark in ("{&#39;", "{'", "': [", "&#39;: ", "[-", "parameter cases"):
        assert repr_mark not in text, repr_mark
    for w in rob["worst"]:
        assert ": " not in w["params"] and "{" not in w["params"]


def test_failing_sets_are_drawn_red():
    """The figure's legend says "fail" only with red points drawn (the failing
    sets' metric is plotted whatever the other cases' metrics)."""
    from toolbox.report.plots import robustness_svg

    cases = ([{"label": f"d axis: m{k}", "metrics": {f"m{k}": 1.0 + k}, "pass": True}
              for k in range(4)]
             + [{"label": f"unstable set {k}", "metrics": {"spectral_radius": 1.1 + k / 10},
                 "pass": False} for k in range(3)])
    svg = robustness_svg(cases, ["d axis: m0"])
    red = svg.count('fill="#c23b22"')
    assert red >= 3 + 1, red  # three sets and the legend's sample
    assert "fail (unstable set)" in svg


def test_fcs_mpc_margins_are_labelled_baseline(full_data):
    from toolbox.artifact._fields import FcsWeights

    art = dataclasses.replace(full_data.artifact, method="fcs_mpc", fcs=FcsWeights())
    verify = copy.deepcopy(full_data.verification)
    verify["robustness"] = {"n_unstable": 3, "n_sets": 10, "worst_disk_margin": 0.0,
                            "box_text": "default drift box", "first_unstable": None}
    ctx = build_context(dataclasses.replace(full_data, artifact=art, verification=verify))
    assert ctx["baseline"] == BASELINE_LABEL == "baseline PI, informational, not executed"
    assert ctx["verdict_card"]["status"] == "info"
    html = render_html(ctx)
    summary = html[html.index('class="summary"'):html.index("<nav>")]
    assert summary.count(BASELINE_LABEL) == 3  # GM, PM and robustness cards
    margins = html[html.index('<section id="margins">'):html.index('<section id="plots">')]
    assert BASELINE_LABEL in margins
    assert BASELINE_LABEL in html[html.index('<section id="plots">'):]
