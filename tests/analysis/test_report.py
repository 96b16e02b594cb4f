"""analysis.json content, controller.json MARGINS and the compare rows."""

import json

from analysis_helpers import AZAIZ, DRIVE
from toolbox.analysis import (MARGIN_KEYS, analysis_report, compare_designs,
                              compute_margins)
from toolbox.artifact import ControllerArtifact


def test_analysis_report_is_plain_json(pi):
    """Strict JSON (no NaN/inf literals), the documented layout, and the discrete
    margins equal compute_margins'."""
    rep = analysis_report(pi, AZAIZ, DRIVE, sweep_sets=100)
    text = json.dumps(rep, allow_nan=False)
    assert json.loads(text) == rep
    assert rep["schema"] == "cct.analysis/1" and rep["method"] == "pi"
    assert set(rep["margins"]) == {"discrete", "continuous", "continuous_delay"}
    for dom in rep["margins"].values():
        for ax in "dq":
            assert list(dom[ax])[:9] == list(MARGIN_KEYS)
    m = compute_margins(pi, AZAIZ)["q"]
    assert rep["margins"]["discrete"]["q"]["phase_margin_deg"] == m.phase_margin_deg
    assert {"worst_disk_margin", "worst_speed_rad_s", "disk_margin"} <= set(rep["mimo_at_speed"])
    assert {"n_unstable", "worst", "static_error"} <= set(rep["sweep"])
    # The PI design with decoupling on its own motor is certified on about two
    # thirds of the default box (R, L x0.5..x2, |omega| <= max speed): the
    # bisection (tolerance 0.05 on the scale) ends at 0.65625 = 21/32. The band
    # 0.6..0.72 allows one bisection step either way for solver noise at the
    # boundary; a wrong LMI assembly or solver failure gives certified False
    # (scale 0) or another scale, a skipped bisection gives 1.
    cert = rep["certificate"]
    assert cert["certified"] is True and 0.6 <= cert["scale"] <= 0.72, cert


def test_margins_round_trip_through_the_artifact(tc):
    """MARGINS written into controller.json as the pipeline does (sampled loop
    with delay) survive the exact JSON round trip of the artifact; infinite
    values become "inf"."""
    art = tc.with_margins({ax: r.to_json() for ax, r in compute_margins(tc, AZAIZ).items()})
    back = ControllerArtifact.loads(art.dumps())
    assert back.margins == art.margins
    assert set(MARGIN_KEYS) <= set(back.margins["q"])
    assert back.margins["d"]["phase_margin_deg"] == "inf"       # |L| < 1 everywhere (d axis)


def test_compare_rows(pi, tc):
    """One row per design with margins, response times, sweep worst cases and
    certificate; the PI (integrators) has zero static error, both rows serialise."""
    rows = compare_designs([pi, tc], AZAIZ, DRIVE, sweep_sets=50, certificate=False)
    assert [r["method"] for r in rows] == ["pi", "tc"]
    for r in rows:
        assert set(r["margins"]["q"]) == set(MARGIN_KEYS)
        assert r["response_times"]["q"]["response_time_5pct"] > 0
        assert set(r["worst_case"]["d"]) == {"gain_margin_db", "phase_margin_deg",
                                             "stability_margin", "disk_margin"}
        json.dumps(r, allow_nan=False)
    assert rows[0]["margins"]["q"]["static_error"] == 0.0


def test_public_api_documented():
    """Every public name of toolbox.analysis (and of its modules' __all__) has a
    docstring; functions taking parameters document them in a Parameters section
    or (for small helpers) in their summary."""
    import inspect
    import toolbox.analysis as A
    from toolbox.analysis import certificate, margins, robustness
    for mod in (A, margins, robustness, certificate):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if isinstance(obj, (str, tuple, dict)):
                continue
            assert inspect.getdoc(obj), f"{mod.__name__}.{name} has no docstring"
    for fn in (A.compute_margins, A.mimo_disk_margins, A.robustness_sweep, A.certify,
               A.analysis_report, A.largest_certified_scale):
        doc = inspect.getdoc(fn)
        assert "Returns" in doc or "Return" in doc, fn.__name__
