"""Torque-speed grid verification: the current loop at the envelope's
references over a default grid of the operating range.

Each grid point runs :func:`toolbox.sim.simulate` at an imposed constant speed
(``kind = "current_step"``, mechanical state held) with the current
references of :class:`toolbox.plant.OperatingEnvelope` applied from ``t = 0``
to the motor at zero current, and checks that the loop settles on them (mean
of the last quarter of the run). Above base speed this start is a flying
start into field weakening (the back-EMF alone may exceed the voltage
limit): the peak current of the transient is reported beside the settled
error. Measured on paper 003's motor and H-infinity law at 1.5 x base
speed: d-axis priority starves ``v_q`` while the d loop takes the voltage,
the back-EMF drives ``|i|`` to 94 A (``i_q`` -65 A, ``i_d`` -55 A) before it
settles (~0.1 s); the radial limit stays within 16.4 A (PI: 15.9 A either way). Torques are fractions of the standstill torque limit, clamped to the
limit at each speed by the envelope; speeds are fractions of its base speed;
a speed at which no current fits (the back-EMF beyond the voltage limit with
the current limit reached) is reported, not simulated.

Not wired into ``cct design`` yet: a function for scripts and tests.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from toolbox.errors import SpecError
from toolbox.plant import OperatingEnvelope
from toolbox.sim import ControlLaw, DriveParams, simulate
from toolbox.spec import Scenario

__all__ = ["GridPoint", "torque_speed_grid", "DEFAULT_TORQUES", "DEFAULT_SPEEDS"]

#: Default grid: fractions of the standstill torque limit and of base speed.
DEFAULT_TORQUES = (0.0, 0.5, 1.0)
DEFAULT_SPEEDS = (0.0, 0.5, 1.0, 1.5, 2.0)


@dataclass(frozen=True)
class GridPoint:
    """One point of :func:`torque_speed_grid`.

    ``torque`` is the torque the envelope gives (the request clamped to the
    limit at that speed), ``region`` its :class:`OperatingPoint` region
    (``"infeasible"`` when nothing fits: not simulated, ``error = nan``);
    ``i_d``, ``i_q`` the mean simulated currents over the last quarter;
    ``error`` their distance from the reference (A); ``ok`` whether it is
    within the tolerance; ``saturation_time`` (s) from the simulator's metrics;
    ``peak_current`` the largest ``|i|`` of the run (A).
    """

    speed_fraction: float
    torque_fraction: float
    speed: float
    torque: float
    region: str
    i_d_ref: float
    i_q_ref: float
    i_d: float
    i_q: float
    error: float
    saturation_time: float
    ok: bool
    peak_current: float


def torque_speed_grid(law: ControlLaw, motor, drive: DriveParams, envelope=None, *,
                      torques=DEFAULT_TORQUES, speeds=DEFAULT_SPEEDS,
                      headroom: float = 0.05, duration: float = 0.2,
                      tolerance: float = 0.02) -> list[GridPoint]:
    """Run the current loop at the envelope's references on a torque-speed grid.

    Parameters
    ----------
    law : ControlLaw
        The current controller (``toolbox.sim.control_law(artifact)``).
    motor : Motor
        The plant (and the envelope's motor unless ``envelope`` is given).
    drive : DriveParams
        The simulated drive; ``voltage_priority = "d_axis"`` is what
        field-weakening drives use (with ``"radial"`` the limit drags ``i_d``).
    envelope : OperatingEnvelope, optional
        Default: ``motor`` with ``v_max = (1 - headroom)`` times the drive's
        circle radius (the loop keeps ``headroom`` for its transients).
    torques, speeds : sequence of float
        Fractions of the standstill torque limit and of base speed.
    headroom : float
        Voltage fraction kept out of the envelope (default 5 %).
    duration : float
        Simulated time per point (s).
    tolerance : float
        Allowed steady-state current error, as a fraction of the current limit.

    Returns
    -------
    list of GridPoint
        Speeds outer, torques inner.
    """
    if envelope is None:
        if not 0.0 <= headroom < 1.0:
            raise SpecError("headroom", "a fraction in [0, 1)", headroom)
        v_max = drive.radii(motor.torque_factor)[1]
        envelope = OperatingEnvelope(motor, v_max=(1.0 - headroom) * v_max)
    base = envelope.base_speed()
    t_max = envelope.max_torque_point(0.0).torque
    out = []
    for sf in speeds:
        speed = sf * base
        for tf in torques:
            try:
                op = envelope.operating_point(tf * t_max, speed)
            except SpecError:
                out.append(GridPoint(sf, tf, speed, float("nan"), "infeasible", *[float("nan")] * 5,
                                     0.0, False, float("nan")))
                continue
            scen = Scenario(kind="current_step", duration=duration, id_ref0=op.i_d,
                            iq_ref0=op.i_q, id_ref=op.i_d, iq_ref=op.i_q,
                            initial_speed=speed, keep_traces=True, trace_step=drive.sample_time)
            res = simulate(law, motor, scen, drive)
            n = max(1, len(res.t) // 4)
            i_d, i_q = float(np.mean(res.id[-n:])), float(np.mean(res.iq[-n:]))
            err = float(np.hypot(i_d - op.i_d, i_q - op.i_q))
            out.append(GridPoint(sf, tf, speed, op.torque, op.region, op.i_d, op.i_q, i_d, i_q,
                                 err, float(res.metrics["saturation_time"]),
                                 err <= tolerance * envelope.I,
                                 float(np.hypot(res.id, res.iq).max())))
    return out
