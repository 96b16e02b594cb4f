"""Exportability of a controller artifact: :func:`check_exportable` and its
result :class:`ExportCheck`.

The rules (unstable poles, Nyquist ringing, coefficient dynamic range,
rounding sensitivity to float32 and Q31) are listed in
:mod:`toolbox.export.c_header`; this module also holds the minimal laws and
executed realisations of both axes (:func:`minimal_laws`,
:func:`realisations`), the Q31 pole check (:func:`check_fixed`) and the
motor and drive lookup shared by the header writer.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..lti import invariant_zeros as _zeros
from ..errors import ExportRefused, SpecError
from . import _fixed
from ._minimal import MinimalLaw, minimal_law
from ._plausible import speed_range
from ._sos import Realisation, realise_axis
from ..spec import drive_from_dict, motor_from_dict, spec_from_dict


AXES = ("d", "q")
INTEGRATOR_TOL = 1e-9
RING_RADIUS = 0.9
CANCEL_TOL = 1e-2
DYNAMIC_RANGE = 2.0 ** 30
POLE_REL_TOL = 1e-2
POLE_ABS_RAD_S = 1e-2


HORIZON = 0.02   # s, window of the reported quantisation error bound


# ---------------------------------------------------------------------------
# exportability
# ---------------------------------------------------------------------------
def _fmt(z: complex) -> str:
    z = complex(z)
    return f"{z.real:.9g}{z.imag:+.3g}j" if z.imag else f"{z.real:.9g}"


def _law_key(artifact) -> str:
    """The spec key of the controller parameters that made the law."""
    return f"controller.{artifact.method}"


def _is_integrator(p: complex) -> bool:
    return abs(p - 1.0) <= INTEGRATOR_TOL


def _check_poles(poles: np.ndarray, zeros: np.ndarray, key: str, ax: str) -> None:
    poles = np.atleast_1d(np.asarray(poles, complex))
    n_int = int(sum(_is_integrator(p) for p in poles))
    if n_int > 1:
        raise ExportRefused(key, f"at most one integrator (pole at z = 1) in the {ax}-axis law",
                            f"{n_int} poles at z = 1")
    for p in poles:
        if not _is_integrator(p) and abs(p) >= 1.0:
            raise ExportRefused(key, f"a stable discrete {ax}-axis law (poles |z| < 1; one simple "
                            "integrator exactly at z = 1 is allowed)",
                            f"pole z = {_fmt(p)} with |z| = {abs(p):.9g}",
                            hint="the controller diverges on its own; refusing to export it")
    zs = list(np.atleast_1d(np.asarray(zeros, complex)))
    for p in poles:
        if p.real < 0 and abs(p) > RING_RADIUS:
            d = [abs(z - p) for z in zs]
            if d and min(d) <= CANCEL_TOL * (1.0 - abs(p)):
                zs.pop(int(np.argmin(d)))
                continue
            raise ExportRefused(key, f"no lightly damped pole of the {ax}-axis law near z = -1 (Re z < 0 and "
                            f"|z| > {RING_RADIUS}) unless a zero cancels it",
                            f"pole z = {_fmt(p)}",
                            hint="a controller pole far beyond the Nyquist frequency "
                                 "makes the discrete controller ill-conditioned")


def _pole_tol(p: complex, ts: float) -> float:
    return POLE_REL_TOL * max(1.0 - abs(p), 0.0) + ts * POLE_ABS_RAD_S


def _check_shift(exact: np.ndarray, rounded: np.ndarray, ts: float, key: str,
                 what: str) -> float:
    """Worst pole displacement / tolerance; ExportRefused above 1 or if unstable."""
    left = list(np.atleast_1d(rounded))
    worst = 0.0
    for p in sorted(np.atleast_1d(exact), key=lambda z: -abs(z)):
        d = [abs(q - p) for q in left]
        q = left.pop(int(np.argmin(d)))
        tol = _pole_tol(p, ts)
        worst = max(worst, abs(q - p) / tol)
        bad = abs(q) >= 1.0 and not (_is_integrator(p) and _is_integrator(q))
        if abs(q - p) > tol or bad:
            raise ExportRefused(key, f"{what} coefficient rounding to move each pole by at "
                            f"most 1 % of (1 - |p|) + Ts x 0.01 rad/s ({tol:.3g}) and keep "
                            "it stable", f"pole {_fmt(p)} moves to {_fmt(q)}",
                            hint="the controller is too sensitive to coefficient rounding")
    return worst


def _dynamic_range(c: np.ndarray) -> float:
    a = np.abs(np.asarray(c, float).ravel())
    a = a[a > 0]
    return float(a.max() / a.min()) if a.size > 1 else 1.0


def _coefficient_sets(real: Realisation) -> list[np.ndarray]:
    if real.form == "sos":
        return [row for row in real.cmsis_coefficients()]
    return [np.concatenate([real.A[i], real.B[i], [real.aw[i]]]) for i in range(real.order)] \
        + [np.concatenate([real.C[0], real.D[0]])]


def _rounded_poles_f32(real: Realisation) -> np.ndarray:
    if real.form == "sos":
        sos = real.sos.astype(np.float32).astype(float)
        out = []
        for b0, b1, b2, _, a1, a2 in sos:
            out.extend(np.roots([1.0, a1, a2]) if a2 != 0 else ([-a1] if a1 != 0 else [0.0]))
            if a2 == 0:
                out.append(0.0)
        return np.asarray(out, complex)
    return np.linalg.eigvals(real.A.astype(np.float32).astype(float))


def minimal_laws(artifact) -> dict[str, MinimalLaw]:
    """Each axis law without round-off entries and unreachable states.

    See :mod:`toolbox.export._minimal`: the result equals the artifact's law
    (anti-windup channel included) within 1e-7 on the unit circle, else it is
    the artifact's law unchanged.
    """
    out = {}
    for ax in AXES:
        law = artifact.axes[ax].law
        aw = artifact.axes[ax].antiwindup
        out[ax] = minimal_law(law.A, law.B, law.C, law.D,
                              None if aw is None else aw.ravel(), artifact.sample_time)
    return out


def realisations(artifact) -> dict[str, Realisation]:
    """The executed realisation of each axis (SOS or state space) of the minimal law."""
    return {ax: realise_axis(m.A, m.B, m.C, m.D, m.aw)
            for ax, m in minimal_laws(artifact).items()}


#: ``drive.voltage_priority`` values the float path executes.
PRIORITIES = ("radial", "d_axis")
_D_PRIORITY_FLOAT_ONLY = ('voltage_priority = "d_axis" is implemented in the float path only; '
                          '{variant} need voltage_priority = "radial"')


@dataclass
class ExportCheck:
    """What :func:`check_exportable` found.

    Attributes
    ----------
    realisations : dict
        ``{"d": Realisation, "q": Realisation}`` executed by the header.
    float_pole_shift : dict
        Per axis, worst float32 pole displacement / tolerance (<= 1).
    fixed : FixedPlan or None
        The Q31 plan, None when the fixed-point variant is not available.
    fixed_reason : str
        Why not (empty when available).
    fixed_pole_shift : dict
        Per axis, worst Q31 pole displacement / tolerance.
    saturated_radius : dict
        Per axis with anti-windup, spectral radius of ``A - aw C`` (the
        state recursion while the voltage limit acts).
    fixed_error_bound : dict
        Per axis, worst-case |v_Q31 - v_exact| (V) over a 20 ms window from
        equal states with every input anywhere in its range.
    v_max : float
        Voltage limit (V): circle radius, or the hexagon's apothem (the
        distance from the centre to an edge, r_hex sqrt(3)/2: the same number).
    limit : str
        ``"circle"`` or ``"hexagon"`` (``drive.voltage_limit``).
    priority : str
        ``"radial"`` or ``"d_axis"`` (``drive.voltage_priority``).
    minimal : dict
        ``{"d": MinimalLaw, "q": MinimalLaw}`` (:func:`minimal_laws`), which
        the realisations and the vendor plan are made from (computed once:
        about half of a header's time; an empty dict: the vendor
        plan computes them).
    """

    realisations: dict
    float_pole_shift: dict
    fixed: Any = None
    fixed_reason: str = ""
    fixed_pole_shift: dict = field(default_factory=dict)
    v_max: float = math.inf
    limit: str = "circle"
    priority: str = "radial"
    saturated_radius: dict = field(default_factory=dict)
    fixed_error_bound: dict = field(default_factory=dict)
    minimal: dict = field(default_factory=dict)

    @property
    def marginal_antiwindup(self) -> list[str]:
        """Axes whose saturated recursion ``A - aw C`` is not strictly stable."""
        return [ax for ax, r in self.saturated_radius.items() if r >= 1.0 - 1e-9]


def _motor_drive(artifact, motor, drive):
    if motor is not None and drive is not None:
        return motor, drive
    raw = artifact.spec or {}
    try:
        spec = spec_from_dict(raw)
        return motor or spec.motor, drive or spec.drive
    except SpecError:
        pass
    # the controller section may name a method this build cannot read: take
    # the motor and drive tables alone
    if motor is None and isinstance(raw.get("motor"), dict):
        try:
            motor = motor_from_dict(raw["motor"])
        except SpecError:
            motor = None
    if drive is None and isinstance(raw.get("drive"), dict):
        try:
            drive = drive_from_dict(raw["drive"])
        except SpecError:
            drive = None
    return motor, drive


def _ranges(artifact, motor, drive, v_max: float) -> tuple[float, float]:
    """Current (A) and mechanical speed (rad/s) ranges of the fixed-point scaling."""
    i_max = None
    if motor is not None:
        i_max = motor.max_current or (2.0 * motor.rated_current if motor.rated_current else None)
    if i_max is None:
        dec = artifact.decoupling
        i_max = v_max / max(dec.R_c, 1e-3)         # the voltage-limited current
    # the speed range is the float path's (plausibility_limits'): drive.max_speed, else
    # the larger of the rated speed and twice the back-EMF speed of the voltage limit
    return float(i_max), speed_range(artifact, motor, drive, v_max)


def _dec_coeffs(dec) -> dict[str, float]:
    """The decoupling terms as coefficients of the mechanical speed, the form the
    integer variants scale: ``v_d += dd w_m i_q``, ``v_q += dq w_m i_d + de w_m``."""
    p = dec.pole_pairs
    return {"dd": -float(dec.cross) * p * dec.Lq_c,
            "dq": float(dec.cross) * p * dec.Ld_c,
            "de": float(dec.emf) * p * dec.flux_c}


def check_exportable(artifact, motor=None, drive=None, *, fixed_point: bool = False,
                     v_max: float | None = None, limit: str | None = None,
                     priority: str | None = None) -> ExportCheck:
    """Refuse controllers that must not reach firmware; plan the export.

    Parameters
    ----------
    artifact : ControllerArtifact
        The designed controller.
    motor, drive : Motor, Drive, optional
        Motor and drive data (default: read from ``artifact.spec``); the
        voltage limit ``drive.max_voltage(motor.convention)`` (V) and the
        fixed-point input ranges come from them.
    fixed_point : bool
        Also require the Q31 variant to be available (else ExportRefused).
    v_max : float, optional
        Override of the voltage-limit radius (V).
    limit : {"circle", "hexagon"}, optional
        Voltage-limit shape (default ``drive.voltage_limit``, else circle).
    priority : {"radial", "d_axis"}, optional
        Voltage-limit priority (default ``drive.voltage_priority``, else radial).

    Returns
    -------
    ExportCheck
        Realisations, measured rounding sensitivity and the fixed-point plan.

    Raises
    ------
    ExportRefused
        Key ``controller.<method>`` for an unstable or ill-conditioned law
        (rules in the module docstring), ``export.fixed_point`` (or
        ``drive.voltage_limit`` for the hexagon) when the Q31 variant is asked
        for but impossible, ``drive`` when no voltage limit is known.
    """
    motor, drive = _motor_drive(artifact, motor, drive)
    if v_max is None:
        if drive is None:
            raise ExportRefused("drive", "drive data (vdc) for the voltage limit",
                            hint="pass drive= or keep [drive] in the artifact's spec")
        v_max = drive.max_voltage(motor.convention if motor is not None else "amplitude")
    if limit is None:
        limit = getattr(drive, "voltage_limit", None) or "circle"
    if limit not in ("circle", "hexagon"):
        raise ExportRefused("drive.voltage_limit", '"circle" or "hexagon"', limit)
    if priority is None:
        priority = getattr(drive, "voltage_priority", None) or "radial"
    if priority not in PRIORITIES:
        raise ExportRefused("drive.voltage_priority", '"radial" or "d_axis"', priority)
    ts = artifact.sample_time
    for ax in AXES:
        law = artifact.axes[ax].law
        if not all(np.all(np.isfinite(m)) for m in (law.A, law.B, law.C, law.D)):
            raise ExportRefused(_law_key(artifact), f"finite coefficients in the {ax}-axis law")
    mins = minimal_laws(artifact)
    reals = {ax: realise_axis(m.A, m.B, m.C, m.D, m.aw) for ax, m in mins.items()}
    shifts = {}
    for ax in AXES:
        key = _law_key(artifact)
        law = mins[ax]
        poles = np.linalg.eigvals(law.A) if law.A.shape[0] else np.zeros(0)
        zeros = _law_zeros(law)
        _check_poles(poles, zeros, key, ax)
        real = reals[ax]
        for i, cs in enumerate(_coefficient_sets(real)):
            rng = _dynamic_range(cs)
            if rng > DYNAMIC_RANGE:
                raise ExportRefused(key, f"{ax}-axis law: coefficient dynamic range <= 2**30 "
                                    "per coefficient set",
                                f"{rng:.3g} in set {i}",
                                hint="ill-conditioned realisation; reduce or rescale the controller")
        exact = np.linalg.eigvals(real.A) if real.order else np.zeros(0)
        shifts[ax] = _check_shift(exact, _rounded_poles_f32(real), ts, key, f"{ax}-axis float32")
    res = ExportCheck(reals, shifts, v_max=float(v_max), limit=limit, priority=priority,
                      minimal=mins)
    for ax in AXES:
        r = reals[ax]
        if r.order and np.any(r.aw != 0):
            F = r.A - np.outer(r.aw, r.C[0])
            res.saturated_radius[ax] = float(max(abs(np.linalg.eigvals(F))))
    if res.marginal_antiwindup:
        warnings.warn(f"axes {res.marginal_antiwindup}: in voltage saturation the "
                      "back-calculation recursion A - aw C is not strictly stable (spectral "
                      f"radius {max(res.saturated_radius.values()):.9g}); the controller "
                      "states can ring or drift while saturated", RuntimeWarning, stacklevel=2)
    i_max, w_max = _ranges(artifact, motor, drive, v_max)
    dec_coeffs = _dec_coeffs(artifact.decoupling)
    if limit == "hexagon":
        # the hexagon needs sin/cos of the electrical angle: not written in Q31
        plan, reason = None, ('voltage_limit = "hexagon" is implemented in the float path '
                              'only; the Q31 variant needs voltage_limit = "circle"')
    elif priority != "radial":
        plan, reason = None, _D_PRIORITY_FLOAT_ONLY.format(variant="the Q31 variant")
    else:
        plan, reason = _fixed.plan_fixed(reals, I_MAX=i_max, W_MAX=w_max, V_MAX=v_max,
                                         dec_coeffs=dec_coeffs)
    if plan is not None:
        try:
            res.fixed_pole_shift = check_fixed(plan, ts, _law_key(artifact))
            res.fixed_error_bound = _fixed.horizon_bound(plan, round(HORIZON / ts))
        except ExportRefused as err:
            plan, reason = None, str(err)
    res.fixed, res.fixed_reason = plan, reason
    if fixed_point and plan is None:
        raise ExportRefused("drive.voltage_limit" if limit == "hexagon" else
                            "drive.voltage_priority" if priority != "radial" else
                            "export.fixed_point", "a controller the Q31 variant can represent",
                        reason)
    return res


def check_fixed(plan, sample_time: float, key: str = "controller") -> dict:
    """Pole displacement of the Q31-quantised laws (refused beyond tolerance).

    Parameters
    ----------
    plan : FixedPlan
        Output of :func:`toolbox.export._fixed.plan_fixed`.
    sample_time : float
        Controller period (s).
    key : str
        Spec key named in the refusal.

    Returns
    -------
    dict
        Per axis, worst displacement / tolerance (<= 1).

    Raises
    ------
    ExportRefused
        Key ``key`` when quantisation moves a pole beyond
        ``1 % (1 - |p|) + Ts * 0.01 rad/s`` or destabilises it.
    """
    out = {}
    for ax in AXES:
        fa = plan.axes[ax]
        exact = np.linalg.eigvals(fa.An) if fa.An.size else np.zeros(0)
        rounded = np.linalg.eigvals(fa.Aq) if fa.Aq.size else np.zeros(0)
        out[ax] = _check_shift(exact, rounded, sample_time, key, f"{ax}-axis Q31")
    return out


def _law_zeros(law) -> np.ndarray:
    """Invariant zeros of both channels of the law (``i_ref -> v`` and
    ``i_meas -> v``), each from its system pencil (:func:`toolbox.lti._zeros`)."""
    return np.concatenate([_zeros(law.A, law.B[:, j:j + 1], law.C, law.D[:, j:j + 1])
                           for j in range(law.B.shape[1])])
