"""The scenarios verification runs when a spec has no ``[[scenario]]``.

Scaled to the motor and the drive from the design stage's defaults
(:func:`toolbox.design.current_scale`, ``speed_scale``,
``default_bandwidth``) and the voltage the plant allows
(:func:`toolbox.plant.voltage_limited_speed`); plain
:class:`toolbox.spec.Scenario` data, run like the spec's own.
"""

from __future__ import annotations

import math

from toolbox.design import current_scale, default_bandwidth, speed_scale
from toolbox.plant import voltage_limited_speed
from toolbox.spec import Scenario

__all__ = ["default_scenarios"]


def default_scenarios(motor, drive=None, horizon: float | None = None) -> tuple[Scenario, ...]:
    """Scenarios used when a spec has no ``[[scenario]]``, scaled to the motor.

    A q-current step to half the current scale at standstill, the same step
    during free acceleration (unloaded start), and the same step at half the
    speed scale (speed held), capped at half the speed the voltage allows at
    that current (:func:`toolbox.plant.voltage_limited_speed`: the speed scale alone ignores
    the ``R i`` and ``w L i`` drops). The scales
    (:func:`toolbox.design._defaults.current_scale`, ``speed_scale``) are
    the rated (else maximum) current and speed, else what the voltage
    allows; each scenario's ``name`` states its numbers.

    Durations: at least 20 ms and 30 time constants of the slowest default
    crossover (``3/wc`` is the 5 % time of a first-order loop: ten of them
    leave room for the slower second-order defaults), and at least
    ``horizon`` when given: :func:`toolbox.analysis.executed.settling_horizon`,
    10 time constants of the executed loop's slowest closed-loop pole that
    shows in the step (so that the settling time the checks require is
    reached within the span). The unloaded start
    must not pass the speed scale nor 80 % of the voltage-limited speed
    (beyond, the back-EMF would saturate the voltage: a field-weakening
    question, not the loop's): a rotor light enough to pass that sooner gets
    a smaller step, sized to arrive there at the end of the span.

    Parameters
    ----------
    motor : Motor
        Rated/max current and speed, torque constant and inertia.
    drive : Drive, optional
        Sample time, delay and voltage; without it the step is half the
        rated current (10 A when unknown) and the speed scenario is left out.
    horizon : float, optional
        Shortest span after the step (s), from the designed loop.
    """
    if drive is None:
        i_step = 0.5 * (motor.rated_current or motor.max_current or 10.0)
        return (Scenario(name="q step at standstill", kind="current_step", duration=0.02,
                         iq_ref=i_step, step_time=0.001, keep_traces=True),
                Scenario(name="q step, unloaded start", kind="unloaded_start", duration=0.02,
                         iq_ref=i_step, step_time=0.001, keep_traces=True))
    i_scale, _ = current_scale(motor, drive)
    w_scale, _ = speed_scale(motor, drive)
    i_step = 0.5 * i_scale
    w_reach = voltage_limited_speed(motor, drive.max_voltage(motor.convention), i_step)
    w_held = 0.5 * min(w_scale, w_reach)
    wc = default_bandwidth(drive, zero=True).value
    step_time = 0.001
    span = max(0.02, 30.0 / wc, horizon or 0.0)
    # free acceleration may end at the speed scale or at 80 % of the voltage-limited speed
    # (20 % of the voltage left for the loop); a rotor light enough to pass that within the
    # span steps less current, sized to arrive there at the end (the same span as the
    # other scenarios: the EMF ramp is a disturbance the slower 2-DOF laws reject over
    # several integral time constants, and a shorter span cut them off: the corpus's
    # gimbal motors with ip and lq)
    w_end = min(w_scale, 0.8 * w_reach)
    torque_per_amp = motor.torque_factor * motor.pole_pairs * motor.flux
    i_start = i_step
    if torque_per_amp > 0 and math.isfinite(w_end):
        i_start = min(i_step, w_end * motor.J / (torque_per_amp * span))
    start_txt = (f"{i_start:.4g} A, unloaded start" if i_start == i_step else
                 f"{i_start:.4g} A, unloaded start (reaches {w_end:.4g} rad/s at the end)")
    out = [Scenario(name=f"q step to {i_step:.4g} A (0.5 x current scale) at standstill",
                    kind="current_step", duration=step_time + span, iq_ref=i_step,
                    step_time=step_time, keep_traces=True),
           Scenario(name=f"q step to {start_txt}",
                    kind="unloaded_start", duration=step_time + span, iq_ref=i_start,
                    step_time=step_time, keep_traces=True)]
    if math.isfinite(w_held):
        held_txt = ("0.5 x speed scale" if w_held == 0.5 * w_scale else
                    "0.5 x the speed the voltage allows at this current")
        out.append(Scenario(name=f"q step to {i_step:.4g} A at {w_held:.4g} rad/s ({held_txt})",
                            kind="current_step", duration=step_time + span, iq_ref=i_step,
                            initial_speed=w_held, step_time=step_time, keep_traces=True))
    return tuple(out)
