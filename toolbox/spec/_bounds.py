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
           "MAX_TRACE_ROWS", "MIN_PLANT_STEP", "TAU_SAMPLES", "RATE_TS", "SCALE_RANGE",
           "MAX_POLE_PAIRS", "check_motor", "check_drive", "check_motor_drive",
           "check_scenario_count", "check_work", "check_rate", "check_time_constant",
           "check_scale", "check_gain", "check_speed", "check_plant_variant"]

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

#: Most pole pairs of a motor (large direct-drive machines have a few hundred).
MAX_POLE_PAIRS = 1000

#: A rate of a design (a bandwidth, integral bandwidth, natural frequency or
#: pole-placement gain, rad/s or 1/s; a time constant T as the rate 1/T) in
#: units of 1/sample_time. Above 1e3 the sampled loop's numbers are nonsense
#: (a spectral radius of 1e148 for 1e300 rad/s, overflow in the responses);
#: a design above the largest stable bandwidth but below this is still made
#: and fails its checks (exit 1) so the report shows why. Below 1e-7 (a
#: response time of 3e7 sample periods, a year at 1 ms) the loop is open for
#: every purpose and the margins' frequency grids do not reach its crossover.
RATE_TS = (1e-7, 1e3)

#: A design scale (a current or voltage limit of Bryson's rule) relative to
#: its nominal value (the motor's current scale, the drive's voltage): the
#: weights are inverse squares of these, 1e-300 A made 1/i^2 overflow.
SCALE_RANGE = (1e-6, 1e6)

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
    check_motor_values(motor, collector, lambda name: f"motor.{name}")


def check_motor_values(motor, collector: Collector, key) -> None:
    """:data:`MOTOR_RANGES` and the pole pairs of ``motor``, each error under
    ``key(name)`` (the one rule of ``[motor]`` and of a scenario's plant)."""
    for name, (low, high, what, unit) in MOTOR_RANGES.items():
        with collector.check():
            _range(key(name), getattr(motor, name), low, high, what, unit)
    with collector.check():
        pp = motor.pole_pairs
        if isinstance(pp, bool) or not isinstance(pp, int) or not 1 <= pp <= MAX_POLE_PAIRS:
            raise SpecError(key("pole_pairs"), f"an integer from 1 to {MAX_POLE_PAIRS} "
                            "(pole pairs)", pp)


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
        nyquist = nyquist_speed(motor, drive)
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


# ---------------------------------------------------------------- design parameters
# One rule for every method's rates, time constants and scales: the method
# readers (toolbox.design) call these while the spec is read, so that
# `cct check` refuses what the design would choke on.


def _rate_text(ts: float, unit: str) -> str:
    low, high = RATE_TS
    return (f"a number between {low / ts:.3g} and {high / ts:.3g} {unit} "
            f"({low:g} to {high:g} / drive.sample_time)")


def check_rate(key: str, value: float, drive, unit: str = "rad/s") -> float:
    """Refuse a design rate outside :data:`RATE_TS` / sample time.

    Parameters
    ----------
    key : str
        Dotted key path named in the error (``controller.pi.bandwidth``).
    value : float
        The rate (``unit``, rad/s by default).
    drive : Drive
        Supplies the sample time.
    unit : str
        Unit shown in the message.
    """
    low, high = RATE_TS
    ts = drive.sample_time
    if not low <= value * ts <= high:
        raise SpecError(key, _rate_text(ts, unit), value)
    return value


def check_time_constant(key: str, value: float, drive, scale: float = 1.0) -> float:
    """Refuse a design time constant ``T`` whose rate ``scale / T`` is
    outside :data:`RATE_TS` / sample time (``scale = ln 20`` for a 5 %
    response time).

    Parameters
    ----------
    key : str
        Dotted key path named in the error.
    value : float
        The time constant (s).
    drive : Drive
        Supplies the sample time.
    scale : float
        The rate is ``scale / value``.
    """
    low, high = RATE_TS
    ts = drive.sample_time
    if not low <= scale / value * ts <= high:
        raise SpecError(key, f"a time between {scale * ts / high:.3g} and "
                        f"{scale * ts / low:.3g} s (a rate of {low:g} to {high:g} / "
                        "drive.sample_time)", value)
    return value


def check_gain(key: str, value: float, L: float, drive, unit: str, order: int = 1) -> float:
    """Refuse a loop gain whose rate ``(value / L) ** (1 / order)`` is outside
    :data:`RATE_TS` / sample time: ``Kp / L`` (order 1) and ``sqrt(Ki / L)``
    (order 2) for a PI on ``1 / (R + L s)``; ``L = 1`` for gains already in
    1/s or 1/s^2.

    Parameters
    ----------
    key : str
        Dotted key path named in the error (``controller.pi.Kp``).
    value : float
        The gain.
    L : float
        The inductance (H) the gain divides by, 1 for gains in 1/s.
    drive : Drive
        Supplies the sample time.
    unit : str
        Unit of the gain in the message.
    order : int
        1 for a proportional gain, 2 for an integral gain.
    """
    low, high = RATE_TS
    ts = drive.sample_time
    if not low <= (value / L) ** (1.0 / order) * ts <= high:
        lo, hi = L * (low / ts) ** order, L * (high / ts) ** order
        rate = "K / L" if L != 1.0 else "K"
        rate = {1: rate, 2: f"sqrt({rate})"}.get(order, f"({rate}) ** (1/{order})")
        raise SpecError(key, f"a number between {lo:.3g} and {hi:.3g} {unit} (the rate "
                        f"{rate} between {low:g} and {high:g} / drive.sample_time)", value)
    return value


def check_scale(key: str, value: float, nominal: float, what: str, unit: str) -> float:
    """Refuse a design scale outside :data:`SCALE_RANGE` x its nominal value.

    Parameters
    ----------
    key : str
        Dotted key path named in the error (``controller.lq.current_limit``).
    value : float
        The scale given.
    nominal : float
        Its nominal value (the default the method would use).
    what : str
        What it is, for the message ("current limit").
    unit : str
        Its unit.
    """
    low, high = SCALE_RANGE
    if not low * nominal <= value <= high * nominal:
        raise SpecError(key, f"a {what} between {low * nominal:.3g} and {high * nominal:.3g} "
                        f"{unit} ({low:g} to {high:g} x the nominal {nominal:.4g} {unit})",
                        value)
    return value


def nyquist_speed(motor, drive) -> float:
    """The mechanical speed whose electrical speed is the Nyquist rate
    pi / sample_time (rad/s): beyond it the rotation aliases."""
    return math.pi / (drive.sample_time * motor.pole_pairs)


def check_speed(key: str, value: float, motor, drive) -> None:
    """A mechanical speed (a scenario's initial or final speed) below the
    Nyquist speed, as ``drive.max_speed``."""
    limit = nyquist_speed(motor, drive)
    if not abs(value) < limit:
        raise SpecError(key, "a mechanical speed below the Nyquist electrical speed "
                        f"pi / (pole_pairs sample_time) = {limit:.4g} rad/s in magnitude",
                        value)


def check_plant_variant(motor, drive, values, scale, key: str,
                        collector: Collector) -> None:
    """A scenario's true plant (``plant_values`` then ``plant_scale`` on the
    spec's motor) within the ranges of ``[motor]`` and its time constants
    against the sample time, each error naming the scenario key that set it."""
    def where(name: str) -> str:
        table = "plant_scale" if name in scale else "plant_values" if name in values else None
        return f"{key}.{table}.{name}" if table else f"motor.{name}"

    variant = motor.with_overrides(values, scale)
    before = len(collector.errors)
    check_motor_values(variant, collector, where)
    if len(collector.errors) == before:
        low, high = TAU_SAMPLES
        for axis in ("Ld", "Lq"):
            tau = getattr(variant, axis) / variant.R
            with collector.check():
                if not low <= tau / drive.sample_time <= high:
                    name = next((n for n in (axis, "R") if n in values or n in scale), axis)
                    raise SpecError(where(name), f"a plant whose time constant {axis}/R is "
                                    f"between {low:g} and {high:g} sample times",
                                    f"{axis}/R = {tau:.3g} s")
