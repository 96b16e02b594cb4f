"""PI, IP and PI-with-lag current controllers in the dq frame.

Sources
-------
* Le Pioufle, Georgiou, Louis, J. Phys. III 2 (1992) (paper 000), sect. 2:
  PI (Fig. 2a) and IP (Fig. 2b) in dq; closed loop eq (3); normalised gains
  ``Kp = 3.5/256``, ``KI = 660/256`` scaled by the inverter voltage ``E`` and
  the current-sensor gain ``k_i`` (appendix), i.e. ``v = E k_i (Kp e + KI int e)``.
* Cormerais et al., IFAC 2002 (paper 002), eq (19)-(20): ``K = 10 R``,
  ``Ti = L/R`` (pole-zero cancellation, first-order closed loop).
* Takami, JPE 4-4 (2004) (paper 001), Fig. 2b: standard PI with a
  first-order time lag ``1/(1 + T_d s)`` "acting as a filter on the two
  current components" -- the lag filters the *measured* currents (feedback
  path), not the error; the reference enters the PI unfiltered.

Gain rules (``[controller.<method>] rule``), all in effective units
(``Kp`` V/A, ``Ki`` V/(A s)), the loop being ``v = Kp e + Ki int e``:

``cancellation``
    ``Kp = L wc``, ``Ki = R wc``: the PI zero ``-Ki/Kp = -R/L`` cancels the
    plant pole, the closed loop is ``wc/(s + wc)`` (``wc`` = closed-loop
    bandwidth, rad/s; from a 5 % response time ``t5``: ``wc = ln(20)/t5``).
``bandwidth``
    The firmware rule of ODrive (``Motor::update_current_controller_gains``:
    ``p_gain = current_control_bandwidth * phase_inductance``,
    ``i_gain = (phase_resistance/phase_inductance) * p_gain``, bandwidth in
    rad/s; Tinymovr does the same) and VESC Tool (from a time constant
    ``tc``, ``wc = 1/tc``): same numbers as cancellation, with ``wc`` read
    as the open-loop crossover ``|L(j wc)| = 1``.
``symmetric_optimum``
    Kessler's symmetric optimum as gym-electric-motor's controllers
    (gem-control) tune the current PI: ``Kp = L/(a T_sigma)``,
    ``Ti = a^2 T_sigma``, ``Ki = Kp/Ti``. Defaults here: ``a = 2`` and the
    sum of small time constants ``T_sigma = (delay_samples + 0.5) Ts``
    (computation delay plus half a sample for the zero-order hold).
    gem-control itself uses ``T_sigma = tau`` (its sample time) and
    ``a = 4``: set ``small_time_constant = Ts`` and ``a = 4`` to reproduce it.
``complex_vector``
    After motulator's synchronous-frame complex-vector PI (Briz 1999/2000),
    NOT motulator's controller itself. A continuous design in rotor
    coordinates, bandwidth ``alpha_c``. Its delay compensation angle ``1.5 Ts
    omega`` (Bae & Sul 2003, motulator's PWM ``k_comp = 1.5``) is the drive's
    voltage placement for one period of delay, which every method shares
    (``drive.angle_compensation``, toolbox/ARCHITECTURE.md "The digital
    loop"). By default ``Kp = alpha_c L``,
    ``Ki = alpha_c R``: a 1DOF cancellation PI (motulator has no such
    default), with the cross-coupling and EMF in the decoupling feedforward.
    With ``integral_bandwidth`` (``alpha_i``, method ``pi`` only) the
    two-degree-of-freedom gains: reference feedforward ``Kt = alpha_c L``,
    ``Kp = (alpha_c + alpha_i) L - R``, ``Ki = alpha_c alpha_i L``, law
    ``v = Kt r - Kp y + Ki int (r - y)``: reference tracking
    ``alpha_c/(s + alpha_c)``, poles exactly ``-alpha_c``, ``-alpha_i``.
    How it differs from motulator 0.5's ``drive.control.sm.CurrentController``
    (``k_p = 2 alpha_c``, ``k_i = alpha_c^2``, ``k_t = alpha_c`` on
    ``psi = L i``; tested against motulator in
    ``tests/design/test_pi_motulator.py``):

    * ``Kp`` subtracts ``R``; motulator's does not (``alpha_i = alpha_c``,
      ``Kp = 2 alpha_c L``): with ``alpha_i = alpha_c``, ``euler``
      discretisation, ``w = 0`` and no voltage limit our law's output is
      motulator's plus ``R i_meas``, exactly;
    * motulator's integrator is complex, ``u_i += Ts (alpha_i + j w)(u - v)``:
      the ``j w`` cross-axis term, absent here (two real per-axis laws plus
      the decoupling feedforward; motulator's synchronous-machine control
      has no feedforward, ``u_ff = 0``);
    * motulator updates the integrator with the realised (limited) voltage;
      the executed law here has Hanus's conditioning (``antiwindup = Ts/Kt``
      with ``euler``), which is the same update: with ``R -> 0`` and a
      circle limit the two agree exactly (tested);
    * motulator's integrator is forward Euler; ours is discretised by
      ``discretisation`` (default ``tustin``);
    * motulator's flux-map state and its direct discrete-time variants are
      not reproduced.
``explicit``
    ``Kp``, ``Ki`` (V/A, V/(A s)), or paper 000's normalised
    ``Kp_normalised``, ``Ki_normalised`` with ``voltage_gain`` E (V, default
    ``drive.vdc``) and ``sensor_gain`` k_i (1/A): ``Kp = E k_i Kp_n``,
    ``Ki = E k_i Ki_n`` (000: 10.5 V/A and 1980 V/(A s)). For ``ip`` paper
    000 says the integral gain is ``Kp KI`` (sect. 2, note on the IP
    controller: its IP is ``v = E k_i Kp (KI int e - y)``), so with
    normalised gains ``Ki = E k_i Kp_n Ki_n``.

Structures (two-input laws ``[i_ref, i_meas] -> v``):

* ``pi``: ``v = (Kp + Ki/s)(r - y)``.
* ``ip``: ``v = Ki/s (r - y) - Kp y`` (same loop, no closed-loop zero;
  with cancellation gains the reference response is
  ``1/((1 + s L/R)(1 + s/wc))``, slow: a warning says so).
* ``pi_lag``: ``v = (Kp + Ki/s)(r - y_f)``, ``y_f = y/(1 + T_d s)``. The
  gain rules ignore the lag; ``design_parameters["poles"]`` gives the resulting poles.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..lti import StateSpace, as_statespace
from ..artifact import AxisController, ControllerArtifact
from ..errors import SpecError
from ..spec import Collector, Table, check_gain, check_rate, check_time_constant
from . import _defaults
from ._common import decoupling_from_motor, make_artifact

__all__ = [
    "PiCfg", "RULES", "read_cfg", "design", "design_pi", "pi_law",
    "gains_cancellation", "gains_symmetric_optimum", "bandwidth_from_response_time",
    "gains_complex_vector_2dof", "closed_loop_poles",
    "gains_from_normalised", "plant_RL",
]

RULES = ("cancellation", "bandwidth", "symmetric_optimum", "complex_vector", "explicit")
STRUCTURES = ("pi", "ip", "pi_lag")
DISCRETISATIONS = ("tustin", "zoh", "backward_diff", "euler")

#: keys each rule reads (besides the common ones)
_RULE_KEYS = {
    "cancellation": ("bandwidth", "response_time"),
    "bandwidth": ("bandwidth", "response_time"),
    "complex_vector": ("bandwidth", "response_time", "integral_bandwidth"),
    "symmetric_optimum": ("a", "small_time_constant"),
    "explicit": ("Kp", "Ki", "Kp_normalised", "Ki_normalised", "voltage_gain", "sensor_gain"),
}
_COMMON_KEYS = ("rule", "decoupling", "discretisation")
_ALL_RULE_KEYS = tuple(dict.fromkeys(k for keys in _RULE_KEYS.values() for k in keys))

LN20 = math.log(20.0)


@dataclass(frozen=True)
class PiCfg:
    """Validated ``[controller.pi|ip|pi_lag]``.

    Attributes
    ----------
    structure : str
        ``pi``, ``ip`` or ``pi_lag``.
    rule : str
        Gain rule (see module docstring).
    Kp : tuple of float
        Effective proportional gains (d, q) (V/A).
    Ki : tuple of float
        Effective integral gains (d, q) (V/(A s)).
    decoupling : bool
        Feedforward of cross-coupling and back-EMF (default true).
    lag_time_constant : float or None
        ``T_d`` of paper 001 Fig. 2b (s), ``pi_lag`` only.
    discretisation : str
        How the continuous law is discretised (default ``tustin``).
    Kt : tuple of float or None
        Reference feedforward gains (V/A) of a two-degree-of-freedom PI
        (``complex_vector`` with ``integral_bandwidth``); ``None``: ``Kt = Kp``.
    details : dict
        Rule-specific values kept in the artifact's design_parameters (bandwidth,
        T_sigma, normalisation, ...).
    """

    structure: str
    rule: str
    Kp: tuple[float, float]
    Ki: tuple[float, float]
    decoupling: bool = True
    lag_time_constant: float | None = None
    discretisation: str = "tustin"
    Kt: tuple[float, float] | None = None
    details: dict = field(default_factory=dict)

    def to_spec(self, spec=None) -> dict[str, Any] | None:
        """``[controller.<structure>]`` keys that read back to the same gains.

        The gains are written as the explicit rule (effective ``Kp``, ``Ki``
        per axis): whatever rule or default gave them, the same law results.
        A two-degree-of-freedom PI (``Kt``) has no explicit form, and the
        complex-vector rule carries its delay compensation: None (the table
        is printed as given).

        Parameters
        ----------
        spec : Spec, optional
            Unused (same signature as the other methods' ``to_spec``).

        Returns
        -------
        dict or None
        """
        if self.Kt is not None or self.rule == "complex_vector":
            return None
        out: dict[str, Any] = {"rule": "explicit", "Kp": _per_axis(self.Kp),
                               "Ki": _per_axis(self.Ki), "decoupling": bool(self.decoupling),
                               "discretisation": self.discretisation}
        if self.structure == "pi_lag":
            out["lag_time_constant"] = float(self.lag_time_constant)
        return out


def _per_axis(pair) -> dict[str, float]:
    """``(d, q)`` as the spec's per-axis inline table ``{d = .., q = ..}``."""
    return {"d": float(pair[0]), "q": float(pair[1])}


def bandwidth_from_response_time(response_time: float) -> float:
    """Bandwidth of a first-order loop with the given 5 % response time.

    ``exp(-wc t5) = 0.05`` gives ``wc = ln(20)/t5`` (rad/s) for
    ``response_time`` ``t5`` (s).
    """
    return LN20 / response_time


def gains_cancellation(L: float, R: float, bandwidth: float) -> tuple[float, float]:
    """Pole-zero cancellation PI gains.

    Parameters
    ----------
    L : float
        Axis inductance (H).
    R : float
        Resistance (ohm).
    bandwidth : float
        Closed-loop bandwidth ``wc`` (rad/s).

    Returns
    -------
    Kp : float
        ``L wc`` (V/A).
    Ki : float
        ``R wc`` (V/(A s)); closed loop ``wc/(s + wc)``.
    """
    return L * bandwidth, R * bandwidth


def gains_symmetric_optimum(L: float, T_sigma: float, a: float = 2.0) -> tuple[float, float]:
    """Symmetric-optimum PI gains (gym-electric-motor's current PI tuning).

    ``Kp = L/(a T_sigma)`` (V/A), ``Ti = a^2 T_sigma`` (s), ``Ki = Kp/Ti``
    (V/(A s)); ``T_sigma`` (s) is the sum of the small time constants.
    """
    Kp = L / (a * T_sigma)
    return Kp, Kp / (a * a * T_sigma)


def gains_complex_vector_2dof(L: float, R: float, alpha_c: float,
                              alpha_i: float) -> tuple[float, float, float]:
    """motulator's complex-vector 2DOF PI gains, per axis.

    Parameters
    ----------
    L : float
        Axis inductance (H).
    R : float
        Resistance (ohm).
    alpha_c, alpha_i : float
        Reference-tracking and integral-action bandwidths (rad/s).

    Returns
    -------
    Kt, Kp, Ki : float
        ``alpha_c L`` (V/A), ``(alpha_c + alpha_i) L - R`` (V/A),
        ``alpha_c alpha_i L`` (V/(A s)); closed loop ``alpha_c/(s + alpha_c)``.
    """
    return alpha_c * L, (alpha_c + alpha_i) * L - R, alpha_c * alpha_i * L


def gains_from_normalised(Kp_n: float, Ki_n: float, voltage_gain: float,
                          sensor_gain: float, structure: str = "pi") -> tuple[float, float]:
    """Effective gains from paper 000's normalised ones.

    ``Kp = E k_i Kp_n`` (V/A) and ``Ki = E k_i Ki_n`` (V/(A s)) for a PI;
    for 000's IP (``structure = "ip"``, ``v = E k_i Kp_n (Ki_n int e - y)``)
    ``Ki = E k_i Kp_n Ki_n``. ``voltage_gain`` E in V, ``sensor_gain`` k_i
    in 1/A (000: 150, 256/50).
    """
    scale = voltage_gain * sensor_gain
    Ki = scale * Kp_n * Ki_n if structure == "ip" else scale * Ki_n
    return scale * Kp_n, Ki


def plant_RL(plant: Any) -> tuple[float, float]:
    """``(R, L)`` of a first-order axis plant ``1/(R + L s)``.

    ``plant`` is anything :func:`toolbox.lti.as_statespace` reads (e.g.
    :func:`toolbox.plant.axis_plant_models`, or a python-control system): one state,
    no feedthrough, ``G = c b/(s - a)`` so ``L = 1/(c b)`` and ``R = -a L``.
    """
    g = as_statespace(plant)
    if (g.nstates, g.ninputs, g.noutputs) != (1, 1, 1) or g.D[0, 0] != 0.0 \
            or g.B[0, 0] * g.C[0, 0] == 0.0:
        raise SpecError("plant", "a first-order plant 1/(R + L s)", repr(g))
    gain = float(g.C[0, 0] * g.B[0, 0])
    return float(-g.A[0, 0] / gain), 1.0 / gain


def pi_law(Kp: float, Ki: float, structure: str = "pi",
           lag_time_constant: float | None = None,
           Kt: float | None = None) -> StateSpace:
    """Continuous two-input law ``[i_ref, i_meas] -> v`` of one axis.

    Parameters
    ----------
    Kp : float
        Proportional gain (V/A).
    Ki : float
        Integral gain (V/(A s)).
    structure : {"pi", "ip", "pi_lag"}
        ``pi``: ``v = Kp e + Ki x``, ``x' = e``;
        ``ip``: ``v = Ki x - Kp y``, ``x' = r - y``;
        ``pi_lag``: ``y_f' = (y - y_f)/T_d``, ``x' = r - y_f``,
        ``v = Kp (r - y_f) + Ki x``.
    lag_time_constant : float, optional
        ``T_d`` (s) for ``pi_lag``.
    Kt : float, optional
        Reference feedforward gain (V/A) of a 2DOF ``pi``:
        ``v = Kt r - Kp y + Ki x`` (default ``Kt = Kp``).

    Returns
    -------
    toolbox.lti.StateSpace
        Continuous, states ``[x]`` or ``[x, y_f]``.
    """
    if structure == "pi":
        return StateSpace([[0.0]], [[1.0, -1.0]], [[Ki]], [[Kp if Kt is None else Kt, -Kp]])
    if structure == "ip":
        return StateSpace([[0.0]], [[1.0, -1.0]], [[Ki]], [[0.0, -Kp]])
    if structure == "pi_lag":
        if lag_time_constant is None or not lag_time_constant > 0:
            raise SpecError("lag_time_constant", "a number > 0 (s)", lag_time_constant)
        Td = lag_time_constant
        return StateSpace([[0.0, -1.0], [0.0, -1.0 / Td]], [[1.0, 0.0], [0.0, 1.0 / Td]],
                          [[Ki, -Kp]], [[Kp, 0.0]])
    raise SpecError("structure", f"one of {list(STRUCTURES)}", structure)


def design_pi(Kp: tuple[float, float], Ki: tuple[float, float], sample_time: float, *,
              structure: str = "pi", lag_time_constant: float | None = None,
              method: str = "tustin",
              Kt: tuple[float, float] | None = None) -> dict[str, AxisController]:
    """Per-axis controllers for given gains.

    Parameters
    ----------
    Kp, Ki : tuple of float
        (d, q) gains (V/A, V/(A s)).
    sample_time : float
        Controller period (s).
    structure, lag_time_constant
        See :func:`pi_law`.
    method : str
        Discretisation of the law (``tustin``, ``zoh``, ``backward_diff``, ``euler``).
    Kt : tuple of float, optional
        (d, q) reference feedforward gains (V/A) of a 2DOF ``pi``.

    Returns
    -------
    dict
        ``{"d": AxisController, "q": AxisController}``; the error controller
        is ``Kp + Ki/s`` (times ``1/(1 + T_d s)`` for ``pi_lag``).
    """
    axes = {}
    for k, name in enumerate(("d", "q")):
        law = pi_law(Kp[k], Ki[k], structure, lag_time_constant,
                     None if Kt is None else Kt[k])
        axes[name] = AxisController.from_law(law, sample_time=sample_time, method=method)
    return axes


# ------------------------------------------------------------------ spec side
def _reject_foreign(t: Table, rule: str, structure: str) -> None:
    mine = set(_RULE_KEYS[rule])
    for name in t.data:
        if name in _ALL_RULE_KEYS and name not in mine:
            raise SpecError(t.key(name), f'only keys that rule = "{rule}" reads',
                            hint=f"its keys: {', '.join(_RULE_KEYS[rule])}")


def _bandwidth(t: Table, default: float | None = None) -> tuple[float, float]:
    if t.has("bandwidth") and t.has("response_time"):
        raise SpecError(t.key("response_time"), "either bandwidth or response_time, not both",
                        t.raw("response_time"))
    if t.has("response_time"):
        t5 = t.per_axis("response_time", positive=True, unit="s")
        return (bandwidth_from_response_time(t5[0]), bandwidth_from_response_time(t5[1]))
    if not t.has("bandwidth"):
        if default is not None:
            return default, default
        raise SpecError(t.key("bandwidth"), "a number > 0 (rad/s) or response_time (missing)")
    return t.per_axis("bandwidth", positive=True, unit="rad/s")


def _check_rates(t: Table, drive, names: tuple[str, ...]) -> None:
    """The rates and time constants given in ``t`` within the one design range
    (toolbox/spec/_bounds.py ``RATE_TS``; ``cct check`` refuses them)."""
    times = {"response_time": LN20, "lag_time_constant": 1.0, "small_time_constant": 1.0}
    for name in names:
        if not t.has(name):
            continue
        for value in set(t.per_axis(name, positive=True)):
            if name in times:
                check_time_constant(t.key(name), value, drive, times[name])
            else:
                check_rate(t.key(name), value, drive)


def _check_gains(t: Table, Kp: tuple, Ki: tuple, L: tuple, drive) -> None:
    """Explicit gains within the design range: ``Kp / L`` and ``sqrt(Ki / L)``
    as rates (toolbox/spec/_bounds.py ``check_gain``)."""
    normalised = t.has("Kp_normalised") or t.has("Ki_normalised")
    kp_key = t.key("Kp_normalised" if normalised else "Kp")
    ki_key = t.key("Ki_normalised" if normalised else "Ki")
    for k in (0, 1):
        check_gain(kp_key, Kp[k], L[k], drive, "V/A" if not normalised else "V/A (after scaling)")
        check_gain(ki_key, Ki[k], L[k], drive,
                   "V/(A s)" if not normalised else "V/(A s) (after scaling)", order=2)


def _default_lag(drive) -> float:
    """Default ``lag_time_constant`` of ``pi_lag`` (s): one sample period, an
    anti-aliasing filter at the sampling rate (paper 001 gives no value)."""
    return float(drive.sample_time)


def _ip_default_gains(L: float, R: float, wc: float) -> tuple[float, float]:
    """IP gains for crossover ``wc`` with the integral zero at ``wc/4``.

    ``Kp = L wc``, ``Ki = Kp wc/4``: the characteristic polynomial
    ``L s^2 + (R + L wc) s + L wc^2/4`` is ``L (s + wc/2)^2`` for ``R -> 0``,
    so the IP reference response (no closed-loop zero) settles with a double
    pole at ``wc/2`` instead of the plant time constant ``L/R`` that the
    cancellation rule leaves it.
    """
    Kp = L * wc
    return Kp, Kp * wc / _defaults.ZERO_RATIO


def _explicit(t: Table, structure: str, drive) -> tuple[tuple, tuple, dict]:
    has_plain = t.has("Kp") or t.has("Ki")
    has_norm = t.has("Kp_normalised") or t.has("Ki_normalised")
    if has_plain and has_norm:
        raise SpecError(t.key("Kp_normalised"), "either Kp/Ki or Kp_normalised/Ki_normalised",
                        t.raw("Kp_normalised", t.raw("Ki_normalised")))
    errors = Collector()  # the gains are read together: every bad one reported
    if has_norm:
        Kp_n = Ki_n = k_i = None
        E = drive.vdc
        with errors.check():
            Kp_n = t.per_axis("Kp_normalised", positive=True)
        with errors.check():
            Ki_n = t.per_axis("Ki_normalised", positive=True)
        with errors.check():
            E = t.number("voltage_gain", drive.vdc, positive=True, unit="V")
        with errors.check():
            k_i = t.number("sensor_gain", positive=True, unit="1/A")
        errors.raise_if_any()
        gains = [gains_from_normalised(Kp_n[k], Ki_n[k], E, k_i, structure) for k in (0, 1)]
        details = {"Kp_normalised": _axes(Kp_n), "Ki_normalised": _axes(Ki_n),
                   "voltage_gain": E, "sensor_gain": k_i}
        return (gains[0][0], gains[1][0]), (gains[0][1], gains[1][1]), details
    for name in ("voltage_gain", "sensor_gain"):
        if t.has(name):
            raise SpecError(t.key(name), "Kp_normalised and Ki_normalised alongside it",
                            hint="voltage_gain and sensor_gain scale the normalised gains")
    Kp = Ki = None
    with errors.check():
        Kp = t.per_axis("Kp", positive=True, unit="V/A")
    with errors.check():
        Ki = t.per_axis("Ki", positive=True, unit="V/(A s)")
    errors.raise_if_any()
    return Kp, Ki, {}


def _axes(pair: tuple[float, float]) -> dict[str, float]:
    return {"d": float(pair[0]), "q": float(pair[1])}


def read_cfg(method: str, table: Table, motor, drive) -> PiCfg:
    """Validate ``[controller.pi]`` / ``[controller.ip]`` / ``[controller.pi_lag]``.

    Parameters
    ----------
    method : {"pi", "ip", "pi_lag"}
        The structure.
    table : Table
        The ``[controller.<method>]`` table.
    motor : Motor
        Supplies R, Ld, Lq for the gain rules.
    drive : Drive
        Supplies vdc (default ``voltage_gain``), sample time and delay.

    Returns
    -------
    PiCfg

    Raises
    ------
    SpecError
        Unknown key, key foreign to the chosen rule, non-positive bandwidth,
        gains or lag time constant; the key path is ``controller.<method>.<key>``.
    """
    allowed = _COMMON_KEYS + _ALL_RULE_KEYS + (("lag_time_constant",) if method == "pi_lag" else ())
    if method != "pi_lag" and "lag_time_constant" in table.data:
        raise SpecError(table.key("lag_time_constant"), 'method = "pi_lag" for a lag',
                        hint="the PI with first-order lag of paper 001 Fig. 2b")
    t = Table(table.data, table.prefix, allowed)
    explicit_given = any(t.has(k) for k in ("Kp", "Ki", "Kp_normalised", "Ki_normalised"))
    rule = t.string("rule", "explicit" if explicit_given else "cancellation", choices=RULES)
    _reject_foreign(t, rule, method)
    L = (motor.Ld, motor.Lq)
    details: dict[str, Any] = {}
    Kt = None
    lag = None
    if method == "pi_lag":
        lag = t.number("lag_time_constant", _default_lag(drive), positive=True, unit="s")
        if not t.has("lag_time_constant"):
            details.setdefault("defaults", {})["lag_time_constant"] = {
                "value": lag, "rule": "T_d = Ts (anti-aliasing lag at the sampling rate)"}
    # nothing of the rule given: the bandwidth is derived from Ts and the delay
    # (_defaults module docstring), the lag counted as extra delay
    no_gain_keys = not any(t.has(k) for k in ("rule",) + _ALL_RULE_KEYS)
    ip_default = method == "ip" and no_gain_keys
    default_wc = _defaults.default_bandwidth(drive, zero=ip_default, extra_delay=lag or 0.0)
    if ip_default:
        wc = (default_wc.value, default_wc.value)
        g = [_ip_default_gains(L[k], motor.R, wc[k]) for k in (0, 1)]
        Kp, Ki = (g[0][0], g[1][0]), (g[0][1], g[1][1])
        rule = "ip_default"
        details["bandwidth_rad_s"] = _axes(wc)
        details.setdefault("defaults", {})["bandwidth"] = {
            **default_wc.as_dict(),
            "gains": "Kp = L wc, Ki = Kp wc/4 (closed-loop double pole near wc/2)"}
    elif rule in ("cancellation", "bandwidth", "complex_vector"):
        wc = _bandwidth(t, default_wc.value)
        if not (t.has("bandwidth") or t.has("response_time")):
            details.setdefault("defaults", {})["bandwidth"] = default_wc.as_dict()
        g = [gains_cancellation(L[k], motor.R, wc[k]) for k in (0, 1)]
        Kp, Ki = (g[0][0], g[1][0]), (g[0][1], g[1][1])
        details["bandwidth_rad_s"] = _axes(wc)
        limit = _defaults.largest_stable_pi_bandwidth(drive)
        if max(wc) >= limit:
            # the design exists (exit 1, outputs written): say which bandwidth would do
            key = t.key("bandwidth" if t.has("bandwidth") else "response_time")
            details["design_warnings"] = [
                f"{key}: {max(wc):.5g} rad/s is at or above the largest stable bandwidth "
                f"{limit:.5g} rad/s of the sampled loop (2 sin(pi/(4 delay + 2))/Ts, "
                f"delay_samples {drive.delay_samples}); {default_wc.value:.5g} rad/s keeps "
                f"a phase margin of about {_defaults.TARGET_PM_DEG:g} deg (leave bandwidth "
                "out for it)"]
        if rule == "complex_vector":
            if t.has("integral_bandwidth"):
                if method != "pi":
                    raise SpecError(t.key("integral_bandwidth"), 'method = "pi" for a 2DOF PI',
                                    hint="the two-degree-of-freedom complex-vector PI has its "
                                         "own reference feedforward")
                wi = t.per_axis("integral_bandwidth", positive=True, unit="rad/s")
                g = [gains_complex_vector_2dof(L[k], motor.R, wc[k], wi[k]) for k in (0, 1)]
                Kt = (g[0][0], g[1][0])
                Kp, Ki = (g[0][1], g[1][1]), (g[0][2], g[1][2])
                details["integral_bandwidth_rad_s"] = _axes(wi)
                details["Kt"] = _axes(Kt)
                if min(Kp) <= 0:
                    raise SpecError(t.key("bandwidth"), "alpha_c + alpha_i > R/L (a positive Kp)",
                                    t.raw("bandwidth"))
    elif rule == "symmetric_optimum":
        # a = 1 gives Ti = T_sigma (no phase margin); a = 100 already a PM of
        # 89 deg with Kp = L/(100 T_sigma): beyond it the integral action is nil
        a = t.number("a", 2.0)
        if not 1.0 < a <= 100.0:
            raise SpecError(t.key("a"), "a number > 1 and <= 100", a)
        T_sigma = t.number("small_time_constant", (drive.delay_samples + 0.5) * drive.sample_time,
                           positive=True, unit="s")
        g = [gains_symmetric_optimum(L[k], T_sigma, a) for k in (0, 1)]
        Kp, Ki = (g[0][0], g[1][0]), (g[0][1], g[1][1])
        details.update(a=a, T_sigma=T_sigma, Ti=a * a * T_sigma)
    else:
        Kp, Ki, explicit_details = _explicit(t, method, drive)
        details.update(explicit_details)
        _check_gains(t, Kp, Ki, L, drive)
    _check_rates(t, drive, ("bandwidth", "response_time", "integral_bandwidth",
                            "lag_time_constant", "small_time_constant"))
    if method == "ip" and rule in ("cancellation", "bandwidth", "complex_vector"):
        warnings.warn(
            f'ip with rule = "{rule}": the loop has the PI\'s poles (-R/L, -wc), but the '
            "IP reference response has no zero to cancel -R/L, so it follows the plant "
            f"time constant L/R = {1e3 * max(L) / motor.R:.3g} ms; give explicit Kp, Ki "
            "for a faster IP", stacklevel=2)
    return PiCfg(structure=method, rule=rule, Kp=tuple(map(float, Kp)),
                 Kt=None if Kt is None else tuple(map(float, Kt)),
                 Ki=tuple(map(float, Ki)), decoupling=t.boolean("decoupling", True),
                 lag_time_constant=lag,
                 discretisation=t.string("discretisation", "tustin", choices=DISCRETISATIONS),
                 details=details)


def closed_loop_poles(L: float, R: float, Kp: float, Ki: float,
                      lag_time_constant: float | None = None) -> np.ndarray:
    """Nominal closed-loop poles (rad/s) of one decoupled axis ``1/(R + L s)``.

    Roots of ``L s^2 + (R + Kp) s + Ki`` (PI, IP, 2DOF PI) or, with the
    measurement lag ``T_d`` = ``lag_time_constant`` (s), of
    ``T_d L s^3 + (L + R T_d) s^2 + (R + Kp) s + Ki``; ``L`` in H, ``R`` in
    ohm, ``Kp`` in V/A, ``Ki`` in V/(A s).
    """
    if lag_time_constant is None:
        poly = [L, R + Kp, Ki]
    else:
        Td = lag_time_constant
        poly = [Td * L, L + R * Td, R + Kp, Ki]
    return np.sort_complex(np.roots(poly).astype(complex))


def _gains(cfg: PiCfg, sample_time: float, motor) -> dict[str, Any]:
    Kp, Ki = cfg.Kp, cfg.Ki
    gains: dict[str, Any] = {
        "rule": cfg.rule, "structure": cfg.structure,
        "Kp": _axes(Kp), "Ki": _axes(Ki),
        "Ti": _axes((Kp[0] / Ki[0], Kp[1] / Ki[1])),
        "Ki_per_sample": _axes((Ki[0] * sample_time, Ki[1] * sample_time)),
        "decoupling": cfg.decoupling,
        "discretisation": cfg.discretisation,
        "poles": {ax: [[float(p.real), float(p.imag)] for p in
                       closed_loop_poles(L, motor.R, Kp[k], Ki[k], cfg.lag_time_constant)]
                  for k, (ax, L) in enumerate((("d", motor.Ld), ("q", motor.Lq)))},
    }
    if cfg.lag_time_constant is not None:
        gains["lag_time_constant"] = cfg.lag_time_constant
    gains.update(cfg.details)
    return gains


_EQUATIONS = {
    "pi": ["000 sect. 2, Fig. 2a and eq (3): v = E k_i (Kp e + KI int e)",
           "002 eq (19)-(20): K = 10 R, Ti = L/R (pole-zero cancellation)"],
    "ip": ["000 sect. 2, Fig. 2b: IP, v = Ki/s (r - y) - Kp y"],
    "pi_lag": ["001 Fig. 2b: PI with first-order lag 1/(1 + T_d s) on the measured currents"],
}
_RULE_EQUATIONS = {
    "cancellation": "Kp = L wc, Ki = R wc (closed loop wc/(s + wc), wc = ln(20)/t5)",
    "bandwidth": "Kp = L wc, Ki = R wc (ODrive/VESC: wc = current-loop crossover)",
    "symmetric_optimum": "Kp = L/(a T_sigma), Ti = a^2 T_sigma, T_sigma = (delay + 0.5) Ts",
    "complex_vector": ("Kp = alpha_c L, Ki = alpha_c R (or 2DOF: Kt = alpha_c L, "
                       "Kp = (alpha_c + alpha_i) L - R, Ki = alpha_c alpha_i L); "
                       "delay compensation angle 1.5 Ts omega"),
    "explicit": "Kp = E k_i Kp_n, Ki = E k_i Ki_n (000 appendix: E = 150 V, k_i = 256/50)",
    "ip_default": ("Kp = L wc, Ki = Kp wc/4, wc = (90 deg - 65 deg - atan(1/4))/((delay + 0.5) Ts) "
                   "(defaults from the sample time, toolbox.design._defaults)"),
}


def design(spec) -> ControllerArtifact:
    """Design the PI / IP / PI-with-lag controller a spec asks for.

    Parameters
    ----------
    spec : Spec
        Validated spec with ``controller.method`` in ``pi``, ``ip``, ``pi_lag``.

    Returns
    -------
    ControllerArtifact
        Axes from :func:`design_pi`, decoupling from the motor (cross and
        EMF on when ``decoupling = true``), gains and equations.
    """
    cfg: PiCfg = spec.controller.cfg
    Ts = spec.drive.sample_time
    axes = design_pi(cfg.Kp, cfg.Ki, Ts, structure=cfg.structure,
                     lag_time_constant=cfg.lag_time_constant, method=cfg.discretisation,
                     Kt=cfg.Kt)
    dec = decoupling_from_motor(spec.motor, cross=cfg.decoupling, emf=cfg.decoupling)
    equations = _EQUATIONS[cfg.structure] + [_RULE_EQUATIONS[cfg.rule]]
    return make_artifact(spec, axes, dec, _gains(cfg, Ts, spec.motor), equations)
