"""The torque-speed grid's linear proof (toolbox/verify/_envelope_grid.py
``with_tangent_loops``; toolbox/ARCHITECTURE.md "One controller, proved per
point"): every reachable point carries the executed loop at its tangent plant
(verify.json ``envelope.points[].linear``), a point whose tangent loop is
unstable fails with the reason (even when its simulation passed),
unreachable points are left alone, and the summary line counts the stable
tangent loops."""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import replace
from pathlib import Path

import toolbox
from toolbox.verify._envelope_grid import EnvelopeGrid, GridPoint, with_tangent_loops
from toolbox.verify._verify import envelope_grid

ROOT = Path(__file__).resolve().parents[2]
PMSYRM = ROOT / "tests" / "corpus" / "motors" / "baldor_ecs101m0h7ef4_pmsyrm.toml"


def _point(sf, tf, speed, i_d, i_q, status="pass", reason=None):
    return GridPoint(sf, tf, speed, 1.0, "mtpa", 0.0, 0.0, i_d, i_q, i_d, i_q, 0.01,
                     math.hypot(i_d, i_q), status, reason)


def test_unstable_tangent_loop_fails_its_point():
    """The PM-SyRM with the PI designed for its unsaturated inductances: the
    points at the current limit fail on the linear proof with the reason;
    the unloaded point passes; the unreachable one is not analysed."""
    data = tomllib.loads(PMSYRM.read_text())
    data["controller"] = {"method": "pi"}
    spec = toolbox.spec_from_dict(data)
    m = spec.motor
    Ld, Lq, flux = replace(m.magnetics, nominal_current=0.0).nominal()
    raw = dict(spec.raw)
    raw["motor"] = {k: v for k, v in raw["motor"].items() if k != "saturation"}
    raw["motor"].update(Ld=Ld, Lq=Lq, flux=flux)
    bad = toolbox.design_spec(toolbox.spec_from_dict(raw))
    i_d, i_q = m.magnetics.mtpa(m.max_current, m.pole_pairs, m.torque_factor)
    nan = float("nan")
    pts = (_point(0.0, 0.0, 0.0, 0.0, 0.0), _point(0.0, 1.0, 0.0, i_d, i_q),
           _point(0.5, 1.0, 60.0, i_d, i_q, "fail", "peak current 40 A after the step"),
           GridPoint(2.0, 1.0, 300.0, nan, "unreachable", *[nan] * 8, "unreachable",
                     "no current fits"))
    grid = EnvelopeGrid(pts, 120.0, 30.0, 300.0, m.max_current, "radial", 0.02, 0.04)
    out = with_tangent_loops(grid, bad, m)
    p0, p1, p2, p3 = out.points
    assert p0.status == "pass" and p0.linear["stable"] is True and p0.reason is None
    assert p1.status == "fail" and "tangent loop unstable (spectral radius" in p1.reason
    assert p1.linear["spectral_radius"] > 1.0 and p1.linear["mimo_disk_margin"] == 0.0
    # the simulation's reason is kept, the linear one appended
    assert p2.status == "fail" and p2.reason.startswith("peak current 40 A after the step; "
                                                        "tangent loop unstable")
    assert p3.status == "unreachable" and p3.linear is None
    assert out.counts() == {"pass": 1, "fail": 2, "unreachable": 1} and not out.passed
    assert "tangent loops: 1 stable of 3" in out.summary()
    assert any("tangent loop unstable" in f for f in out.failures())
    doc = json.loads(json.dumps(out.to_json()))           # JSON-ready
    assert doc["points"][1]["linear"]["L_inc"][1][1] < Lq / 2
    # the nominal design passes the same points
    ok = with_tangent_loops(grid, toolbox.design_spec(spec), m)
    assert [p.status for p in ok.points] == ["pass", "pass", "fail", "unreachable"]
    assert ok.points[2].reason == "peak current 40 A after the step"
    assert "tangent loops: 3 stable of 3" in ok.summary()


def test_verification_grid_carries_the_linear_result():
    """End to end (verify.json ``envelope`` of paper 003's PI): every reachable
    point has its tangent loop, stable, and the summary says so."""
    spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
    art = toolbox.design_spec(spec)
    env = envelope_grid(art, spec)
    reach = [p for p in env["points"] if p["status"] != "unreachable"]
    assert reach and all(p["linear"]["analysed"] and p["linear"]["stable"] for p in reach)
    assert all(p["linear"] is None for p in env["points"] if p["status"] == "unreachable")
    assert f"tangent loops: {len(reach)} stable of {len(reach)}" in env["summary"]
    speeds = {p["speed"]: p["linear"]["omega_e_rad_s"] for p in reach}
    assert all(w_e == spec.motor.pole_pairs * s for s, w_e in speeds.items())
