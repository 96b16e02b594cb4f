"""Closed-loop scenarios: the ``[[scenario]]`` tables of a spec.

Plain data read and validated here (the spec stage); the simulator
(``toolbox.sim.simulate``) runs one and verification (``toolbox.verify``)
runs the spec's list.

A :class:`Scenario` says what happens to the drive during a simulation: which
references step and when, how the speed evolves (imposed or following the
mechanics), loads, sensor errors, plant-parameter drift, the inverter model
and the plant integration step.

Speed handling by ``kind``:

``current_step``
    Current references step at ``step_time``; mechanical speed imposed constant
    at ``initial_speed`` (rad/s).
``constant_acceleration``
    As ``current_step`` with the mechanical speed imposed as
    ``Omega(t) = initial_speed + acceleration * t`` (paper 000, Fig 9).
``unloaded_start``
    Current step with the speed following the mechanics from ``initial_speed``
    (free acceleration, no load).
``load_step``
    Speed loop holds ``speed_ref``; ``load_torque`` applied at ``load_time``.
``speed_step``
    Speed loop; the speed reference steps from ``speed_ref0`` to ``speed_ref``
    at ``step_time``.
``sinusoidal_torque``
    ``T_ref(t) = torque_amplitude * sin(2 pi torque_frequency t)`` turned into
    ``i_q,ref`` with the controller's flux (paper 002, 36 sin(10 pi t));
    speed follows the mechanics.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Mapping

from ..errors import SpecError
from ._fields import did_you_mean, is_finite_number
from ._model import MOTOR_PARAMETER_KEYS

__all__ = ["Scenario", "SCENARIO_KINDS", "INVERTER_KINDS", "PLANT_KEYS"]

SCENARIO_KINDS = ("current_step", "constant_acceleration", "unloaded_start",
                  "load_step", "speed_step", "sinusoidal_torque")
INVERTER_KINDS = ("average", "svm", "fcs_mpc")
NOISE_KINDS = ("uniform", "gaussian")
PLANT_KEYS = MOTOR_PARAMETER_KEYS  # a scenario's true plant is a Motor.with_overrides
SPEED_LOOP_KEYS = ("kp", "ki", "kd", "sample_time", "iq_limit")


@dataclass(frozen=True)
class Scenario:
    """One closed-loop simulation case.

    Parameters
    ----------
    kind : str
        One of :data:`SCENARIO_KINDS` (see the module docstring).
    duration : float
        Simulated time (s), > 0.
    id_ref, iq_ref : float
        Current references after ``step_time`` (A).
    id_ref0, iq_ref0 : float
        Current references before ``step_time`` (A).
    torque_ref : float or None
        Torque reference after the step (N m); when given it sets ``iq_ref``
        through the controller's flux (``iq = T / (tf p flux_c)``).
    step_time : float
        Time of the reference step (s), >= 0 and < duration.
    speed_ref, speed_ref0 : float
        Mechanical speed reference after/before ``step_time`` (rad/s), for
        ``speed_step`` and ``load_step``.
    load_torque : float
        Load torque (N m) applied from ``load_time`` (s).
    acceleration : float
        Imposed mechanical acceleration (rad/s^2), ``constant_acceleration`` only.
    torque_amplitude, torque_frequency : float
        Sinusoidal torque reference (N m, Hz).
    initial_speed : float
        Mechanical speed at t = 0 (rad/s).
    speed_gain_error, speed_offset : float
        Speed sensor: ``Omega_m = (1 + gain) Omega + offset + noise`` (-, rad/s).
    speed_noise : float
        Speed noise amplitude (rad/s): half-width (uniform) or std (gaussian).
    noise : str
        ``"uniform"`` or ``"gaussian"``.
    current_noise : float
        Current-sensor noise amplitude (A), same distribution.
    current_quantum : float
        Current-sensor quantisation step (A), 0 = none.
    current_gain_d, current_gain_q : float
        Current-sensor gains: the controller reads ``gain * i`` (after noise
        and quantisation), default 1 (paper 002 sect. 5).
    current_delay_d, current_delay_q : int
        Current-sensor delays (controller periods, 0 to 10): the controller
        reads the current measured that many periods earlier (paper 002
        sect. 5), on top of the computation delay of the drive.
    seed : int
        Seed of the sensor-noise generator (deterministic runs).
    plant_values : mapping
        True plant parameters replacing the nominal ones (SI), keys in
        :data:`PLANT_KEYS`.
    plant_scale : mapping
        Multipliers applied to the nominal plant parameters (after values).
    inverter : str or None
        Overrides the drive's inverter model: ``"average"``, ``"svm"``, ``"fcs_mpc"``.
    plant_step : float
        Plant integration step (s), default 1e-6; must not exceed the sample time.
    keep_traces : bool
        Return decimated traces (otherwise metrics only, flat memory).
    trace_step : float or None
        Trace sampling interval (s); ``None`` = every controller period.
    name : str
        Label shown in reports and verify.json (default: the kind).
    speed_loop : mapping
        Outer speed PID for ``load_step`` and ``speed_step``: ``kp`` (A s/rad),
        ``ki`` (A/rad), ``kd`` (A s^2/rad), ``sample_time`` (s), ``iq_limit`` (A)
        (papers 001 and 003).
    """

    name: str = ""
    kind: str = "current_step"
    duration: float = 0.02
    id_ref: float = 0.0
    iq_ref: float = 0.0
    id_ref0: float = 0.0
    iq_ref0: float = 0.0
    torque_ref: float | None = None
    step_time: float = 0.0
    speed_ref: float = 0.0
    speed_ref0: float = 0.0
    load_torque: float = 0.0
    load_time: float = 0.0
    acceleration: float = 0.0
    torque_amplitude: float = 0.0
    torque_frequency: float = 0.0
    initial_speed: float = 0.0
    speed_gain_error: float = 0.0
    speed_offset: float = 0.0
    speed_noise: float = 0.0
    noise: str = "uniform"
    current_noise: float = 0.0
    current_quantum: float = 0.0
    current_gain_d: float = 1.0
    current_gain_q: float = 1.0
    current_delay_d: int = 0
    current_delay_q: int = 0
    seed: int = 0
    plant_values: Mapping[str, float] = field(default_factory=dict)
    plant_scale: Mapping[str, float] = field(default_factory=dict)
    inverter: str | None = None
    plant_step: float = 1e-6
    keep_traces: bool = False
    trace_step: float | None = None
    speed_loop: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # freeze the mappings (hashable, immutable)
        object.__setattr__(self, "plant_values", _Frozen(self.plant_values))
        object.__setattr__(self, "plant_scale", _Frozen(self.plant_scale))
        object.__setattr__(self, "speed_loop", _Frozen(self.speed_loop))
        self.validate()

    # ------------------------------------------------------------------ checks
    def validate(self, key: str = "scenario") -> None:
        """Raise :class:`SpecError` (key path under ``key``) for an invalid scenario
        (``plant_step <= sample_time``, which depends on the drive, is
        :meth:`check_plant_step`)."""
        def err(name, expected, got, hint=None):
            return SpecError(f"{key}.{name}", expected, got, hint=hint)

        if self.kind not in SCENARIO_KINDS:
            raise err("kind", "one of " + ", ".join(SCENARIO_KINDS), self.kind,
                      did_you_mean(self.kind, SCENARIO_KINDS))
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or v is None or isinstance(v, (str, Mapping)):
                continue
            if isinstance(v, (int, float)) and not is_finite_number(v):
                raise err(f.name, "a finite number", v)
        if not self.duration > 0:
            raise err("duration", "a number > 0 (s)", self.duration)
        if not 0 <= self.step_time < self.duration:
            raise err("step_time", f"a number >= 0 and < duration ({self.duration} s)",
                      self.step_time)
        if self.load_time < 0:
            raise err("load_time", "a number >= 0 (s)", self.load_time)
        if not self.plant_step > 0:
            raise err("plant_step", "a number > 0 (s)", self.plant_step)
        if self.trace_step is not None and not self.trace_step > 0:
            raise err("trace_step", "a number > 0 (s)", self.trace_step)
        for name in ("speed_noise", "current_noise", "current_quantum",
                     "torque_frequency"):
            if getattr(self, name) < 0:
                raise err(name, "a number >= 0", getattr(self, name))
        for name in ("current_gain_d", "current_gain_q"):
            if not getattr(self, name) > 0:
                raise err(name, "a number > 0 (sensor gain)", getattr(self, name))
        for name in ("current_delay_d", "current_delay_q"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 10:
                raise err(name, "an integer from 0 to 10 (periods)", v)
        if self.noise not in NOISE_KINDS:
            raise err("noise", '"uniform" or "gaussian"', self.noise,
                      did_you_mean(self.noise, NOISE_KINDS))
        if self.inverter is not None and self.inverter not in INVERTER_KINDS:
            raise err("inverter", "one of " + ", ".join(INVERTER_KINDS), self.inverter,
                      did_you_mean(self.inverter, INVERTER_KINDS))
        if self.acceleration != 0 and self.kind != "constant_acceleration":
            raise err("acceleration", 'no acceleration unless kind = "constant_acceleration"',
                      self.acceleration, "the speed follows the mechanics for this kind")
        for name, v in self.speed_loop.items():
            if name not in SPEED_LOOP_KEYS:
                raise err(f"speed_loop.{name}", "one of " + ", ".join(SPEED_LOOP_KEYS), name,
                          did_you_mean(name, SPEED_LOOP_KEYS))
            if not is_finite_number(v) or v < 0:
                raise err(f"speed_loop.{name}", "a finite number >= 0", v)
        for table in ("plant_values", "plant_scale"):
            for name, v in getattr(self, table).items():
                if name not in PLANT_KEYS:
                    raise err(f"{table}.{name}", "a plant parameter ("
                              + ", ".join(PLANT_KEYS) + ")", name,
                              did_you_mean(name, PLANT_KEYS))
                if not is_finite_number(v) or v < 0 \
                        or (v == 0 and name not in ("friction",)):
                    raise err(f"{table}.{name}", "a finite number > 0", v)

    def check_plant_step(self, sample_time: float, key: str = "scenario") -> None:
        """Raise :class:`SpecError` unless ``plant_step <= sample_time`` (s).

        The one check of :meth:`validate` that depends on the drive:
        ``simulate()`` and :meth:`from_dict` run it alone, the frozen scenario
        having been validated when it was built (the full validation, ~16 us,
        ran on every call).
        """
        if self.plant_step > sample_time * (1 + 1e-9):
            raise SpecError(f"{key}.plant_step", f"a number <= the sample time "
                            f"({sample_time} s)", self.plant_step,
                            hint="the plant is integrated at least once per period")

    # ----------------------------------------------------------- construction
    @classmethod
    def from_dict(cls, d: Mapping[str, Any], key: str = "scenario[0]",
                  sample_time: float | None = None) -> "Scenario":
        """Build and validate a scenario from a spec table.

        Unknown keys, wrong types, NaN/inf, negative durations, unknown kinds
        and a plant step above ``sample_time`` raise :class:`SpecError` whose
        key path starts with ``key`` (e.g. ``scenario[2].duration``).
        """
        if not isinstance(d, Mapping):
            raise SpecError(key, "a table", d)
        names = [f.name for f in fields(cls)]
        kw = {}
        for k, v in d.items():
            if k not in names:
                raise SpecError(f"{key}.{k}", "a known scenario key", k,
                                hint=did_you_mean(k, names) or "known keys: "
                                + ", ".join(names))
            kw[k] = _check_type(f"{key}.{k}", k, v)
        if "plant_step" not in kw and sample_time is not None and sample_time > 0:
            # the default step (1 us) is capped at the sample time, so a fast
            # drive does not fail on a key the user never wrote
            default_step = next(f.default for f in fields(cls) if f.name == "plant_step")
            kw["plant_step"] = min(default_step, sample_time)
        try:
            sc = cls(**kw)
        except SpecError as e:
            if e.key.startswith("scenario."):
                raise SpecError(key + e.key[len("scenario"):], e.expected,
                                e.got if e.has_got else SpecError._MISSING,
                                hint=e.hint) from None
            raise
        if sample_time is not None:   # the rest was validated on construction
            sc.check_plant_step(sample_time, key)
        return sc


_STR_KEYS = {"kind", "noise", "inverter", "name"}
_MAP_KEYS = {"plant_values", "plant_scale", "speed_loop"}


def _check_type(path: str, name: str, v: Any) -> Any:
    if name == "inverter" and v is None:
        return v
    if name in _STR_KEYS:
        if not isinstance(v, str):
            raise SpecError(path, "a string", v)
        return v
    if name in _MAP_KEYS:
        if not isinstance(v, Mapping):
            raise SpecError(path, "a table", v)
        return dict(v)
    if name == "keep_traces":
        if not isinstance(v, bool):
            raise SpecError(path, "true or false", v)
        return v
    if name in ("seed", "current_delay_d", "current_delay_q"):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise SpecError(path, "an integer >= 0", v)
        if v > 2 ** 53:  # as toolbox.spec's integer keys (Table.integer)
            raise SpecError(path, "an integer >= 0 of magnitude at most 2**53", v)
        return v
    if v is None and name in ("torque_ref", "trace_step"):
        return v
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise SpecError(path, "a number", v)
    if not is_finite_number(v):
        raise SpecError(path, "a finite number", v)
    return v


class _Frozen(dict):
    """A read-only, hashable dict for frozen dataclass fields."""

    def _ro(self, *a, **k):
        raise TypeError("scenario parameter tables are read-only")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = _ro

    def __hash__(self):
        return hash(tuple(sorted(self.items())))

    def __reduce__(self):
        return (_Frozen, (dict(self),))

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self
