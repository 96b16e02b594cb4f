"""Torque-speed grid verification (toolbox/verify/_envelope_grid.py) on paper
003's motor and designs: 0 / 50 / 100 % torque at 0 / 50 / 100 / 150 / 200 %
base speed, the envelope's references (5 % voltage headroom), imposed speed,
a torque step at each point (from the zero-torque reference; the 0 % point
down from the 100 % one) after a flying start that is not judged.

Paper 003's motor has ``psi / Ld = 86 A`` against a 20 A current limit: field
weakening reaches ~1.5 x base speed (3.3 N m of 14.8 N m), and at 2 x base
nothing fits (the back-EMF with the largest d current still exceeds the
voltage limit): those points are "unreachable", not simulated, and do not
fail the verdict. Every reachable point settles within 2 % of the current
limit (0.4 A) with either voltage priority, and the peak current after the
step stays within 1.2 x the limit (the step's own start at the limit, 20 A).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

import toolbox
from toolbox.sim import DriveParams, control_law
from toolbox.verify import DEFAULT_SPEEDS, DEFAULT_TORQUES, torque_speed_grid

ROOT = Path(__file__).resolve().parents[2]


def _setup(design, priority="radial"):
    spec = toolbox.load_spec(ROOT / "designs" / design)
    art = toolbox.design_spec(spec)
    drive = DriveParams(vdc=spec.drive.vdc, sample_time=spec.drive.sample_time,
                        delay_samples=spec.drive.delay_samples, voltage_priority=priority)
    return spec, art, drive


@pytest.mark.slow
@pytest.mark.parametrize("priority", ["radial", "d_axis"])
@pytest.mark.parametrize("design", ["003_azaiz2007_pi.toml", "003_azaiz2007_hinf.toml"])
def test_torque_speed_grid_paper003(design, priority):
    spec, art, drive = _setup(design, priority)
    grid = torque_speed_grid(control_law(art), spec.motor, drive, span=0.05)
    pts = grid.points
    assert len(pts) == len(DEFAULT_TORQUES) * len(DEFAULT_SPEEDS)
    print("\n" + grid.summary())
    for p in pts:
        print(f"{design} {priority} {p.speed_fraction:.1f} x base, {p.torque_fraction:.1f} "
              f"T: {p.status:11s} {p.region:26s} T {p.torque:6.3f} N m, err {p.error:.3g} A, "
              f"peak {p.peak_current:.1f} A {p.reason or ''}")
        if p.speed_fraction >= 2.0:
            assert p.status == "unreachable" and math.isnan(p.error)
            assert "back-EMF exceeds the voltage limit" in p.reason
            continue
        assert p.status == "pass", p
        assert p.error <= 0.02 * grid.i_max and p.peak_current <= 1.2 * grid.i_max
        if p.speed_fraction <= 1.0:
            # below base speed every torque fits, on MTPA or at the current limit
            assert p.region in ("mtpa", "current_limit", "current_and_voltage_limit")
            assert abs(p.torque - p.torque_fraction * grid.torque_limit) \
                < 1e-6 * grid.torque_limit
            assert p.reason is None
        elif p.torque_fraction > 0:
            # 1.5 x base: the torque the limits allow (3.3 N m), and the point says so
            assert p.region == "current_and_voltage_limit" and 3.0 < p.torque < 3.6
            assert p.reason.startswith("torque limited to")
        else:
            assert p.region == "field_weakening" and p.i_d_ref < -5.0
    assert grid.passed and grid.counts() == {"pass": 12, "fail": 0, "unreachable": 3}
    regions = {p.region for p in pts}
    assert {"mtpa", "field_weakening", "current_and_voltage_limit", "unreachable"} <= regions


def test_grid_names_failures_and_max_speed():
    """A bound the loop cannot meet (settled within 1e-6 of the current
    limit) fails every reachable point with its reason and fails the grid;
    speeds above ``drive.max_speed`` are unreachable with that reason."""
    spec, art, drive = _setup("003_azaiz2007_pi.toml")
    grid = torque_speed_grid(control_law(art), spec.motor, drive, span=0.02,
                             max_speed=100.0, tolerance=1e-6)
    c = grid.counts()
    # 0, 0.5 x base (69.7 rad/s) reachable; 1 x base (139 rad/s) and above beyond 100 rad/s
    assert c == {"pass": 0, "fail": 6, "unreachable": 9}, c
    assert not grid.passed
    for p in grid.points:
        if p.status == "fail":
            assert p.reason.startswith("settled") and "bound 2e-05 A" in p.reason
        else:
            assert "above drive.max_speed (100 rad/s)" in p.reason
    assert len(grid.failures()) == 6 and "0.5 x torque limit at 0.5 x base speed" \
        in grid.failures()[4]
    doc = grid.to_json()
    assert doc["passed"] is False and doc["counts"] == c
    assert all(v is None or math.isfinite(v) for p in doc["points"] for v in p.values()
               if isinstance(v, float))


def test_verify_json_envelope_and_verdict():
    """verify() writes the grid under ``envelope`` (existing keys kept); a
    failing reachable point fails the verdict, unreachable points do not."""
    from toolbox.verify import verify
    spec, art, _ = _setup("003_azaiz2007_pi.toml")
    res = verify(art, spec, keep_traces=False)
    doc = res.to_json()
    assert {"schema", "method", "passed", "scenarios", "margin_requirements"} <= set(doc)
    env = doc["envelope"]
    assert env["counts"] == {"pass": 12, "fail": 0, "unreachable": 3} and env["passed"]
    assert env["torque_fractions"] == [0.0, 0.5, 1.0]
    assert env["speed_fractions"] == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert len(env["curves"]["speed_rad_s"]) == len(env["curves"]["torque_limit"]) == 41
    assert res.passed
    failing = replace(res, envelope={**env, "passed": False})
    assert not failing.passed and failing.to_json()["passed"] is False


@pytest.mark.slow
def test_predictive_law_is_judged_with_its_design_band():
    """fcs_mpc leaves the ripple band of paper 002's criterion (23) by design
    (toolbox.verify.fcs_ripple: covering radius plus the switching-penalty dead
    band); the grid allows it on top of 2 % of the current limit, as the
    scenarios' checks do. On paper 002's design the half-torque standstill
    point settles 3.7 A off its 75 A reference: more than 2 % of 150 A, inside
    the band."""
    from toolbox.pipeline import design_spec, run_verification
    from toolbox.spec import load_spec

    spec = load_spec(ROOT / "designs" / "002_cormerais2002_fcs_mpc.toml")
    env = run_verification(design_spec(spec), spec).envelope
    assert env["passed"], env["failures"]
    assert env["design_band_a"] > 0.0
    worst = max(p["error"] for p in env["points"] if p["status"] == "pass")
    assert 0.02 * env["i_max"] < worst <= 0.02 * env["i_max"] + env["design_band_a"]
