"""Firmware export: the controller artifact as a C99 header (``controller.h``).

The header is self-contained (header-only, include guards, no dynamic
memory, only ``sqrtf`` from libm) and implements the whole current-control
law of the artifact in one ``static inline`` step function:

1. per axis, the discrete two-input law ``[i_ref, i_meas] -> v`` of
   :class:`toolbox.artifact.AxisController` (``law``), as CMSIS-DSP style
   second-order sections when the law is one-degree-of-freedom
   (``v = K (i_ref - i_meas)``), else in state-space form;
2. the decoupling of :class:`toolbox.artifact.Decoupling`:
   ``v_d += -cross w_m Lq_c i_q``, ``v_q += cross w_m Ld_c i_d + emf w_m flux_c``
   with ``w_m = pole_pairs Omega_m``;
3. the voltage limit (circle of radius ``drive.max_voltage(convention)``,
   radial scaling as in the toolbox simulator);
4. back-calculation anti-windup ``x += aw (v_sat - v_unsat)`` with the
   artifact's vector mapped into the executed coordinates.

A fixed-point variant (``#define CCT_FIXED_POINT`` before including) adds
``cct_step_q31`` with Q31 signals and int64 accumulators; see
:mod:`toolbox.export._fixed` for the scaling rules.

Exportability rules (:func:`check_exportable`) -- a controller is refused with
:class:`toolbox.errors.SpecError` (key ``axes.<d|q>.law``) when:

* **unstable**: a pole of the discrete law has ``|z| >= 1``, other than one
  simple integrator exactly at ``z = 1`` (``|z - 1| <= 1e-9``) per axis;
* **Nyquist ringing**: a pole with ``Re z < 0`` and ``|z| > 0.9`` (the Tustin
  image of a continuous pole faster than ~12 x the Nyquist frequency) that
  no zero cancels to within 1 % of its distance to the unit circle (the pair
  then changes |K| by at most 1 % at any frequency, the rule of
  :func:`toolbox.design._hinf_riccati.effective_poles` transposed to z);
* **coefficient dynamic range** of one coefficient set (SOS stage or state
  row) above ``2**30`` (beyond Q31 resolution even with per-set scaling);
* **rounding sensitivity**: rounding the executed coefficients to float32
  (or to Q31 for the fixed-point variant) moves a pole by more than
  ``1 % (1 - |p|) + Ts * 0.01 rad/s`` or destabilises it. The absolute term
  is a 0.01 rad/s shift of the pole's continuous equivalent, immaterial for
  current loops and the only fair yardstick for near-integrators (paper 003's
  controller pole at 0.0117 rad/s lies 1.2e-6 inside the unit circle).

The fixed-point variant is additionally refused (the header then carries an
``#error`` under ``CCT_FIXED_POINT``) when no finite state bound exists.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import SpecError
from . import _fixed
from ._sos import Realisation, realise_axis

__all__ = ["write_header", "check_exportable", "ExportCheck", "sanitise_comment",
           "realisations", "reference_law", "ReferenceLaw", "check_fixed", "INTEGRATOR_TOL", "RING_RADIUS",
           "DYNAMIC_RANGE"]

AXES = ("d", "q")
INTEGRATOR_TOL = 1e-9
RING_RADIUS = 0.9
CANCEL_TOL = 1e-2
DYNAMIC_RANGE = 2.0 ** 30
POLE_REL_TOL = 1e-2
POLE_ABS_RAD_S = 1e-2
PI_METHODS = ("pi", "ip", "pi_lag")
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


def _is_integrator(p: complex) -> bool:
    return abs(p - 1.0) <= INTEGRATOR_TOL


def _check_poles(poles: np.ndarray, zeros: np.ndarray, key: str) -> None:
    poles = np.atleast_1d(np.asarray(poles, complex))
    n_int = int(sum(_is_integrator(p) for p in poles))
    if n_int > 1:
        raise SpecError(key, "at most one integrator (pole at z = 1) per axis",
                        f"{n_int} poles at z = 1")
    for p in poles:
        if not _is_integrator(p) and abs(p) >= 1.0:
            raise SpecError(key, "a stable discrete law (poles |z| < 1; one simple "
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
            raise SpecError(key, f"no lightly damped pole near z = -1 (Re z < 0 and "
                            f"|z| > {RING_RADIUS}) unless a zero cancels it",
                            f"pole z = {_fmt(p)}",
                            hint="a controller pole far beyond the Nyquist frequency "
                                 "makes the discrete controller ill-conditioned")


def _pole_tol(p: complex, ts: float) -> float:
    return POLE_REL_TOL * max(1.0 - abs(p), 0.0) + ts * POLE_ABS_RAD_S


def _check_shift(exact: np.ndarray, rounded: np.ndarray, ts: float, key: str,
                 what: str) -> float:
    """Worst pole displacement / tolerance; SpecError above 1 or if unstable."""
    left = list(np.atleast_1d(rounded))
    worst = 0.0
    for p in sorted(np.atleast_1d(exact), key=lambda z: -abs(z)):
        d = [abs(q - p) for q in left]
        q = left.pop(int(np.argmin(d)))
        tol = _pole_tol(p, ts)
        worst = max(worst, abs(q - p) / tol)
        bad = abs(q) >= 1.0 and not (_is_integrator(p) and _is_integrator(q))
        if abs(q - p) > tol or bad:
            raise SpecError(key, f"{what} coefficient rounding to move each pole by at "
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


def realisations(artifact) -> dict[str, Realisation]:
    """The executed realisation of each axis (SOS or state space)."""
    out = {}
    for ax in AXES:
        law = artifact.axes[ax].law
        aw = artifact.axes[ax].antiwindup
        out[ax] = realise_axis(law.A, law.B, law.C, law.D,
                               None if aw is None else aw.ravel())
    return out


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
        Voltage limit (V).
    """

    realisations: dict
    float_pole_shift: dict
    fixed: Any = None
    fixed_reason: str = ""
    fixed_pole_shift: dict = field(default_factory=dict)
    v_max: float = math.inf
    saturated_radius: dict = field(default_factory=dict)
    fixed_error_bound: dict = field(default_factory=dict)

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


def check_exportable(artifact, motor=None, drive=None, *, fixed_point: bool = False,
                     v_max: float | None = None) -> ExportCheck:
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
        Also require the Q31 variant to be available (else SpecError).
    v_max : float, optional
        Override of the voltage-limit radius (V).

    Returns
    -------
    ExportCheck
        Realisations, measured rounding sensitivity and the fixed-point plan.

    Raises
    ------
    SpecError
        Key ``axes.<axis>.law`` for an unstable or ill-conditioned law (rules
        in the module docstring), ``export.fixed_point`` when the Q31 variant
        is asked for but impossible, ``drive`` when no voltage limit is known.
    """
    motor, drive = _motor_drive(artifact, motor, drive)
    if v_max is None:
        if drive is None:
            raise SpecError("drive", "drive data (vdc) for the voltage limit",
                            hint="pass drive= or keep [drive] in the artifact's spec")
        v_max = drive.max_voltage(motor.convention if motor is not None else "amplitude")
    ts = artifact.sample_time
    reals = realisations(artifact)
    shifts = {}
    for ax in AXES:
        key = f"axes.{ax}.law"
        law = artifact.axes[ax].law
        if not all(np.all(np.isfinite(m)) for m in (law.A, law.B, law.C, law.D)):
            raise SpecError(key, "finite coefficients")
        poles = np.linalg.eigvals(law.A) if law.order else np.zeros(0)
        zeros = _law_zeros(law)
        _check_poles(poles, zeros, key)
        real = reals[ax]
        for i, cs in enumerate(_coefficient_sets(real)):
            rng = _dynamic_range(cs)
            if rng > DYNAMIC_RANGE:
                raise SpecError(key, f"coefficient dynamic range <= 2**30 per coefficient set",
                                f"{rng:.3g} in set {i}",
                                hint="ill-conditioned realisation; reduce or rescale the controller")
        exact = np.linalg.eigvals(real.A) if real.order else np.zeros(0)
        shifts[ax] = _check_shift(exact, _rounded_poles_f32(real), ts, key, "float32")
    res = ExportCheck(reals, shifts, v_max=float(v_max))
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
    dec = artifact.decoupling
    p = dec.pole_pairs
    dec_coeffs = {"dd": -float(dec.cross) * p * dec.Lq_c,
                  "dq": float(dec.cross) * p * dec.Ld_c,
                  "de": float(dec.emf) * p * dec.flux_c}
    plan, reason = _fixed.plan_fixed(reals, I_MAX=i_max, W_MAX=w_max, V_MAX=v_max,
                                     dec_coeffs=dec_coeffs)
    if plan is not None:
        try:
            res.fixed_pole_shift = check_fixed(plan, ts)
            res.fixed_error_bound = _fixed.horizon_bound(plan, round(HORIZON / ts))
        except SpecError as err:
            plan, reason = None, str(err)
    res.fixed, res.fixed_reason = plan, reason
    if fixed_point and plan is None:
        raise SpecError("export.fixed_point", "a controller the Q31 variant can represent",
                        reason)
    return res


def check_fixed(plan, sample_time: float) -> dict:
    """Pole displacement of the Q31-quantised laws (refused beyond tolerance).

    Parameters
    ----------
    plan : FixedPlan
        Output of :func:`toolbox.export._fixed.plan_fixed`.
    sample_time : float
        Controller period (s).

    Returns
    -------
    dict
        Per axis, worst displacement / tolerance (<= 1).

    Raises
    ------
    SpecError
        Key ``axes.<axis>.law`` when quantisation moves a pole beyond
        ``1 % (1 - |p|) + Ts * 0.01 rad/s`` or destabilises it.
    """
    out = {}
    for ax in AXES:
        fa = plan.axes[ax]
        exact = np.linalg.eigvals(fa.An) if fa.An.size else np.zeros(0)
        rounded = np.linalg.eigvals(fa.Aq) if fa.Aq.size else np.zeros(0)
        out[ax] = _check_shift(exact, rounded, sample_time, f"axes.{ax}.law", "Q31")
    return out


def _law_zeros(law) -> np.ndarray:
    """Transmission zeros of the reference channel (the error channel for 1-DOF laws)."""
    import scipy.signal
    if law.order == 0:
        return np.zeros(0)
    z, _, _ = scipy.signal.ss2zpk(law.A, law.B[:, :1], law.C, law.D[:, :1])
    z2, _, _ = scipy.signal.ss2zpk(law.A, law.B[:, 1:], law.C, law.D[:, 1:])
    return np.concatenate([z[np.isfinite(z)], z2[np.isfinite(z2)]])


# ---------------------------------------------------------------------------
# Python reference of the executed law (double precision)
# ---------------------------------------------------------------------------
class ReferenceLaw:
    """The executed law in double precision, one period at a time.

    Uses the artifact's own state-space law (not the exported realisation),
    so it is an independent route to the header's input-output map: per axis
    ``v = C x + D u``, decoupling, circle limit (radial scaling), then
    ``x <- A x + B u + aw (v_sat - v_unsat)``.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller.
    v_max : float
        Voltage-limit radius (V).
    """

    def __init__(self, artifact, v_max: float) -> None:
        self.dec = artifact.decoupling
        self.v_max = float(v_max)
        self.laws = [artifact.axes[ax].law for ax in AXES]
        self.aws = [np.zeros(l.order) if artifact.axes[ax].antiwindup is None
                    else artifact.axes[ax].antiwindup.ravel()
                    for l, ax in zip(self.laws, AXES)]
        self.xs = [np.zeros(l.order) for l in self.laws]

    def step(self, i_d_ref: float, i_q_ref: float, i_d: float, i_q: float,
             omega_m: float) -> tuple[float, float, int]:
        """One period: currents (A), mechanical speed (rad/s) -> (v_d, v_q (V), saturated)."""
        dec = self.dec
        u = [np.array([i_d_ref, i_d]), np.array([i_q_ref, i_q])]
        v_lin = [float((l.C @ x + l.D @ uu)[0]) for l, x, uu in zip(self.laws, self.xs, u)]
        w = dec.pole_pairs * omega_m
        vd = v_lin[0] - dec.cross * w * dec.Lq_c * i_q
        vq = v_lin[1] + dec.cross * w * dec.Ld_c * i_d + dec.emf * w * dec.flux_c
        mag = math.hypot(vd, vq)
        vds, vqs, sat = vd, vq, 0
        if mag > self.v_max:
            vds, vqs, sat = vd * self.v_max / mag, vq * self.v_max / mag, 1
        dv = (vds - vd, vqs - vq)
        self.xs = [l.A @ x + l.B @ uu + a * d
                   for l, x, uu, a, d in zip(self.laws, self.xs, u, self.aws, dv)]
        return vds, vqs, sat


def reference_law(artifact, inputs: np.ndarray, v_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Run :class:`ReferenceLaw` over an input sequence.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller.
    inputs : ndarray
        (N, 5): ``i_d_ref, i_q_ref, i_d, i_q`` (A), ``Omega_m`` (rad/s).
    v_max : float
        Voltage-limit radius (V).

    Returns
    -------
    (ndarray, ndarray)
        (N, 2) voltages ``v_d, v_q`` (V) and (N,) saturation flags.
    """
    law = ReferenceLaw(artifact, v_max)
    out = np.zeros((len(inputs), 2))
    sat = np.zeros(len(inputs), dtype=int)
    for k, row in enumerate(np.asarray(inputs, float)):
        out[k, 0], out[k, 1], sat[k] = law.step(*row)
    return out, sat


# ---------------------------------------------------------------------------
# C text
# ---------------------------------------------------------------------------
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,30}$")


def _f(v: float) -> str:
    """A float literal (float32-rounded, 9 significant digits, always valid C)."""
    v = float(np.float32(v))
    if v == 0.0:
        return "0.0f"
    return f"{v:.9e}f"


def _farr(values) -> str:
    return ", ".join(_f(v) for v in values)


class _Text:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def __call__(self, line: str = "") -> None:
        self.lines.append(line)

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


def _pi_gains(artifact, ax: str) -> tuple[float, float] | None:
    """Parallel-form (Kp V/A, Ki V/(A s)) of a PI-type axis, or None."""
    g = artifact.gains or {}

    def pick(name):
        v = g.get(name)
        if isinstance(v, dict):
            v = v.get(ax)
        elif isinstance(v, (list, tuple)) and len(v) == 2:
            v = v[AXES.index(ax)]
        return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None

    kp = pick("Kp") if pick("Kp") is not None else pick(f"Kp_{ax}")
    ki = pick("Ki") if pick("Ki") is not None else pick(f"Ki_{ax}")
    if kp is not None and ki is not None:
        return kp, ki
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


def _delay_comp_time(artifact) -> float | None:
    """Delay-compensation time (s) the design assumes, or None.

    ``gains["delay_compensation_time"]`` (s) when present; else
    ``gains["delay_compensation"]``: a number is a multiple of Ts, any other
    truthy value means the usual 1.5 Ts (one period of computation delay plus
    half a period of PWM/ZOH delay).
    """
    g = artifact.gains or {}
    v = g.get("delay_compensation_time")
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0:
        return float(v)
    dc = g.get("delay_compensation")
    if dc is None or dc is False or dc == 0:
        return None
    if isinstance(dc, (int, float)) and not isinstance(dc, bool):
        return float(dc) * artifact.sample_time
    return 1.5 * artifact.sample_time


def _header_top(t: _Text, artifact, motor, drive, N: str, check: ExportCheck,
                title: str) -> None:
    prov = artifact.provenance or {}
    t("/*")
    t(" * controller.h -- current controller exported by current-control-toolbox")
    t(f" * title:       {sanitise_comment(title)}")
    t(f" * method:      {sanitise_comment(artifact.method)}")
    t(f" * version:     {sanitise_comment(prov.get('version', 'unknown'))}")
    t(f" * spec sha256: {sanitise_comment(prov.get('spec_sha256', 'unknown'))}")
    t(f" * created:     {sanitise_comment(prov.get('created', 'unknown'))}")
    eqs = prov.get("equations")
    if eqs:
        t(f" * equations:   {sanitise_comment('; '.join(map(str, eqs)), 400)}")
    t(" *")
    t(" * C99, header-only, no dynamic memory; libm: sqrtf only (float path).")
    t(f" * Call {N}_init() once, then {N}_step() once per controller period. The")
    t(" * voltage returned is applied by the inverter in the NEXT period: the")
    t(" * computation delay is part of the plant the design assumed, not of this code.")
    t(" * Law per axis: x' = A x + B [i_ref; i_meas], v = C x + D [i_ref; i_meas]")
    t(f" *   (1-DOF laws as second-order sections of K(z) = v / (i_ref - i_meas)),")
    t(" * then decoupling  v_d += -cross w_e Lq_c i_q,")
    t(" *                  v_q +=  cross w_e Ld_c i_d + emf w_e flux_c,  w_e = p Omega_m,")
    t(" * then the circle limit |v| <= V_MAX (radial scaling; the inscribed circle of")
    t(" * the SVM hexagon, also when the spec asks for the hexagon) and back-calculation")
    t(" * anti-windup x += aw (v_sat - v_unsat).")
    t(" * SOS coefficient layout = CMSIS-DSP arm_biquad_cascade_df2T_f32:")
    t(" *   {b0, b1, b2, a1, a2} per stage with a1, a2 NEGATED with respect to the")
    t(" *   denominator 1 + a1 z^-1 + a2 z^-2 (scipy / MATLAB convention), i.e.")
    t(" *   y = b0 x + s1; s1 = b1 x + a1 y + s2; s2 = b2 x + a2 y.")
    if artifact.method == "fcs_mpc":
        t(" * NOTE: method fcs_mpc chooses inverter switch states online; that predictive")
        t(" *   law is not exported. This header runs the linear axis controllers stored")
        t(" *   in the artifact (the SVM + PI baseline).")
    for ax in check.marginal_antiwindup:
        t(f" * WARNING ({ax} axis): in saturation the anti-windup recursion A - aw C has")
        t(f" *   spectral radius {check.saturated_radius[ax]:.9g} >= 1 (not strictly stable):")
        t(" *   states may ring at the Nyquist frequency or drift while the limit acts.")
    t(" */")


def _defines(t: _Text, artifact, motor, drive, P: str, check: ExportCheck) -> None:
    dec = artifact.decoupling
    t(f"#define {P}SAMPLE_TIME {_f(artifact.sample_time)} /* controller period, s */")
    t(f"#define {P}DELAY_SAMPLES {int(artifact.delay_samples)} /* computation delay the design assumed, periods */")
    t(f"#define {P}V_MAX {_f(check.v_max)} /* voltage-limit circle radius, V */")
    if motor is not None:
        t(f"/* motor ({sanitise_comment(motor.convention)}-invariant dq convention) */")
        t(f"#define {P}MOTOR_R {_f(motor.R)} /* stator resistance, ohm */")
        t(f"#define {P}MOTOR_LD {_f(motor.Ld)} /* d-axis inductance, H */")
        t(f"#define {P}MOTOR_LQ {_f(motor.Lq)} /* q-axis inductance, H */")
        t(f"#define {P}MOTOR_FLUX {_f(motor.flux)} /* PM flux linkage, Wb */")
        t(f"#define {P}MOTOR_POLE_PAIRS {int(motor.pole_pairs)} /* pole pairs */")
        t(f"#define {P}MOTOR_J {_f(motor.J)} /* inertia, kg m^2 */")
        t(f"#define {P}MOTOR_FRICTION {_f(motor.friction)} /* viscous friction, N m s/rad */")
        if motor.max_current:
            t(f"#define {P}MOTOR_MAX_CURRENT {_f(motor.max_current)} /* dq current amplitude limit, A */")
        if motor.rated_current:
            t(f"#define {P}MOTOR_RATED_CURRENT {_f(motor.rated_current)} /* A */")
        if motor.rated_speed:
            t(f"#define {P}MOTOR_RATED_SPEED {_f(motor.rated_speed)} /* mechanical, rad/s */")
    if drive is not None:
        t("/* drive */")
        t(f"#define {P}DRIVE_VDC {_f(drive.vdc)} /* DC-link voltage, V */")
        if drive.switching_frequency:
            t(f"#define {P}DRIVE_SWITCHING_FREQUENCY {_f(drive.switching_frequency)} /* PWM carrier, Hz */")
    t("/* decoupling: controller-side model parameters */")
    t(f"#define {P}DEC_CROSS {int(bool(dec.cross))} /* 1: cross-coupling terms on */")
    t(f"#define {P}DEC_EMF {int(bool(dec.emf))} /* 1: back-EMF term on */")
    t(f"#define {P}DEC_LD {_f(dec.Ld_c)} /* H */")
    t(f"#define {P}DEC_LQ {_f(dec.Lq_c)} /* H */")
    t(f"#define {P}DEC_FLUX {_f(dec.flux_c)} /* Wb */")
    t(f"#define {P}POLE_PAIRS {int(dec.pole_pairs)} /* w_e = POLE_PAIRS * Omega_m */")
    t_comp = _delay_comp_time(artifact)
    if t_comp is not None:
        k = t_comp / artifact.sample_time
        t(f"#define {P}DELAY_COMP_TIME {_f(t_comp)} /* s ({k:g} Ts): the design assumes v_dq "
          f"rotated by angle = {P}DELAY_COMP_TIME * w_e (rad) before the inverse Park transform "
          f"(not applied inside {P.lower()}step) */")
    if artifact.method in PI_METHODS:
        for ax in AXES:
            g = _pi_gains(artifact, ax)
            if g is None:
                continue
            kp, ki = g
            A = ax.upper()
            t(f"/* {ax} axis PI gains (method {artifact.method}); the law below is what runs */")
            t(f"#define {P}{A}_KP {_f(kp)} /* parallel proportional gain, V/A */")
            t(f"#define {P}{A}_KI {_f(ki)} /* parallel integral gain, V/(A s) */")
            t(f"#define {P}{A}_KI_TS {_f(ki * artifact.sample_time)} /* integral gain per sample Ki*Ts, V/A */")
            if kp:
                t(f"#define {P}{A}_TI {_f(kp / ki) if ki else '0.0f'} /* series form Kp (1 + 1/(Ti s)): Ti = Kp/Ki, s */")


def _axis_float(t: _Text, real: Realisation, N: str, P: str, ax: str) -> None:
    A = ax.upper()
    n = real.order
    t(f"/* {ax} axis linear law: returns v (V); updates the state to A x + B u */")
    t(f"static inline float {N}_{ax}_linear(float *x, float r, float y)")
    t("{")
    if real.form == "sos":
        co = real.cmsis_coefficients()
        m = co.shape[0]
        t(f"    /* {m} stage(s) {{b0, b1, b2, a1, a2}} (a1, a2 negated, CMSIS df2T), gain {P}{A}_GAIN */")
        if m == 0:
            t("    (void)x;")
            t(f"    return {_f(real.gain)} * (r - y);")
        else:
            t(f"    static const float c[{5 * m}] = {{")
            for row in co:
                t(f"        {_farr(row)},")
            t("    };")
            t("    float in = r - y;")
            t("    unsigned k;")
            t(f"    for (k = 0u; k < {m}u; ++k) {{")
            t("        const float *s = &c[5u * k];")
            t("        const float out = s[0] * in + x[2u * k];")
            t("        x[2u * k] = s[1] * in + s[3] * out + x[2u * k + 1u];")
            t("        x[2u * k + 1u] = s[2] * in + s[4] * out;")
            t("        in = out;")
            t("    }")
            t(f"    return {P}{A}_GAIN * in;")
    else:
        if n == 0:
            t("    (void)x;")
            t(f"    return {_f(real.D[0, 0])} * r + {_f(real.D[0, 1])} * y;")
        else:
            t(f"    static const float a[{n * n}] = {{ {_farr(real.A.ravel())} }};")
            t(f"    static const float b[{2 * n}] = {{ {_farr(real.B.ravel())} }};")
            t(f"    static const float c[{n}] = {{ {_farr(real.C.ravel())} }};")
            t(f"    float xn[{n}];")
            t(f"    float v = {_f(real.D[0, 0])} * r + {_f(real.D[0, 1])} * y;")
            t("    unsigned i, j;")
            t(f"    for (i = 0u; i < {n}u; ++i) {{")
            t("        float acc = b[2u * i] * r + b[2u * i + 1u] * y;")
            t(f"        for (j = 0u; j < {n}u; ++j) {{")
            t(f"            acc += a[{n}u * i + j] * x[j];")
            t("        }")
            t("        v += c[i] * x[i];")
            t("        xn[i] = acc;")
            t("    }")
            t(f"    for (i = 0u; i < {n}u; ++i) {{")
            t("        x[i] = xn[i];")
            t("    }")
            t("    return v;")
    t("}")
    t("")


def _aw_lines(real: Realisation, field_: str, dv: str) -> list[str]:
    out = []
    for i, a in enumerate(real.aw):
        if a != 0.0:
            out.append(f"    s->{field_}[{i}] += {_f(a)} * {dv};")
    return out


def _float_section(t: _Text, reals: dict, N: str, P: str) -> None:
    nd = max(reals["d"].order, 1)
    nq = max(reals["q"].order, 1)
    t("/* inputs: currents in A, measured MECHANICAL speed in rad/s */")
    t("typedef struct {")
    t("    float i_d_ref; /* A */")
    t("    float i_q_ref; /* A */")
    t("    float i_d;     /* measured, A */")
    t("    float i_q;     /* measured, A */")
    t("    float omega_m; /* measured mechanical speed, rad/s */")
    t(f"}} {N}_input_t;")
    t("")
    t("typedef struct {")
    t("    float v_d;     /* V, to apply next period */")
    t("    float v_q;     /* V */")
    t("    int saturated; /* 1 when the voltage limit acted */")
    t(f"}} {N}_output_t;")
    t("")
    t(f"/* controller states ({reals['d'].form} d axis: {reals['d'].order}, "
      f"{reals['q'].form} q axis: {reals['q'].order}; arrays have at least one element) */")
    t("typedef struct {")
    t(f"    float d[{nd}];")
    t(f"    float q[{nq}];")
    t(f"}} {N}_state_t;")
    t("")
    t(f"static inline void {N}_init({N}_state_t *s)")
    t("{")
    t("    unsigned i;")
    t(f"    for (i = 0u; i < {nd}u; ++i) {{ s->d[i] = 0.0f; }}")
    t(f"    for (i = 0u; i < {nq}u; ++i) {{ s->q[i] = 0.0f; }}")
    t("}")
    t("")
    for ax in AXES:
        _axis_float(t, reals[ax], N, P, ax)
    t(f"/* one controller period: the whole law (linear laws, decoupling, limit, anti-windup) */")
    t(f"static inline void {N}_step({N}_state_t *s, const {N}_input_t *in, {N}_output_t *out)")
    t("{")
    t(f"    const float w = (float){P}POLE_PAIRS * in->omega_m; /* electrical speed, rad/s */")
    t(f"    const float vd_lin = {N}_d_linear(s->d, in->i_d_ref, in->i_d);")
    t(f"    const float vq_lin = {N}_q_linear(s->q, in->i_q_ref, in->i_q);")
    t(f"    const float vd = vd_lin - (float){P}DEC_CROSS * w * {P}DEC_LQ * in->i_q;")
    t(f"    const float vq = vq_lin + (float){P}DEC_CROSS * w * {P}DEC_LD * in->i_d")
    t(f"                   + (float){P}DEC_EMF * w * {P}DEC_FLUX;")
    t("    const float mag2 = vd * vd + vq * vq;")
    t("    float vds = vd;")
    t("    float vqs = vq;")
    t("    out->saturated = 0;")
    t(f"    if (mag2 > {P}V_MAX * {P}V_MAX) {{")
    t(f"        const float k = {P}V_MAX / sqrtf(mag2);")
    t("        vds = vd * k;")
    t("        vqs = vq * k;")
    t("        out->saturated = 1;")
    t("    }")
    lines = _aw_lines(reals["d"], "d", "(vds - vd)") + _aw_lines(reals["q"], "q", "(vqs - vq)")
    if lines:
        t("    /* back-calculation anti-windup */")
        for ln in lines:
            t(ln)
    t("    out->v_d = vds;")
    t("    out->v_q = vqs;")
    t("}")


def _fixed_section(t: _Text, check: ExportCheck, N: str, P: str, artifact) -> None:
    plan = check.fixed
    t("")
    t("#ifdef CCT_FIXED_POINT")
    if plan is None:
        t(f"#error \"fixed-point variant not available: {sanitise_comment(check.fixed_reason).replace(chr(34), chr(39))}\"")
        t("#endif /* CCT_FIXED_POINT */")
        return
    t("/*")
    t(" * Fixed point: Q31 words (value / 2^31), int64 accumulators, arithmetic")
    t(" * right shifts (as gcc and arm-none-eabi implement >> on negative values).")
    t(" * Each coefficient set is an int32 mantissa vector m with one shift F:")
    t(" * c = m / 2^F (integer gains with power-of-two divisors, as STM32 MCSDK).")
    t(f" * Inputs up to I_MAX = {plan.I_MAX:.6g} A and W_MAX = {plan.W_MAX:.6g} rad/s (mechanical),")
    t(f" * voltage limit {plan.V_MAX:.6g} V: bases below are powers of two above rigorous")
    t(" * bounds of every signal and state, so no accumulator or word overflows.")
    for ax in AXES:
        if ax in check.fixed_error_bound:
            t(f" * Quantisation error bound, {ax} axis: |v_q31 - v_exact| <= "
              f"{check.fixed_error_bound[ax]:.3g} V over {HORIZON * 1e3:g} ms from equal states.")
    t(" */")
    t("#include <stdint.h>")
    t(f"#define {P}Q31_I_BASE {_f(plan.I_BASE)} /* A at full scale */")
    t(f"#define {P}Q31_V_BASE {_f(plan.V_BASE)} /* V at full scale */")
    t(f"#define {P}Q31_W_BASE {_f(plan.W_BASE)} /* mechanical rad/s at full scale */")
    t(f"#define {P}Q31_V_MAX {plan.vmax_q31}L /* V_MAX / V_BASE in Q31 */")
    for ax in AXES:
        fa = plan.axes[ax]
        for i, s in enumerate(fa.S):
            t(f"#define {P}Q31_{ax.upper()}_X{i}_BASE {_f(s)} /* state {i} full scale */")
    for name, (m, F, val) in plan.dec.items():
        t(f"#define {P}Q31_DEC_{name.upper()} {m}L /* decoupling coefficient {val:.6g} p.u. = m / 2^shift */")
        t(f"#define {P}Q31_DEC_{name.upper()}_SHIFT {F}u")
    if artifact.method in PI_METHODS:
        for ax in AXES:
            g = _pi_gains(artifact, ax)
            if g is None:
                continue
            kp, ki = g
            for label, val in (("KP", kp * plan.I_BASE / plan.V_BASE),
                               ("KI_TS", ki * artifact.sample_time * plan.I_BASE / plan.V_BASE)):
                q = _fixed._quantise_row(np.array([val]), 1)
                if q is None:
                    continue
                t(f"#define {P}Q31_{ax.upper()}_{label}_GAIN {int(q[0][0])}L /* per-unit {label}: {val:.6g} */")
                t(f"#define {P}Q31_{ax.upper()}_{label}_DIV_LOG2 {q[1]} /* divisor 2^{q[1]} */")
    t("")
    t("typedef struct {")
    t("    int32_t i_d_ref; /* Q31 of Q31_I_BASE */")
    t("    int32_t i_q_ref;")
    t("    int32_t i_d;")
    t("    int32_t i_q;")
    t("    int32_t omega_m; /* Q31 of Q31_W_BASE (mechanical) */")
    t(f"}} {N}_input_q31_t;")
    t("")
    t("typedef struct {")
    t("    int32_t v_d; /* Q31 of Q31_V_BASE */")
    t("    int32_t v_q;")
    t("    int saturated;")
    t(f"}} {N}_output_q31_t;")
    t("")
    nd = max(plan.axes["d"].S.size, 1)
    nq = max(plan.axes["q"].S.size, 1)
    t("typedef struct {")
    t(f"    int32_t d[{nd}];")
    t(f"    int32_t q[{nq}];")
    t(f"}} {N}_state_q31_t;")
    t("")
    t(f"static inline void {N}_init_q31({N}_state_q31_t *s)")
    t("{")
    t("    unsigned i;")
    t(f"    for (i = 0u; i < {nd}u; ++i) {{ s->d[i] = 0; }}")
    t(f"    for (i = 0u; i < {nq}u; ++i) {{ s->q[i] = 0; }}")
    t("}")
    t("")
    t(f"static inline int32_t {N}_sat32(int64_t v)")
    t("{")
    t("    if (v > (int64_t)INT32_MAX) { return INT32_MAX; }")
    t("    if (v < -(int64_t)INT32_MAX) { return -INT32_MAX; }")
    t("    return (int32_t)v;")
    t("}")
    t("")
    t(f"static inline int64_t {N}_shr(int64_t acc, unsigned f)")
    t("{")
    t("    return f ? (acc + ((int64_t)1 << (f - 1u))) >> f : acc;")
    t("}")
    t("")
    t(f"static inline uint32_t {N}_isqrt64(uint64_t v)")
    t("{")
    t("    uint64_t r = 0u, bit = (uint64_t)1 << 62;")
    t("    while (bit > v) { bit >>= 2; }")
    t("    while (bit != 0u) {")
    t("        if (v >= r + bit) { v -= r + bit; r = (r >> 1) + bit; } else { r >>= 1; }")
    t("        bit >>= 2;")
    t("    }")
    t("    return (uint32_t)r;")
    t("}")
    t("")
    for ax in AXES:
        fa = plan.axes[ax]
        n = fa.S.size
        t(f"/* {ax} axis: v_lin (Q31, int64 before limiting) and x <- A x + B u */")
        t(f"static inline int64_t {N}_{ax}_linear_q31(int32_t *x, int32_t r, int32_t y)")
        t("{")
        mo, Fo = fa.out
        t(f"    static const int32_t co[{n + 2}] = {{ {', '.join(f'{int(v)}L' for v in mo)} }};")
        if n:
            t(f"    static const int32_t ca[{n * (n + 3)}] = {{")
            for m, F in fa.rows:
                t(f"        {', '.join(f'{int(v)}L' for v in m)},")
            t("    };")
            t(f"    static const unsigned fa[{n}] = {{ {', '.join(f'{F}u' for _, F in fa.rows)} }};")
            t(f"    int32_t xn[{n}];")
            t("    unsigned i, j;")
        t(f"    int64_t acc = (int64_t)co[{n}] * r + (int64_t)co[{n + 1}] * y;")
        if n:
            t(f"    for (j = 0u; j < {n}u; ++j) {{ acc += (int64_t)co[j] * x[j]; }}")
        t(f"    acc = {N}_shr(acc, {Fo}u);")
        if n:
            t(f"    for (i = 0u; i < {n}u; ++i) {{")
            t(f"        const int32_t *m = &ca[{n + 3}u * i];")
            t(f"        int64_t a = (int64_t)m[{n}] * r + (int64_t)m[{n + 1}] * y;")
            t(f"        for (j = 0u; j < {n}u; ++j) {{ a += (int64_t)m[j] * x[j]; }}")
            t(f"        xn[i] = {N}_sat32({N}_shr(a, fa[i]));")
            t("    }")
            t(f"    for (i = 0u; i < {n}u; ++i) {{ x[i] = xn[i]; }}")
        else:
            t("    (void)x;")
        t("    return acc;")
        t("}")
        t("")
        t(f"static inline void {N}_{ax}_antiwindup_q31(int32_t *x, int64_t dv)")
        t("{")
        if n and any(m[n + 2] != 0 for m, _ in fa.rows):
            t(f"    static const int32_t aw[{n}] = {{ {', '.join(f'{int(m[n + 2])}L' for m, _ in fa.rows)} }};")
            t(f"    static const unsigned fa[{n}] = {{ {', '.join(f'{F}u' for _, F in fa.rows)} }};")
            t("    unsigned i;")
            t(f"    for (i = 0u; i < {n}u; ++i) {{")
            t(f"        x[i] = {N}_sat32((int64_t)x[i] + {N}_shr((int64_t)aw[i] * dv, fa[i]));")
            t("    }")
        else:
            t("    (void)x;")
            t("    (void)dv;")
        t("}")
        t("")
    t(f"static inline void {N}_step_q31({N}_state_q31_t *s, const {N}_input_q31_t *in, {N}_output_q31_t *out)")
    t("{")
    t(f"    const int64_t vd_lin = {N}_d_linear_q31(s->d, in->i_d_ref, in->i_d);")
    t(f"    const int64_t vq_lin = {N}_q_linear_q31(s->q, in->i_q_ref, in->i_q);")
    t(f"    const int64_t wiq = {N}_shr((int64_t)in->omega_m * in->i_q, 31u);")
    t(f"    const int64_t wid = {N}_shr((int64_t)in->omega_m * in->i_d, 31u);")
    t(f"    const int64_t vd = vd_lin + {N}_shr((int64_t){P}Q31_DEC_DD * wiq, {P}Q31_DEC_DD_SHIFT);")
    t(f"    const int64_t vq = vq_lin + {N}_shr((int64_t){P}Q31_DEC_DQ * wid, {P}Q31_DEC_DQ_SHIFT)")
    t(f"                     + {N}_shr((int64_t){P}Q31_DEC_DE * in->omega_m, {P}Q31_DEC_DE_SHIFT);")
    t(f"    const int64_t vdc = {N}_sat32(vd);")
    t(f"    const int64_t vqc = {N}_sat32(vq);")
    t("    const uint64_t mag2 = (uint64_t)(vdc * vdc) + (uint64_t)(vqc * vqc);")
    t("    int64_t vds = vdc;")
    t("    int64_t vqs = vqc;")
    t("    out->saturated = 0;")
    t(f"    if (mag2 > (uint64_t){P}Q31_V_MAX * (uint64_t){P}Q31_V_MAX) {{")
    t(f"        const int64_t mag = (int64_t){N}_isqrt64(mag2);")
    t(f"        vds = (vdc * {P}Q31_V_MAX) / mag;")
    t(f"        vqs = (vqc * {P}Q31_V_MAX) / mag;")
    t("        out->saturated = 1;")
    t("    }")
    t(f"    {N}_d_antiwindup_q31(s->d, vds - vd);")
    t(f"    {N}_q_antiwindup_q31(s->q, vqs - vq);")
    t("    out->v_d = (int32_t)vds;")
    t("    out->v_q = (int32_t)vqs;")
    t("}")
    t("#endif /* CCT_FIXED_POINT */")


def write_header(artifact, motor=None, drive=None, *, name: str = "cct",
                 title: str | None = None) -> str:
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
    title : str, optional
        Title for the provenance comment (default: ``artifact.spec["title"]``);
        sanitised by :func:`sanitise_comment`.

    Returns
    -------
    str
        The header text (the CLI writes it atomically).

    Raises
    ------
    SpecError
        Refused controller (see :func:`check_exportable`), bad ``name``.
    """
    if not isinstance(name, str) or not _IDENT.match(name):
        raise SpecError("export.name", "a C identifier of at most 31 characters", name)
    motor, drive = _motor_drive(artifact, motor, drive)
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
    t("#include <math.h> /* sqrtf */")
    t("")
    _defines(t, artifact, motor, drive, P, check)
    t("")
    for ax in AXES:
        r = check.realisations[ax]
        if r.form == "sos":
            t(f"#define {P}{ax.upper()}_GAIN {_f(r.gain)} /* {ax} axis SOS output gain, V/A */")
            t(f"#define {P}{ax.upper()}_NUM_STAGES {r.sos.shape[0]}")
    t("")
    _float_section(t, check.realisations, N, P)
    _fixed_section(t, check, N, P, artifact)
    t("")
    t(f"#endif /* {guard} */")
    return t.text()
