"""The report's torque-speed table shows each point's tangent loop
(verify.json ``envelope.points[].linear``; toolbox/ARCHITECTURE.md "One
controller, proved per point"): stable or UNSTABLE with the spectral radius,
the per-axis margins when computed, the multiloop disk margin; the figure's
hover text carries it too; a point without one (unreachable) has an empty cell."""

from __future__ import annotations

import dataclasses

from toolbox.report import build_context, write_html
from toolbox.report.plots import envelope_linear_text

LINEAR_OK = {"analysed": True, "stable": True, "spectral_radius": 0.9512,
             "margins": {"d": {"gain_margin_db": 12.5, "phase_margin_deg": 61.0},
                         "q": {"gain_margin_db": 9.25, "phase_margin_deg": "inf"}},
             "mimo_disk_margin": 0.6213, "mimo_phase_margin_deg": 34.4}
LINEAR_BAD = {"analysed": True, "stable": False, "spectral_radius": 1.3477, "margins": None,
              "mimo_disk_margin": 0.0, "mimo_phase_margin_deg": 0.0}


def _point(sf, status, linear, reason=None):
    return {"speed_fraction": sf, "torque_fraction": 1.0, "speed": 100.0 * sf, "torque": 5.0,
            "region": "mtpa", "status": status, "reason": reason, "linear": linear}


ENVELOPE = {
    "passed": False, "counts": {"pass": 1, "fail": 1, "unreachable": 0},
    "summary": "torque-speed grid: 1 pass, 1 fail, 0 unreachable of 2 points (...); "
               "tangent loops: 1 stable of 2, worst multiloop disk margin 0",
    "failures": [], "base_speed_rad_s": 100.0, "torque_limit_nm": 10.0,
    "curves": {"speed_rad_s": [0.0, 100.0], "torque_limit": [10.0, 10.0],
               "current_limit": [10.0, 10.0], "voltage_limit": [None, 20.0]},
    "points": [_point(0.0, "pass", LINEAR_OK),
               _point(1.0, "fail", LINEAR_BAD, "tangent loop unstable (spectral radius 1.348)")]}


def test_linear_text():
    assert envelope_linear_text(LINEAR_OK) == (
        "stable, spectral radius 0.9512; axis GM 9.25 dB, PM 61 deg; "
        "MIMO disk margin 0.621 (+-34.4 deg)")
    assert envelope_linear_text(LINEAR_BAD) == "UNSTABLE, spectral radius 1.3477"
    assert envelope_linear_text({"analysed": False}) == "not analysed (no linear loop)"
    assert envelope_linear_text(None) == ""


def test_table_and_hover_show_the_tangent_loop(full_data):
    ver = dict(full_data.verification or {})
    ver["envelope"] = ENVELOPE
    data = dataclasses.replace(full_data, verification=ver)
    rows = build_context(data)["envelope"]["rows"]
    assert [r[-1] for r in rows] == [envelope_linear_text(LINEAR_OK),
                                     envelope_linear_text(LINEAR_BAD)]
    html = write_html(data)
    assert "<th>Tangent loop</th>" in html
    assert html.count("UNSTABLE, spectral radius 1.3477") >= 2     # table and hover
