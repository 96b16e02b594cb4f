"""Operating envelope (toolbox/plant/_envelope.py): MTPA closed form, field
weakening, MTPV and the torque limit against independent routes.

* MTPA: the closed form against a bounded numeric maximisation of the torque
  over the current angle (and dT/d(angle) = 0), both conventions, both
  saliencies and the non-salient motor; against motulator 0.5's
  ``TorqueCharacteristics.mtpa`` (Morimoto 1990) on paper 003's motor.
* MTPV with R neglected against motulator's ``mtpv`` flux angle.
* References and torque limits against scipy SLSQP (least |i| subject to the
  torque, voltage and current constraints; largest torque subject to the
  limits), multi-start, on a traction-like motor whose characteristic current
  psi/Ld is inside the current limit (so MTPV is reached): within 2e-3 A and
  1e-4 relative torque (SLSQP's own accuracy is ~1e-6).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize, minimize_scalar

import toolbox
from toolbox.plant import OperatingEnvelope, mtpa_d_current
from toolbox.spec import Drive, Motor

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
TRACTION = Motor(R=0.02, Ld=0.4e-3, Lq=1.1e-3, flux=0.04, pole_pairs=4, J=0.01,
                 friction=0.0, convention="amplitude", max_current=200.0)  # psi/Ld = 100 A
TRACTION_DRIVE = Drive(vdc=300.0, sample_time=1e-4)


def _motors():
    base = dict(R=0.6, J=1e-3, friction=0.0, pole_pairs=4, max_current=20.0)
    return [Motor(Ld=1.4e-3, Lq=2.8e-3, flux=0.12, convention="amplitude", **base),
            Motor(Ld=1.4e-3, Lq=2.8e-3, flux=0.12, convention="power", **base),
            Motor(Ld=2.8e-3, Lq=1.4e-3, flux=0.12, convention="amplitude", **base),
            Motor(Ld=2.0e-3, Lq=2.0e-3, flux=0.12, convention="amplitude", **base)]


@pytest.mark.parametrize("k", range(4))
def test_mtpa_closed_form(k):
    """The closed form is the numeric maximiser of T(i_s cos b, i_s sin b) over
    b to 1e-7 A, and dT/db vanishes there (central difference, 1e-7 of T)."""
    m = _motors()[k]
    env = OperatingEnvelope(m, v_max=1e6)
    for i_s in (0.5, 5.0, 20.0, 60.0):
        i_d = mtpa_d_current(i_s, m.Ld, m.Lq, m.flux)
        b0 = math.atan2(math.sqrt(i_s ** 2 - i_d ** 2), i_d)
        res = minimize_scalar(lambda b: -env.torque(i_s * math.cos(b), i_s * math.sin(b)),
                              bounds=(0.0, math.pi), method="bounded",
                              options={"xatol": 1e-12})
        assert abs(i_s * math.cos(res.x) - i_d) < 1e-7 * max(i_s, 1.0)
        h = 1e-6
        dT = (env.torque(i_s * math.cos(b0 + h), i_s * math.sin(b0 + h))
              - env.torque(i_s * math.cos(b0 - h), i_s * math.sin(b0 - h))) / (2 * h)
        assert abs(dT) < 1e-7 * env.torque(i_d, math.sqrt(i_s ** 2 - i_d ** 2)) / h * 1e-6 + 1e-9
        # the textbook form for Lq > Ld
        if m.Lq > m.Ld:
            dL = m.Lq - m.Ld
            text = (m.flux - math.sqrt(m.flux ** 2 + 8 * dL ** 2 * i_s ** 2)) / (4 * dL)
            assert abs(text - i_d) < 1e-12 * i_s
        # mtpa(torque) inverts it
        T = float(env.torque(i_d, math.sqrt(i_s ** 2 - i_d ** 2)))
        d2, q2 = env.mtpa(T)
        assert abs(d2 - i_d) < 1e-9 * i_s and abs(math.hypot(d2, q2) - i_s) < 1e-9 * i_s
        d3, q3 = env.mtpa(-T)
        assert abs(d3 - d2) < 1e-12 and abs(q3 + q2) < 1e-12


def test_mtpa_and_mtpv_match_motulator():
    """Paper 003's motor (amplitude-invariant, as motulator): motulator's MTPA
    angle gives the same i_d to 1e-12 relative; with R neglected, its MTPV flux
    angle at |psi_s| = V / w gives the same currents as the envelope's largest
    torque on the voltage limit, to 1e-7 relative (the torque to 1e-12)."""
    from motulator.drive.control.sm import TorqueCharacteristics
    from motulator.drive.utils import SynchronousMachinePars
    spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
    m = spec.motor
    tc = TorqueCharacteristics(SynchronousMachinePars(n_p=m.pole_pairs, R_s=m.R, L_d=m.Ld,
                                                      L_q=m.Lq, psi_f=m.flux))
    for i_s in (1.0, 10.0, 20.0, 100.0):
        beta = tc.mtpa(i_s)
        assert abs(i_s * math.cos(beta) - mtpa_d_current(i_s, m.Ld, m.Lq, m.flux)) \
            < 1e-12 * i_s
        assert abs(tc.torque(tc.flux(i_s * np.exp(1j * beta)))
                   - OperatingEnvelope(m, spec.drive).torque(i_s * math.cos(beta),
                                                             i_s * math.sin(beta))) < 1e-12 * i_s
    # MTPV on the traction motor, R neglected
    mt = TRACTION
    env = OperatingEnvelope(mt, TRACTION_DRIVE, resistive=False)
    tct = TorqueCharacteristics(SynchronousMachinePars(n_p=mt.pole_pairs, R_s=0.0,
                                                       L_d=mt.Ld, L_q=mt.Lq, psi_f=mt.flux))
    for speed in (800.0, 1500.0, 3000.0):
        psi = env.V / (mt.pole_pairs * speed)
        delta = tct.mtpv(psi)
        i_ref = tct.current(psi * np.exp(1j * delta))
        d, q = env.mtpv(speed)
        print(f"\nMTPV {speed:g} rad/s: motulator ({i_ref.real:.6f}, {i_ref.imag:.6f}) "
              f"envelope ({d:.6f}, {q:.6f}) A")
        # the torque is flat at its maximum: the argmax to ~sqrt(eps) relative
        assert abs(complex(d, q) - i_ref) < 1e-7 * abs(i_ref)
        assert abs(env.torque(d, q) - tct.torque(tct.flux(i_ref))) < 1e-12 * abs(env.torque(d, q))


def _slsqp_reference(env, T, speed):
    """Least |i| with T(i) = T, |v| <= V, |i| <= I by SLSQP from several starts."""
    cons = [{"type": "eq", "fun": lambda x: (env.torque(*x) - T) / env.kt},
            {"type": "ineq", "fun": lambda x: (env.V ** 2 - env._vmag(*x, speed) ** 2) / env.V},
            {"type": "ineq", "fun": lambda x: (env.I ** 2 - x @ x) / env.I}]
    best = None
    for b in (0.8, 1.6, 2.4):
        x0 = 0.5 * env.I * np.array([math.cos(b), math.copysign(math.sin(b), T or 1.0)])
        r = minimize(lambda x: x @ x, x0, constraints=cons, method="SLSQP",
                     options={"ftol": 1e-12, "maxiter": 200})
        if r.success and all(c["fun"](r.x) > -1e-7 if c["type"] == "ineq"
                             else abs(c["fun"](r.x)) < 1e-8 for c in cons):
            if best is None or r.fun < best.fun:
                best = r
    return best


def _slsqp_max_torque(env, speed, sign):
    cons = [{"type": "ineq", "fun": lambda x: (env.V ** 2 - env._vmag(*x, speed) ** 2) / env.V},
            {"type": "ineq", "fun": lambda x: (env.I ** 2 - x @ x) / env.I}]
    best = None
    for b in (0.8, 1.6, 2.4):
        x0 = 0.3 * env.I * np.array([math.cos(b), sign * math.sin(b)])
        r = minimize(lambda x: -sign * env.torque(*x) / env.kt, x0, constraints=cons,
                     method="SLSQP", options={"ftol": 1e-12, "maxiter": 200})
        if r.success and all(c["fun"](r.x) > -1e-7 for c in cons):
            if best is None or r.fun < best.fun:
                best = r
    return best


@pytest.mark.slow
@pytest.mark.parametrize("motor_name", ["traction", "paper003"])
def test_references_match_numeric_optimisation(motor_name):
    """0 / 25 / 50 / 75 / 100 % of the standstill torque limit, both signs, at
    0.5 .. 4 x base speed (paper 003's motor: up to 1.5 x, beyond it nothing
    fits): the envelope's reference has the least |i| SLSQP finds, to 2e-3 A;
    a torque beyond the limit at that speed comes back as the limit, which
    equals SLSQP's largest torque to 1e-4 relative."""
    if motor_name == "traction":
        env = OperatingEnvelope(TRACTION, TRACTION_DRIVE)
        speeds = np.array([0.5, 1.5, 2.0, 4.0])
    else:
        spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
        env = OperatingEnvelope(spec.motor, spec.drive)
        speeds = np.array([0.5, 1.0, 1.2, 1.5])
    wb = env.base_speed()
    t0 = env.max_torque_point(0.0).torque
    regions = set()
    n = 0
    worst = dt_worst = 0.0
    for speed in speeds * wb:
        for sign in (1.0, -1.0):
            lim = env.max_torque_point(speed, sign)
            ref = _slsqp_max_torque(env, speed, sign)
            assert ref is not None
            dt_worst = max(dt_worst, abs(lim.torque - sign * (-ref.fun) * env.kt) / t0)
            assert abs(lim.torque - sign * (-ref.fun) * env.kt) <= 1e-4 * t0, (speed, sign)
            for frac in (0.0, 0.25, 0.5, 0.75, 1.0):
                T = sign * frac * t0
                op = env.operating_point(T, speed)
                regions.add(op.region)
                assert math.hypot(op.i_d, op.i_q) <= env.I * (1 + 1e-9)
                assert env._vmag(op.i_d, op.i_q, speed) <= env.V * (1 + 1e-9)
                if sign * T > sign * lim.torque + 1e-9 * t0:
                    assert op == lim
                    continue
                assert abs(float(env.torque(op.i_d, op.i_q)) - T) < 1e-9 * t0
                r = _slsqp_reference(env, T, speed)
                assert r is not None, (T, speed)
                err = math.hypot(op.i_d - r.x[0], op.i_q - r.x[1])
                n += 1
                worst = max(worst, err)
                assert err < 2e-3, (T, speed, op, r.x)
    print(f"\n{motor_name}: base speed {wb:.2f} rad/s, {n} references checked, "
          f"regions {sorted(regions)}; worst |di| {worst:.2e} A, torque limit {dt_worst:.2e}")
    assert "field_weakening" in regions and "mtpa" in regions
    if motor_name == "traction":
        assert "voltage_limit" in regions      # MTPV reached: psi/Ld inside the current limit


def test_base_speed_and_limits():
    """At base speed the current-limit MTPA point is on the voltage limit; the
    envelope refuses to be built without a current or voltage limit."""
    env = OperatingEnvelope(TRACTION, TRACTION_DRIVE)
    wb = env.base_speed()
    d = mtpa_d_current(env.I, TRACTION.Ld, TRACTION.Lq, TRACTION.flux)
    q = math.sqrt(env.I ** 2 - d ** 2)
    assert abs(env._vmag(d, q, wb) - env.V) < 1e-9 * env.V
    assert env.max_torque_point(0.5 * wb).region == "current_limit"
    from toolbox.errors import SpecError
    with pytest.raises(SpecError, match="max_current"):
        OperatingEnvelope(Motor(R=0.1, Ld=1e-3, Lq=1e-3, flux=0.1, pole_pairs=2, J=1e-3,
                                friction=0.0), TRACTION_DRIVE)
    with pytest.raises(SpecError, match="drive"):
        OperatingEnvelope(TRACTION)


def _fw_quartic(env, T, speed):
    """Field weakening in closed form (R = 0): the constant-torque curve
    ``i_q = T / (k (psi + (Ld - Lq) i_d))`` on the voltage ellipse
    ``(Ld i_d + psi)^2 + (Lq i_q)^2 = (V / w)^2`` is the quartic
    ``(Ld i_d + psi)^2 (psi + a i_d)^2 + (Lq T / k)^2 - (V / w)^2 (psi + a i_d)^2 = 0``
    (``a = Ld - Lq``); its real root of least current amplitude within the
    current limit, roots by numpy (companion-matrix eigenvalues)."""
    from numpy.polynomial import polynomial as P
    a = env.Ld - env.Lq
    p1, p2 = [env.flux, env.Ld], [env.flux, a]
    rho = env.V / (env.p * speed)
    poly = P.polysub(P.polyadd(P.polymul(P.polymul(p1, p1), P.polymul(p2, p2)),
                               [(env.Lq * T / env.kt) ** 2]),
                     P.polymul([rho ** 2], P.polymul(p2, p2)))
    best = None
    for r in P.polyroots(poly):
        if abs(r.imag) > 1e-9 * env.I or env.flux + a * r.real <= 0:
            continue
        d = r.real
        q = T / (env.kt * (env.flux + a * d))
        if math.hypot(d, q) <= env.I * (1 + 1e-9) and (best is None
                                                       or math.hypot(d, q) < math.hypot(*best)):
            best = (d, q)
    return best


def _corner(env, speed):
    """The current-and-voltage corner in closed form (R = 0): the circle
    ``i_d^2 + i_q^2 = I^2`` on the ellipse gives
    ``i_d = (psi Ld - sqrt((psi Ld)^2 + (Lq^2 - Ld^2)(psi^2 + Lq^2 I^2 - (V/w)^2))) / (Lq^2 - Ld^2)``
    (the root of negative ``i_d``; Morimoto et al. 1990's corner of the
    constant-power region)."""
    rho = env.V / (env.p * speed)
    den = env.Lq ** 2 - env.Ld ** 2
    disc = (env.flux * env.Ld) ** 2 + den * (env.flux ** 2 + (env.Lq * env.I) ** 2 - rho ** 2)
    i_d = (env.flux * env.Ld - math.sqrt(disc)) / den
    return i_d, math.sqrt(env.I ** 2 - i_d ** 2)


@pytest.mark.parametrize("motor_name", ["traction", "paper003"])
def test_field_weakening_closed_form(motor_name):
    """R neglected (``resistive=False``, the textbook ellipse): every
    field-weakening reference of 10 .. 100 % of the standstill torque limit
    at 1.05 .. 4 x base speed equals the closed-form intersection of the
    torque curve with the voltage ellipse (quartic roots) to 1e-9 x I
    (brentq's xtol 1e-13 A; numpy's roots ~1e-12 relative); every point
    limited by both limits below MTPV equals the circle-ellipse corner to
    1e-7 x I (the boundary search's argmax: bounded search to 1e-13 rad on a
    flat maximum, ~sqrt(eps)). MTPA below base speed is the closed form
    ``(psi - sqrt(psi^2 + 8 dL^2 i^2)) / (4 dL)`` (test_mtpa_closed_form)."""
    if motor_name == "traction":
        env = OperatingEnvelope(TRACTION, TRACTION_DRIVE, resistive=False)
    else:
        spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
        env = OperatingEnvelope(spec.motor, spec.drive, resistive=False)
    base = env.base_speed()
    t_max = env.max_torque_point(0.0).torque
    n_fw = n_corner = 0
    for sf in (1.05, 1.2, 1.5, 2.0, 3.0, 4.0):
        for tf in (0.1, 0.25, 0.5, 0.75, 1.0):
            try:
                op = env.operating_point(tf * t_max, sf * base)
            except toolbox.errors.SpecError:
                continue
            if op.region == "field_weakening":
                ref = _fw_quartic(env, tf * t_max, sf * base)
                assert ref is not None
                assert math.hypot(op.i_d - ref[0], op.i_q - ref[1]) < 1e-9 * env.I, (sf, tf)
                n_fw += 1
            elif op.region == "current_and_voltage_limit":
                mtpv = env.mtpv(sf * base)
                if math.hypot(*mtpv) > env.I:   # the corner, not MTPV
                    ref = _corner(env, sf * base)
                    assert math.hypot(op.i_d - ref[0], op.i_q - ref[1]) < 1e-7 * env.I, (sf, tf)
                    n_corner += 1
    print(f"\n{motor_name}: {n_fw} field-weakening points, {n_corner} corners checked")
    assert n_fw >= 5 and n_corner >= 2


def _dense_max_torque(env, speed, sign, n=20000):
    """Independent route for the torque limit with ``R``: both boundaries
    (the current circle, the voltage boundary ``i = Z^{-1} (V e^{jf} - e)``)
    sampled at ``n`` angles, the feasible samples' best refined by scipy's
    bounded scalar search within one sample, a feasibility end by brentq."""
    from scipy.optimize import brentq
    w = env.p * speed
    Z = np.array([[env.R, -w * env.Lq], [w * env.Ld, env.R]])
    curves = [(lambda t: (env.I * np.cos(t), env.I * np.sin(t)),
               lambda d, q: env._vmag(d, q, speed) ** 2 - env.V ** 2)]
    if abs(np.linalg.det(Z)) > 0:
        def vb(t):
            i = np.linalg.solve(Z, np.vstack([env.V * np.cos(t), env.V * np.sin(t)
                                              - w * env.flux]))
            return i[0], i[1]
        curves.append((vb, lambda d, q: d * d + q * q - env.I ** 2))
    best = None
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    dt = t[1]
    for curve, g in curves:
        d, q = curve(t)
        f = np.where(g(d, q) <= 0, sign * env.torque(d, q), -np.inf)
        k = int(np.argmax(f))
        if not np.isfinite(f[k]):
            continue
        fun = lambda s: -sign * float(env.torque(*curve(np.array([s])))[0])  # noqa: E731
        gs = lambda s: float(g(*curve(np.array([s])))[0])  # noqa: E731
        cands = [t[k]]
        r = minimize_scalar(fun, bounds=(t[k] - dt, t[k] + dt), method="bounded",
                            options={"xatol": 1e-13})
        if gs(r.x) <= 0:
            cands.append(r.x)
        for nb in (t[k] - dt, t[k] + dt):
            if gs(nb) > 0:
                cands.append(brentq(gs, min(nb, t[k]), max(nb, t[k]), xtol=1e-15))
        for c in cands:
            if gs(c) <= 1e-9 * max(env.V, env.I) ** 2 and (best is None or fun(c) < best[0]):
                best = (fun(c), c, curve)
    if best is None:
        return None
    d, q = best[2](np.array([best[1]]))
    return float(d[0]), float(q[0])


#: The traction motor (the widest speed range, 4 x base speed) on every edit;
#: the dense-search cross-check of the other shapes with the slow tests.
@pytest.mark.parametrize("motor_name", ["traction"] + [
    pytest.param(m, marks=pytest.mark.slow) for m in ("paper003", "non_salient", "ld_above_lq")])
def test_torque_limit_and_field_weakening_with_r(motor_name):
    """``R`` kept: the torque limit (stationary points of the torque on both
    boundaries and their crossings, roots of degree-2 trigonometric
    polynomials) equals a dense search of both boundaries refined by scipy
    to 1e-12 of the standstill limit in torque and 1e-6 x I in current (the
    search's argmax on a flat maximum: ~sqrt(eps)); every field-weakening
    reference (the quartic's root) is on the voltage limit to 1e-12, gives
    the torque to 1e-12 and is brentq's first root of ``|v| = V`` along the
    torque curve from the MTPA point (a scan of 4000 steps towards
    negative i_d, then brentq, xtol 1e-13 A) to 1e-9 x I; a request of the
    limit's own torque gets the limit's currents (to 1e-9 x I: below base
    speed as the MTPA point of the current limit)."""
    from scipy.optimize import brentq
    speeds = (0.0, 0.5, 1.0, 1.05, 1.2, 1.4, 1.5)
    if motor_name == "traction":
        env = OperatingEnvelope(TRACTION, TRACTION_DRIVE)
        speeds = (0.0, 0.5, 1.0, 1.05, 1.5, 2.0, 3.0, 4.0)
    elif motor_name == "paper003":
        spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
        env = OperatingEnvelope(spec.motor, spec.drive)
    else:   # Ld = Lq (the torque linear in i_q: degree-1 polynomials), Ld > Lq
        env = OperatingEnvelope(_motors()[3 if motor_name == "non_salient" else 2],
                                v_max=150.0)
    base = env.base_speed()
    t0 = env.max_torque_point(0.0).torque
    n_lim = n_fw = 0
    for sf in speeds:
        w = sf * base
        for sign in (1.0, -1.0):
            lim = env.max_torque_point(w, sign)
            ref = _dense_max_torque(env, w, sign)
            assert abs(lim.torque - float(env.torque(*ref))) <= 1e-12 * t0, (sf, sign)
            assert math.hypot(lim.i_d - ref[0], lim.i_q - ref[1]) <= 1e-6 * env.I, (sf, sign)
            op = env.operating_point(lim.torque, w)   # the limit's own torque: its point
            assert op.torque == lim.torque
            assert math.hypot(op.i_d - lim.i_d, op.i_q - lim.i_q) <= 1e-9 * env.I, (sf, sign)
            n_lim += 1
            for tf in (0.1, 0.3, 0.5, 0.7, 0.9):
                T = sign * tf * abs(lim.torque)
                op = env.operating_point(T, w)
                if op.region != "field_weakening":
                    continue
                assert abs(env._vmag(op.i_d, op.i_q, w) - env.V) <= 1e-12 * env.V
                assert abs(float(env.torque(op.i_d, op.i_q)) - T) <= 1e-12 * t0
                d0, _ = env.mtpa(T)
                a = env.Ld - env.Lq
                iq = lambda d: T / (env.kt * (env.flux + a * d))  # noqa: E731
                vex = lambda d: float(env._vmag(d, iq(d), w)) - env.V  # noqa: E731
                grid = np.linspace(d0, -env.I, 4001)
                k = next(j for j in range(1, len(grid)) if vex(grid[j]) <= 0)
                d = brentq(vex, grid[k], grid[k - 1], xtol=1e-13, rtol=1e-15)
                assert math.hypot(op.i_d - d, op.i_q - iq(d)) <= 1e-9 * env.I, (sf, tf)
                n_fw += 1
    print(f"\n{motor_name}: {n_lim} torque limits, {n_fw} field-weakening references checked")
    assert n_fw >= 10
