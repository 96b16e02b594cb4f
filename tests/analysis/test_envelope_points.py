"""The one controller proved per operating point (toolbox/analysis/envelope_points.py;
toolbox/ARCHITECTURE.md "One controller, proved per point").

* At the design point (zero speed, zero current, constant-parameter motor) the
  per-point result is the nominal analysis: per-axis margins equal
  ``compute_margins``, the spectral radius the per-axis ``loop_stability`` one
  (at standstill the coupled loop is the two axis loops side by side), the
  multiloop disk margin ``mimo_disk_margins`` at speed 0; at speed, the
  coupled loop assembled from ``incremental_dq_matrices`` equals
  ``coupled_closed_loop`` (assembled from ``dq_matrices``) and the disk margin
  ``mimo_disk_margins`` at that speed.
* A constant-parameter motor has one tangent plant per speed: the result does
  not change with the current, and does change with the speed.
* The saturated corpus PM-SyRM (Baldor ECS101M0H7EF4): the tangent inductance
  is ``incremental_dq_matrices``' (and ``at_operating_point``'s diagonal);
  the PI designed at the nominal point is stable at every MTPA point up to the
  current limit, the PI designed with the unsaturated inductances (i = 0:
  Lq 2.9 x the nominal) is unstable at the loaded points, and the flux-state
  simulation agrees point by point: a 0.5 A q step at an unstable tangent
  point ends in a limit cycle (> 1 A peak to peak), at a stable one it settles
  (< 0.25 A).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import toolbox
from tolerances import C2D_RTOL, EIG_RTOL, REFINED_MARGIN_RTOL, REORDERED_RTOL
from toolbox.analysis import compute_margins, mimo_disk_margins
from toolbox.analysis.envelope_points import POINT_MARGIN_KEYS, tangent_loops
from toolbox.analysis.executed import loop_stability
from toolbox.analysis.margins import coupled_closed_loop
from toolbox.analysis._laws import executed_laws
from toolbox.plant import at_operating_point, incremental_dq_matrices
from toolbox.sim import scenario_setup, simulate
from toolbox.spec import FluxMapData, MagneticModel, Scenario

ROOT = Path(__file__).resolve().parents[2]
PMSYRM = ROOT / "tests" / "corpus" / "motors" / "baldor_ecs101m0h7ef4_pmsyrm.toml"
#: The multiloop disk margin by the closed-form ZOH (zoh_2x2) against expm
#: (mimo_disk_margins): the plant matrices agree to C2D_RTOL; 1/max mu over the
#: grid is a well-conditioned function of them near its peak (|S| ~ 1-3).
MIMO_RTOL = 1e3 * C2D_RTOL


def _design(name):
    spec = toolbox.load_spec(ROOT / "designs" / name)
    return spec, toolbox.design_spec(spec)


@pytest.mark.parametrize("name", ["003_azaiz2007_pi.toml", "003_azaiz2007_hinf.toml",
                                  "000_lepioufle1992_tci.toml", "003_azaiz2007_cv.toml"])
def test_design_point_is_the_nominal_analysis(name):
    spec, art = _design(name)
    motor = spec.motor
    (res,) = tangent_loops(art, motor, [(0.0, 0.0, 0.0)], axis_loops=True)
    nominal = compute_margins(art, motor)
    for ax in ("d", "q"):
        want = nominal[ax].to_json(extras=False)
        for key in POINT_MARGIN_KEYS:
            got, exp = float(res.margins[ax][key]), float(want[key])
            assert got == pytest.approx(exp, rel=REORDERED_RTOL) or got == exp, (ax, key)
    rho = max(s["spectral_radius"] for s in loop_stability(art, motor).values())
    assert res.spectral_radius == pytest.approx(rho, rel=EIG_RTOL)
    assert res.stable and res.passed and res.reason is None
    mimo = mimo_disk_margins(art, motor, max_speed_rad_s=0.0)
    assert res.mimo_disk_margin == pytest.approx(mimo.worst_disk_margin, rel=MIMO_RTOL)
    assert res.L_inc == ((motor.Ld, 0.0), (0.0, motor.Lq))


@pytest.mark.parametrize("name", ["003_azaiz2007_pi.toml", "003_azaiz2007_cv.toml"])
def test_at_speed_equals_the_coupled_loop_and_mimo_margins(name):
    spec, art = _design(name)
    motor = spec.motor
    w_e = 400.0                                    # electrical rad/s
    (res,) = tangent_loops(art, motor, [(w_e / motor.pole_pairs, 0.0, 5.0)])
    loop = coupled_closed_loop(executed_laws(art), art.decoupling, art.sample_time,
                               art.delay_samples, R=motor.R, Ld=motor.Ld, Lq=motor.Lq,
                               omega=w_e)
    assert res.spectral_radius == pytest.approx(float(loop.spectral_radius()[0]), rel=EIG_RTOL)
    mimo = mimo_disk_margins(art, motor, max_speed_rad_s=w_e, n_speeds=3)
    assert mimo.speeds_rad_s[2] == w_e
    assert res.mimo_disk_margin == pytest.approx(mimo.disk_margin[2], rel=MIMO_RTOL)
    # the speed matters: the standstill margin differs by far more than the tolerance
    assert abs(mimo.disk_margin[1] - mimo.disk_margin[2]) > 1e-3


def test_constant_motor_tangent_plant_changes_with_speed_only():
    spec, art = _design("003_azaiz2007_pi.toml")
    currents = [(0.0, 0.0), (0.0, 15.0), (-10.0, 12.0), (5.0, -20.0)]
    for speed in (0.0, 60.0, 120.0):
        res = tangent_loops(art, spec.motor, [(speed, a, b) for a, b in currents],
                            axis_loops=True)
        for r in res[1:]:
            assert r.L_inc == res[0].L_inc
            assert r.spectral_radius == res[0].spectral_radius
            assert r.mimo_disk_margin == res[0].mimo_disk_margin
            assert r.margins == res[0].margins
    slow, fast = tangent_loops(art, spec.motor, [(0.0, 0.0, 0.0), (120.0, 0.0, 0.0)])
    assert abs(slow.mimo_disk_margin - fast.mimo_disk_margin) > 0.1


@pytest.mark.parametrize("name", ["003_azaiz2007_hinf.toml", "001_takami2004_ilq.toml"])
def test_linear_flux_map_is_the_constant_motor(name):
    """The saturated route (inductance from the magnetic model, cross term,
    per-axis loops on its own grid) on a flux map that is linear, psi = L i +
    psi_pm, gives the constant-parameter motor's numbers at every point."""
    spec, art = _design(name)
    m = spec.motor
    i_d, i_q = np.linspace(-40.0, 40.0, 9), np.linspace(-40.0, 40.0, 11)
    D, Q = np.meshgrid(i_d, i_q, indexing="ij")
    flux_map = FluxMapData(i_d=i_d, i_q=i_q, psi_d=m.Ld * D + m.flux, psi_q=m.Lq * Q)
    mapped = replace(m, magnetics=MagneticModel("map", flux_map, nominal_current=10.0))
    points = [(0.0, 0.0, 0.0), (50.0, -5.0, 12.0), (150.0, -15.0, 3.0)]
    sat = tangent_loops(art, mapped, points, axis_loops=True)
    const = tangent_loops(art, m, points, axis_loops=True)
    for a, b in zip(sat, const):
        np.testing.assert_allclose(np.array(a.L_inc), np.array(b.L_inc), rtol=0,
                                   atol=REORDERED_RTOL * max(m.Ld, m.Lq))
        assert a.spectral_radius == pytest.approx(b.spectral_radius, rel=EIG_RTOL)
        assert a.mimo_disk_margin == pytest.approx(b.mimo_disk_margin, rel=MIMO_RTOL)
        for ax in ("d", "q"):
            for key in POINT_MARGIN_KEYS:
                x, y = float(a.margins[ax][key]), float(b.margins[ax][key])
                assert x == y or x == pytest.approx(y, rel=REFINED_MARGIN_RTOL), (ax, key)


# ----------------------------------------------------------- saturated PM-SyRM

@pytest.fixture(scope="module")
def pmsyrm():
    """The corpus PM-SyRM, the PI designed at the nominal point and the PI
    designed for the unsaturated motor (inductances at i = 0)."""
    data = tomllib.loads(PMSYRM.read_text())
    data["controller"] = {"method": "pi"}
    spec = toolbox.spec_from_dict(data)
    good = toolbox.design_spec(spec)
    Ld, Lq, flux = replace(spec.motor.magnetics, nominal_current=0.0).nominal()
    raw = dict(spec.raw)
    raw["motor"] = {k: v for k, v in raw["motor"].items() if k != "saturation"}
    raw["motor"].update(Ld=Ld, Lq=Lq, flux=flux)
    bad = toolbox.design_spec(toolbox.spec_from_dict(raw))
    m = spec.motor
    mtpa = [m.magnetics.mtpa(f * m.max_current, m.pole_pairs, m.torque_factor)
            for f in (0.5, 1.0)]
    points = [(0.0, 0.0, 0.0), (0.0, *mtpa[0]), (0.0, *mtpa[1]), (100.0, *mtpa[1]),
              (0.0, 0.0, 10.0)]
    return spec, good, bad, points


def test_pmsyrm_tangent_inductance_is_the_incremental_one(pmsyrm):
    spec, good, _bad, points = pmsyrm
    m = spec.motor
    res = tangent_loops(good, m, points)
    for (speed, i_d, i_q), r in zip(points, res):
        _A, B = incremental_dq_matrices(m, i_d, i_q, m.pole_pairs * speed)
        L = m.magnetics.incremental_inductance(i_d, i_q)
        # B = L^-1 inverted back: cond(L) < 10, a few ulps
        np.testing.assert_allclose(np.array(r.L_inc), L, rtol=REORDERED_RTOL, atol=0)
        np.testing.assert_allclose(np.linalg.inv(np.array(r.L_inc)), B, rtol=REORDERED_RTOL)
        tangent = at_operating_point(m, i_d, i_q)
        assert r.L_inc[0][0] == pytest.approx(tangent.Ld, rel=REORDERED_RTOL)
        assert r.L_inc[1][1] == pytest.approx(tangent.Lq, rel=REORDERED_RTOL)
    # saturation: the q inductance at the current limit is below half the unloaded one
    assert res[2].L_inc[1][1] < 0.5 * res[0].L_inc[1][1]


def _q_step_ripple(art, spec, point) -> float:
    """Peak-to-peak i_q (A) over the last 10 ms of a 0.5 A q step at ``point``
    (speed imposed, flying start to the point's currents, flux-state plant)."""
    speed, i_d, i_q = point
    sc = Scenario(kind="current_step", duration=0.04, step_time=0.02, id_ref0=i_d,
                  iq_ref0=i_q, id_ref=i_d, iq_ref=i_q + 0.5, initial_speed=speed,
                  keep_traces=True, trace_step=spec.drive.sample_time)
    law, drive = scenario_setup(art, sc, spec.drive)
    res = simulate(law, spec.motor, sc, drive)
    return float(np.ptp(res.iq[res.t >= 0.03]))


def test_pmsyrm_mistuned_design_is_caught_and_the_simulation_agrees(pmsyrm):
    spec, good, bad, points = pmsyrm
    lin_good = tangent_loops(good, spec.motor, points)
    lin_bad = tangent_loops(bad, spec.motor, points)
    assert all(r.stable and r.passed for r in lin_good)
    # the unsaturated design: stable unloaded and at half the current limit, unstable at
    # the current limit (standstill and 100 rad/s) and at 10 A on the q axis
    assert [r.stable for r in lin_bad] == [True, True, False, False, False]
    for r in lin_bad[2:]:
        assert not r.passed and "tangent loop unstable" in r.reason and r.spectral_radius > 1.0
        assert r.mimo_disk_margin == 0.0
    # the nonlinear simulation at every point agrees with the linear verdict
    for art, lin in ((good, lin_good), (bad, lin_bad)):
        for p, r in zip(points, lin):
            ripple = _q_step_ripple(art, spec, p)
            if r.stable:
                assert ripple < 0.25, (art.decoupling, p, ripple)
            else:
                assert ripple > 1.0, (p, ripple)


def test_margin_requirements_are_judged_per_point(pmsyrm):
    """A margin bound of the spec fails the points whose tangent loop misses it,
    with the reason; the nominal point passes it."""
    spec, good, _bad, points = pmsyrm
    data = tomllib.loads(PMSYRM.read_text())
    data["requirements"] = {"min_gain_margin_db": 8.0}
    req = toolbox.spec_from_dict(data).requirements
    res = tangent_loops(good, spec.motor, points, requirements=req)
    gm = [min(float(r.margins[a]["gain_margin_db"]) for a in "dq") for r in res]
    assert gm[0] > 8.0 > gm[2]                   # unloaded passes, the current limit does not
    for r, g in zip(res, gm):
        assert r.passed == (g >= 8.0)
        if not r.passed:
            assert "min_gain_margin_db 8" in r.reason and r.checks["min_gain_margin_db"][
                "pass"] is False


def test_predictive_law_is_not_analysed():
    spec, art = _design("002_cormerais2002_fcs_mpc.toml")
    (r,) = tangent_loops(art, spec.motor, [(10.0, 0.0, 1.0)])
    assert not r.analysed and r.passed and r.stable is None and math.isnan(r.spectral_radius)
    assert "not analysed" in r.basis
