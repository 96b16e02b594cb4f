"""Property-based checks on random plausible motors (hypothesis).

Every linear method is designed for motors drawn over the range a drive
engineer meets (R 0.01-10 ohm, L 10 uH-100 mH, vdc 12-800 V, Ts 25-500 us,
1-12 pole pairs), with its parameters scaled to the motor and the sample
time, then driven through large saturating current steps at standstill and at
speed. The properties:

* no traceback: the design exists (or is refused with a SpecError that names
  a key, which these well-posed cases must not need), every number is finite;
* the current reaches its reference within the voltage-limited bound
  ``t_min = L di / (V_avail - R i - EMF)`` plus a few closed-loop time
  constants and the delay (anti-windup that works);
* no windup overshoot;
* the analysis (sampled loop with ZOH and delay) and the simulation agree on
  stability.

The draws are derandomised so that CI runs the same cases every time, and
bounded in number so that the module stays within about a minute.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from toolbox.analysis import compute_margins
from toolbox.pipeline import design_spec, run_verification
from toolbox.spec import spec_from_dict

#: slow: designs and simulations of many random motors
pytestmark = pytest.mark.slow

# Closed-loop bandwidth scaled to the sample time: with one period of
# computation delay plus the ZOH half period, wc = 0.15/Ts costs
# 1.5 * 0.15 rad = 13 deg of phase, a sound design point for every method.
WC_TS = 0.15

PROFILE = settings(max_examples=6, deadline=None, derandomize=True,
                   suppress_health_check=[HealthCheck.too_slow,
                                          HealthCheck.filter_too_much])


def _log_uniform(lo: float, hi: float):
    return st.floats(math.log(lo), math.log(hi)).map(math.exp)


@st.composite
def motors(draw):
    """A plausible motor and drive (SI units), amplitude-invariant dq."""
    R = draw(_log_uniform(0.01, 10.0))
    Lq = draw(_log_uniform(1e-5, 0.1))
    Ld = Lq * draw(st.floats(0.4, 1.0))
    Ts = draw(_log_uniform(25e-6, 500e-6))
    vdc = draw(_log_uniform(12.0, 800.0))
    p = draw(st.integers(1, 12))
    flux = draw(_log_uniform(1e-3, 0.5))
    tau = Lq / R
    # a current loop only makes sense when the electrical time constant is
    # resolved by the sampling, and no real stator has tau above a second
    assume(5 * Ts <= Ld / R and tau <= 2.0)
    # rated current: what 10 % of the inverter's voltage drives through R
    rated = 0.1 * vdc / math.sqrt(3) / R
    return {"R": R, "Ld": Ld, "Lq": Lq, "flux": flux, "pole_pairs": p,
            "J": 1e-3, "friction": 0.0, "rated_current": rated}, {"vdc": vdc, "sample_time": Ts,
                                           "delay_samples": 1}


def _controller(method: str, motor: dict, Ts: float) -> dict:
    wc = WC_TS / Ts
    if method == "pi":
        return {method: {"rule": "cancellation", "bandwidth": wc}}
    if method == "ip":
        # not rule = "cancellation": its IP reference response follows the
        # plant's own L/R by design (the design warns), up to 2 s here, which
        # no bound on the saturated rise can cover. Explicit gains put both
        # poles of L s^2 + (R + Kp) s + Ki at -wc: reference response
        # wc^2/(s + wc)^2, 5 % time 4.7/wc; Kp = 2 wc L - R > 0 since
        # wc L = 0.15 L/Ts >= 0.75 R (the draw's L/R >= 5 Ts).
        L = motor["Lq"]
        return {"ip": {"rule": "explicit", "Kp": 2 * wc * L - motor["R"], "Ki": wc ** 2 * L}}
    if method == "pi_lag":
        return {method: {"rule": "cancellation", "bandwidth": 0.5 * wc,
                         "lag_time_constant": Ts}}
    if method == "tc":
        return {"tc": {"K1": wc, "K2": wc}}
    if method == "tci":
        return {"tci": {"natural_frequency": 0.5 * wc, "damping": 1.0}}
    if method == "ilq":
        # sigma given explicitly: when the motor's own pole -R/L is already
        # faster than s*, the eq (3) bound is 0 and any sigma > 0 is optimal
        return {"ilq": {"poles": -wc, "sigma": 2 * wc}}
    if method == "lq":
        return {"lq": {"domain": "discrete", "bandwidth": wc}}
    if method == "hinf":
        # S/KS mixed sensitivity: a biproper W3 puts its (fast) pole into the
        # controller, beyond pi/Ts for these bandwidths, which the design
        # rightly refuses without an order reduction
        weight = {"w1": {"dc_gain": 1000.0, "crossover": 0.5 * wc, "crossover_gain": 1.0,
                         "hf_gain": 0.5, "order": 1},
                  "w2": 1.0 / (motor["Lq"] * 5 * wc)}
        return {"hinf": {"gamma": "optimal", "backoff": 0.1,
                         "weights": {"d": weight, "q": weight}}}
    if method == "fcs_mpc":
        return {"fcs_mpc": {"alpha": 1.0, "beta": 1.0, "gamma": 0.0}}
    if method == "cv":
        # the direct discrete-time complex-vector law: tracking pole at wc, the
        # integral pole twice as fast (the gallery's ratio)
        return {"cv": {"bandwidth": wc, "integral_bandwidth": 2 * wc}}
    raise AssertionError(method)


def _step_case(motor: dict, drive: dict, speed_frac: float):
    """Reference step and imposed speed that saturate the voltage yet stay reachable.

    Returns (iq_step in A, mechanical speed in rad/s, available q voltage in V).
    """
    v_max = drive["vdc"] / math.sqrt(3)        # inscribed circle, amplitude-invariant
    Ts = drive["sample_time"]
    i_step = 0.3 * v_max / motor["R"]           # R i uses at most 30 % of the voltage
    w_e = speed_frac * v_max / motor["flux"]    # EMF = speed_frac * v_max
    w_e = min(w_e, 0.05 / Ts)                   # at most 3 deg of rotation per period
    # the d-axis voltage w Lq i_q eats into the circle; keep it below 20 %
    i_step = min(i_step, 0.2 * v_max / max(w_e * motor["Lq"], 1e-30))
    v_d = w_e * motor["Lq"] * i_step
    v_q_avail = math.sqrt(v_max ** 2 - v_d ** 2) - motor["R"] * i_step - w_e * motor["flux"]
    return i_step, w_e / motor["pole_pairs"], v_q_avail


def _spec(method: str, motor: dict, drive: dict, i_step: float, speed: float,
          duration: float) -> dict:
    return {"title": f"random {method}", "motor": motor, "drive": drive,
            "controller": {"method": method, **_controller(method, motor, drive["sample_time"])},
            "scenario": [{"name": "saturating q step", "kind": "current_step",
                          "duration": duration, "iq_ref": i_step, "step_time": 0.0,
                          "initial_speed": speed, "keep_traces": True}]}


def _check_method(method: str, motor: dict, drive: dict, speed_frac: float) -> None:
    Ts = drive["sample_time"]
    wc = WC_TS / Ts
    i_step, speed, v_q_avail = _step_case(motor, drive, speed_frac)
    assume(v_q_avail > 0.2 * drive["vdc"] / math.sqrt(3))
    # linear loop would ask L wc i_step at the step: saturating by construction?
    t_min = motor["Lq"] * i_step / v_q_avail
    # bound: voltage-limited rise, plus 3/wc for the 5 % tail of the linear
    # loop after desaturation (ln 20 = 3.0 time constants of a first-order
    # loop), plus the computation delay and the ZOH (2 periods); a factor 1.5
    # on t_min covers the resistive and d-axis voltage growing during the rise
    # and the hexagon/circle margin the bound ignores
    t_bound = 1.5 * t_min + 3.0 * math.log(20) / wc + 4 * Ts
    duration = max(3 * t_bound, 200 * Ts)
    spec = spec_from_dict(_spec(method, motor, drive, i_step, speed, duration))
    artifact = design_spec(spec)
    margins = compute_margins(artifact, spec.motor, step=False)
    for axis, m in margins.items():
        data = m.to_json()
        assert data.get("stable") is True, (method, axis, data)
    result = run_verification(artifact, spec)
    (outcome,) = result.scenarios
    trace = outcome.result
    iq = np.asarray(trace.iq)
    t = np.asarray(trace.t)
    assert np.all(np.isfinite(iq)) and np.all(np.isfinite(trace.vq))
    inside = np.abs(iq - i_step) <= 0.05 * i_step
    # 5 % time from the trace: last instant outside the band
    outside = np.nonzero(~inside)[0]
    assert outside.size < iq.size, f"{method}: never within 5 % (final {iq[-1]:.4g} of {i_step:.4g} A)"
    t5 = t[outside[-1] + 1] if outside.size else 0.0
    assert t5 <= t_bound, (f"{method}: 5 % time {t5:.4g} s > bound {t_bound:.4g} s "
                           f"(t_min {t_min:.4g} s)")
    # no windup overshoot: a 2-DOF law or a PI without windup overshoots at
    # most as the linear design does (below 25 % for these bandwidths)
    overshoot = (iq.max() - i_step) / i_step
    assert overshoot <= 0.25, f"{method}: overshoot {100 * overshoot:.3g} %"


METHODS = ["pi", "ip", "pi_lag", "tc", "tci", "ilq", "lq", "hinf"]


def _check_fcs_mpc(motor: dict, drive: dict, speed_frac: float) -> None:
    """Boolean predictive control (paper 002 criterion (23)): no linear loop,
    so the bound is the voltage-limited rise plus a few periods, and the
    reference is met on average (the switching ripple, about V Ts / L, is
    inherent to a finite-control-set law)."""
    Ts = drive["sample_time"]
    i_step, speed, v_q_avail = _step_case(motor, drive, speed_frac)
    assume(v_q_avail > 0.2 * drive["vdc"] / math.sqrt(3))
    t_min = motor["Lq"] * i_step / v_q_avail
    # 1.5 t_min as for the linear laws; 10 periods for the delay and the
    # last approach, which the predictive law makes in single vectors
    t_bound = 1.5 * t_min + 10 * Ts
    duration = max(4 * t_bound, 400 * Ts)
    data = _spec("fcs_mpc", motor, drive, i_step, speed, duration)
    data["scenario"][0]["inverter"] = "fcs_mpc"
    spec = spec_from_dict(data)
    artifact = design_spec(spec)
    (outcome,) = run_verification(artifact, spec).scenarios
    trace = outcome.result
    t, iq = np.asarray(trace.t), np.asarray(trace.iq)
    assert np.all(np.isfinite(iq))
    ripple = 2.0 * drive["vdc"] * Ts / motor["Lq"]        # one full vector for a period
    reached = np.nonzero(iq >= i_step - max(0.05 * i_step, ripple))[0]
    assert reached.size, f"fcs_mpc: never reached {i_step:.4g} A (max {iq.max():.4g})"
    assert t[reached[0]] <= t_bound, (t[reached[0]], t_bound, t_min)
    tail = iq[t >= 0.5 * duration]
    assert abs(tail.mean() - i_step) <= max(0.05 * i_step, ripple), (tail.mean(), i_step)


@PROFILE
@given(case=motors(), at_speed=st.booleans())
def test_fcs_mpc_reaches_reference(case, at_speed):
    motor, drive = case
    drive = {**drive, "delay_samples": 1, "voltage_limit": "hexagon"}
    _check_fcs_mpc(motor, drive, 0.4 if at_speed else 0.0)


@PROFILE
@given(case=motors(), at_speed=st.booleans())
def test_cv_saturating_step_reaches_reference(case, at_speed):
    """Method ``cv`` (its gains recomputed at the measured speed, the realised-
    voltage integrator) under the same saturating step and bounds as the
    linear laws below; kept out of ``METHODS``, whose header tests also try
    the hexagon limit that the cv header refuses."""
    motor, drive = case
    _check_method("cv", motor, drive, 0.4 if at_speed else 0.0)


@pytest.mark.parametrize("method", METHODS)
@PROFILE
@given(case=motors(), at_speed=st.booleans())
def test_saturating_step_reaches_reference(method, case, at_speed):
    motor, drive = case
    _check_method(method, motor, drive, 0.4 if at_speed else 0.0)
