"""Validated spec objects: motor, drive, controller choice, requirements.

Field names equal the TOML keys, so an attribute path is the key path used in
error messages (``motor.Ld``). All quantities are SI.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Mapping

from ..errors import SpecError

__all__ = ["inverter_radii", "Motor", "Drive", "ControllerChoice", "Requirements", "Spec",
           "METHODS", "REQUIREMENT_KEYS", "MOTOR_PARAMETER_KEYS"]

#: The physical parameters of a :class:`Motor` a robustness set or a scenario
#: may replace or scale (``Motor.with_overrides``; a scenario's
#: ``plant_values``/``plant_scale`` keys).
MOTOR_PARAMETER_KEYS = ("R", "Ld", "Lq", "flux", "pole_pairs", "J", "friction")

#: Design methods the toolbox knows (toolbox/ARCHITECTURE.md "Spec file").
METHODS = ("pi", "ip", "pi_lag", "tc", "tci", "ilq", "lq", "hinf", "fcs_mpc", "robust_pi", "tune",
           "cv")

#: ``[requirements]`` keys: (stage, direction, quantity, unit). Stage
#: ``margins`` bounds the worst axis of the loop analysis, ``sim`` every
#: verification scenario; ``min`` means the value must be >= the bound.
REQUIREMENT_KEYS: dict[str, tuple[str, str, str, str]] = {
    "min_gain_margin_db": ("margins", "min", "gain_margin_db", "dB"),
    "min_phase_margin_deg": ("margins", "min", "phase_margin_deg", "deg"),
    "min_stability_margin": ("margins", "min", "stability_margin", "1"),
    "min_disk_margin": ("margins", "min", "disk_margin", "1"),
    "max_sensitivity_peak": ("margins", "max", "sensitivity_peak", "1"),
    "min_bandwidth_rad_s": ("margins", "min", "bandwidth_rad_s", "rad/s"),
    "max_static_error": ("margins", "max", "static_error", "1"),
    "max_response_time": ("sim", "max", "response_time_5pct", "s"),
    "max_rise_time": ("sim", "max", "rise_time_10_90", "s"),
    "max_settling_time": ("sim", "max", "settling_time_2pct", "s"),
    "max_overshoot_pct": ("sim", "max", "overshoot_pct", "%"),
    "max_static_error_A": ("sim", "max", "static_error_abs", "A"),
    "max_static_speed_error": ("sim", "max", "static_speed_error_abs", "rad/s"),
    "max_torque_mse": ("sim", "max", "mse_torque", "(N m)^2"),
    "max_id_mse": ("sim", "max", "mse_id", "A^2"),
    "max_commutations_per_s": ("sim", "max", "commutations_per_s", "1/s"),
    "max_saturation_time": ("sim", "max", "saturation_time", "s"),
}


@dataclass(frozen=True)
class Motor:
    """Permanent-magnet synchronous motor.

    Attributes
    ----------
    R : float
        Stator resistance per phase (ohm).
    Ld, Lq : float
        d- and q-axis inductances (H).
    flux : float
        Permanent-magnet flux linkage in the chosen dq convention (Wb).
    pole_pairs : int
        Number of pole pairs.
    J : float
        Rotor (and load) inertia (kg m^2).
    friction : float
        Viscous friction (N m s/rad).
    convention : str
        dq transform the parameters refer to: ``amplitude`` (2/3, torque
        factor 3/2) or ``power`` (sqrt(2/3), torque factor 1).
    rated_current, max_current : float or None
        dq current amplitude limits (A).
    rated_speed : float or None
        Rated mechanical speed (rad/s).
    catalog : str or None
        Catalog entry the defaults came from.
    magnetics : toolbox.spec.MagneticModel or None
        A saturated motor's magnetics (``[motor] flux_map`` or
        ``[motor.saturation]``): then ``Ld``, ``Lq`` and ``flux`` are its
        incremental inductances and d flux at ``i = 0``
        (``MagneticModel.nominal``), the simulator integrates the flux
        linkage through it, and ``None`` (default) is today's constant-parameter
        motor.
    """

    R: float
    Ld: float
    Lq: float
    flux: float
    pole_pairs: int
    J: float
    friction: float = 0.0
    convention: str = "amplitude"
    rated_current: float | None = None
    max_current: float | None = None
    rated_speed: float | None = None
    catalog: str | None = None
    magnetics: Any = None

    @property
    def torque_factor(self) -> float:
        """3/2 for the amplitude-invariant convention, 1 for power-invariant."""
        return 1.5 if self.convention == "amplitude" else 1.0

    @property
    def tau_d(self) -> float:
        """d-axis electrical time constant Ld/R (s)."""
        return self.Ld / self.R

    @property
    def tau_q(self) -> float:
        """q-axis electrical time constant Lq/R (s)."""
        return self.Lq / self.R

    @property
    def torque_constant(self) -> float:
        """Torque per q current at i_d = 0 (N m/A)."""
        return self.torque_factor * self.pole_pairs * self.flux

    @property
    def emf_constant(self) -> float:
        """Back-EMF amplitude per mechanical speed, p * flux (V s/rad)."""
        return self.pole_pairs * self.flux

    def with_overrides(self, values: Mapping[str, float] | None = None,
                       scale: Mapping[str, float] | None = None) -> "Motor":
        """The same motor with some parameters replaced, then multiplied.

        This is how a robustness set or a scenario's true plant is made: the
        result is again a :class:`Motor` (the one parameter type), so every
        model of :mod:`toolbox.plant` and the simulator apply to it unchanged.
        No physical check is made here; the consumer (e.g. the simulator)
        checks the values it needs, naming its own key path.

        Parameters
        ----------
        values : mapping, optional
            Parameter name (one of :data:`MOTOR_PARAMETER_KEYS`) -> value
            (SI) replacing the nominal one.
        scale : mapping, optional
            Parameter name -> multiplier, applied after ``values``.

        Returns
        -------
        Motor
            A new motor; ``self`` is unchanged.

        Raises
        ------
        SpecError
            A name that is not one of :data:`MOTOR_PARAMETER_KEYS`.
        """
        kw = {k: getattr(self, k) for k in MOTOR_PARAMETER_KEYS}
        for table, entries in (("values", values or {}), ("scale", scale or {})):
            for k in entries:
                if k not in kw:
                    raise SpecError(f"plant_{table}.{k}", "a motor parameter ("
                                    + ", ".join(MOTOR_PARAMETER_KEYS) + ")", k)
        kw.update(values or {})
        for k, m in (scale or {}).items():
            kw[k] = kw[k] * m
        return replace(self, **kw)


@dataclass(frozen=True)
class Drive:
    """Inverter and controller timing.

    Attributes
    ----------
    vdc : float
        DC-link voltage (V).
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay (controller periods).
    switching_frequency : float or None
        PWM carrier frequency (Hz); the sample time must be a whole number
        of half carrier periods.
    voltage_limit : str
        ``circle`` (inscribed circle, linear modulation) or ``hexagon``.
    max_speed : float or None
        Highest mechanical speed the analysis grids cover (rad/s).
    hold_frame : str
        Frame in which the simulated average inverter holds the voltage over
        a period: ``rotor`` (constant dq voltage) or ``stationary``
        (constant alpha-beta voltage, rotating in dq, as a PWM inverter).
    angle_compensation : str or float
        Where the firmware places the computed voltage (toolbox/ARCHITECTURE.md
        "The digital loop"): the header rotates ``v_dq`` by
        ``angle_compensation_time * w_e`` before the inverse Park transform at
        the sampled angle. ``"mid_period"`` (default): ``(delay_samples + 1/2)
        Ts``, the angle of the middle of the application period; ``"none"``: 0
        (the voltage lags by ``(delay_samples + 1/2) Ts w_e``); or a time (s).
    voltage_priority : str
        How the law's voltage limit acts (simulator and header alike):
        ``"radial"`` (default; ``v_dq`` scaled onto the limit) or ``"d_axis"``
        (``v_d`` kept, ``v_q`` gets the rest: the limiter of field-weakening
        drives, which holds ``i_d`` during a saturated q step).
    """

    vdc: float
    sample_time: float
    delay_samples: int = 1
    switching_frequency: float | None = None
    voltage_limit: str = "circle"
    max_speed: float | None = None
    hold_frame: str = "rotor"
    angle_compensation: str | float = "mid_period"
    voltage_priority: str = "radial"

    @property
    def angle_compensation_time(self) -> float:
        """The rotation time ``t_c`` (s) of the voltage placement: ``v_dq`` is
        placed at ``theta_k + t_c w_e`` (``angle_compensation``)."""
        if self.angle_compensation == "mid_period":
            return (self.delay_samples + 0.5) * self.sample_time
        if self.angle_compensation == "none":
            return 0.0
        return float(self.angle_compensation)

    def max_voltage(self, convention: str) -> float:
        """Largest dq voltage amplitude in linear modulation (V): the circle
        inscribed in the SVM hexagon (see :func:`inverter_radii`)."""
        return inverter_radii(self.vdc, convention)[1]


def inverter_radii(vdc: float, convention: str) -> tuple[float, float]:
    """Voltage limits of a two-level inverter in the dq frame (V).

    Parameters
    ----------
    vdc : float
        DC-link voltage (V).
    convention : {"amplitude", "power"}
        dq transform: amplitude-invariant (2/3) or power-invariant (sqrt(2/3)).

    Returns
    -------
    hexagon : float
        Vertex radius of the SVM hexagon, the length of an active inverter
        vector: 2/3 vdc (amplitude) or sqrt(2/3) vdc (power).
    circle : float
        Radius of the inscribed circle (linear modulation), sqrt(3)/2 of the
        vertex radius: vdc/sqrt(3) or vdc/sqrt(2).
    """
    hexagon = (2.0 / 3.0 if convention == "amplitude" else math.sqrt(2.0 / 3.0)) * vdc
    return hexagon, hexagon * math.sqrt(3.0) / 2.0


@dataclass(frozen=True)
class ControllerChoice:
    """The chosen method and its validated configuration object."""

    method: str
    cfg: Any


#: Parameters ``[requirements] parameter_drift`` may name, and the widest
#: factor range accepted (a drift beyond x0.1..x10 is another motor).
DRIFT_PARAMETERS = ("R", "Ld", "Lq", "flux")
DRIFT_FACTOR_RANGE = (0.1, 10.0)


@dataclass(frozen=True)
class Requirements:
    """Bounds verification checks (``None`` = not required).

    Attributes
    ----------
    bounds : dict
        ``REQUIREMENT_KEYS`` key -> bound.
    parameter_drift : dict
        ``{name: (low, high)}`` factors on the nominal R, Ld, Lq, flux that the
        loop must stay stable over, at every speed up to ``drive.max_speed``
        (``[requirements] parameter_drift``; checked by verification on the
        coupled sampled loop, ARCHITECTURE.md "Spec file").
    """

    bounds: dict = field(default_factory=dict)
    parameter_drift: dict = field(default_factory=dict)

    @property
    def given(self) -> bool:
        """Whether the spec states any requirement (else: default checks only)."""
        return bool(self.bounds or self.parameter_drift)

    def check_margins(self, margins: dict) -> dict:
        """Pass/fail of the ``margins`` bounds against the worst axis of
        ``margins`` (``{"d": MARGINS, "q": MARGINS}``, as in controller.json)."""
        worst: dict = {}
        for axis in margins.values():
            for quantity, value in axis.items():
                if value in ("inf", "-inf", "nan"):  # non-finite floats are strings in JSON
                    value = float(value)
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    continue
                if quantity not in worst:
                    worst[quantity] = value
                elif quantity in ("sensitivity_peak", "static_error"):  # larger is worse
                    worst[quantity] = max(worst[quantity], value)
                else:
                    worst[quantity] = min(worst[quantity], value)
        return self.check(worst, "margins")

    def check(self, measured: dict, stage: str) -> dict:
        """Pass/fail of the bounds of ``stage`` (``margins`` or ``sim``) against
        ``measured`` (quantity -> value)."""
        out = {}
        for key, bound in self.bounds.items():
            where, direction, quantity, unit = REQUIREMENT_KEYS[key]
            if where != stage:
                continue
            value = measured.get(quantity)
            ok = (value is not None and math.isfinite(value)
                  and (value >= bound if direction == "min" else value <= bound))
            out[key] = {"quantity": quantity, "bound": bound, "value": value,
                        "unit": unit, "pass": bool(ok)}
        return out


@dataclass(frozen=True)
class Spec:
    """A validated spec file.

    Attributes
    ----------
    title : str
        Free text (escaped wherever it is shown).
    motor : Motor
    drive : Drive
    controller : ControllerChoice
    requirements : Requirements
    scenarios : tuple
        Validated scenarios (:class:`toolbox.spec.Scenario`).
    raw : dict
        The resolved plain data (catalog defaults applied), for the artifact.
    source : str or None
        The file the spec came from.
    conversions : tuple of Conversion
        Datasheet keys and unit strings converted to the model's SI values:
        what was given, the value derived and the formula
        (:mod:`toolbox.spec._datasheet`).
    export_prefix : str
        ``[export] prefix``: the prefix of every C identifier of controller.h
        (``cct_`` by default; ``motor1_`` gives ``motor1_step``, ``MOTOR1_V_MAX``).
    campaign : CampaignCfg or None
        The ``[campaign]`` table (:mod:`toolbox.spec._campaign`), if any.
    """

    title: str
    motor: Motor
    drive: Drive
    controller: ControllerChoice
    requirements: Requirements
    scenarios: tuple = ()
    raw: dict = field(default_factory=dict)
    source: str | None = None
    conversions: tuple = ()
    export_prefix: str = "cct_"
    campaign: Any = None

    def motor_dict(self) -> dict:
        return asdict(self.motor)
