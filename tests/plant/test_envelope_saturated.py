"""The saturated operating envelope (toolbox/plant/_envelope_saturated.py,
toolbox/ARCHITECTURE.md "Operating envelope").

* **Linear magnetics equal the constant envelope**: a motor whose magnetic
  model is linear (``psi = (Ld i_d + flux, Lq i_q)``), once as the algebraic
  model (no self/cross saturation, constant bridge term: ``W = 0``) and once
  as a flux map of that linear flux (bilinear interpolation of linear data is
  exact), gives :class:`toolbox.plant.OperatingEnvelope`'s MTPA,
  field-weakening, current-limit, corner and MTPV points and base speed to
  1e-7 x I (measured 3.2e-8 x I: the saturated envelope solves the optimality
  conditions by Newton's method with central differences, exact for the
  quadratic voltage and current and the bilinear torque up to rounding; the
  constant envelope is exact to 1e-9 x I), in both torque signs, at 0 to 3 x
  base speed.
* **The corpus PM-SyRM against an independent route**: motulator 0.5 (the
  installed one) has no saturated loci (its ``TorqueCharacteristics``
  "omits the magnetic saturation"; the saturated control loci came with a
  later motulator whose API the simulator's cross-checks do not use), so the
  reference here is a nested scalar search on ``MagneticModel.torque`` /
  ``flux`` in current coordinates (brentq / bounded minimize_scalar; none of
  the envelope's flux-coordinate Newton machinery): the MTPA point of a
  torque (the current amplitude whose best angle gives that torque), the
  field-weakening point (along the torque curve by angle, the root of
  ``|v| = V``), the corner of both limits (the angle on the current circle
  where ``|v| = V``) and the MTPV point (the largest torque on the voltage
  boundary, polar around the zero-flux current). Tolerance 1e-5 x I: both
  routes solve the same conditions, the reference to 1e-10 in angle and
  amplitude, the envelope to its stencil's 1e-8 of the model scale; measured
  2.9e-7 x I. The same for the motor's flux tabulated as a 41 x 41 flux map
  (bilinear: its optima sit on cell edges where Newton's method stalls, the
  envelope's scalar routes take over; measured 2.6e-8 x I).
* The factory picks the saturated envelope for a saturated motor only.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import toolbox
from toolbox.plant import OperatingEnvelope, SaturatedEnvelope, envelope_of
from toolbox.spec import AlgebraicSaturation, FluxMapData, MagneticModel, Motor

ROOT = Path(__file__).resolve().parents[2]
PMSYRM = ROOT / "tests" / "corpus" / "motors" / "baldor_ecs101m0h7ef4_pmsyrm.toml"

R, LD, LQ, PSI, P = 0.63, 0.018, 0.05, 0.48, 2


def _linear_motors():
    """The same linear magnetics as an algebraic model and as a flux map."""
    base = Motor(R=R, Ld=LD, Lq=LQ, flux=PSI, pole_pairs=P, J=0.01, max_current=25.0)
    # i_d = a_d0 psi_d + G_b (psi_d - psi_n) with W = 0: G_b = a_b / (1 + a_bp), constant
    a_b = 10.0
    a_d0 = 1.0 / LD - a_b
    alg = AlgebraicSaturation(a_d0=a_d0, a_dd=0.0, S=4, a_q0=1.0 / LQ, a_qq=0.0, T=6,
                              a_dq=0.0, U=1, V=1, a_b=a_b, a_bp=0.0, k_q=0.0,
                              psi_n=PSI * (a_d0 + a_b) / a_b, W=0.0, current_range=40.0)
    ig = np.linspace(-40.0, 40.0, 9)
    D, Q = np.meshgrid(ig, ig, indexing="ij")
    fmap = FluxMapData(ig, ig, LD * D + PSI, LQ * Q)
    return base, {"algebraic": replace(base, magnetics=MagneticModel("algebraic", alg, 12.5)),
                  "map": replace(base, magnetics=MagneticModel("map", fmap, 12.5))}


def _dist(a, b):
    return math.hypot(a[0] - b[0], a[1] - b[1])


@pytest.mark.parametrize("kind", ["algebraic", "map"])
def test_linear_magnetics_equal_the_constant_envelope(kind):
    base, motors = _linear_motors()
    lin = OperatingEnvelope(base, v_max=300.0)
    sat = envelope_of(motors[kind], v_max=300.0)
    assert isinstance(sat, SaturatedEnvelope) and isinstance(envelope_of(base, v_max=300.0),
                                                             OperatingEnvelope)
    tol = 1e-7 * lin.I
    wb = lin.base_speed()
    assert abs(sat.base_speed() - wb) <= 1e-9 * wb
    t_lim = lin.max_torque_point(0.0).torque
    err, regions = 0.0, set()
    for sf in (0.0, 0.5, 1.0, 1.5, 2.0, 3.0):
        w = sf * wb
        for sign in (1.0, -1.0):
            a, b = sat.max_torque_point(w, sign), lin.max_torque_point(w, sign)
            assert a.region == b.region and abs(a.torque - b.torque) <= 1e-7 * t_lim
            err = max(err, _dist((a.i_d, a.i_q), (b.i_d, b.i_q)))
            regions.add(b.region)
        for tf in (0.0, 0.25, 0.5, 0.75, 1.0, -0.5):
            a, b = sat.operating_point(tf * t_lim, w), lin.operating_point(tf * t_lim, w)
            assert a.region == b.region, (sf, tf, a, b)
            err = max(err, _dist((a.i_d, a.i_q), (b.i_d, b.i_q)))
            regions.add(b.region)
        if sf >= 2.0:   # MTPV within the linear model's 40 A range
            err = max(err, _dist(sat.mtpv(w), lin.mtpv(w)))
        elif sf > 0.0:  # beyond it: NaN, not an extrapolation
            assert all(math.isnan(x) for x in sat.mtpv(w))
    # every region of the envelope was compared
    assert regions >= {"mtpa", "field_weakening", "current_limit", "current_and_voltage_limit"}
    print(f"\n{kind}: max |di| {err:.3g} A ({err / lin.I:.2g} x I)")
    assert err <= tol


# ------------------------------------------------------------- PM-SyRM corpus
def _pmsyrm(kind="algebraic"):
    """The corpus PM-SyRM; ``kind = "map"``: its flux tabulated on a 41 x 41
    grid over +-30 A (1.5 A steps) and read as a flux map (bilinear)."""
    spec = toolbox.spec_from_dict(tomllib.loads(PMSYRM.read_text()))
    m = spec.motor
    if kind == "map":
        ig = np.linspace(-30.0, 30.0, 41)
        D, Q = np.meshgrid(ig, ig, indexing="ij")
        pd, pq = m.magnetics.flux(D, Q)
        m = replace(m, magnetics=MagneticModel("map", FluxMapData(ig, ig, pd, pq),
                                               m.magnetics.nominal_current))
    env = envelope_of(m, v_max=(1 - OperatingEnvelope.HEADROOM)
                      * spec.drive.max_voltage(m.convention))
    return m, env


def _torque(m, r, b):
    return float(m.magnetics.torque(r * math.cos(b), r * math.sin(b), m.pole_pairs,
                                    m.torque_factor))


def _vmag(m, env, d, q, speed):
    ps_d, ps_q = m.magnetics.flux(d, q)
    w = m.pole_pairs * speed
    return math.hypot(m.R * d - w * float(ps_q), m.R * q + w * float(ps_d))


def _best_angle(m, r):
    res = minimize_scalar(lambda b: -_torque(m, r, b), bounds=(0.5 * math.pi, math.pi),
                          method="bounded", options={"xatol": 1e-10})
    return res.x, -res.fun


def _ref_mtpa(m, torque, i_hi):
    r = brentq(lambda r: _best_angle(m, r)[1] - torque, 1e-3, i_hi, xtol=1e-10)
    b = _best_angle(m, r)[0]
    return r * math.cos(b), r * math.sin(b)


def _ref_field_weakening(m, env, torque, speed, b_mtpa):
    def r_of(b):   # the torque curve by angle: the amplitude giving the torque
        return brentq(lambda r: _torque(m, r, b) - torque, 1e-3, 3 * env.I, xtol=1e-11)

    def vex(b):
        r = r_of(b)
        return _vmag(m, env, r * math.cos(b), r * math.sin(b), speed) - env.V

    # bracket: the first angle of a scan beyond MTPA where the voltage fits
    lo = b_mtpa
    for hi in np.linspace(b_mtpa, math.pi, 41)[1:]:
        if _torque(m, 3 * env.I, hi) < torque or vex(hi) < 0:
            break
        lo = hi
    b = brentq(vex, lo, hi, xtol=1e-11)
    r = r_of(b)
    return r * math.cos(b), r * math.sin(b)


def _ref_corner(m, env, speed, b_mtpa):
    I = env.I
    b = brentq(lambda b: _vmag(m, env, I * math.cos(b), I * math.sin(b), speed) - env.V,
               b_mtpa, math.pi, xtol=1e-11)
    return I * math.cos(b), I * math.sin(b)


def _ref_mtpv(m, env, speed):
    c_d, c_q = (float(x) for x in m.magnetics.current(0.0, 0.0))   # zero flux

    def on_boundary(a):
        rho = brentq(lambda r: _vmag(m, env, c_d + r * math.cos(a), c_q + r * math.sin(a),
                                     speed) - env.V, 0.0, 10.0, xtol=1e-11)
        return c_d + rho * math.cos(a), c_q + rho * math.sin(a)

    res = minimize_scalar(lambda a: -float(m.magnetics.torque(*on_boundary(a), m.pole_pairs,
                                                              m.torque_factor)),
                          bounds=(0.0, math.pi), method="bounded", options={"xatol": 1e-10})
    return on_boundary(res.x)


#: The algebraic model's search inverts the model by Newton at every sample
#: (~1.7 s): a cross-check run with the slow tests; the route itself runs on
#: every edit in tests/corpus/test_saturated_corpus.py (the corpus PM-SyRM).
@pytest.mark.parametrize("kind", [pytest.param("algebraic", marks=pytest.mark.slow), "map"])
def test_pmsyrm_envelope_against_nested_scalar_search(kind):
    m, env = _pmsyrm(kind)
    I = env.I
    tol = 1e-5 * I
    wb = env.base_speed()
    lim0 = env.max_torque_point(0.0)
    assert lim0.region == "current_limit"
    errs = {}
    # MTPA of the current limit and of two torques
    b_lim, t_lim = _best_angle(m, I)
    assert abs(lim0.torque - t_lim) <= 1e-8 * t_lim
    errs["mtpa I"] = _dist((lim0.i_d, lim0.i_q), (I * math.cos(b_lim), I * math.sin(b_lim)))
    for frac in (0.25, 0.6):
        op = env.operating_point(frac * t_lim, 0.5 * wb)
        assert op.region == "mtpa"
        errs[f"mtpa {frac}"] = _dist((op.i_d, op.i_q), _ref_mtpa(m, frac * t_lim, I))
    # base speed: the current limit's MTPA point on the voltage limit
    assert abs(_vmag(m, env, lim0.i_d, lim0.i_q, wb) - env.V) <= 1e-9 * env.V
    # field weakening at 1.5 and 2 x base speed, half the standstill limit
    for sf in (1.5, 2.0):
        op = env.operating_point(0.5 * t_lim, sf * wb)
        assert op.region == "field_weakening"
        b_m = math.atan2(*reversed(_ref_mtpa(m, 0.5 * t_lim, I)))
        errs[f"fw {sf}"] = _dist((op.i_d, op.i_q),
                                 _ref_field_weakening(m, env, 0.5 * t_lim, sf * wb, b_m))
        lim = env.max_torque_point(sf * wb)
        assert lim.region == "current_and_voltage_limit"
        errs[f"corner {sf}"] = _dist((lim.i_d, lim.i_q), _ref_corner(m, env, sf * wb, b_lim))
    # MTPV: this PM-SyRM's zero-flux current (26.5 A) exceeds its current limit
    # (infinite speed capability), so MTPV lies beyond it; at 16 x base speed
    # it is within the model's 30 A range
    d, q = env.mtpv(16.0 * wb)
    assert I < math.hypot(d, q) < env.model_range
    errs["mtpv 16"] = _dist((d, q), _ref_mtpv(m, env, 16.0 * wb))
    assert all(math.isnan(x) for x in env.mtpv(2.0 * wb))   # beyond the model's data there
    print(f"\n{kind}: " + ", ".join(f"{k}: {v:.2g} A" for k, v in errs.items()))
    assert max(errs.values()) <= tol, errs


@pytest.mark.parametrize("kind", ["algebraic", "map"])
def test_slsqp_route_agrees_with_the_newton_routes(kind):
    """The route a non-converging Newton solve falls back to (SLSQP on the
    full inequality-constrained problem) gives the torque limit at 0, 1.5 and
    2 x base speed and two field-weakening points within 1e-5 x I of the
    Newton / scalar routes (measured 1.3e-6 x I: the map's current-limit
    MTPA point on a cell edge, where SLSQP's constraint accuracy is 1e-5)."""
    m, env = _pmsyrm(kind)
    wb = env.base_speed()
    t_lim = env.max_torque_point(0.0).torque
    err = 0.0
    for sf in (0.0, 1.5, 2.0):
        a, b = env.max_torque_point(sf * wb), env._max_torque(sf * wb, 1.0, True)
        assert a.region == b.region
        err = max(err, _dist((a.i_d, a.i_q), (b.i_d, b.i_q)))
    for sf, tf in ((1.5, 0.5), (2.0, 0.25)):
        op = env.operating_point(tf * t_lim, sf * wb)
        t = tf * t_lim / env._Tscale
        seed = env._seed(env._sample_c() + 100.0 * (env._sT / env._Tscale - t) ** 2)
        u, _ = env._solve(sf * wb, lambda v, j: (v[1], j[1]), eq=lambda v, j: (v[0] - t, j[0]),
                          ineq=[env._volt_le], seed=seed)
        err = max(err, _dist((op.i_d, op.i_q), env._point(u)))
    print(f"\n{kind}: SLSQP vs Newton max |di| {err:.2g} A")
    assert err <= 1e-5 * env.I
