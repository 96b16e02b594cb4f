"""Default checks applied to every verification scenario ("a pass
must mean something").

A spec without ``[requirements]`` used to pass whatever the simulated loop
did. Every scenario now gets these checks, derived from the spec alone:

``default.reach``
    The stepped current reaches its reference: it stays within a band
    ``tol = max(0.05 |delta|, floor)`` around the final reference from a time
    after the step no later than ``t_bound`` (see :func:`reach_time_bound`).
    ``floor = max(0.01 I_scale, 2 current_quantum, 3 current_noise, ripple)``:
    1 % of the current scale is the accuracy of a typical drive current
    sensor, and quantisation and noise cannot be tracked below their own size,
    so no band narrower than that is demanded of a small step; a band wider
    than ``RESOLVE_FRACTION`` (50 %) of the step fails: the step is not
    resolved, any current within the band would pass. ``ripple`` is
    zero for the average and SVM inverters (symmetric PWM samples the current
    at the centre of its ripple) and :func:`fcs_ripple` for the predictive
    switching inverter, which holds one of the eight voltage vectors (vertex
    radius ``r_hex``) for a whole period: the currents it can reach in one
    period are the centre and six vertices of a hexagon of radius
    ``d = r_hex Ts / L``, and the law picks the one nearest the reference, so
    the error it leaves is up to the covering radius of that lattice,
    ``d / sqrt(3)`` (the centroid of one of its equilateral triangles), not
    ``d / 2``: along a vertex direction it is ``d / 2``, between two vertices
    ``d / sqrt(3)``. With a switching penalty ``gamma`` in criterion (23) of
    paper 002 the law keeps the present vector while ``w e^2 <= gamma n``
    (``w`` the weight of the axis' squared error, ``n`` the commutations the
    better vector costs, at most 3): it tolerates, by design, a current error
    up to ``sqrt(3 gamma / w)`` before it switches, and :func:`fcs_ripple`
    adds that dead band. For that inverter the step metrics use the same band
    (:mod:`toolbox.verify._fcs_metrics`).
``default.bounded_current``
    Nothing diverges: the peak current magnitude ``|i_dq|`` (with traces) or
    the RMS tracking error ``sqrt(mse_id + mse_iq)`` (without) stays under
    ``CURRENT_FACTOR`` x ``I_scale`` (the largest reference or current limit
    of the scenario and motor). A well-damped loop overshoots by well under
    100 %, windup after saturation by about as much again; five times the
    scale is reached only by a loop that is oscillating or diverging.
``default.bounded_speed``
    The mechanical speed (peak with traces, final value without) stays under
    ``SPEED_FACTOR`` x the largest speed the scenario can produce: its
    references and imposed speeds, the drive's ``max_speed``, the motor's
    rated speed and the no-load speed ``V_max / (p psi_eff)`` at which the
    back-EMF uses the whole voltage (``psi_eff`` the flux weakened by a
    negative ``i_d`` reference). Twice that is out of reach of a sound drive.
``default.finite``
    Every metric is a finite number. A step metric of a scenario without a
    step is *not applicable* (left out); a step metric that cannot be
    computed (the response never settled in its band, never reached 90 %)
    is a failure with a reason.

Every failing record carries a ``reason`` string; values that are not finite
are stored as ``None`` (JSON has no NaN).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from toolbox.metrics import STEP_METRICS, band_entry_time
from toolbox.plant import steady_state_voltage

__all__ = ["fcs_ripple", "CURRENT_FACTOR", "SPEED_FACTOR", "REACH_BAND", "SENSOR_ACCURACY",
           "LinearFigures",
           "StepFacts", "step_facts", "reach_time_bound", "default_checks", "finalise_check"]

#: Relative band of the reach check (paper 000's "5 % response time").
REACH_BAND = 0.05
#: Widest reach band accepted, as a fraction of the step: a band (ripple,
#: sensor accuracy, noise) wider than this passes a current anywhere in it, so
#: the step is not resolved and ``default.reach`` fails.
RESOLVE_FRACTION = 0.5
#: Relative accuracy of a drive current sensor (fraction of the current scale).
SENSOR_ACCURACY = 0.01
#: Bound of ``default.bounded_current`` in units of the current scale.
CURRENT_FACTOR = 5.0
#: Bound of ``default.bounded_speed`` in units of the largest plausible speed.
SPEED_FACTOR = 2.0
#: Slack on the first-order settling time ``ln(20)/bandwidth``.
BANDWIDTH_FACTOR = 3.0
#: Slack on the linear closed-loop 5 % response time.
LINEAR_FACTOR = 1.5
#: Scenario kinds whose response signal is a current (the reach check applies).
CURRENT_STEP_KINDS = ("current_step", "constant_acceleration", "unloaded_start")


@dataclass(frozen=True)
class LinearFigures:
    """Linear (small-signal) figures of the executed sampled loop of one axis.

    Attributes
    ----------
    bandwidth_rad_s : float
        Closed-loop -3 dB bandwidth (rad/s); NaN when the loop is unstable.
    response_time_5pct : float
        Linear 5 % response time of the reference step (s); NaN if unknown.
    """

    bandwidth_rad_s: float
    response_time_5pct: float


@dataclass(frozen=True)
class StepFacts:
    """What a scenario asks of its response signal.

    Attributes
    ----------
    axis : str or None
        ``"q"`` or ``"d"`` for a current step, ``None`` when the reach check
        does not apply (speed loops, sinusoidal torque, no step).
    y0, yf : float
        Reference of the stepped current before and after the step (A).
    id_f, iq_f : float
        Both current references after the step (A).
    has_step : bool
        The response signal steps (step metrics apply).
    """

    axis: str | None
    y0: float
    yf: float
    id_f: float
    iq_f: float
    has_step: bool


def step_facts(scenario, plant, flux_c: float) -> StepFacts:
    """The stepped signal of a scenario, as the simulator chooses it.

    Parameters
    ----------
    scenario : Scenario
    plant : Motor
        True plant (pole pairs, torque factor).
    flux_c : float
        Controller model flux (Wb): a torque reference becomes ``i_q`` with it.
    """
    iq_f = scenario.iq_ref
    if scenario.torque_ref is not None:
        iq_f = scenario.torque_ref / (plant.torque_factor * plant.pole_pairs * flux_c)
    if scenario.kind in ("speed_step", "load_step"):
        return StepFacts(None, 0.0, 0.0, scenario.id_ref, iq_f,
                         scenario.kind == "speed_step"
                         and scenario.speed_ref != scenario.speed_ref0)
    if scenario.kind == "sinusoidal_torque":
        return StepFacts(None, 0.0, 0.0, scenario.id_ref, iq_f, False)
    # same choice as the simulator: i_d only when i_q does not step and i_d does
    if iq_f == scenario.iq_ref0 and scenario.id_ref != scenario.id_ref0:
        return StepFacts("d", scenario.id_ref0, scenario.id_ref, scenario.id_ref, iq_f, True)
    has = iq_f != scenario.iq_ref0
    return StepFacts("q" if has else None, scenario.iq_ref0, iq_f, scenario.id_ref, iq_f, has)


def _speed_extent(scenario, final_speed: float) -> float:
    """Largest mechanical speed magnitude (rad/s) the scenario runs at."""
    speeds = [abs(scenario.initial_speed)]
    if scenario.kind == "constant_acceleration":
        speeds.append(abs(scenario.initial_speed + scenario.acceleration * scenario.duration))
    elif math.isfinite(final_speed):
        # free acceleration under a constant torque is monotonic: the end is the extreme
        speeds.append(abs(final_speed))
    return max(speeds)


def reach_time_bound(facts: StepFacts, scenario, plant, v_max: float, delay_samples: int,
                     sample_time: float, linear: LinearFigures,
                     final_speed: float) -> tuple[float, str | None, dict]:
    """Latest acceptable time (s after the step) to enter the reach band.

    ``t_bound = t_min + max(3 ln(20)/w_b, 1.5 t_5,lin) + (d + 1) Ts``:

    * ``t_min = L |delta| / (V_avail - |v_ss|)`` is the physical lower bound
      of a voltage-limited step: the inductance can change its current no
      faster than the voltage left after the steady-state drop ``v_ss`` of the
      stepped axis (``R i_q + w (L_d i_d + psi)`` on q, ``R i_d - w L_q i_q``
      on d, at the largest electrical speed ``w`` of the run) allows.
      ``V_avail = sqrt(V_max^2 - v_other^2)`` is what the circle limit leaves
      to that axis once the other axis holds its steady voltage. R, L and psi
      are the true (simulated) plant's.
    * ``max(3 ln(20)/w_b, 1.5 t_5,lin)`` is the small-signal part: a
      first-order loop of bandwidth ``w_b`` enters its 5 % band at
      ``ln(20)/w_b``; the slack of 3 (and 1.5 on the linear 5 % time of the
      executed sampled loop, which already holds the delay) covers
      higher-order and lightly damped loops, mismatch and the transition out
      of saturation without letting a crawling loop pass.
    * ``(d + 1) Ts``: the computation delay plus the sample on which the
      step is seen.

    Parameters
    ----------
    facts : StepFacts
        The step (axis and references).
    scenario : Scenario
    plant : Motor
        True plant of the scenario (overrides applied).
    v_max : float
        dq voltage limit of the drive (V, linear modulation circle).
    delay_samples : int
    sample_time : float
        Controller period (s).
    linear : LinearFigures
        Figures of the executed loop of the stepped axis.
    final_speed : float
        Mechanical speed at the end of the run (rad/s).

    Returns
    -------
    t_bound : float
        Seconds after the step (inf when no bound exists).
    problem : str or None
        Why no finite bound exists (reference out of voltage reach, no
        linear bandwidth), else None.
    parts : dict
        ``t_min``, ``t_linear``, ``t_delay`` (s) for the record.
    """
    w_e = plant.pole_pairs * _speed_extent(scenario, final_speed)
    vd, vq = steady_state_voltage(plant.R, plant.Ld, plant.Lq, plant.flux, w_e,
                                  facts.id_f, facts.iq_f)
    v_own, v_other, L = (vq, vd, plant.Lq) if facts.axis == "q" else (vd, vq, plant.Ld)
    if plant.magnetics is not None:
        # a saturated plant: the same bound in flux linkage, exact for any
        # magnetics (toolbox/ARCHITECTURE.md "Saturated motors"): the stepped
        # axis' flux changes by psi(i_f) - psi(i_0) at no more than the
        # headroom, with the steady state v_d = R i_d - w psi_q, v_q = R i_q +
        # w psi_d; L below is the chord inductance of that flux change
        mag = plant.magnetics
        psd, psq = (float(x) for x in mag.flux(facts.id_f, facts.iq_f))
        vd, vq = plant.R * facts.id_f - w_e * psq, plant.R * facts.iq_f + w_e * psd
        if facts.axis == "q":
            v_own, v_other = vq, vd
            dpsi = psq - float(mag.flux(facts.id_f, facts.y0)[1])
        else:
            v_own, v_other = vd, vq
            dpsi = psd - float(mag.flux(facts.y0, facts.iq_f)[0])
        L = abs(dpsi) / max(abs(facts.yf - facts.y0), 1e-300)
    headroom = math.sqrt(max(v_max ** 2 - v_other ** 2, 0.0)) - abs(v_own)
    t_delay = (delay_samples + 1) * sample_time
    lin = [BANDWIDTH_FACTOR * math.log(20.0) / linear.bandwidth_rad_s
           if _pos_finite(linear.bandwidth_rad_s) else math.nan,
           LINEAR_FACTOR * linear.response_time_5pct
           if _pos_finite(linear.response_time_5pct) else math.nan]
    lin = [x for x in lin if math.isfinite(x)]
    parts = {"t_min": None, "t_linear": max(lin) if lin else None, "t_delay": t_delay}
    if headroom <= 0.0:
        return math.inf, (f"the reference is out of voltage reach: holding it needs "
                          f"{math.hypot(vd, vq):.4g} V at {w_e:.4g} rad/s (electrical), "
                          f"the drive gives {v_max:.4g} V"), parts
    t_min = L * abs(facts.yf - facts.y0) / headroom
    parts["t_min"] = t_min
    if not lin:
        return math.inf, ("the executed sampled loop has no finite closed-loop bandwidth "
                          "(unstable?), so no response time can be expected"), parts
    return t_min + max(lin) + t_delay, None, parts


def _pos_finite(x) -> bool:
    return x is not None and math.isfinite(x) and x > 0


def _current_scale(scenario, motor, facts: StepFacts, speed_loop_limit: float) -> float:
    """Largest reference or limit magnitude of the scenario (A)."""
    refs = [scenario.id_ref, scenario.id_ref0, scenario.iq_ref0, facts.iq_f,
            motor.rated_current or 0.0, motor.max_current or 0.0]
    if math.isfinite(speed_loop_limit):
        refs.append(speed_loop_limit)
    return max(abs(float(r)) for r in refs)


def finalise_check(check: dict) -> dict:
    """A check record ready for JSON: non-finite values as ``None``, and a
    ``reason`` on every failure (kept when the check states its own).

    Parameters
    ----------
    check : dict
        ``{quantity, bound, value, unit, pass, ...}``.
    """
    out = dict(check)
    value = out.get("value")
    finite = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if value is not None and not isinstance(value, bool) and not finite:
        out["value"] = None
    bound = out.get("bound")
    if isinstance(bound, float) and not math.isfinite(bound):
        out["bound"] = None
    if out["pass"]:
        out.pop("reason", None)
    elif not out.get("reason"):
        q, unit = out.get("quantity", "value"), out.get("unit", "")
        if not finite:
            out["reason"] = (f"{q} could not be computed (the response never settled, never "
                             f"reached its level, or diverged); a missing value is a failure")
        else:
            out["reason"] = f"{q} = {value:.4g} {unit} is outside the bound {bound!r} {unit}"
    return out


def _record(quantity: str, value, bound, unit: str, ok: bool, reason: str | None,
            **extra) -> dict:
    rec = {"quantity": quantity, "bound": bound, "value": value, "unit": unit,
           "pass": bool(ok), **extra}
    if not ok:
        rec["reason"] = reason
    return finalise_check(rec)


def default_checks(scenario, metrics: dict, result, *, plant, motor, v_max: float,
                   delay_samples: int, sample_time: float, linear: dict,
                   flux_c: float, ripple: float = 0.0) -> dict[str, dict]:
    """The ``default.*`` checks of one scenario (see the module docstring).

    Parameters
    ----------
    scenario : Scenario
    metrics : dict
        The simulator's metrics of the run.
    result : SimResult or None
        The run, with traces when the scenario kept them (peaks, reach band).
    plant : Motor
        True plant of the scenario (overrides applied).
    motor : Motor
        Spec motor (rated/maximum current and speed).
    v_max : float
        dq voltage limit (V).
    delay_samples : int
    sample_time : float
        Controller period (s).
    linear : dict
        ``{"d": LinearFigures, "q": LinearFigures}`` of the executed loop.
    flux_c : float
        Controller model flux (Wb).
    ripple : float or dict
        Current ripple the inverter leaves at the sampling instants (A), one
        value or one per axis (``{"d": .., "q": ..}``); see the module
        docstring and :func:`fcs_ripple`.

    Returns
    -------
    dict
        Check key -> record ``{quantity, bound, value, unit, pass[, reason]}``.
    """
    facts = step_facts(scenario, plant, flux_c)
    traces = result is not None and getattr(result, "t", None) is not None
    sl_limit = float(dict(scenario.speed_loop).get("iq_limit", math.inf))
    i_scale = _current_scale(scenario, motor, facts, sl_limit)
    if scenario.kind == "sinusoidal_torque":
        i_scale = max(i_scale, abs(scenario.torque_amplitude
                                   / (plant.torque_factor * plant.pole_pairs * flux_c)))
    if traces:  # a speed loop's own current demand is part of the scale
        i_scale = max(i_scale, float(np.nanmax(np.abs(result.iq_ref), initial=0.0)),
                      float(np.nanmax(np.abs(result.id_ref), initial=0.0)))
    if i_scale == 0.0:  # no reference, no limit: the standstill current at full voltage
        i_scale = v_max / plant.R
    out = {}
    if facts.axis is not None:
        out["default.reach"] = _reach(facts, scenario, metrics, result, traces, plant, v_max,
                                      delay_samples, sample_time, linear[facts.axis], i_scale,
                                      ripple)
    out["default.bounded_current"] = _bounded_current(metrics, result, traces, i_scale)
    out["default.bounded_speed"] = _bounded_speed(scenario, metrics, result, traces, plant,
                                                  motor, v_max, facts)
    out["default.finite"] = _finite(metrics, facts)
    return out


def fcs_ripple(r_hex: float, sample_time: float, L: float, weight: float,
               gamma: float, other_weight: float | None = None) -> float:
    """Current error the predictive switching law leaves by design (A).

    The covering radius of the currents one period can reach, plus the dead
    band of the switching penalty of criterion (23) (paper 002). The eight
    inverter states reach, one period ahead, the centre and the six vertices
    of a hexagon of radius ``d = r_hex Ts / L`` around the free response
    (``L`` the smallest inductance: a larger one only shrinks that axis). The
    law picks the state of least ``alpha e_q^2 + beta e_d^2``; in the
    Euclidean metric no point of the hexagon is further than ``d / sqrt(3)``
    from one of the seven (the centroid of an equilateral triangle of side
    ``d``). With unequal weights the weighted covering radius is at most
    ``sqrt(w_max) d / sqrt(3)``, i.e. an error of ``sqrt(w_max / w) d /
    sqrt(3)`` on the axis of weight ``w``. A switch costing ``n <= 3``
    commutations is taken only once it lowers ``w e^2`` by more than
    ``gamma n``, so errors up to ``sqrt(3 gamma / w)`` more may persist. With
    ``w = 0`` the axis is not regulated (infinite).

    Parameters
    ----------
    r_hex : float
        Hexagon vertex voltage radius (V).
    sample_time : float
        Period (s).
    L : float
        Smallest inductance of the plant (H).
    weight : float
        Weight of the axis' squared current error in criterion (23) (1/A^2).
    gamma : float
        Switching penalty of criterion (23).
    other_weight : float, optional
        Weight of the other axis (default ``weight``: equal weights).

    Examples
    --------
    >>> round(fcs_ripple(8.0, 1e-4, 1e-3, 1.0, 35.0), 3)
    10.709
    >>> round(fcs_ripple(8.0, 1e-4, 1e-3, 1.0, 0.0), 4)    # 0.8 A / sqrt(3)
    0.4619
    """
    if weight <= 0:
        return math.inf
    w_max = max(weight, other_weight if other_weight is not None else weight)
    cover = math.sqrt(w_max / weight) * r_hex * sample_time / (math.sqrt(3.0) * L)
    return cover + math.sqrt(3.0 * gamma / weight)


def _reach(facts, scenario, metrics, result, traces, plant, v_max, delay_samples,
           sample_time, linear, i_scale, ripple) -> dict:
    delta = facts.yf - facts.y0
    if isinstance(ripple, dict):
        ripple = ripple[facts.axis]
    floor = max(SENSOR_ACCURACY * i_scale, 2.0 * scenario.current_quantum,
                3.0 * scenario.current_noise, ripple)
    tol = max(REACH_BAND * abs(delta), floor)
    t_bound, problem, parts = reach_time_bound(facts, scenario, plant, v_max, delay_samples,
                                               sample_time, linear,
                                               metrics.get("final_speed", math.nan))
    if traces:
        y = result.iq if facts.axis == "q" else result.id
        t_reach = band_entry_time(result.t, y, facts.yf, tol, scenario.step_time,
                                  scenario.duration)
        basis = "traces"
    else:
        # the simulator's 5 % time uses the band 0.05 |delta| <= tol: stricter, never laxer
        t_reach = metrics.get("response_time_5pct", math.nan)
        basis = "response_time_5pct"
    extra = {"tolerance_A": tol, "axis": facts.axis, "reference_A": facts.yf,
             "basis": basis, **parts}
    if delta != 0.0 and tol > RESOLVE_FRACTION * abs(delta):
        what = ("the predictive law's ripple (one vector per period; it scales with "
                f"Ts / L: a sample time of {sample_time * RESOLVE_FRACTION * abs(delta) / tol:.3g}"
                " s or less would resolve it)" if tol == ripple else
                "the current sensor accuracy, quantum or noise")
        return _record("time to reach the reference band", t_reach, t_bound, "s", False,
                       f"the {facts.axis} current step of {abs(delta):.4g} A is not resolved: "
                       f"the band +/-{tol:.4g} A set by {what} is "
                       f"{100.0 * tol / abs(delta):.0f} % of the step (at most "
                       f"{100.0 * RESOLVE_FRACTION:.0f} %), so any current within it "
                       "would pass", **extra)
    if problem is not None:
        return _record("time to reach the reference band", t_reach, t_bound, "s", False,
                       problem, **extra)
    if not math.isfinite(t_reach):
        final = metrics.get("final_value", math.nan)
        return _record("time to reach the reference band", None, t_bound, "s", False,
                       f"the {facts.axis} current never stayed within +/-{tol:.4g} A of its "
                       f"reference {facts.yf:.4g} A before the end of the run (final value "
                       f"{final:.4g} A)", **extra)
    ok = t_reach <= t_bound
    return _record("time to reach the reference band", t_reach, t_bound, "s", ok,
                   f"the {facts.axis} current took {t_reach:.4g} s to stay within "
                   f"+/-{tol:.4g} A of {facts.yf:.4g} A; the bound is {t_bound:.4g} s "
                   f"(voltage-limited {parts['t_min']:.4g} s + linear "
                   f"{parts['t_linear']:.4g} s + delay {parts['t_delay']:.4g} s)", **extra)


def _bounded_current(metrics, result, traces, i_scale) -> dict:
    bound = CURRENT_FACTOR * i_scale
    if traces:
        mag = np.hypot(np.asarray(result.id, float), np.asarray(result.iq, float))
        value = float(np.max(mag)) if np.all(np.isfinite(mag)) else math.nan
        quantity = "peak current magnitude |i_dq|"
    else:
        value = math.sqrt(metrics.get("mse_id", math.nan) + metrics.get("mse_iq", math.nan))
        quantity = "RMS current tracking error"
    ok = math.isfinite(value) and value <= bound
    reason = (f"{quantity} is not finite: the currents diverged" if not math.isfinite(value)
              else f"{quantity} {value:.4g} A exceeds {CURRENT_FACTOR:g} x the current scale "
                   f"{i_scale:.4g} A: the loop oscillates or diverges")
    return _record(quantity, value, bound, "A", ok, reason)


def _bounded_speed(scenario, metrics, result, traces, plant, motor, v_max, facts) -> dict:
    id_min = min(scenario.id_ref, scenario.id_ref0, 0.0)
    # flux weakened by a negative i_d, never below a tenth (no-load speed stays finite)
    psi = max(plant.flux + plant.Ld * id_min, 0.1 * plant.flux)
    candidates = [v_max / (plant.pole_pairs * psi), abs(scenario.initial_speed),
                  abs(scenario.speed_ref), abs(scenario.speed_ref0),
                  abs(scenario.initial_speed + scenario.acceleration * scenario.duration),
                  motor.rated_speed or 0.0]
    plausible = max(candidates)
    bound = SPEED_FACTOR * plausible
    if traces:
        speed = np.asarray(result.speed, float)
        value = float(np.max(np.abs(speed))) if np.all(np.isfinite(speed)) else math.nan
        quantity = "peak mechanical speed magnitude"
    else:
        value = abs(metrics.get("final_speed", math.nan))
        quantity = "final mechanical speed magnitude"
    ok = math.isfinite(value) and value <= bound
    reason = (f"{quantity} is not finite: the mechanics diverged" if not math.isfinite(value)
              else f"{quantity} {value:.4g} rad/s exceeds {SPEED_FACTOR:g} x the largest "
                   f"plausible speed {plausible:.4g} rad/s")
    return _record(quantity, value, bound, "rad/s", ok, reason)


def _finite(metrics: dict, facts: StepFacts) -> dict:
    bad = []
    for name, value in metrics.items():
        if name in STEP_METRICS and not facts.has_step:
            continue  # not applicable: no step
        if value is None or not math.isfinite(value):
            bad.append(name)
    reason = None
    if bad:
        why = {"response_time_5pct": "never stayed within the 5 % band",
               "settling_time_2pct": "never stayed within the 2 % band",
               "rise_time_10_90": "never reached 90 % of the step"}
        reason = "not computable: " + "; ".join(
            f"{n} ({why.get(n, 'not finite')})" for n in bad)
    return _record("metrics not finite", len(bad), 0, "count", not bad, reason,
                   failed_metrics=bad)
