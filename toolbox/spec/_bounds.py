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
           "check_scale", "check_gain", "check_speed", "check_plant_variant",
           "INERTIA_ACCELERATION", "REQUIREMENT_RANGES", "check_inertia", "check_requirement"]

#: key -> (low, high, what, unit) for the motor parameters.
MOTOR_RANGES = {
    "R": (1e-6, 1e4, "stator resistance", "ohm"),
    "Ld": (1e-9, 10.0, "d-axis inductance", "H"),
    "Lq": (1e-9, 10.0, "q-axis inductance", "H"),
    # flux = 0 (a synchronous reluctance machine) is outside the PMSM models:
    # torque-to-current conversion and the analysis divide by it
    "flux": (1e-6, 100.0, "PM flux linkage", "Wb"),
    # 1e-10 kg m^2 (0.001 g cm^2) is below the rotors of the smallest
    # micro-motors (of order 0.01 g cm^2); 1e5 kg m^2 is above the rotor of a
    # multi-MW direct-drive generator (of order 1e4 kg m^2). The
    # motor-relative bound (:func:`check_inertia`) catches unit mistakes.
    "J": (1e-10, 1e5, "rotor inertia", "kg m^2"),
    # 0 (no friction) is the default; 1e3 N m s/rad loses 1e6 W at 1000 rad/s
    "friction": (0.0, 1e3, "viscous friction", "N m s/rad"),
    # 1 mA (a micro-motor's no-load current) .. 100 kA (beyond any traction
    # inverter, ~1 kA): a current in kA or mA mistaken for A falls outside
    "rated_current": (1e-3, 1e5, "rated current", "A"),
    "max_current": (1e-3, 1e5, "largest current", "A"),
    # 0.01 rad/s (0.1 rpm, a direct drive) .. 1e5 rad/s (~1e6 rpm, beyond the
    # fastest spindle at 200,000 rpm); rpm written as rad/s is x 9.5 only, so
    # this bound catches krpm/rpm slips only
    "rated_speed": (1e-2, 1e5, "rated speed", "rad/s"),
}

#: Torque-to-inertia ratio of a motor (rad/s^2): ``T_char / J`` with the
#: characteristic torque ``T_char = 1.5 p flux^2 / max(Ld, Lq)`` (the torque
#: at the characteristic current flux / L, a current scale every PMSM has
#: whether or not its rated current is given). Over the 39 corpus motors
#: (tests/corpus/motors: a 10 W gimbal to 150 kW traction) and the four
#: papers it spans 291 rad/s^2 (paper 002, J = 1 kg m^2) to 3.4e6 rad/s^2
#: (tests/corpus/motors/gimbal_24v_7pp.toml). The low bound, 100 rad/s^2, is a factor 2.9
#: under the slowest of them (a large industrial motor with a heavy load
#: coupled belongs in ``J``, and still clears it when its rotor alone does
#: by that factor); the high bound leaves a decade over the fastest. A
#: datasheet inertia in kg cm^2 written as a bare number (read as kg m^2,
#: 1e4 x too large) is refused for every motor whose ratio is below 1e6
#: rad/s^2 (38 of the 39 corpus motors and all the papers':
#: tests/spec/test_units_everywhere.py); in g cm^2 (1e7 x) for all of them.
INERTIA_ACCELERATION = (100.0, 3e7)

#: (low, high, unit) of each ``[requirements]`` bound with a physical range:
#: a phase margin is an angle in 0 .. 180 deg; a gain margin above 60 dB (a
#: factor 1000) is no current loop's; a disk margin is at most 2 (Seiler et
#: al. 2020: alpha < 2 for the symmetric disk); an overshoot above 1000 %
#: is no step response worth bounding.
REQUIREMENT_RANGES = {
    "min_phase_margin_deg": (0.0, 180.0, "deg"),
    "min_gain_margin_db": (-60.0, 60.0, "dB"),
    "min_disk_margin": (0.0, 2.0, ""),
    "max_overshoot_pct": (0.0, 1000.0, "%"),
}

#: key -> (low, high, what, unit) for the drive parameters.
DRIVE_RANGES = {
    "vdc": (0.0, 1e5, "DC-link voltage", "V"),
    "sample_time": (1e-7, 1.0, "controller sample time", "s"),
    # 100 Hz (a large thyristor-era drive) .. 10 MHz (beyond GaN at ~1 MHz);
    # kHz written as Hz (x 1e-3) falls below
    "switching_frequency": (100.0, 1e7, "switching frequency", "Hz"),
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
    before = len(collector.errors)
    for name, (low, high, what, unit) in MOTOR_RANGES.items():
        with collector.check():
            _range(key(name), getattr(motor, name), low, high, what, unit)
    with collector.check():
        pp = motor.pole_pairs
        if isinstance(pp, bool) or not isinstance(pp, int) or not 1 <= pp <= MAX_POLE_PAIRS:
            raise SpecError(key("pole_pairs"), f"an integer from 1 to {MAX_POLE_PAIRS} "
                            "(pole pairs)", pp)
    if len(collector.errors) == before:  # against plausible R, L, flux, p
        with collector.check():
            check_inertia(motor, key("J"))


#: Likely unit slips of a bare inertia, tried in order: (factor that makes
#: it plausible, what was probably meant).
_INERTIA_SLIPS = ((1e-4, "kg cm^2"), (1e-7, "g cm^2"), (1e-3, "g m^2"))


def check_inertia(motor, key: str = "motor.J") -> None:
    """Refuse a rotor inertia implausible for the motor's torque
    (:data:`INERTIA_ACCELERATION`), naming the likely unit mistake.

    Raises
    ------
    SpecError
        With the bound in kg m^2 for this motor and, when a power-of-ten
        unit slip makes the value plausible, that slip (``kg·cm² written as
        kg·m²?``) and the value to write.
    """
    L = max(motor.Ld, motor.Lq)
    t_char = 1.5 * motor.pole_pairs * motor.flux ** 2 / L
    low, high = INERTIA_ACCELERATION
    j_low, j_high = t_char / high, t_char / low
    if j_low <= motor.J <= j_high:
        return
    hint = None
    for factor, unit in _INERTIA_SLIPS:
        if j_low <= motor.J * factor <= j_high:
            hint = (f"{unit.replace(' ', '·').replace('^2', '²')} written as kg·m²? "
                    f"write J = \"{motor.J:g} {unit}\" (= {motor.J * factor:.3g} kg m^2)")
            break
    raise SpecError(key, f"a rotor inertia plausible for this motor: between {j_low:.3g} and "
                    f"{j_high:.3g} kg m^2 (its characteristic torque 1.5 p flux^2 / L = "
                    f"{t_char:.3g} N m over {low:g} .. {high:g} rad/s^2, the torque-to-inertia "
                    "range of real motors, widened)", motor.J,
                    hint=hint or "check the unit of J (a datasheet prints kg cm^2 or g cm^2: "
                    'write it with its unit, e.g. J = "1.2 kg cm^2")')


def check_requirement(key: str, value: float) -> None:
    """A ``[requirements]`` bound within :data:`REQUIREMENT_RANGES`."""
    if key in REQUIREMENT_RANGES:
        low, high, unit = REQUIREMENT_RANGES[key]
        _range(f"requirements.{key}", value, low, high, key.split("_")[1] + " margin"
               if "margin" in key else "overshoot", unit)


def check_drive(drive, collector: Collector) -> None:
    """Record every drive parameter outside :data:`DRIVE_RANGES`."""
    with collector.check():
        _range("drive.vdc", drive.vdc, *DRIVE_RANGES["vdc"], low_open=True)
    with collector.check():
        _range("drive.sample_time", drive.sample_time, *DRIVE_RANGES["sample_time"])
    with collector.check():
        _range("drive.switching_frequency", drive.switching_frequency,
               *DRIVE_RANGES["switching_frequency"])


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
