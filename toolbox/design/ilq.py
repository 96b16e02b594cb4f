"""Inverse-LQ (ILQ) optimal servo current control (paper 001).

H. Takami, "Robust current control for permanent magnet synchronous motors by
the inverse LQ method", JPE 4-4 (2004). Equation numbers refer to it.

Per axis (after decoupling) the plant is eq (1), ``di/dt = a i + b u`` with
``a = -R/L`` (1/s) and ``b = 1/L`` (1/H). The basic gains of eq (2) (damaged
in the text copy, re-derived here) are ``K_F0 = L`` and ``K_I0 = -L s*``; the
tuned gains are ``K_F = sigma K_F0``, ``K_I = sigma K_I0`` and the law is the
one-degree-of-freedom servo of Fig. 1 / Fig. 2(a)::

    u = -K_F i + K_I * integral(i_ref - i)      (plus decoupling, Fig. 2a)

so that the closed loop has the characteristic equation (4)
``s^2 + (sigma - a) s - sigma s* = 0``. The gains are LQ-optimal iff sigma
exceeds the bound of eq (3), ``2 (a - s*)`` when ``s* < a`` (else 0).

Inverse LQ (the weights for which the gain is optimal) on the servo state
``x = [i, z]``, ``z' = i_ref - i``, ``u = -K x`` with ``K = [K_F, -K_I]``:
with ``R`` fixed, ``P B = K' R`` fixes the first column of ``P``; the free
entry ``P22`` is chosen to make ``Q`` diagonal, which gives the closed form

    Q = R diag(K_F^2 (1 - 2 (a - s*)/sigma), K_I^2),

PSD exactly when eq (3) holds. :func:`inverse_lq_sdp` solves the same question
as a semidefinite programme (cvxpy + CLARABEL) as an independent route, and
:func:`inverse_lq` re-solves the CARE with the weights to recover the gains.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla

from ..lti import StateSpace, as_statespace
from ..artifact import AxisController, ControllerArtifact
from ..errors import SpecError
from ..plant import axis_coefficients
from ..spec import Table
from . import _defaults
from ._common import decoupling_from_motor, make_artifact

__all__ = ["IlqCfg", "IlqAxis", "IlqDesign", "sigma_bound", "ilq_axis", "ilq_axis_from_plant",
           "first_order_coefficients", "servo_matrices",
           "inverse_lq", "inverse_lq_sdp", "design_ilq", "read_cfg", "design"]

_KEY = "controller.ilq"
AXES = ("d", "q")


@dataclass(frozen=True)
class IlqCfg:
    """Validated ``[controller.ilq]``.

    Attributes
    ----------
    poles : tuple of float
        Assigned poles ``(s1*, s2*)`` of the d and q axes (rad/s, < 0).
    sigma : tuple of float
        Gain-adjusting parameters ``(sigma_1, sigma_2)`` (1/s, > 0).
    allow_non_optimal : bool
        Accept sigma at or below the bound of eq (3) with a warning.
    defaults : dict or None
        The default poles and the rule that gave them (no poles in the spec).
    """

    poles: tuple[float, float]
    sigma: tuple[float, float]
    allow_non_optimal: bool = False
    defaults: dict | None = None

    def to_spec(self, spec=None) -> dict[str, Any]:
        """``[controller.ilq]`` keys that read back to this configuration:
        ``poles`` and ``sigma`` per axis (whatever default or factor gave
        them) and ``allow_non_optimal``.

        Parameters
        ----------
        spec : Spec, optional
            Unused (same signature as the other methods' ``to_spec``).

        Returns
        -------
        dict
        """
        return {"poles": {"d": float(self.poles[0]), "q": float(self.poles[1])},
                "sigma": {"d": float(self.sigma[0]), "q": float(self.sigma[1])},
                "allow_non_optimal": bool(self.allow_non_optimal)}


def sigma_bound(a: float, s_star: float) -> float:
    """Lower bound of sigma for LQ optimality, eq (3) (1/s).

    Parameters
    ----------
    a : float
        Plant pole ``-R/L`` (1/s).
    s_star : float
        Assigned pole (rad/s, < 0).

    Returns
    -------
    float
        ``2 (a - s*)`` when ``s* < a``, else 0.
    """
    return 2.0 * (a - s_star) if s_star < a else 0.0


def _check_sigma(sigma: float, bound: float, axis: str, allow: bool) -> bool:
    """True when optimal; raise or warn otherwise (eq 3)."""
    if sigma > bound:
        return True
    text = (f"sigma_{axis} > the optimality bound of Takami eq (3), "
            f"2(a - s*) = {bound:.6g} 1/s" if bound > 0 else
            f"sigma_{axis} > 0 (eq (3) bound is 0 since a <= s*)")
    if not allow:
        raise SpecError(f"{_KEY}.sigma", text, sigma,
                        hint="raise sigma, or set allow_non_optimal = true")
    warnings.warn(f"{_KEY}.sigma: {sigma:g} does not satisfy {text}; the gains are "
                  "not LQ-optimal (no inverse-LQ weights exist)", RuntimeWarning, stacklevel=3)
    return False


def servo_matrices(a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """Servo-augmented plant on ``x = [i, z]``, ``z' = i_ref - i`` (i_ref = 0).

    Returns
    -------
    A : ndarray, shape (2, 2)
        ``[[a, 0], [-1, 0]]`` (1/s).
    B : ndarray, shape (2, 1)
        ``[[b], [0]]`` (1/H).
    """
    return np.array([[a, 0.0], [-1.0, 0.0]]), np.array([[b], [0.0]])


def inverse_lq(a: float, b: float, K_F: float, K_I: float,
               R_weight: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Closed-form inverse LQ weights of one axis, verified through the CARE.

    Parameters
    ----------
    a, b : float
        Plant ``di/dt = a i + b u`` (1/s, 1/H).
    K_F, K_I : float
        ILQ gains (V/A, V/(A s)).
    R_weight : float
        Input weight (1/V^2), > 0.

    Returns
    -------
    Q : ndarray (2, 2)
        State weight on ``[i, z]`` (diagonal).
    R : ndarray (1, 1)
    P : ndarray (2, 2)
        Riccati solution (``R^-1 B' P = K``).
    care_error : float
        Relative error ``|K_care - K| / |K|`` of the gains recovered by
        ``scipy.linalg.solve_continuous_are`` with (Q, R).
    """
    K1, K2 = K_F, -K_I
    r = float(R_weight)
    P11, P12 = r * K1 / b, r * K2 / b
    P22 = r * K2 * (a / b - K1)                      # makes Q12 = 0
    Q = np.diag([r * K1 ** 2 - 2 * a * P11 + 2 * P12, r * K2 ** 2])
    P = np.array([[P11, P12], [P12, P22]])
    A, B = servo_matrices(a, b)
    R = np.array([[r]])
    P_care = sla.solve_continuous_are(A, B, Q, R)
    K_care = (B.T @ P_care) / r
    K = np.array([[K1, K2]])
    return Q, R, P, float(np.linalg.norm(K_care - K) / np.linalg.norm(K))


def inverse_lq_sdp(a: float, b: float, K_F: float, K_I: float,
                   R_weight: float = 1.0) -> tuple[float, np.ndarray, np.ndarray]:
    """Inverse LQ as a semidefinite programme (cvxpy + CLARABEL).

    Find symmetric ``P`` with ``R^-1 B' P = K`` (linear), ``P >= 0`` and
    ``Q = K' R K - A' P - P A >= t S``, maximising ``t``, with the scaling
    ``S = R diag(K_F^2, K_I^2)``. The gains are LQ-optimal iff ``t >= 0``;
    the closed form gives ``t = min(1, 1 - bound/sigma)`` for the ILQ gains.

    Parameters
    ----------
    a, b : float
        Plant ``di/dt = a i + b u`` (1/s, 1/H).
    K_F, K_I : float
        Gains to test (V/A, V/(A s)).
    R_weight : float
        Input weight (1/V^2), > 0.

    Returns
    -------
    t : float
        Optimal margin (dimensionless).
    P, Q : ndarray
    """
    import cvxpy as cp  # lazy: cvxpy, 819 modules (inverse_lq_sdp only)

    A, B = servo_matrices(a, b)
    K = np.array([[K_F, -K_I]])
    r = float(R_weight)
    S = r * np.diag([K_F ** 2, K_I ** 2])
    D = np.diag(1.0 / np.sqrt(np.diag(S)))          # scale to O(1)
    P = cp.Variable((2, 2), symmetric=True)
    t = cp.Variable()
    Q = r * K.T @ K - A.T @ P - P @ A
    Qs = D @ Q @ D
    cons = [P @ B == K.T * r, (Qs + Qs.T) / 2 - t * np.eye(2) >> 0, P >> 0, t <= 10]
    prob = cp.Problem(cp.Maximize(t), cons)
    with warnings.catch_warnings():     # infeasible cases end "optimal_inaccurate"
        warnings.simplefilter("ignore")
        prob.solve(solver=cp.CLARABEL)
    if prob.status not in ("optimal", "optimal_inaccurate"):
        raise RuntimeError(f"inverse LQ SDP: solver status {prob.status}")
    Qv = r * K.T @ K - A.T @ P.value - P.value @ A
    return float(t.value), np.array(P.value), np.array(Qv)


@dataclass(frozen=True)
class IlqAxis:
    """ILQ design of one axis (eq 1-4).

    Attributes
    ----------
    a, b : float
        Plant coefficients (1/s, 1/H).
    s_star, sigma, bound : float
        Assigned pole (rad/s), tuning parameter and its eq (3) bound (1/s).
    K_F0, K_I0, K_F, K_I : float
        Basic and tuned gains (V/A, V/(A s)), eq (2).
    poles : ndarray
        Closed-loop roots of eq (4) (rad/s).
    optimal : bool
    Q, R, P : ndarray or None
        Inverse-LQ weights and Riccati solution (None when not optimal).
    care_error : float or None
    """

    a: float
    b: float
    s_star: float
    sigma: float
    bound: float
    K_F0: float
    K_I0: float
    K_F: float
    K_I: float
    poles: np.ndarray
    optimal: bool
    Q: np.ndarray | None = None
    R: np.ndarray | None = None
    P: np.ndarray | None = None
    care_error: float | None = None

    def law(self) -> StateSpace:
        """Continuous two-input law ``[i_ref, i] -> u`` (state ``z``), Fig. 2(a)."""
        return StateSpace([[0.0]], [[1.0, -1.0]], [[self.K_I]], [[0.0, -self.K_F]])

    def error_controller(self) -> StateSpace:
        """Equivalent error -> voltage controller ``K_F + K_I/s`` (V/A)."""
        return StateSpace([[0.0]], [[1.0]], [[self.K_I]], [[self.K_F]])


def ilq_axis(R: float, L: float, s_star: float, sigma: float, *, axis: str = "q",
             allow_non_optimal: bool = False, R_weight: float = 1.0) -> IlqAxis:
    """ILQ gains of one axis from eq (1)-(4).

    Parameters
    ----------
    R, L : float
        Resistance (ohm) and inductance (H) of the axis.
    s_star : float
        Assigned pole (rad/s), < 0.
    sigma : float
        Tuning parameter (1/s), > 0.
    axis : str
        Axis name for messages.
    allow_non_optimal : bool
        Warn instead of raising when sigma <= the eq (3) bound.
    R_weight : float
        Input weight of the inverse-LQ problem (1/V^2).

    Returns
    -------
    IlqAxis

    Raises
    ------
    SpecError
        ``controller.ilq.poles`` for a non-negative pole,
        ``controller.ilq.sigma`` for sigma <= 0 or below the bound.
    """
    if not (math.isfinite(s_star) and s_star < 0):
        raise SpecError(f"{_KEY}.poles", f"a stable assigned pole s{AXES.index(axis) + 1}* < 0 "
                        f"(rad/s) for the {axis} axis", s_star)
    if not (math.isfinite(sigma) and sigma > 0):
        raise SpecError(f"{_KEY}.sigma", "a number > 0 (1/s)", sigma)
    a, b = axis_coefficients(R, L)                       # eq (1)
    bound = sigma_bound(a, s_star)                       # eq (3)
    optimal = _check_sigma(sigma, bound, axis, allow_non_optimal)
    K_F0, K_I0 = L, -L * s_star                          # eq (2)
    K_F, K_I = sigma * K_F0, sigma * K_I0
    poles = np.roots([1.0, sigma - a, -sigma * s_star])  # eq (4)
    Q = Rw = P = err = None
    if optimal:
        Q, Rw, P, err = inverse_lq(a, b, K_F, K_I, R_weight)
    return IlqAxis(a, b, s_star, sigma, bound, K_F0, K_I0, K_F, K_I, poles, optimal,
                   Q, Rw, P, err)


def first_order_coefficients(G: Any) -> tuple[float, float]:
    """``(a, b)`` of a first-order plant ``G(s) = b/(s - a)``, e.g. ``1/(R + s L)``.

    Parameters
    ----------
    G : toolbox.lti.StateSpace or python-control LTI
        SISO, one state, no feedthrough (A/V).

    Returns
    -------
    a : float
        Plant pole (1/s), ``-R/L``.
    b : float
        Input gain (1/H), ``1/L``.

    Raises
    ------
    ValueError
        G is not a strictly proper first-order SISO system.
    """
    sys = as_statespace(G)
    if sys.ninputs != 1 or sys.noutputs != 1 or sys.nstates != 1 or abs(float(sys.D[0, 0])) > 0:
        raise ValueError("first_order_coefficients: expected a strictly proper first-order "
                         f"SISO plant b/(s - a), got {sys.nstates} states, "
                         f"{sys.ninputs} inputs, {sys.noutputs} outputs")
    return float(sys.A[0, 0]), float(sys.B[0, 0] * sys.C[0, 0])


def ilq_axis_from_plant(G: Any, s_star: float, sigma: float, **options: Any) -> IlqAxis:
    """ILQ design of one axis from a plant ``1/(R + s L)``.

    Parameters
    ----------
    G : toolbox.lti.StateSpace or python-control LTI
        First-order plant (A/V), e.g. ``axis_plant_models(motor)["q"]``.
    s_star : float
        Assigned pole (rad/s), < 0.
    sigma : float
        Tuning parameter (1/s).
    **options
        ``axis``, ``allow_non_optimal``, ``R_weight`` as for :func:`ilq_axis`.

    Returns
    -------
    IlqAxis
    """
    a, b = first_order_coefficients(G)
    L = 1.0 / b
    return ilq_axis(-a * L, L, s_star, sigma, **options)


@dataclass(frozen=True)
class IlqDesign:
    """Both axes of an ILQ design.

    Attributes
    ----------
    axes : dict of str to IlqAxis
    sample_time : float
        Controller period (s).
    """

    axes: dict[str, IlqAxis]
    sample_time: float
    notes: list[str] = field(default_factory=list)

    def gains(self) -> dict[str, Any]:
        """Named gains for the artifact (plain data)."""
        d, q = self.axes["d"], self.axes["q"]
        g: dict[str, Any] = {
            "K_F0": [[d.K_F0, 0.0], [0.0, q.K_F0]],
            "K_I0": [[d.K_I0, 0.0], [0.0, q.K_I0]],
            "Sigma": [[d.sigma, 0.0], [0.0, q.sigma]],
            "K_F": [[d.K_F, 0.0], [0.0, q.K_F]],
            "K_I": [[d.K_I, 0.0], [0.0, q.K_I]],
            "s_star": {"d": d.s_star, "q": q.s_star},
            "sigma": {"d": d.sigma, "q": q.sigma},
            "sigma_bound": {"d": d.bound, "q": q.bound},
            "closed_loop_poles": {k: [complex(p) for p in v.poles] for k, v in self.axes.items()},
            "optimal": bool(d.optimal and q.optimal),
            "inverse_lq_state": "[i, integral(i_ref - i)], u = -[K_F, -K_I] x",
        }
        if d.optimal and q.optimal:
            g["Q"] = {k: v.Q for k, v in self.axes.items()}
            g["R"] = {k: v.R for k, v in self.axes.items()}
            g["care_gain_rel_error"] = {k: v.care_error for k, v in self.axes.items()}
        return g


def design_ilq(Ld: float, Lq: float, R: float, poles: tuple[float, float],
               sigma: tuple[float, float], sample_time: float, *,
               allow_non_optimal: bool = False, R_weight: float = 1.0) -> IlqDesign:
    """ILQ design of both axes (eq 1-4) with inverse-LQ weights.

    Parameters
    ----------
    Ld, Lq : float
        Inductances (H).
    R : float
        Resistance (ohm).
    poles : (float, float)
        Assigned poles ``(s1*, s2*)`` (rad/s, < 0).
    sigma : (float, float)
        ``(sigma_1, sigma_2)`` (1/s).
    sample_time : float
        Controller period (s).
    allow_non_optimal : bool
        Warn instead of raising below the eq (3) bound.
    R_weight : float
        Input weight of the inverse LQ problem (1/V^2).

    Returns
    -------
    IlqDesign

    Examples
    --------
    >>> des = design_ilq(1.788e-3, 1.788e-3, 0.4, (-1000.0, -1000.0), (5000.0, 5000.0), 1e-4)
    >>> round(des.axes["q"].K_F, 3)
    8.94
    """
    axes = {ax: ilq_axis(R, L, p, s, axis=ax, allow_non_optimal=allow_non_optimal,
                         R_weight=R_weight)
            for ax, L, p, s in zip(AXES, (Ld, Lq), poles, sigma)}
    return IlqDesign(axes, sample_time)


def read_cfg(method: str, table, motor, drive) -> IlqCfg:
    """Validate ``[controller.ilq]``.

    Keys: ``poles`` (number or {d=, q=}, rad/s, < 0) or ``s1``/``s2``;
    ``sigma`` (number or {d=, q=}, 1/s) or ``sigma_factor`` (sigma = factor x
    eq (3) bound, > 1; default 2); ``allow_non_optimal`` (default false).

    Parameters: as :func:`toolbox.design.read_method_cfg`.

    Returns
    -------
    IlqCfg

    Raises
    ------
    SpecError
        Unknown keys, missing poles, non-negative poles, sigma <= 0, sigma at or
        below the eq (3) bound (unless ``allow_non_optimal``).
    """
    t = Table(table.data, table.prefix,
              ("poles", "s1", "s2", "sigma", "sigma_factor", "allow_non_optimal"))
    if t.has("poles") and (t.has("s1") or t.has("s2")):
        raise SpecError(t.key("poles"), "either poles or s1/s2, not both")
    default_note = None
    if t.has("poles"):
        poles = t.per_axis("poles", negative=True, unit="rad/s")
    elif t.has("s1") or t.has("s2"):
        poles = (t.number("s1", negative=True, unit="rad/s"),
                 t.number("s2", negative=True, unit="rad/s"))
    else:
        poles, default_note = _default_poles(t, motor, drive)
    allow = t.boolean("allow_non_optimal", False)
    bounds = tuple(sigma_bound(axis_coefficients(motor.R, L)[0], p)
                   for L, p in zip((motor.Ld, motor.Lq), poles))
    if t.has("sigma") and t.has("sigma_factor"):
        raise SpecError(t.key("sigma"), "either sigma or sigma_factor, not both")
    if t.has("sigma"):
        # sigma Ts is the discrete loop gain scale (paper 001's case: 0.25);
        # above 100 per sample period the sampled loop is far unstable
        sigma = t.per_axis("sigma", positive=True, maximum=100.0 / drive.sample_time,
                           unit="1/s")
    else:
        # sigma is the closed-loop speed scale; 1000 x the optimality bound is
        # far past any loop the sampling can realise
        factor = t.number("sigma_factor", 2.0, positive=True, maximum=1e3)
        if min(bounds) <= 0:
            raise SpecError(t.key("sigma_factor"), "an eq (3) bound > 0 on both axes to scale "
                            "(the bound is 0 when a <= s*)", factor, hint="give sigma instead")
        sigma = tuple(factor * b for b in bounds)
    for ax, s, b in zip(AXES, sigma, bounds):
        _check_sigma(s, b, ax, allow)
    return IlqCfg(poles=poles, sigma=sigma, allow_non_optimal=allow, defaults=default_note)


def _default_poles(t: Table, motor, drive) -> tuple[tuple[float, float], dict | None]:
    """Assigned poles from the sample time and delay when the spec gives none.

    With ``sigma = factor x 2 (a - s*)`` (eq 3, ``a = -R/L``) the loop
    crosses over near ``sigma`` (``K_F = sigma L``) with its integral zero at
    ``-s*``; ``s* = a - wc/(2 factor)`` makes ``sigma = wc``, the default
    crossover of :func:`toolbox.design._defaults.default_bandwidth` (for the
    default factor 2 the zero sits at ``wc/4 + R/L``, counted in ``wc``).
    An explicit ``sigma`` keeps ``wc = sigma``'s axis value instead.
    """
    bw = _defaults.default_bandwidth(drive, zero=True)
    if t.has("sigma"):
        wc = t.per_axis("sigma", positive=True, unit="1/s")
        factor = 2.0
    else:
        wc = (bw.value, bw.value)
        factor = t.number("sigma_factor", 2.0, positive=True, maximum=1e3)
    poles = tuple(axis_coefficients(motor.R, L)[0] - w / (2.0 * factor)
                  for L, w in zip((motor.Ld, motor.Lq), wc))
    return poles, {"poles": {**bw.as_dict(),
                             "s_star": f"s* = -R/L - wc/(2 sigma_factor), sigma_factor {factor:g}",
                             "d": poles[0], "q": poles[1]}}


def design(spec) -> ControllerArtifact:
    """ILQ artifact from a validated spec (method ``ilq``).

    The executed law is the Fig. 2(a) servo, continuous, discretised with
    Tustin at ``drive.sample_time``; the axis error controller is
    ``K_F + K_I/s``. Decoupling: cross-coupling and back-EMF with the motor's
    nominal parameters (no resistance term: the ILQ law does not use r_1).

    Parameters
    ----------
    spec : Spec
        Validated spec with ``controller.method = "ilq"``.

    Returns
    -------
    ControllerArtifact
    """
    cfg: IlqCfg = spec.controller.cfg
    m, ts = spec.motor, spec.drive.sample_time
    with warnings.catch_warnings():
        if cfg.allow_non_optimal:
            warnings.simplefilter("ignore", RuntimeWarning)   # already warned in read_cfg
        des = design_ilq(m.Ld, m.Lq, m.R, cfg.poles, cfg.sigma, ts,
                         allow_non_optimal=cfg.allow_non_optimal)
    axes = {ax: AxisController.from_law(des.axes[ax].law(), sample_time=ts, method="tustin",
                                        error_controller=des.axes[ax].error_controller())
            for ax in AXES}
    gains = des.gains()
    if cfg.defaults:
        gains["defaults"] = cfg.defaults
    return make_artifact(spec, axes, decoupling_from_motor(m), gains,
                         ["001 eq (1)", "001 eq (2)", "001 eq (3)", "001 eq (4)", "001 Fig. 2(a)"])
