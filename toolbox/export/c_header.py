"""Firmware export: the controller artifact as a C99 header (``controller.h``).

The header is self-contained (header-only, include guards, no dynamic
memory, only ``sqrtf`` from libm; ``sinf``/``cosf`` too for the hexagon) and
implements the whole current-control law of the artifact in one
``static inline`` step function:

1. per axis, the discrete two-input law ``[i_ref, i_meas] -> v`` of
   :class:`toolbox.artifact.AxisController` (``law``), realised minimally
   with round-off treated as zero (:mod:`toolbox.export._minimal`), as CMSIS-DSP style
   second-order sections when the law is one-degree-of-freedom
   (``v = K (i_ref - i_meas)``), else in state-space form;
2. the decoupling of :class:`toolbox.artifact.Decoupling`:
   ``v_d += -cross w_m Lq_c i_q``, ``v_q += cross w_m Ld_c i_d + emf w_m flux_c``
   with ``w_m = pole_pairs Omega_m``;
3. the voltage limit of ``drive.voltage_limit``, radial scaling as in the
   toolbox simulator (:mod:`toolbox.sim._kernel`): the circle of radius
   ``drive.max_voltage(convention)``, or the SVM hexagon with that apothem
   seen at the electrical angle ``theta_e + w_e Ts (delay + 1/2)`` (the header
   then takes the input ``theta_e``);
   With ``drive.voltage_priority = "d_axis"`` the limit keeps ``v_d``
   (clamped to the limit's d extent) and gives ``v_q`` the rest instead
   (``sign(v_q) sqrt(V_MAX^2 - v_d^2)`` on the circle, the hexagon's chord at
   that ``v_d``), as the simulator's ``_voltage_limit``;
4. back-calculation anti-windup ``x += aw (v_sat - v_unsat)`` with the
   artifact's vector mapped into the executed coordinates.

Faults (float path): a non-finite input, or a non-finite result, repeats the
last good output, leaves the state unchanged and sets ``out.status`` (1 and 2;
0 otherwise). :class:`ReferenceLaw` is the same law in double precision.

Every emitted constant is range-checked first (float32 range and normal
numbers, integer ranges of C); out of range, the export is refused with
:class:`toolbox.errors.ExportRefused` naming the spec key responsible
(``drive.vdc``, ``motor.R``, ...), so the header never holds ``inff``/``nan``.

A fixed-point variant (``#define CCT_FIXED_POINT`` before including) adds
``cct_step_q31`` with Q31 signals and int64 accumulators; see
:mod:`toolbox.export._fixed` for the scaling rules.

Every identifier carries the prefix (``prefix=``, default ``cct_``: guard
``CCT_CONTROLLER_H``, switch ``CCT_FIXED_POINT``). The voltage limit in use is
set at run time from the measured bus (``<p>set_vdc``); the delay
compensation is applied in ``<p>step`` (outputs ``v_d_comp``, ``v_q_comp``);
a usage example closes the header under ``#if 0``.

STM32 MCSDK-style (``<P>MCSDK``) and TI IQmath-style (``<P>IQMATH``) integer
variants of a one-degree-of-freedom PI law: :mod:`toolbox.export._vendor`
(templates/vendor.c.j2).

Method ``fcs_mpc`` exports its predictive switching law instead (paper 002
criterion (23) over the 8 inverter states with the switching penalty, one
forward-Euler prediction, the one-period delay handled as the simulator's
``_fcs_choice``; templates/fcs.c.j2), float only.

Exportability rules (:func:`check_exportable`) -- a controller is refused with
:class:`toolbox.errors.ExportRefused` (key ``controller.<method>``, the
message names the axis) when:

* **unstable**: a pole of the discrete law has ``|z| >= 1``, other than one
  simple integrator exactly at ``z = 1`` (``|z - 1| <= 1e-9``) per axis;
* **Nyquist ringing**: a pole with ``Re z < 0`` and ``|z| > 0.9`` (the Tustin
  image of a continuous pole faster than ~12 x the Nyquist frequency) that
  no zero cancels to within 1 % of its distance to the unit circle (the pair
  then changes |K| by at most 1 % at any frequency, the rule of
  :func:`toolbox.design._hinf_gamma.effective_poles` transposed to z);
* **coefficient dynamic range** of one coefficient set (SOS stage or state
  row) above ``2**30`` (beyond Q31 resolution even with per-set scaling);
* **rounding sensitivity**: rounding the executed coefficients to float32
  (or to Q31 for the fixed-point variant) moves a pole by more than
  ``1 % (1 - |p|) + Ts * 0.01 rad/s`` or destabilises it. The absolute term
  is a 0.01 rad/s shift of the pole's continuous equivalent, immaterial for
  current loops and the only fair yardstick for near-integrators (paper 003's
  controller pole at 0.0117 rad/s lies 1.2e-6 inside the unit circle).

The fixed-point variant is additionally refused (the header then carries an
``#error`` under ``CCT_FIXED_POINT``) when no finite state bound exists, when
one of its constants is out of range, for ``voltage_limit = "hexagon"`` and
for ``voltage_priority = "d_axis"`` (not implemented in Q31, MCSDK, IQmath).
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._lti import invariant_zeros as _zeros
from ..errors import CctError, ExportRefused, SpecError
from . import _fixed, _vendor
from ._minimal import MinimalLaw, minimal_law
from ._sos import Realisation, realise_axis

__all__ = ["write_header", "check_exportable", "ExportCheck", "sanitise_comment",
           "realisations", "reference_law", "ReferenceLaw", "check_fixed", "INTEGRATOR_TOL", "RING_RADIUS",
           "DYNAMIC_RANGE", "prefix_name", "example_source"]

AXES = ("d", "q")
INTEGRATOR_TOL = 1e-9
RING_RADIUS = 0.9
CANCEL_TOL = 1e-2
DYNAMIC_RANGE = 2.0 ** 30
POLE_REL_TOL = 1e-2
POLE_ABS_RAD_S = 1e-2
PI_METHODS = ("pi", "ip", "pi_lag", "robust_pi", "tune")
HORIZON = 0.02   # s, window of the reported quantisation error bound


# ---------------------------------------------------------------------------
# comment sanitising
# ---------------------------------------------------------------------------
def sanitise_comment(text: Any, max_len: int = 200) -> str:
    """Make a user string safe inside a C block comment, on one line.

    Non-ASCII and control characters become ``\\uXXXX``/``\\xXX`` escapes,
    ``*/`` and ``/*`` are broken with a space, ``??`` (trigraph opener) is
    written ``?-?``, a backslash becomes ``\\x5c`` (never a line splice), and
    the text is cut to ``max_len`` characters.

    Parameters
    ----------
    text : object
        The user string (converted with ``str``).
    max_len : int
        Longest result (characters).

    Returns
    -------
    str
        Printable ASCII, safe inside ``/* ... */`` on one line.
    """
    out = []
    for ch in str(text):
        o = ord(ch)
        if ch == "\\":
            out.append("\\x5c")
        elif 32 <= o < 127:
            out.append(ch)
        elif o < 256:
            out.append(f"\\x{o:02x}")
        elif o < 0x10000:
            out.append(f"\\u{o:04x}")
        else:
            out.append(f"\\U{o:08x}")
    s = "".join(out)
    while "*/" in s or "/*" in s:
        s = s.replace("*/", "* /").replace("/*", "/ *")
    while "??" in s:
        s = s.replace("??", "?-?")
    if len(s) > max_len:
        s = s[:max_len - 3] + "..."
    return s


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
        from ..spec import spec_from_dict
        spec = spec_from_dict(raw)
        return motor or spec.motor, drive or spec.drive
    except SpecError:
        pass
    # the controller section may name a method this build cannot read: take
    # the motor and drive tables alone
    from ..spec import drive_from_dict, motor_from_dict
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
    w_max = None
    if drive is not None and getattr(drive, "max_speed", None):
        w_max = drive.max_speed
    elif motor is not None and motor.rated_speed:
        w_max = motor.rated_speed
    else:
        dec = artifact.decoupling
        w_max = 2.0 * v_max / max(dec.pole_pairs * dec.flux_c, 1e-9)
    return float(i_max), float(w_max)


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
    ``i_meas -> v``), each from its system pencil (:func:`toolbox._lti._zeros`)."""
    return np.concatenate([_zeros(law.A, law.B[:, j:j + 1], law.C, law.D[:, j:j + 1])
                           for j in range(law.B.shape[1])])


# ---------------------------------------------------------------------------
# Python reference of the executed law (double precision)
# ---------------------------------------------------------------------------
class ReferenceLaw:
    """The executed law in double precision, one period at a time.

    Uses the artifact's own state-space law (not the exported realisation),
    so it is an independent route to the header's input-output map: per axis
    ``v = C x + D u``, decoupling, the voltage limit, then
    ``x <- A x + B u + aw (v_sat - v_unsat)``. The simulator kernel
    (:mod:`toolbox.sim._kernel`) runs the same law; tests/export compare the
    three (kernel, this class, the C header).

    Voltage limit, as the simulator:

    * ``"circle"``: radial scaling onto ``|v| <= v_max``;
    * ``"hexagon"``: the SVM hexagon of apothem ``v_max`` (vertex radius
      ``2 v_max / sqrt(3)``, vertices at 0, 60, ... deg in the stationary frame),
      seen at the placement angle ``theta_e + t_c w_e`` (``t_c`` the
      decoupling's ``delay_compensation_time``, toolbox/ARCHITECTURE.md "The
      digital loop"); radial scaling onto its edge.

    Priority (``drive.voltage_priority``): ``"radial"`` as above; ``"d_axis"``
    keeps ``v_d`` (clamped to the limit's d extent) and clips ``v_q`` into
    what is left: ``|v_q| <= sqrt(v_max^2 - v_d^2)`` on the circle, the
    hexagon's chord at that ``v_d`` in the placement frame
    (:func:`d_priority_limit`).

    Faults, as the header: a non-finite input returns the last good output
    with ``status = 1`` and leaves the state unchanged; a non-finite result
    (overflow) does the same with ``status = 2``; ``status = 0`` otherwise.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller.
    v_max : float
        Voltage-limit radius (V): the circle's radius or the hexagon's apothem.
    limit : {"circle", "hexagon"}
        Voltage-limit shape.
    priority : {"radial", "d_axis"}
        Voltage-limit priority.
    """

    def __init__(self, artifact, v_max: float, limit: str = "circle",
                 priority: str = "radial") -> None:
        if limit not in ("circle", "hexagon"):
            raise ExportRefused("drive.voltage_limit", '"circle" or "hexagon"', limit)
        if priority not in PRIORITIES:
            raise ExportRefused("drive.voltage_priority", '"radial" or "d_axis"', priority)
        self.priority = priority
        self.dec = artifact.decoupling
        self.v_max = float(v_max)
        self.limit = limit
        self.t_comp = float(artifact.decoupling.delay_compensation_time)
        self.laws = [artifact.axes[ax].law for ax in AXES]
        self.aws = [np.zeros(l.order) if artifact.axes[ax].antiwindup is None
                    else artifact.axes[ax].antiwindup.ravel()
                    for l, ax in zip(self.laws, AXES)]
        self.xs = [np.zeros(l.order) for l in self.laws]
        self.hold = (0.0, 0.0)
        self.status = 0

    def _limit(self, vd: float, vq: float, w: float, theta_e: float) -> float:
        """Scale factor k <= 1 applied to (vd, vq) (radial priority)."""
        if self.limit == "circle":
            mag = math.hypot(vd, vq)
            return self.v_max / mag if mag > self.v_max else 1.0
        th = theta_e + w * self.t_comp
        c, sn = math.cos(th), math.sin(th)
        va, vb = vd * c - vq * sn, vd * sn + vq * c
        # largest projection on the edge normals at 30, 90 and 150 deg
        h = math.sqrt(3.0) / 2.0
        pm = max(abs(h * va + 0.5 * vb), abs(vb), abs(-h * va + 0.5 * vb))
        return self.v_max / pm if pm > self.v_max else 1.0

    def step(self, i_d_ref: float, i_q_ref: float, i_d: float, i_q: float,
             omega_m: float, theta_e: float = 0.0) -> tuple[float, float, int]:
        """One period: currents (A), mechanical speed (rad/s), electrical angle
        (rad, hexagon only) -> (v_d, v_q (V), saturated); sets ``self.status``."""
        args = (i_d_ref, i_q_ref, i_d, i_q, omega_m) + ((theta_e,) if self.limit == "hexagon" else ())
        if not all(math.isfinite(a) for a in args):
            self.status = 1
            return self.hold[0], self.hold[1], 0
        dec = self.dec
        u = [np.array([i_d_ref, i_d]), np.array([i_q_ref, i_q])]
        with np.errstate(all="ignore"):
            v_lin = [float((l.C @ x + l.D @ uu)[0]) for l, x, uu in zip(self.laws, self.xs, u)]
            w = dec.pole_pairs * omega_m
            vd = v_lin[0] - dec.cross * w * dec.Lq_c * i_q
            vq = v_lin[1] + dec.cross * w * dec.Ld_c * i_d + dec.emf * w * dec.flux_c
            if not (math.isfinite(vd) and math.isfinite(vq)):
                vds = vqs = math.nan
                sat = 0
            elif self.priority == "d_axis":
                vds, vqs = d_priority_limit(vd, vq, self.v_max, self.limit,
                                            theta_e + w * self.t_comp)
                sat = int(vds != vd or vqs != vq)
            else:
                k = self._limit(vd, vq, w, theta_e)
                vds, vqs, sat = (vd * k, vq * k, 1) if k < 1.0 else (vd, vq, 0)
            dv = (vds - vd, vqs - vq)
            xs = [l.A @ x + l.B @ uu + a * d
                  for l, x, uu, a, d in zip(self.laws, self.xs, u, self.aws, dv)]
        if not (math.isfinite(vds) and math.isfinite(vqs)
                and all(np.all(np.isfinite(x)) for x in xs)):
            self.status = 2
            return self.hold[0], self.hold[1], 0
        self.xs, self.hold, self.status = xs, (vds, vqs), 0
        return vds, vqs, sat


def d_priority_limit(vd: float, vq: float, v_max: float, limit: str = "circle",
                     theta: float = 0.0) -> tuple[float, float]:
    """d-axis priority voltage limit (the limiter of field-weakening drives,
    Briz et al., IEEE Trans. Ind. Appl. 37(1) 2001): ``v_d`` clamped to the
    limit's d extent, then ``v_q`` clipped into the chord at that ``v_d``.

    Circle of radius ``v_max``: ``|v_d| <= v_max``, ``|v_q| <= sqrt(v_max^2 -
    v_d^2)``. Hexagon of apothem ``v_max`` (vertex radius ``r = 2 v_max /
    sqrt(3)``) seen from the dq frame at ``theta``: the edge normal at ``alpha``
    (30, 90, 150 deg) is ``(cos(alpha - theta), sin(alpha - theta))`` in dq, each
    edge pair bounds ``|c v_d + s v_q| <= v_max``; the d extent is the support
    function ``r max_j |cos(theta - 60 j deg)|``.
    """
    if limit == "circle":
        vds = min(max(vd, -v_max), v_max)
        q = math.sqrt(max(v_max * v_max - vds * vds, 0.0))
        return vds, min(max(vq, -q), q)
    h = math.sqrt(3.0) / 2.0
    r_hex = v_max / h
    c0, s0 = math.cos(theta), math.sin(theta)
    d_max = r_hex * max(abs(c0), abs(0.5 * c0 + h * s0), abs(-0.5 * c0 + h * s0))
    vds = min(max(vd, -d_max), d_max)
    lo, hi = -math.inf, math.inf
    for ca, sa in ((h, 0.5), (0.0, 1.0), (-h, 0.5)):
        ck, sk = ca * c0 + sa * s0, sa * c0 - ca * s0
        if abs(sk) > 1e-12:
            b1, b2 = sorted(((v_max - ck * vds) / sk, (-v_max - ck * vds) / sk))
            lo, hi = max(lo, b1), min(hi, b2)
    if lo > hi:  # v_d on a vertex, rounding: the chord is one point
        lo = hi = 0.5 * (lo + hi)
    return vds, min(max(vq, lo), hi)


def reference_law(artifact, inputs: np.ndarray, v_max: float, limit: str = "circle",
                  priority: str = "radial") -> tuple[np.ndarray, np.ndarray]:
    """Run :class:`ReferenceLaw` over an input sequence.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller.
    inputs : ndarray
        (N, 5): ``i_d_ref, i_q_ref, i_d, i_q`` (A), ``Omega_m`` (rad/s); (N, 6)
        with the electrical angle ``theta_e`` (rad) for the hexagon.
    v_max : float
        Voltage-limit radius (V).
    limit : {"circle", "hexagon"}
        Voltage-limit shape.
    priority : {"radial", "d_axis"}
        Voltage-limit priority.

    Returns
    -------
    (ndarray, ndarray)
        (N, 2) voltages ``v_d, v_q`` (V) and (N,) saturation flags.
    """
    law = ReferenceLaw(artifact, v_max, limit, priority)
    out = np.zeros((len(inputs), 2))
    sat = np.zeros(len(inputs), dtype=int)
    for k, row in enumerate(np.asarray(inputs, float)):
        out[k, 0], out[k, 1], sat[k] = law.step(*row)
    return out, sat


# ---------------------------------------------------------------------------
# C text
# ---------------------------------------------------------------------------
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,30}")  # fullmatch (no trailing newline)
TEMPLATES = Path(__file__).parent / "templates"
_ENV = None


F32_MAX = float(np.finfo(np.float32).max)
F32_TINY = float(np.finfo(np.float32).tiny)       # smallest normal float32
C_INT_MAX = 32767          # the C99 guaranteed range of int (INT_MAX >= 32767)
C_INT32_MAX = 2 ** 31 - 1  # Q31 words and long constants


def _f(v: float, key: str, what: str) -> str:
    """A float literal (float32-rounded, 9 significant digits, always valid C).

    Parameters
    ----------
    v : float
        The value.
    key : str
        Spec key responsible for the value (named in the refusal).
    what : str
        The constant, in words (named in the refusal).

    Raises
    ------
    ExportRefused
        ``v`` is not finite, overflows float32 (|v| > 3.40e38, C would read
        ``inff``) or is a non-zero value below the smallest normal float32
        (1.18e-38; it would lose its precision or vanish).
    """
    try:
        x = float(v)
    except (TypeError, ValueError, OverflowError):
        raise ExportRefused(key, f"{what}: a number", v) from None
    with np.errstate(over="ignore"):
        f32 = float(np.float32(x))
    if not (math.isfinite(x) and math.isfinite(f32)):
        raise ExportRefused(key, f"{what} within the float32 range (|x| <= {F32_MAX:.3g})", x,
                            hint="controller.h would not compile or would compute inf/nan")
    if f32 == 0.0 and x != 0.0 or 0.0 < abs(f32) < F32_TINY:
        raise ExportRefused(key, f"{what} representable as a normal float32 (0 or |x| >= "
                            f"{F32_TINY:.3g})", x, hint="it would vanish or lose precision")
    if f32 == 0.0:
        return "0.0f"
    return f"{f32:.9e}f"


def _farr(values, key: str, what: str) -> str:
    return ", ".join(_f(v, key, what) for v in values)


def _int(v: Any, key: str, what: str, lo: int = -C_INT_MAX, hi: int = C_INT_MAX) -> int:
    """An integer constant within ``[lo, hi]`` (default: the C99 ``int`` range).

    Raises
    ------
    ExportRefused
        ``v`` is not an integral number in range.
    """
    try:
        ok = float(v) == int(v) and lo <= int(v) <= hi
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ExportRefused(key, f"{what}: an integer in [{lo}, {hi}]", v,
                            hint="controller.h would not compile or would overflow")
    return int(v)


def _q31(v: Any, key: str, what: str) -> str:
    """An int32 literal with the ``L`` suffix (long is at least 32 bits)."""
    return f"{_int(v, key, what, -C_INT32_MAX, C_INT32_MAX)}L"


def _shift(v: Any, key: str, what: str) -> str:
    """An unsigned shift count of an int64 value (0..62)."""
    return f"{_int(v, key, what, 0, 62)}u"


class _Text:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def __call__(self, line: str = "") -> None:
        self.lines.append(line)

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


def _pi_gains(artifact, ax: str) -> tuple[float, float] | None:
    """Parallel-form (Kp V/A, Ki V/(A s)) of a PI-type axis, or None.

    Read from the executed law, never from informational design parameters:
    the continuous error controller ``Kp + Ki/s`` (one state, an integrator)
    when there is one, else the discrete one with the discretisation's
    feedthrough correction. Laws of another structure (a lag, 2 states)
    export no KP/KI defines; the law below them is what runs anyway.
    """
    axc = artifact.axes[ax]
    if axc.continuous is not None and axc.continuous.order == 1 \
            and abs(axc.continuous.A[0, 0]) < 1e-12:
        c = axc.continuous
        return float(c.D[0, 0]), float(c.C[0, 0] * c.B[0, 0])
    dsc = axc.discrete
    if dsc.order == 1 and _is_integrator(dsc.A[0, 0]):
        kits = float(dsc.C[0, 0] * dsc.B[0, 0])
        corr = {"tustin": 0.5, "backward_diff": 1.0}.get(dsc.method or "", 0.0)
        return float(dsc.D[0, 0]) - corr * kits, kits / artifact.sample_time
    return None


def _informational_pi_gains(artifact) -> list[tuple[str, float, float]]:
    """``(axis, Kp, Ki)`` of each PI-type axis (:func:`_pi_gains`) of a PI
    method, for the comments marked "for information only"; empty otherwise."""
    if artifact.method not in PI_METHODS:
        return []
    return [(ax, *g) for ax in AXES if (g := _pi_gains(artifact, ax)) is not None]


def _delay_comp_time(artifact) -> float | None:
    """The voltage placement's rotation time (s), or None when it is 0.

    The typed ``decoupling.delay_compensation_time`` (``drive.angle_compensation``,
    toolbox/ARCHITECTURE.md "The digital loop").
    """
    t_comp = artifact.decoupling.delay_compensation_time
    return float(t_comp) if t_comp > 0 else None


def _placement_convention(artifact) -> str:
    """``drive.angle_compensation`` as written in the header's comment."""
    t_comp = artifact.decoupling.delay_compensation_time
    if t_comp == 0:
        return '"none"'
    if math.isclose(t_comp, (artifact.delay_samples + 0.5) * artifact.sample_time,
                    rel_tol=1e-12):
        return '"mid_period"'
    return f"{t_comp:.9g} s"


def _provenance(artifact, title: str) -> dict:
    """The provenance strings of the header comment (every user string
    sanitised), for the ``provenance`` macro of ``templates/common.c.j2``."""
    prov = artifact.provenance or {}
    return {"title": sanitise_comment(title), "method": sanitise_comment(artifact.method),
            **{k: sanitise_comment(prov.get(k, "unknown"))
               for k in ("version", "spec_sha256", "created")},
            "law_sha256": artifact.law_sha256()}


def _header_top(t: _Text, artifact, motor, drive, N: str, check: ExportCheck,
                title: str) -> None:
    """The opening comment of a linear law's header (``templates/top.c.j2``)."""
    eqs = (artifact.provenance or {}).get("equations")
    t.lines.extend(_render(
        "top.c.j2", prov=_provenance(artifact, title), N=N, U=N.upper(),
        equations=sanitise_comment('; '.join(map(str, eqs)), 400) if eqs else None,
        hexagon=check.limit == "hexagon", comp=_delay_comp_time(artifact) is not None,
        d_priority=check.priority == "d_axis",
        warnings=[(ax, f"{check.saturated_radius[ax]:.9g}") for ax in check.marginal_antiwindup]))


def _defines(t: _Text, artifact, motor, drive, P: str, check: ExportCheck) -> None:
    """The ``#define`` block (``templates/defines.c.j2``); every number is
    formatted and range-checked here, in the order of the lines."""
    dec = artifact.decoupling
    ts_ = _f(artifact.sample_time, "drive.sample_time", "controller period SAMPLE_TIME")
    nd_ = _int(artifact.delay_samples, "drive.delay_samples", "DELAY_SAMPLES", 0)
    vmax_ = _f(check.v_max, "drive.vdc", "voltage limit V_MAX")
    if check.v_max ** 2 > F32_MAX:
        # the step function compares |v|^2 with V_MAX^2 in float
        raise ExportRefused("drive.vdc", f"a voltage limit whose square fits float32 "
                            f"(V_MAX <= {math.sqrt(F32_MAX):.3g} V)", check.v_max)
    per_vdc = (_f(check.v_max / drive.vdc, 'drive.vdc', 'V_MAX_PER_VDC')
               if drive is not None and drive.vdc > 0 else None)
    mot = None
    if motor is not None:
        mot = {"convention": sanitise_comment(motor.convention),
               "R": _f(motor.R, 'motor.R', 'MOTOR_R'),
               "Ld": _f(motor.Ld, 'motor.Ld', 'MOTOR_LD'),
               "Lq": _f(motor.Lq, 'motor.Lq', 'MOTOR_LQ'),
               "flux": _f(motor.flux, 'motor.flux', 'MOTOR_FLUX'),
               "pole_pairs": _int(motor.pole_pairs, 'motor.pole_pairs', 'MOTOR_POLE_PAIRS', 1),
               "J": _f(motor.J, 'motor.J', 'MOTOR_J'),
               "friction": _f(motor.friction, 'motor.friction', 'MOTOR_FRICTION')}
        for name in ("max_current", "rated_current", "rated_speed"):
            v = getattr(motor, name)
            mot[name] = _f(v, f"motor.{name}", f"MOTOR_{name.upper()}") if v else None
    drv = None
    if drive is not None:
        fsw = drive.switching_frequency
        drv = {"vdc": _f(drive.vdc, 'drive.vdc', 'DRIVE_VDC'),
               "switching_frequency": (_f(fsw, 'drive.switching_frequency',
                                          'DRIVE_SWITCHING_FREQUENCY') if fsw else None)}
    dec_ = {"cross": int(bool(dec.cross)), "emf": int(bool(dec.emf)),
            "Ld": _f(dec.Ld_c, 'motor.Ld', 'decoupling DEC_LD'),
            "Lq": _f(dec.Lq_c, 'motor.Lq', 'decoupling DEC_LQ'),
            "flux": _f(dec.flux_c, 'motor.flux', 'decoupling DEC_FLUX'),
            "pole_pairs": _int(dec.pole_pairs, 'motor.pole_pairs', 'POLE_PAIRS', 1)}
    t_comp = artifact.decoupling.delay_compensation_time
    comp = {"time": _f(t_comp, 'drive.angle_compensation', 'DELAY_COMP_TIME'),
            "periods": f"{t_comp / artifact.sample_time:g}",
            "convention": _placement_convention(artifact)}
    pi = [{"axis": ax, "kp": f"{kp:.9g}", "ki": f"{ki:.9g}",
           "ki_ts": f"{ki * artifact.sample_time:.9g}",
           "ti": f"{kp / ki:.9g}" if kp and ki else None}
          for ax, kp, ki in _informational_pi_gains(artifact)]
    lines = _render("defines.c.j2", P=P, p=P.lower(), ts=ts_, nd=nd_, vmax=vmax_,
                    what="hexagon apothem" if check.limit == "hexagon" else "circle radius",
                    vmax_per_vdc=per_vdc, motor=mot, drive=drv, dec=dec_, comp=comp,
                    method=artifact.method, pi=pi)
    t.lines.extend(lines[:-1] if lines and lines[-1] == "" else lines)


def _axis_context(real: Realisation, ax: str, key: str) -> dict:
    """Template data of one axis linear law (numbers formatted and range-checked)."""
    what = f"{ax}-axis law coefficient"
    n = real.order
    ctx: dict[str, Any] = {"ax": ax, "A": ax.upper(), "form": real.form, "n": n}
    if real.form == "sos":
        co = real.cmsis_coefficients()
        ctx["m"] = co.shape[0]
        ctx["rows"] = [_farr(row, key, what) for row in co]
        if co.shape[0] == 0:
            ctx["gain"] = _f(real.gain, key, what)
        return ctx
    ctx["d0"] = _f(real.D[0, 0], key, what)
    ctx["d1"] = _f(real.D[0, 1], key, what)
    if n:
        ctx.update(a=_farr(real.A.ravel(), key, what), b=_farr(real.B.ravel(), key, what),
                   c=_farr(real.C.ravel(), key, what))
    return ctx


def _aw_lines(real: Realisation, field_: str, dv: str, key: str) -> list[str]:
    out = []
    for i, a in enumerate(real.aw):
        if a != 0.0:
            out.append(f"    s->{field_}[{i}] += {_f(a, key, f'{field_}-axis anti-windup gain')} * {dv};")
    return out


def _render(template: str, **context: Any) -> list[str]:
    """Lines of ``templates/<template>`` rendered with ``context``."""
    return _environment().get_template(template).render(**context).split("\n")


def _environment():
    """The jinja2 environment of the C templates (no autoescape: C, not HTML;
    every user string is sanitised by :func:`sanitise_comment` before)."""
    global _ENV
    if _ENV is None:
        import jinja2

        from .._cache import template_bytecode_cache
        _ENV = jinja2.Environment(
            loader=jinja2.FileSystemLoader(str(TEMPLATES)), autoescape=False,
            bytecode_cache=template_bytecode_cache(__file__),
            trim_blocks=True, lstrip_blocks=True, undefined=jinja2.StrictUndefined)
    return _ENV


#: the plausible ranges of the measured signals are this many times the
#: ranges the drive is rated for (a transient overshoot never trips them; an
#: ADC or encoder glitch does)
PLAUSIBLE_MARGIN = 2.0
#: set_vdc accepts VDC_MIN_PER_NOMINAL x .. VDC_MAX_PER_NOMINAL x the nominal bus
VDC_MIN_PER_NOMINAL = 1e-3
VDC_MAX_PER_NOMINAL = 2.0


def plausibility_limits(artifact, motor, drive, v_max: float) -> dict[str, float]:
    """The plausible ranges the float header checks its measurements against.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller (its decoupling model supplies the fallbacks).
    motor, drive : Motor, Drive or None
        Ratings: ``motor.max_current`` (else 2 x ``motor.rated_current``),
        ``drive.max_speed``, ``drive.vdc``.
    v_max : float
        Voltage limit at the nominal bus (V).

    Returns
    -------
    dict
        ``i`` (A): ``|i_d|``, ``|i_q|`` measured beyond it are refused;
        ``PLAUSIBLE_MARGIN`` x the current range: ``motor.max_current``, else
        the largest of 2 x rated, the voltage-limited current ``V_MAX / R``
        and the short-circuit current ``flux / min(Ld, Lq)`` (currents the
        drive can produce are never refused without a stated maximum).
        ``w`` (rad/s, mechanical): ``PLAUSIBLE_MARGIN`` x ``drive.max_speed``,
        else x the larger of ``motor.rated_speed`` and the speed at which the
        back-EMF is twice ``V_MAX``. ``vdc_min``, ``vdc_max`` (V): the bus
        readings ``set_vdc`` accepts, ``1e-3`` and ``2`` x ``drive.vdc``.
    """
    dec = artifact.decoupling
    i_rng = motor.max_current if motor is not None else None
    if not i_rng:
        # currents the drive can produce: never refused without a stated maximum
        rated = 2.0 * motor.rated_current if motor is not None and motor.rated_current else 0.0
        i_rng = max(rated, v_max / max(dec.R_c, 1e-9),
                    dec.flux_c / max(min(dec.Ld_c, dec.Lq_c), 1e-12))
    w_rng = getattr(drive, "max_speed", None) if drive is not None else None
    if not w_rng:
        w_emf = 2.0 * v_max / max(dec.pole_pairs * dec.flux_c, 1e-9)
        w_rng = max(w_emf, (motor.rated_speed or 0.0) if motor is not None else 0.0)
    vdc = drive.vdc if drive is not None else v_max * math.sqrt(3.0)
    return {"i": PLAUSIBLE_MARGIN * float(i_rng), "w": PLAUSIBLE_MARGIN * float(w_rng),
            "vdc_min": VDC_MIN_PER_NOMINAL * float(vdc), "vdc_max": VDC_MAX_PER_NOMINAL * float(vdc)}


def _plausible_context(artifact, motor, drive, v_max: float) -> dict[str, str]:
    """The plausibility macros' values, formatted and range-checked."""
    lim = plausibility_limits(artifact, motor, drive, v_max)
    return {"i": _f(lim["i"], "motor.max_current", "I_PLAUSIBLE"),
            "w": _f(lim["w"], "drive.max_speed", "W_PLAUSIBLE"),
            "vdc_min": _f(lim["vdc_min"], "drive.vdc", "VDC_MIN"),
            "vdc_max": _f(lim["vdc_max"], "drive.vdc", "VDC_PLAUSIBLE")}


def preset_coefficients(real: Realisation) -> tuple[np.ndarray, np.ndarray]:
    """The bumpless-transfer state of one axis law: ``x = g c + H u``.

    For inputs ``u = [i_ref, i_meas]`` held and a wanted linear-law output
    ``v``, ``c = v - D u``; ``x`` solves ``C x = c`` exactly (the next output is
    ``v``) and, among those states, is the closest to the steady-state manifold
    ``(I - A) x = B u`` in least squares: with an integrator (a pole at z = 1)
    on the manifold exactly, so the output stays ``v`` while the error stays
    0. ``[I - A; C]`` has full column rank for an observable (minimal) law,
    which makes the solution unique. In the executed coordinates of ``real``
    (SOS: the df2T states ``x[2k], x[2k+1]`` of stage ``k``).

    Returns
    -------
    (ndarray, ndarray)
        ``g`` (n,) and ``H`` (n, 2); empty for a static law (n = 0).
    """
    n = real.order
    if n == 0:
        return np.zeros(0), np.zeros((0, 2))
    M = np.eye(n) - real.A
    C = real.C.reshape(1, n)
    K = np.block([[M.T @ M, C.T], [C, np.zeros((1, 1))]])
    # right-hand sides for c (unit) and for each input channel of u
    rhs = np.zeros((n + 1, 3))
    rhs[n, 0] = 1.0
    rhs[:n, 1:] = M.T @ real.B
    sol = np.linalg.solve(K, rhs)
    return sol[:n, 0], sol[:n, 1:]


def _preset_context(real: Realisation, key: str, ax: str) -> dict:
    what = f"{ax}-axis preset coefficient"
    g, H = preset_coefficients(real)
    ctx = {"n": real.order, "d0": _f(real.D[0, 0], key, what), "d1": _f(real.D[0, 1], key, what),
           "one_dof": real.form == "sos"}
    if real.order:
        # coefficients below 1e-30 are round-off of exact zeros
        clean = lambda a: np.where(np.abs(a) < 1e-30, 0.0, a)  # noqa: E731
        ctx.update(g=_farr(clean(g), key, what), h=_farr(clean(H).ravel(), key, what))
    return ctx


def _float_section(t: _Text, reals: dict, N: str, P: str, key: str, hexagon: bool,
                   comp: bool, plausible: dict | None = None, convention: str = "amplitude",
                   d_priority: bool = False) -> None:
    """The float path (templates/float.c.j2)."""
    inputs = ["i_d_ref", "i_q_ref", "i_d", "i_q", "omega_m"] + (["theta_e"] if hexagon else [])
    checks = [f"{N}_finite(in->{v})" for v in inputs]
    aw = _aw_lines(reals["d"], "d", "(vds - vd)", key) + \
        _aw_lines(reals["q"], "q", "(vqs - vq)", key)
    t.lines.extend(_render(
        "float.c.j2", N=N, P=P, U=N.upper(), hexagon=hexagon, comp=comp,
        d_priority=d_priority, nd=max(reals["d"].order, 1), nq=max(reals["q"].order, 1),
        form_d=reals["d"].form, order_d=reals["d"].order,
        form_q=reals["q"].form, order_q=reals["q"].order,
        axes=[_axis_context(reals[ax], ax, key) for ax in AXES],
        checks=checks,
        check_pairs=[" && ".join(checks[i:i + 2]) for i in range(2, len(checks), 2)],
        plausible=plausible, convention=convention,
        presets=[_preset_context(reals[ax], key, ax) for ax in AXES],
        aw=[ln.strip().replace("s->", "nx.") for ln in aw]))


def _fixed_section(t: _Text, check: ExportCheck, N: str, P: str, artifact, drive) -> None:
    """The Q31 variant under ``#ifdef <PREFIX>FIXED_POINT``, or an ``#error`` saying why not.

    A constant of the Q31 variant out of its range (e.g. a current base beyond
    float32) makes the variant unavailable, not the float header.
    """
    t("")
    t(f"#ifdef {P}FIXED_POINT")
    reason = check.fixed_reason
    if check.fixed is not None:
        body = _Text()
        try:
            _fixed_body(body, check, N, P, artifact, drive)
        except ExportRefused as err:
            reason = str(err)
        else:
            t.lines.extend(body.lines)
            t(f"#endif /* {P}FIXED_POINT */")
            return
    t(_c_error("fixed-point variant not available", reason))
    t(f"#endif /* {P}FIXED_POINT */")


def _c_error(what: str, reason: Any) -> str:
    """An ``#error`` line ``what: reason`` (the reason sanitised, its double
    quotes made single so the C string stays one token)."""
    return f"#error \"{what}: {sanitise_comment(reason).replace(chr(34), chr(39))}\""


def vendor_plan(artifact, motor, drive, check: ExportCheck):
    """The MCSDK/IQmath plan of a PI law (:mod:`toolbox.export._vendor`), or (None, why)."""
    i_max, w_max = _ranges(artifact, motor, drive, check.v_max)
    dec_coeffs = _dec_coeffs(artifact.decoupling)
    if check.limit == "hexagon":
        return None, ('voltage_limit = "hexagon" is implemented in the float path only; '
                      'the MCSDK/IQmath variants need voltage_limit = "circle"')
    if check.priority != "radial":
        return None, _D_PRIORITY_FLOAT_ONLY.format(variant="the MCSDK/IQmath variants")
    # an ExportCheck built by hand may lack the minimal laws check_exportable keeps
    minimal = check.minimal or minimal_laws(artifact)
    return _vendor.plan_vendor(minimal, i_max, w_max, check.v_max, dec_coeffs)


def _vendor_section(t: _Text, artifact, motor, drive, check: ExportCheck, N: str,
                    P: str) -> None:
    """MCSDK (``<P>MCSDK``) and IQmath (``<P>IQMATH``) variants, or an #error saying why not."""
    plan, why = vendor_plan(artifact, motor, drive, check)
    key = _law_key(artifact)
    if plan is not None:
        try:
            mc = _vendor.mcsdk_constants(plan)
            iq = _vendor.iq_constants(plan)
        except OverflowError as err:
            plan, why = None, str(err)
    if plan is not None:
        body = _Text()
        try:
            _vendor_body(body, plan, mc, iq, N, P, key,
                         _integer_placement(artifact, plan.W_FS))
        except ExportRefused as err:          # a constant out of range: no variant
            why = str(err)
        else:
            t.lines.extend(body.lines)
            return
    t(f"#if defined({P}MCSDK) || defined({P}IQMATH)")
    t(_c_error("MCSDK/IQmath variants not available", why))
    t("#endif")


def _vendor_body(t: _Text, plan, mc: dict, iq: dict, N: str, P: str, key: str,
                 comp: dict | None) -> None:
    """The MCSDK/IQmath section (``templates/vendor.c.j2``); numbers formatted
    and range-checked here, in line order."""
    gains = [(ax, f"{plan.kp[ax]:.9g}", f"{plan.ki[ax]:.9g}", f"{plan.kaw[ax]:.9g}")
             for ax in AXES]
    d = {"MCSDK_I_FS": _f(plan.I_FS, 'motor.max_current', 'MCSDK_I_FS'),
         "MCSDK_V_FS": _f(plan.V_FS, 'drive.vdc', 'MCSDK_V_FS'),
         "MCSDK_W_FS": _f(plan.W_FS, 'drive.max_speed', 'MCSDK_W_FS'),
         "MCSDK_V_MAX": _int(round(plan.V_MAX / plan.V_FS * 32768), 'drive.vdc', 'MCSDK_V_MAX',
                             0, 32767),
         "IQ_I_BASE": _f(plan.I_FS, 'motor.max_current', 'IQ_I_BASE'),
         "IQ_V_BASE": _f(plan.V_MAX, 'drive.vdc', 'IQ_V_BASE'),
         "IQ_W_BASE": _f(plan.W_FS, 'drive.max_speed', 'IQ_W_BASE')}
    mc_ctx = {k: (_int(g, key, f"MCSDK {k} gain", -32767, 32767), _int(sh, key, f"MCSDK {k} divisor", 0, 15))
              for k, (g, sh) in mc.items()}
    iq_ctx = {k: _int(v, key, f"IQ24 {k}", -C_INT32_MAX, C_INT32_MAX) for k, v in iq.items()}
    t.lines.extend(_render("vendor.c.j2", N=N, P=P, U=N.upper(), gains=gains, d=d, mc=mc_ctx,
                           iq=iq_ctx, comp=comp))


def _fixed_body(t: _Text, check: ExportCheck, N: str, P: str, artifact, drive) -> None:
    """The Q31 section (``templates/fixed.c.j2``); numbers formatted and
    range-checked here, in line order."""
    plan = check.fixed
    key = _law_key(artifact)
    head = {"I_MAX": f"{plan.I_MAX:.6g}", "W_MAX": f"{plan.W_MAX:.6g}",
            "V_MAX": f"{plan.V_MAX:.6g}",
            "bounds": [(ax, f"{check.fixed_error_bound[ax]:.3g}", f"{HORIZON * 1e3:g}")
                       for ax in AXES if ax in check.fixed_error_bound]}
    d = {"I_BASE": _f(plan.I_BASE, 'motor.max_current', 'Q31_I_BASE'),
         "V_BASE": _f(plan.V_BASE, 'drive.vdc', 'Q31_V_BASE'),
         "W_BASE": _f(plan.W_BASE, 'drive.max_speed', 'Q31_W_BASE'),
         "I_MAX": _f(plan.I_MAX, 'motor.max_current', 'Q31_I_MAX'),
         "W_MAX": _f(plan.W_MAX, 'drive.max_speed', 'Q31_W_MAX'),
         "V_MAX": _q31(plan.vmax_q31, 'drive.vdc', 'Q31_V_MAX'),
         "VDC_BASE": (_f(plan.V_BASE * drive.vdc / check.v_max, 'drive.vdc', 'Q31_VDC_BASE')
                      if drive is not None and drive.vdc > 0 else None)}
    state_bases = [(ax.upper(), i, _f(s, key, f'Q31 {ax}-axis state base'))
                   for ax in AXES for i, s in enumerate(plan.axes[ax].S)]
    dec = [(name.upper(), _q31(m, 'motor', f'Q31 decoupling {name}'), f"{val:.6g}",
            _shift(F, 'motor', f'Q31 decoupling {name} shift'))
           for name, (m, F, val) in plan.dec.items()]
    pi = []
    for ax, kp, ki in _informational_pi_gains(artifact):
        rows = []
        for label, val in (("Kp", kp * plan.I_BASE / plan.V_BASE),
                           ("Ki Ts", ki * artifact.sample_time * plan.I_BASE / plan.V_BASE)):
            q = _fixed._quantise_row(np.array([val]), 1)
            if q is not None:
                rows.append((label, _q31(q[0][0], key, f'Q31 {ax}-axis {label}'),
                             _int(q[1], key, f'Q31 {ax}-axis {label} divisor', 0, 62),
                             f"{val:.6g}"))
        pi.append((ax, rows))
    axes = []
    for ax in AXES:
        fa = plan.axes[ax]
        n = fa.S.size
        shifts = ", ".join(_shift(F, key, f"Q31 {ax}-axis shift") for _, F in fa.rows)
        has_aw = bool(n) and any(m[n + 2] != 0 for m, _ in fa.rows)
        axes.append({
            "ax": ax, "n": n, "fa": shifts,
            "co": ", ".join(_q31(v, key, f"Q31 {ax}-axis output row") for v in fa.out[0]),
            "Fo": _shift(fa.out[1], key, f"Q31 {ax}-axis output shift"),
            "rows": [", ".join(_q31(v, key, f"Q31 {ax}-axis state row") for v in m)
                     for m, _ in fa.rows],
            "aw": ", ".join(_q31(m[n + 2], key, f"Q31 {ax}-axis anti-windup")
                            for m, _ in fa.rows) if has_aw else ""})
    t.lines.extend(_render("fixed.c.j2", N=N, P=P, p=P.lower(), head=head, d=d,
                           state_bases=state_bases, dec=dec, pi=pi, axes=axes,
                           comp=_integer_placement(artifact, plan.W_BASE),
                           nd=max(plan.axes["d"].S.size, 1), nq=max(plan.axes["q"].S.size, 1)))


#: Largest placement angle (rad, at the speed base) of the integer variants'
#: Taylor rotation: its truncation error (x^8/8!) stays below 1e-4 up to here.
Q31_MAX_PLACEMENT_ANGLE = 1.5


def _integer_placement(artifact, w_base: float) -> dict | None:
    """An integer variant's voltage placement constant, or None when the
    placement time is 0: ``K`` is the rotation angle at the variant's
    full-scale mechanical speed ``w_base`` (``DELAY_COMP_TIME p w_base``) in
    Q30 radians (``templates/placement.c.j2``)."""
    t_comp = _delay_comp_time(artifact)
    if t_comp is None:
        return None
    angle = t_comp * artifact.decoupling.pole_pairs * w_base
    if angle > Q31_MAX_PLACEMENT_ANGLE:
        raise ExportRefused("drive.angle_compensation",
                            f"a placement angle of at most {Q31_MAX_PLACEMENT_ANGLE} rad at "
                            "the integer variants' speed base (DELAY_COMP_TIME x POLE_PAIRS "
                            "x speed base)", f"{angle:.3g} rad")
    return {"K": _int(round(angle * 2.0 ** 30), 'drive.angle_compensation',
                      'placement angle constant', 0, 2 ** 31 - 1),
            "angle": f"{angle:.6g}"}


def fcs_r_hex_per_vdc(convention: str) -> float:
    """Length of an active inverter vector per volt of bus (the hexagon's
    vertex radius, :func:`toolbox.spec.inverter_radii`)."""
    from ..spec import inverter_radii
    return inverter_radii(1.0, convention)[0]


def _write_fcs_header(artifact, motor, drive, name: str, title: str | None,
                      example: bool) -> str:
    """controller.h of method ``fcs_mpc``: the predictive switching law of paper
    002 criterion (23) as the simulator runs it (``toolbox.sim._kernel._fcs_choice``),
    float only."""
    if drive is None:
        raise ExportRefused("drive", "drive data (vdc) for the inverter vectors",
                            hint="pass drive= or keep [drive] in the artifact's spec")
    conv = motor.convention if motor is not None else "amplitude"
    N = name.lower()
    P = name.upper() + "_"
    guard = f"{P}CONTROLLER_H"
    if title is None:
        title = (artifact.spec or {}).get("title", "")
    fcs = artifact.fcs
    dec = artifact.decoupling
    key = _law_key(artifact)
    predict = int(artifact.delay_samples) >= 1
    k_hex = fcs_r_hex_per_vdc(conv)
    t = _Text()
    d = {"ts": _f(artifact.sample_time, 'drive.sample_time', 'SAMPLE_TIME'),
         "nd": _int(artifact.delay_samples, 'drive.delay_samples', 'DELAY_SAMPLES', 0),
         "vdc": _f(drive.vdc, 'drive.vdc', 'DRIVE_VDC'),
         "r_hex_per_vdc": _f(k_hex, 'drive.vdc', 'R_HEX_PER_VDC'),
         "convention": sanitise_comment(conv),
         "r_hex": _f(k_hex * drive.vdc, 'drive.vdc', 'R_HEX'),
         "R": _f(dec.R_c, 'motor.R', 'DEC_R'), "Ld": _f(dec.Ld_c, 'motor.Ld', 'DEC_LD'),
         "Lq": _f(dec.Lq_c, 'motor.Lq', 'DEC_LQ'), "flux": _f(dec.flux_c, 'motor.flux', 'DEC_FLUX'),
         "pole_pairs": _int(dec.pole_pairs, 'motor.pole_pairs', 'POLE_PAIRS', 1),
         "alpha": _f(fcs.alpha, key + '.alpha', 'FCS_ALPHA'),
         "beta": _f(fcs.beta, key + '.beta', 'FCS_BETA'),
         "gamma": _f(fcs.gamma, key + '.gamma', 'FCS_GAMMA')}
    t.lines.extend(_render("fcs_top.c.j2", prov=_provenance(artifact, title), N=N, P=P,
                           U=N.upper(), guard=guard, delay=int(artifact.delay_samples), d=d))
    t("")
    v_hex = k_hex * drive.vdc * math.sqrt(3.0) / 2.0        # the hexagon's apothem
    t.lines.extend(_render("fcs.c.j2", N=N, P=P, U=N.upper(), predict=predict,
                           plausible=_plausible_context(artifact, motor, drive, v_hex)))
    if example:
        t("")
        _example(t, N, P, fcs=True)
    t("")
    t(f"#endif /* {guard} */")
    return t.text()


EXAMPLE_BEGIN = "EXAMPLE main.c BEGIN"
EXAMPLE_END = "EXAMPLE main.c END"


def example_source(header: str) -> str:
    """The usage example written at the end of a header (the C text between
    the ``EXAMPLE main.c BEGIN`` and ``END`` lines), to compile as ``main.c``."""
    lines = header.splitlines()
    i = next(k for k, ln in enumerate(lines) if EXAMPLE_BEGIN in ln)
    j = next(k for k, ln in enumerate(lines) if EXAMPLE_END in ln)
    return "\n".join(lines[i + 1:j]) + "\n"


def _example(t: _Text, N: str, P: str, *, hexagon: bool = False, fcs: bool = False) -> None:
    """A compilable main.c, inside ``#if 0`` (no ``/*`` in it): ``templates/example.c.j2``,
    the predictive switching law's (``fcs``) or the linear law's."""
    t.lines.extend(_render("example.c.j2", N=N, P=P, U=N.upper(), hexagon=hexagon, fcs=fcs,
                           begin=EXAMPLE_BEGIN, end=EXAMPLE_END))


def write_header(artifact, motor=None, drive=None, *, name: str = "cct",
                 prefix: str | None = None, title: str | None = None,
                 source: str | None = None, example: bool = True) -> str:
    """The C99 header text of a controller artifact.

    Parameters
    ----------
    artifact : ControllerArtifact
        The designed controller (checked by :func:`check_exportable` first).
    motor, drive : Motor, Drive, optional
        Motor and drive data for the ``#define`` block and the voltage limit
        (default: read from ``artifact.spec``).
    name : str
        Prefix of every C identifier (``<name>_step``, ``<NAME>_V_MAX``); a C
        identifier of at most 31 characters.
    prefix : str, optional
        The C prefix (``cct export --prefix``, ``[export] prefix``), ``name``
        with its underscore:
        ``"motor1_"`` gives ``motor1_step``, ``MOTOR1_V_MAX``, the guard
        ``MOTOR1_CONTROLLER_H`` and the switch ``MOTOR1_FIXED_POINT``; a
        trailing underscore is added when missing (``"motor1"`` is the same).
        It must start with a letter; it overrides ``name``. Two headers in one
        program need prefixes that differ in upper case.
    example : bool
        Append the usage example (init, bus-voltage update, per-period call,
        fault handling) as a comment at the end of the header.
    title : str, optional
        Title for the provenance comment (default: ``artifact.spec["title"]``);
        sanitised by :func:`sanitise_comment`.
    source : str, optional
        The design file the artifact came from (``DIR/controller.json``);
        every refusal names it.

    Returns
    -------
    str
        The header text (the CLI writes it atomically).

    Raises
    ------
    ExportRefused
        Refused controller (see :func:`check_exportable`) or a constant out of
        range (float32, C integer ranges), naming the spec key; with the
        ``source`` file when given.
    SpecError
        Bad ``name``.
    """
    try:
        if prefix is not None:
            name = prefix_name(prefix)
        return _write_header(artifact, motor, drive, name, title, example)
    except CctError as err:
        if source and not err.file:
            raise err.with_file(str(source)) from None
        raise


#: Used with fullmatch: ``$`` of re.match also matches before a trailing newline.
PREFIX_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,30}")


def prefix_name(prefix: Any, key: str = "export.prefix") -> str:
    """The identifier stem of a C prefix: ``"motor1_"`` and ``"motor1"`` -> ``"motor1"``.

    Parameters
    ----------
    prefix : str
        A C identifier starting with a letter, at most 31 characters, with
        or without its trailing underscore.
    key : str
        The key named in the error.

    Raises
    ------
    SpecError
        Not such an identifier.
    """
    if not isinstance(prefix, str) or not PREFIX_RE.fullmatch(prefix):
        raise SpecError(key, "a C identifier prefix: a letter, then letters, digits or _ "
                        "(at most 31 characters), e.g. \"motor1_\"", prefix)
    stem = prefix[:-1] if prefix.endswith("_") else prefix
    if not stem:
        raise SpecError(key, "a prefix with a letter before the underscore", prefix)
    return stem


def _write_header(artifact, motor, drive, name: str, title: str | None,
                  example: bool = True) -> str:
    if not isinstance(name, str) or not _IDENT.fullmatch(name):
        raise SpecError("export.name", "a C identifier of at most 31 characters", name)
    motor, drive = _motor_drive(artifact, motor, drive)
    if artifact.method == "fcs_mpc":
        return _write_fcs_header(artifact, motor, drive, name, title, example)
    check = check_exportable(artifact, motor, drive)
    N = name.lower()
    P = name.upper() + "_"
    if title is None:
        title = (artifact.spec or {}).get("title", "")
    guard = f"{P}CONTROLLER_H"
    t = _Text()
    _header_top(t, artifact, motor, drive, N, check, title)
    t(f"#ifndef {guard}")
    t(f"#define {guard}")
    t("")
    trig = check.limit == "hexagon" or _delay_comp_time(artifact) is not None
    t("#include <math.h> /* sqrtf" + (", sinf, cosf" if trig else "") + " */")
    t("#include <stdint.h> /* uint32_t */")
    t("")
    _defines(t, artifact, motor, drive, P, check)
    t("")
    for ax in AXES:
        r = check.realisations[ax]
        if r.form == "sos":
            t(f"#define {P}{ax.upper()}_GAIN {_f(r.gain, _law_key(artifact), f'{ax}-axis SOS gain')} /* {ax} axis SOS output gain, V/A */")
            t(f"#define {P}{ax.upper()}_NUM_STAGES {r.sos.shape[0]}")
    t("")
    _float_section(t, check.realisations, N, P, _law_key(artifact), check.limit == "hexagon",
                   _delay_comp_time(artifact) is not None,
                   _plausible_context(artifact, motor, drive, check.v_max),
                   motor.convention if motor is not None else "amplitude",
                   d_priority=check.priority == "d_axis")
    if _delay_comp_time(artifact) is not None:
        t.lines.extend(_render("placement.c.j2", N=N, P=P))
    _fixed_section(t, check, N, P, artifact, drive)
    t("")
    _vendor_section(t, artifact, motor, drive, check, N, P)
    t("")
    if example:
        _example(t, N, P, hexagon=check.limit == "hexagon")
        t("")
    t(f"#endif /* {guard} */")
    return t.text()
