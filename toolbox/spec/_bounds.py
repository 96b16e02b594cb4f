"""Plausibility and work bounds of a spec, checked before anything runs.

Type checks (``Table.number``) accept any finite positive number, but the
numerics downstream do not: R = 1e300 or Ld = 1e-300 make the Riccati and
eigenvalue solvers fail (``LinAlgError``), flux = 0 divides by zero in the
analysis, and plant_step = 1e-11 or 10,000 scenarios of 60 s run for days.
These bounds turn every such case into a :class:`~toolbox.errors.SpecError`
naming the key, the plausible range and the value, and estimate the work of
the verification (plant steps, trace memory) before it starts.

The ranges are wide on purpose: they bracket every physical PMSM drive from
micro-motors (R ~ 10 ohm, L ~ 10 uH) to traction machines (R ~ 1 mohm,
vdc ~ 1 kV) by several decades, so they refuse only numerical nonsense.
"""

from __future__ import annotations

import math
from typing import Sequence

from ..errors import SpecError
from ._fields import Collector

__all__ = ["MOTOR_RANGES", "DRIVE_RANGES", "MAX_SCENARIOS", "MAX_PLANT_STEPS",
           "MAX_TRACE_ROWS", "MIN_PLANT_STEP", "TAU_SAMPLES", "check_motor",
           "check_drive", "check_motor_drive", "check_scenario_count", "check_work"]

#: key -> (low, high, what, unit) for the motor parameters.
MOTOR_RANGES = {
    "R": (1e-6, 1e4, "stator resistance", "ohm"),
    "Ld": (1e-9, 10.0, "d-axis inductance", "H"),
    "Lq": (1e-9, 10.0, "q-axis inductance", "H"),
    # flux = 0 (a synchronous reluctance machine) is outside the PMSM models:
    # torque-to-current conversion and the analysis divide by it
    "flux": (1e-6, 100.0, "PM flux linkage", "Wb"),
}

#: key -> (low, high, what, unit) for the drive parameters.
DRIVE_RANGES = {
    "vdc": (0.0, 1e5, "DC-link voltage", "V"),
    "sample_time": (1e-7, 1.0, "controller sample time", "s"),
}

#: Electrical time constants L/R allowed, in sample times: below 1e-3 the
#: discretised plant is numerically a pure gain (exp(-1000) underflows), above
#: 1e9 it is numerically a pure integrator and the design matrices are
#: ill-conditioned beyond double precision.
TAU_SAMPLES = (1e-3, 1e9)

#: Work bounds of a verification (estimated before running).
MAX_SCENARIOS = 1000
#: RK4 steps of the plant over all scenarios; ~50 ns each, so about 100 s.
MAX_PLANT_STEPS = 2e9
#: Trace rows kept over all scenarios: 10 doubles each, but the kernel's
#: buffers, the result arrays and the JSON text of verify.json hold them
#: several times (peak RSS measured 3.75 GB for 1e7 rows, ~375 B a row), so
#: about 750 MB at this bound (200 s of traces at 10 kHz).
MAX_TRACE_ROWS = 2e6
#: Peak memory per kept trace row (bytes), measured as above.
TRACE_ROW_BYTES = 375
#: Smallest plant integration step (s); the fastest plausible electrical time
#: constant (1e-3 sample times at the smallest sample time, 1e-10 s) needs no
#: finer step from RK4 for the verification's accuracy.
MIN_PLANT_STEP = 1e-9


def _range(key: str, value: float | None, low: float, high: float, what: str,
           unit: str, low_open: bool = False) -> None:
    if value is None:
        return
    below = value <= low if low_open else value < low
    if below or value > high:
        low_text = f"> {low:g}" if low_open else f"{low:g}"
        expected = (f"a plausible {what} of at most {high:g} {unit}" if low_open
                    else f"a plausible {what} between {low_text} and {high:g} {unit}")
        raise SpecError(key, expected, value)


def check_motor(motor, collector: Collector) -> None:
    """Record every motor parameter outside :data:`MOTOR_RANGES`."""
    for name, (low, high, what, unit) in MOTOR_RANGES.items():
        with collector.check():
            _range(f"motor.{name}", getattr(motor, name), low, high, what, unit)


def check_drive(drive, collector: Collector) -> None:
    """Record every drive parameter outside :data:`DRIVE_RANGES`."""
    with collector.check():
        _range("drive.vdc", drive.vdc, *DRIVE_RANGES["vdc"], low_open=True)
    with collector.check():
        _range("drive.sample_time", drive.sample_time, *DRIVE_RANGES["sample_time"])


def check_motor_drive(motor, drive, collector: Collector) -> None:
    """Time constants against the sample time, maximum speed against Nyquist.

    The sampled current loop sees the motor through L/R in sample times and
    through the electrical speed ``pole_pairs * max_speed``; above the
    Nyquist speed pi / Ts the rotation aliases and no sampled controller can
    decouple the axes.
    """
    ts = drive.sample_time
    low, high = TAU_SAMPLES
    for axis in ("Ld", "Lq"):
        tau = getattr(motor, axis) / motor.R
        with collector.check():
            if not low <= tau / ts <= high:
                raise SpecError(f"motor.{axis}", f"an electrical time constant {axis}/R "
                                f"between {low:g} and {high:g} sample times "
                                f"({low * ts:.3g} .. {high * ts:.3g} s)",
                                f"{axis}/R = {tau:.3g} s",
                                hint="check the units of R, L and drive.sample_time")
    if drive.max_speed is not None:
        nyquist = math.pi / (ts * motor.pole_pairs)
        with collector.check():
            if not drive.max_speed < nyquist:
                raise SpecError("drive.max_speed", "a mechanical speed below the Nyquist "
                                f"electrical speed pi / (pole_pairs sample_time) = "
                                f"{nyquist:.4g} rad/s", drive.max_speed)


def check_scenario_count(count: int) -> None:
    """At most :data:`MAX_SCENARIOS` scenarios (checked before reading them)."""
    if count > MAX_SCENARIOS:
        raise SpecError("scenario", f"at most {MAX_SCENARIOS} [[scenario]] tables",
                        f"{count} tables")


def check_work(scenarios: Sequence, sample_time: float, collector: Collector) -> None:
    """Estimate the verification's work and memory before running it.

    Per scenario: the plant step must be at least :data:`MIN_PLANT_STEP`.
    In total: RK4 steps ``sum(duration / plant_step)`` at most
    :data:`MAX_PLANT_STEPS`, and kept trace rows ``sum(duration / (Ts *
    decimation))`` at most :data:`MAX_TRACE_ROWS`.
    """
    steps = rows = 0.0
    for k, sc in enumerate(scenarios):
        with collector.check():
            if sc.plant_step < MIN_PLANT_STEP:
                raise SpecError(f"scenario[{k}].plant_step",
                                f"a plant integration step >= {MIN_PLANT_STEP:g} s",
                                sc.plant_step)
        steps += sc.duration / max(sc.plant_step, MIN_PLANT_STEP)
        if sc.keep_traces:
            dec = 1 if sc.trace_step is None else max(1, round(sc.trace_step / sample_time))
            rows += sc.duration / (sample_time * dec)
    with collector.check():
        if steps > MAX_PLANT_STEPS:
            raise SpecError("scenario", f"at most {MAX_PLANT_STEPS:g} plant integration steps "
                            "over all scenarios (duration / plant_step, summed)",
                            f"{steps:.3g} steps",
                            hint="shorten the scenarios or raise plant_step")
    with collector.check():
        if rows > MAX_TRACE_ROWS:
            raise SpecError("scenario", f"at most {MAX_TRACE_ROWS:g} kept trace rows over "
                            "all scenarios (duration / (sample_time x decimation), "
                            f"about {TRACE_ROW_BYTES * MAX_TRACE_ROWS / 1e9:.2g} GB of memory)",
                            f"{rows:.3g} rows",
                            hint="set keep_traces = false or a coarser trace_step")
