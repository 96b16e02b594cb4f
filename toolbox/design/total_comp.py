"""Total compensation current controllers (paper 000, sect. 3 and 4).

Le Pioufle, Georgiou, Louis, "A robust total compensation algorithm for the
torque control of a synchronous servomotor", J. Phys. III 2 (1992).

``tc`` -- total compensation, eq (8)-(11). The control (9)
``[v_d, v_q - p psi_f Omega] = B^{-1}(-A i + [K1 e_d, K2 e_q])`` imposes the
first-order error dynamics (8) ``de/dt = -K e``; written out (eq (11), with
the controller-side parameters R_c, L_dc, L_qc, psi_fc of sect. 3.3.1)::

    V_d = R_c i_d - p L_qc Omega i_q + K1 L_dc (i_dref - i_d)
    V_q = R_c i_q + p L_dc Omega i_d + K2 L_qc (i_qref - i_q) + p psi_fc Omega

(the printed eq (11) has ``- K1 L_d i_d``: the paper sets ``i_dref = 0``).

``tci`` -- with integrators, eq (18)-(24)::

    V_d = R_c i_d - p L_qc Omega i_q + K11 L_dc e_d + K12 L_dc int e_d
    V_q = R_c i_q + p L_dc Omega i_d + K21 L_qc e_q + K22 L_qc int e_q + p psi_fc Omega

SIGN MISPRINT in eq (18) (and (21)): printed ``de/dt = K11 e + K12 int e``;
with the control law (20) and ``e = i_ref - i`` the error obeys
``de/dt = -K11 e - K12 int e``, i.e. ``s^2 + K11 s + K12 = 0``, stable for
K11, K12 > 0 (the paper's own values 3750 and 707 100 are positive).

Split of the law: the cross-coupling and back-EMF terms (in Omega) are the
artifact's :class:`~toolbox.artifact.Decoupling` (cross and emf on); the
resistance feedback ``R_c i`` is linear in the measured current and sits in
the law's measurement channel, so the error controller of the loop is
``K L_c - R_c`` (tc) or ``K11 L_c + K12 L_c/s - R_c`` (tci).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..lti import StateSpace, static_gain
from ..artifact import AxisController, ControllerArtifact, Decoupling
from ..errors import SpecError
from ..spec import Collector, Table, check_gain, check_time_constant
from . import _defaults
from ._common import make_artifact
from .pi import DISCRETISATIONS, LN20, _check_gains, _explicit

__all__ = ["TotalCompCfg", "read_cfg", "design", "design_total_compensation",
           "total_comp_law", "gains_from_poles", "gains_from_response_time",
           "gains_match_pi", "designed_poles"]

_MODEL_KEYS = ("R", "Ld", "Lq", "flux")
_TC_KEYS = ("K1", "K2", "response_time", "poles", "model", "discretisation")
_TCI_KEYS = ("K11", "K12", "K21", "K22", "natural_frequency", "damping", "poles",
             "match_pi", "Kp", "Ki", "Kp_normalised", "Ki_normalised", "voltage_gain",
             "sensor_gain", "model", "discretisation")
_TCI_GROUPS = {
    "gains": ("K11", "K12", "K21", "K22"),
    "natural_frequency": ("natural_frequency", "damping"),
    "poles": ("poles",),
    "match_pi": ("match_pi", "Kp", "Ki", "Kp_normalised", "Ki_normalised", "voltage_gain",
                 "sensor_gain"),
}
_TC_GROUPS = {"gains": ("K1", "K2"), "response_time": ("response_time",), "poles": ("poles",)}


@dataclass(frozen=True)
class TotalCompCfg:
    """Validated ``[controller.tc]`` / ``[controller.tci]``.

    Attributes
    ----------
    method : str
        ``tc`` or ``tci``.
    K_prop : tuple of float
        (d, q) proportional error gains: (K1, K2) or (K11, K21) (1/s).
    K_int : tuple of float or None
        (d, q) integral error gains (K12, K22) (1/s^2); ``None`` for ``tc``.
    model : dict
        Controller-side ``R`` (ohm), ``Ld``, ``Lq`` (H), ``flux`` (Wb).
    discretisation : str
        How the continuous law is discretised (``tustin`` default).
    details : dict
        How the gains were obtained (kept in the artifact's design_parameters).
    """

    method: str
    K_prop: tuple[float, float]
    K_int: tuple[float, float] | None
    model: dict
    discretisation: str = "tustin"
    details: dict = field(default_factory=dict)

    def to_spec(self, spec=None) -> dict[str, Any]:
        """``[controller.tc|tci]`` keys that read back to the same gains.

        ``tc``: ``K1`` (d), ``K2`` (q); ``tci``: ``K11``, ``K12`` (d), ``K21``,
        ``K22`` (q), whatever group (poles, response time, match_pi, default)
        gave them; the controller-side ``model`` and the discretisation.

        Parameters
        ----------
        spec : Spec, optional
            Unused (same signature as the other methods' ``to_spec``).

        Returns
        -------
        dict
        """
        if self.K_int is None:
            gains = {"K1": float(self.K_prop[0]), "K2": float(self.K_prop[1])}
        else:
            gains = {"K11": float(self.K_prop[0]), "K12": float(self.K_int[0]),
                     "K21": float(self.K_prop[1]), "K22": float(self.K_int[1])}
        return {**gains, "model": {k: float(v) for k, v in self.model.items()},
                "discretisation": self.discretisation}


# ------------------------------------------------------------------ plain API
def gains_from_response_time(response_time: float) -> float:
    """``K = ln(20)/t5`` (1/s): error dynamics (8) reach 5 % at ``response_time`` ``t5`` (s)."""
    return LN20 / response_time


def gains_from_poles(poles) -> tuple[float, float]:
    """``(K_prop, K_int)`` placing the roots of ``s^2 + K_prop s + K_int``.

    Parameters
    ----------
    poles : sequence of two complex
        Desired closed-loop poles (rad/s), real or a conjugate pair, with
        negative real parts.

    Returns
    -------
    tuple of float
        ``K_prop = -(s1 + s2)`` (1/s), ``K_int = s1 s2`` (1/s^2).
    """
    s1, s2 = (complex(p) for p in poles)
    return float(-(s1 + s2).real), float((s1 * s2).real)


def gains_match_pi(Kp: float, Ki: float, L_c: float) -> tuple[float, float]:
    """000 eq (22)-(23): same proportional and integral voltage action as a PI.

    ``K21 = Kp/L`` (1/s), ``K22 = Ki/L`` (1/s^2) with the effective PI gains
    ``Kp = E k_i Kp_n`` (V/A), ``Ki = E k_i KI_n`` (V/(A s)); ``L_c`` in H.
    """
    return Kp / L_c, Ki / L_c


def designed_poles(K_prop: float, K_int: float | None = None) -> np.ndarray:
    """Nominal closed-loop poles (rad/s): ``-K`` (tc) or roots of ``s^2 + K_prop s + K_int``."""
    if K_int is None:
        return np.array([-K_prop], complex)
    return np.sort_complex(np.roots([1.0, K_prop, K_int]).astype(complex))


def total_comp_law(K_prop: float, L_c: float, R_c: float,
                   K_int: float | None = None) -> StateSpace:
    """Continuous two-input law ``[i_ref, i_meas] -> v`` of one axis (Omega terms excluded).

    ``v = R_c y + K_prop L_c (r - y) [+ K_int L_c int (r - y)]`` (V), 000 eq
    (11) / (20) without the speed terms (those are the Decoupling).
    """
    if K_int is None:
        return static_gain([[K_prop * L_c, R_c - K_prop * L_c]])
    return StateSpace([[0.0]], [[1.0, -1.0]], [[K_int * L_c]],
                      [[K_prop * L_c, R_c - K_prop * L_c]])


def design_total_compensation(K_prop: tuple[float, float], sample_time: float, *,
                              R_c: float, Ld_c: float, Lq_c: float,
                              K_int: tuple[float, float] | None = None,
                              method: str = "tustin") -> dict[str, AxisController]:
    """Per-axis laws of the total compensation controller.

    Parameters
    ----------
    K_prop : tuple of float
        (K1, K2) or (K11, K21) (1/s).
    sample_time : float
        Controller period (s).
    R_c, Ld_c, Lq_c : float
        Controller-side resistance (ohm) and inductances (H).
    K_int : tuple of float, optional
        (K12, K22) (1/s^2) for the version with integrators.
    method : str
        Discretisation of the law.

    Returns
    -------
    dict
        ``{"d": AxisController, "q": AxisController}``.
    """
    axes = {}
    for k, (name, L_c) in enumerate((("d", Ld_c), ("q", Lq_c))):
        Ki = None if K_int is None else K_int[k]
        law = total_comp_law(K_prop[k], L_c, R_c, Ki)
        if law.nstates == 0:
            law_d = static_gain(law.D, sample_time)
            err = static_gain([[-law.D[0, 1]]])
            axes[name] = AxisController.from_law(law_d, sample_time=sample_time,
                                                 method="native", error_controller=err)
        else:
            axes[name] = AxisController.from_law(law, sample_time=sample_time, method=method)
    return axes


# ------------------------------------------------------------------ spec side
def _stable_check(key: str, poles: list[complex], got: Any) -> None:
    for p in poles:
        if not p.real < 0:
            raise SpecError(key, "stable poles (negative real part, rad/s)", got,
                            hint=f"a pole at {p:g} makes the current loop unstable")


def _one_group(t: Table, groups: dict[str, tuple[str, ...]]) -> str:
    given = [g for g, keys in groups.items() if any(t.has(k) for k in keys)]
    if not given:
        first = [keys[0] for keys in groups.values()]
        raise SpecError(t.prefix, f"one of {', '.join(first)} (missing)")
    if len(given) > 1:
        a, b = (groups[g][0] for g in given[:2])
        raise SpecError(t.key(b), f"either {a} or {b}, not both", t.raw(b))
    return given[0]


def _tci_pole_pair(t: Table, key: str, value: Any) -> tuple[complex, complex]:
    expected = ("two real poles [s1, s2] or one complex pair [[re, im]] (rad/s)")
    if not isinstance(value, (list, tuple)):
        raise SpecError(key, expected, value)
    if len(value) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                               and math.isfinite(v) for v in value):
        poles = [complex(value[0]), complex(value[1])]
    elif (1 <= len(value) <= 2 and all(isinstance(v, (list, tuple)) and len(v) == 2 for v in value)
          and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                  for v in value for x in v)):
        p = complex(value[0][0], abs(value[0][1]))
        if len(value) == 2 and (value[1][0] != value[0][0] or abs(value[1][1]) != abs(value[0][1])):
            raise SpecError(key, "a complex-conjugate pair", value)
        poles = [p, p.conjugate()]
    else:
        raise SpecError(key, expected, value)
    _stable_check(key, poles, value)
    return poles[0], poles[1]


def _tci_poles(t: Table) -> tuple[tuple, tuple, dict]:
    value = t.raw("poles")
    if isinstance(value, dict):
        sub = Table(value, t.key("poles"), ("d", "q"))
        for ax in ("d", "q"):
            if not sub.has(ax):
                raise SpecError(sub.key(ax), "the poles of this axis (missing)")
        pd = _tci_pole_pair(sub, sub.key("d"), sub.raw("d"))
        pq = _tci_pole_pair(sub, sub.key("q"), sub.raw("q"))
    else:
        pd = pq = _tci_pole_pair(t, t.key("poles"), value)
    gd, gq = gains_from_poles(pd), gains_from_poles(pq)
    return (gd[0], gq[0]), (gd[1], gq[1]), {}


def _positive_gain(t: Table, name: str, unit: str) -> float:
    if not t.has(name):
        raise SpecError(t.key(name), f"a number > 0 ({unit}) (missing)")
    v = t.number(name, unit=unit)
    if not v > 0:
        raise SpecError(t.key(name), f"a number > 0 ({unit})", v,
                        hint="paper 000 eq (18) prints de/dt = K e + K' int e; the stable "
                             "law (20) needs K, K' > 0 (de/dt = -K e - K' int e)")
    return v


def _gains_together(t: Table, names: tuple[tuple[str, str], ...]) -> tuple[float, ...]:
    """:func:`_positive_gain` of each ``(name, unit)``, every bad one reported."""
    errors = Collector()
    out: list[Any] = []
    for name, unit in names:
        out.append(None)
        with errors.check():
            out[-1] = _positive_gain(t, name, unit)
    errors.raise_if_any()
    return tuple(out)


def _read_model(t: Table, motor) -> dict:
    sub = t.table("model", _MODEL_KEYS)
    return {"R": sub.number("R", motor.R, positive=True, unit="ohm"),
            "Ld": sub.number("Ld", motor.Ld, positive=True, unit="H"),
            "Lq": sub.number("Lq", motor.Lq, positive=True, unit="H"),
            "flux": sub.number("flux", motor.flux, nonnegative=True, unit="Wb")}


def _default_gains(method: str, drive) -> tuple[tuple, tuple | None, dict]:
    """Gains from the sample time and delay when the spec gives none.

    ``tc``: ``K = wc`` (error dynamics ``de/dt = -wc e``, the loop of a
    cancellation PI with crossover ``wc``). ``tci``: ``K11 = wc``,
    ``K12 = wc^2/4`` (damping 1, natural frequency ``wc/2``; the integral
    zero at ``wc/4`` costs ``atan(1/4)`` of phase, counted in ``wc``).
    ``wc`` from :func:`toolbox.design._defaults.default_bandwidth`.
    """
    bw = _defaults.default_bandwidth(drive, zero=method == "tci")
    wc = bw.value
    if method == "tc":
        return (wc, wc), None, {"defaults": {"gains": {**bw.as_dict(), "K": "K1 = K2 = wc"}}}
    K12 = wc * wc / _defaults.ZERO_RATIO
    return (wc, wc), (K12, K12), {
        "natural_frequency": {"d": wc / 2, "q": wc / 2}, "damping": {"d": 1.0, "q": 1.0},
        "defaults": {"gains": {**bw.as_dict(),
                               "K": "K11 = K21 = wc, K12 = K22 = wc^2/4 (damping 1)"}}}


def _check_design_rates(t: Table, group: str, K_prop: tuple, K_int: tuple | None,
                        model: dict, drive) -> None:
    """The error dynamics' rates within the one design range
    (toolbox/spec/_bounds.py ``RATE_TS``): ``K`` (1/s) and ``sqrt(K')``
    (1/s^2), each refusal naming the key the user wrote."""
    if group == "response_time":
        for value in set(t.per_axis("response_time", positive=True)):
            check_time_constant(t.key("response_time"), value, drive, LN20)
        return
    if group == "match_pi":
        Kp, Ki, _ = _explicit(t, "pi", drive)
        _check_gains(t, Kp, Ki, (model["Lq"], model["Lq"]), drive)
        return
    if group == "gains":
        prop_keys = ("K1", "K2") if K_int is None else ("K11", "K21")
        int_keys = ("K12", "K22")
    elif group == "natural_frequency":  # natural_frequency itself: _read_tci
        prop_keys, int_keys = ("damping", "damping"), ("natural_frequency",) * 2
    else:  # poles: the gains they give, named by that key
        prop_keys = int_keys = (group, group)
    for k in (0, 1):
        check_gain(t.key(prop_keys[k]), K_prop[k], 1.0, drive, "1/s")
        if K_int is not None:
            check_gain(t.key(int_keys[k]), K_int[k], 1.0, drive, "1/s^2", order=2)


def _read_tc(t: Table) -> tuple[tuple, None, dict]:
    group = _one_group(t, _TC_GROUPS)
    if group == "gains":
        K = _gains_together(t, (("K1", "1/s"), ("K2", "1/s")))
        return K, None, {}
    if group == "response_time":
        t5 = t.per_axis("response_time", positive=True, unit="s")
        K = (gains_from_response_time(t5[0]), gains_from_response_time(t5[1]))
        return K, None, {"response_time": {"d": t5[0], "q": t5[1]}}
    value = t.raw("poles")
    if isinstance(value, list) and len(value) == 1:  # poles = [-800] for both axes
        value = value[0]
    poles = Table({"poles": value}, t.prefix).per_axis("poles", unit="rad/s")
    _stable_check(t.key("poles"), [complex(p) for p in poles], t.raw("poles"))
    return (-poles[0], -poles[1]), None, {}


def _read_tci(t: Table, model: dict, drive) -> tuple[tuple, tuple, dict]:
    group = _one_group(t, _TCI_GROUPS)
    if group == "gains":
        K11, K12, K21, K22 = _gains_together(t, (("K11", "1/s"), ("K12", "1/s^2"),
                                                 ("K21", "1/s"), ("K22", "1/s^2")))
        return (K11, K21), (K12, K22), {}
    if group == "natural_frequency":
        errors = Collector()  # natural_frequency and damping: both reported
        wn = zeta = None
        with errors.check():
            wn = t.per_axis("natural_frequency", positive=True, unit="rad/s")
            for value in set(wn):  # before wn^2 (1e300 overflowed)
                check_gain(t.key("natural_frequency"), value, 1.0, drive, "rad/s")
        with errors.check():
            if not t.has("damping"):
                raise SpecError(t.key("damping"), "a number > 0 (missing)")
            zeta = t.per_axis("damping", positive=True)
        errors.raise_if_any()
        return ((2 * zeta[0] * wn[0], 2 * zeta[1] * wn[1]), (wn[0] ** 2, wn[1] ** 2),
                {"natural_frequency": {"d": wn[0], "q": wn[1]},
                 "damping": {"d": zeta[0], "q": zeta[1]}})
    if group == "poles":
        return _tci_poles(t)
    if not t.boolean("match_pi", False):
        raise SpecError(t.key("match_pi"), "true (or leave it out)", t.raw("match_pi"))
    Kp, Ki, details = _explicit(t, "pi", drive)
    # eq (22)-(23) for q, eq (24): the d axis copies the q gains.
    K21, K22 = gains_match_pi(Kp[1], Ki[1], model["Lq"])
    details = {**details, "matched_Kp": Kp[1], "matched_Ki": Ki[1]}
    return (K21, K21), (K22, K22), details


def read_cfg(method: str, table: Table, motor, drive) -> TotalCompCfg:
    """Validate ``[controller.tc]`` or ``[controller.tci]``.

    Parameters
    ----------
    method : {"tc", "tci"}
        Without or with integrators.
    table : Table
        The ``[controller.<method>]`` table.
    motor : Motor
        Default controller-side model (``model`` overrides it).
    drive : Drive
        Supplies vdc (default ``voltage_gain`` with ``match_pi``).

    Returns
    -------
    TotalCompCfg

    Raises
    ------
    SpecError
        Unknown key, conflicting gain groups, non-positive gains, unstable
        poles (``controller.tc.poles``: expected stable poles ...).
    """
    t = Table(table.data, table.prefix, _TC_KEYS if method == "tc" else _TCI_KEYS)
    model = _read_model(t, motor)
    groups = _TC_GROUPS if method == "tc" else _TCI_GROUPS
    if not any(t.has(k) for keys in groups.values() for k in keys):
        K_prop, K_int, details = _default_gains(method, drive)
    elif method == "tc":
        K_prop, K_int, details = _read_tc(t)
        _check_design_rates(t, _one_group(t, groups), K_prop, K_int, model, drive)
    else:
        K_prop, K_int, details = _read_tci(t, model, drive)
        _check_design_rates(t, _one_group(t, groups), K_prop, K_int, model, drive)
    return TotalCompCfg(method=method, K_prop=tuple(map(float, K_prop)),
                        K_int=None if K_int is None else tuple(map(float, K_int)),
                        model=model,
                        discretisation=t.string("discretisation", "tustin",
                                                choices=DISCRETISATIONS),
                        details=details)


def _poles_json(K_prop: float, K_int: float | None) -> list:
    return [[float(p.real), float(p.imag)] for p in designed_poles(K_prop, K_int)]


def _gains(cfg: TotalCompCfg) -> dict[str, Any]:
    m = cfg.model
    L = (m["Ld"], m["Lq"])
    gains: dict[str, Any] = {"model": dict(m), "discretisation": cfg.discretisation}
    if cfg.K_int is None:
        gains.update(K1=cfg.K_prop[0], K2=cfg.K_prop[1])
    else:
        gains.update(K11=cfg.K_prop[0], K12=cfg.K_int[0], K21=cfg.K_prop[1], K22=cfg.K_int[1])
    K_int = cfg.K_int or (None, None)
    gains["poles"] = {ax: _poles_json(cfg.K_prop[k], K_int[k]) for k, ax in enumerate("dq")}
    gains["Kp"] = {ax: cfg.K_prop[k] * L[k] for k, ax in enumerate("dq")}
    if cfg.K_int is not None:
        gains["Ki"] = {ax: cfg.K_int[k] * L[k] for k, ax in enumerate("dq")}
    gains["R_feedback"] = m["R"]
    gains.update(cfg.details)
    return gains


def design(spec) -> ControllerArtifact:
    """Design the ``tc`` / ``tci`` controller a spec asks for (000 eq (11) / (20)).

    Returns
    -------
    ControllerArtifact
        Axes with the linear law (``R_c`` feedback included), decoupling with
        cross and EMF on using the controller-side model.
    """
    cfg: TotalCompCfg = spec.controller.cfg
    m = cfg.model
    axes = design_total_compensation(cfg.K_prop, spec.drive.sample_time, R_c=m["R"],
                                     Ld_c=m["Ld"], Lq_c=m["Lq"], K_int=cfg.K_int,
                                     method=cfg.discretisation)
    dec = Decoupling(cross=True, emf=True, R_c=m["R"], Ld_c=m["Ld"], Lq_c=m["Lq"],
                     flux_c=m["flux"], pole_pairs=spec.motor.pole_pairs)
    if cfg.method == "tc":
        eqs = ["000 eq (8): de/dt = -K e", "000 eq (9)-(11): total compensation law",
               "000 eq (12): controller-side parameters R_c, L_dc, L_qc, psi_fc"]
    else:
        eqs = ["000 eq (18) (sign corrected): de/dt = -K11 e - K12 int e",
               "000 eq (19)-(20): total compensation with integrators",
               "000 eq (21): s^2 + K11 s + K12 = 0"]
        if "matched_Kp" in cfg.details:
            eqs.append("000 eq (22)-(24): K21 = E k_i Kp/Lq, K22 = E k_i KI/Lq, "
                       "K11 = K21, K12 = K22")
    return make_artifact(spec, axes, dec, _gains(cfg), eqs)
