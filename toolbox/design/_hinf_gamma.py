"""Gamma iteration and synthesis of the central H-infinity controller (paper 003).

The smallest feasible gamma by plain bisection on Theorem 1
(:mod:`._hinf_riccati`), the back-off that keeps the controller realisable
at the sample time (at the exact optimum 003's q-axis controller has a pole
near -2e10 rad/s, toolbox/ARCHITECTURE.md "H-infinity numerics"), and the
recomputed closed-loop norm (SLICOT ab13dd through :func:`toolbox.lti.hinf_norm`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..lti import StateSpace, hinf_norm
from ..errors import DesignInfeasible, SpecError
from ._hinf_plant import PartitionedPlant, _lft, _poles_zeros
from ._hinf_riccati import (GAMMA_KEY, _check_gamma, _controller_from, _prepare, _Prepared,
                            _unscale_xy)

__all__ = ["GammaBelowOptimum", "gamma_iteration", "HinfResult", "synthesize", "pole_limit",
           "effective_poles", "fastest_pole_modulus"]


class GammaBelowOptimum(DesignInfeasible):
    """A fixed ``gamma`` below the best achievable one (Theorem 1 fails).

    Carries the failed condition as data so callers branch on the class and
    read :attr:`condition`, never on message text.

    Attributes
    ----------
    condition : str
        The condition of Theorem 1 that failed (words, for the message).
    best : float
        Best achievable gamma of this problem (nan if unknown).
    axis : str
        ``"d"`` or ``"q"`` once :func:`toolbox.design.hinf.design_hinf_axis`
        located it (empty before).
    """

    condition: str = ""
    best: float = float("nan")
    axis: str = ""

    def _copy(self, key: str, file: str | None) -> "GammaBelowOptimum":
        new = super()._copy(key, file)
        new.condition, new.best = self.condition, self.best
        return new



# --------------------------------------------------------------------------
# gamma iteration
# --------------------------------------------------------------------------
def gamma_iteration(P: PartitionedPlant, tol: float = 1e-4,
                    gamma_max: float | None = None) -> float:
    """Smallest feasible gamma by bisection on Theorem 1 (relative tolerance).

    The lower end of the bracket is the D11 bound of condition (a) (no
    controller can do better); the upper end starts at max(1, 2 * lower)
    and doubles until feasible.  Bisection stops when
    ``(hi - lo) <= tol * hi``; the feasible end ``hi`` is returned, so the
    result is feasible and at most ``tol`` (relative) above the optimum.

    Parameters
    ----------
    P : PartitionedPlant
    tol : float
        Relative tolerance on gamma, default 1e-4.
    gamma_max : float, optional
        Give up above this level (default 1e8).

    Returns
    -------
    float
        gamma_opt (within ``tol``), dimensionless.

    Raises
    ------
    SpecError
        No feasible gamma up to ``gamma_max`` (key ``controller.hinf.gamma``).
    """
    return _gamma_iteration(_prepare(P), tol, gamma_max)


def _gamma_iteration(prep: _Prepared, tol: float, gamma_max: float | None) -> float:
    """:func:`gamma_iteration` on a prepared plant (Theorem 1 tested at every level)."""
    lo = prep.gf.bound
    top = 1e8 if gamma_max is None else float(gamma_max)
    hi = min(max(1.0, 2.0 * lo), top)
    while not prep.feasibility(hi).feasible:
        if hi >= top:
            raise DesignInfeasible(GAMMA_KEY, f"a problem feasible for some gamma <= {top:g}",
                                   hint="no controller reaches it: raise gamma_max or relax "
                                        "the weights w1/w3")
        lo, hi = hi, min(2.0 * hi, top)
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if prep.feasibility(mid).feasible else (mid, hi)
    return hi


# --------------------------------------------------------------------------
# realisability of the controller at a sample time
# --------------------------------------------------------------------------
def pole_limit(sample_time: float, factor: float = 1.0) -> float:
    """Largest controller pole magnitude realisable at ``sample_time`` (rad/s).

    The limit is ``factor * pi / sample_time``, the Nyquist frequency: a
    controller running every ``sample_time`` seconds cannot represent
    dynamics faster than that (Tustin maps such a pole next to z = -1, ZOH
    next to z = 0, and the discrete controller is then badly conditioned and
    no longer behaves like the design).  For Ts = 1e-4 s this is 31 416 rad/s,
    above the q-axis crossover (145 rad/s) by a factor of 200.

    Parameters
    ----------
    sample_time : float
        Controller period (s), > 0.
    factor : float
        Multiplier of the Nyquist frequency, default 1.

    Returns
    -------
    float
        Limit (rad/s).
    """
    if not (np.isfinite(sample_time) and sample_time > 0):
        raise SpecError("drive.sample_time", "a number > 0 (s)", sample_time)
    return float(factor * np.pi / sample_time)


def effective_poles(K: Any, cancel_tol: float = 1e-2) -> np.ndarray:
    """Poles of K that are not nearly cancelled by a zero.

    A pole p counts as cancelled when a zero z has |z - p| <= cancel_tol * |p|
    (default 1 %): the pair then changes |K| by at most about 1 % at every
    frequency and can be removed without effect (see
    :func:`toolbox.design._reduction.remove_cancellations`).  In paper 003,
    eq (68), the pole 2.717e6 faces the zero 2.714e6 (0.1 % apart).

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
        SISO controller.
    cancel_tol : float
        Relative distance below which a pole-zero pair is a cancellation.

    Returns
    -------
    ndarray of complex
        The remaining poles (rad/s).
    """
    return _effective_poles(*_poles_zeros(K), cancel_tol)


def _effective_poles(poles: np.ndarray, zeros: np.ndarray, cancel_tol: float) -> np.ndarray:
    """:func:`effective_poles` of the given poles and zeros."""
    # Python complex numbers: the same differences and moduli (libm's hypot)
    # as numpy's scalars, at a third of their cost (numpy's vectorised hypot
    # on arrays would differ in the last bit; its scalars do not)
    z = zeros.tolist()
    keep = []
    for pi in sorted(poles.tolist(), key=abs):
        d = [abs(zi - pi) for zi in z]
        if d and min(d) <= cancel_tol * max(abs(pi), 1e-300):
            z.pop(d.index(min(d)))
        else:
            keep.append(pi)
    return np.array(keep, dtype=complex)


def fastest_pole_modulus(K: Any) -> float:
    """Largest ``|s|`` of the controller's effective poles (rad/s), 0 if none.

    Compared with :func:`pole_limit` (``pi/Ts``) to decide whether ``K`` can
    be discretised at the sample time (paper 003 sect. 4 trap at the optimum).
    """
    ep = _effective_poles(*_poles_zeros(K), 1e-2)
    return float(np.abs(ep).max()) if ep.size else 0.0


# --------------------------------------------------------------------------
# synthesis with back-off and a posteriori checks
# --------------------------------------------------------------------------
@dataclass
class HinfResult:
    """Everything :func:`synthesize` found.

    Attributes
    ----------
    K : toolbox.lti.StateSpace
        Central controller, error (A) -> voltage (V).
    gamma : float
        Level the controller was designed for.
    gamma_opt : float or None
        Optimal level from :func:`gamma_iteration` (None for a fixed gamma).
    backoff : float
        Relative back-off finally used (0 for a fixed gamma).
    X, Y : ndarray
        Riccati solutions of eq (18)-(19) at ``gamma``.
    closed_loop_norm : float
        ||F_l(P, K)||_inf recomputed (LFT + :func:`toolbox.lti.hinf_norm`).
    fastest_pole : float
        Largest |pole| of K that is not nearly cancelled (rad/s).
    pole_limit : float or None
        Realisability limit used (rad/s), None without a sample time.
    warnings : list of str
        Every oddity found (also issued through ``warnings.warn``).
    """

    K: StateSpace
    gamma: float
    gamma_opt: float | None
    backoff: float
    X: np.ndarray
    Y: np.ndarray
    closed_loop_norm: float
    fastest_pole: float
    pole_limit: float | None
    warnings: list[str] = field(default_factory=list)



def synthesize(P: PartitionedPlant, gamma: float | Literal["optimal"] = "optimal",
               backoff: float = 0.05, sample_time: float | None = None,
               tol: float = 1e-4, max_backoff: float = 2.0) -> HinfResult:
    """Design the central H-infinity controller, refusing unrealisable ones.

    With ``gamma="optimal"`` the optimum is found by :func:`gamma_iteration`
    and the controller is designed at ``(1 + backoff) * gamma_opt``: at the
    optimum itself the central controller of paper 003's q axis has a pole
    that runs off to minus infinity (python-control's ``mixsyn`` returns one
    near -6e9 .. -2e10 rad/s).  With a ``sample_time`` the back-off is then
    doubled until no (non-cancelled) controller pole is faster than
    :func:`pole_limit`; if ``max_backoff`` is reached a warning says so.
    Finally the closed-loop norm is recomputed independently and a mismatch
    with gamma is reported.

    Parameters
    ----------
    P : PartitionedPlant
    gamma : float or "optimal"
        Fixed level (e.g. 1 as in paper 003 sect. 3.3) or "optimal".
    backoff : float
        Initial relative back-off for "optimal", >= 0 (default 0.05).
    sample_time : float, optional
        Controller period (s) for the realisability test.
    tol : float
        Relative tolerance of the gamma iteration.
    max_backoff : float
        Largest back-off tried.

    Returns
    -------
    HinfResult

    Raises
    ------
    SpecError
        A fixed gamma below the optimum (key ``controller.hinf.gamma``; the
        message names the failed condition and gives the best achievable
        gamma), a bad ``backoff`` or violated assumptions A1-A4.
    """
    if not (isinstance(backoff, (int, float)) and math.isfinite(backoff) and backoff >= 0):
        raise SpecError("controller.hinf.backoff", "a number >= 0", backoff)
    prep = _prepare(P)
    notes: list[str] = []
    limit = pole_limit(sample_time) if sample_time is not None else None
    if isinstance(gamma, str):
        if gamma != "optimal":
            raise SpecError(GAMMA_KEY, 'a number > 0 or "optimal"', gamma)
        gamma_opt = _gamma_iteration(prep, tol, None)
        b = float(backoff)
        while True:
            res = prep.feasibility((1.0 + b) * gamma_opt)
            K = StateSpace._unchecked(*_controller_from(prep, res)) if res.feasible else None
            fast = fastest_pole_modulus(K) if K is not None else math.inf
            ok = limit is None or fast <= limit
            if (K is not None and ok) or b >= max_backoff:
                break
            b = min(max(2.0 * b, 0.01), max_backoff)
        if K is None:
            raise DesignInfeasible(GAMMA_KEY, "a feasible gamma", (1 + b) * gamma_opt,
                            hint=res.message)
    else:
        g = _check_gamma(gamma)
        res = prep.feasibility(g)
        if not res.feasible:
            best = _gamma_iteration(prep, tol, None)
            err = GammaBelowOptimum(GAMMA_KEY, f"gamma >= the best achievable {best:.4g}", g,
                                    hint=f"{res.message}; set gamma above {best:.4g} or "
                                         "\"optimal\"")
            err.condition, err.best = res.message, best
            raise err
        K, gamma_opt, b = StateSpace._unchecked(*_controller_from(prep, res)), None, 0.0
        fast = fastest_pole_modulus(K)
    if limit is not None and fast > limit:
        notes.append(f"controller pole at |s| = {fast:.4g} rad/s exceeds the realisability "
                     f"limit pi/Ts = {limit:.4g} rad/s"
                     + (f" even with back-off {b:g}" if gamma_opt is not None else "")
                     + ": raise gamma (back-off) or lower the high-frequency weights")
    cl_norm = hinf_norm(StateSpace(*_lft(P, (K.A, K.B, K.C, K.D))))
    if not cl_norm <= res.gamma * (1 + 1e-6) + 1e-12:
        notes.append(f"recomputed closed-loop norm {cl_norm:.6g} exceeds the design "
                     f"gamma {res.gamma:.6g}: the Riccati solution is inaccurate")
    for msg in notes:
        warnings.warn(msg, RuntimeWarning, stacklevel=2)
    prep_res = _unscale_xy(res, prep.t)
    return HinfResult(K=K, gamma=res.gamma, gamma_opt=gamma_opt, backoff=b,
                      X=prep_res.X, Y=prep_res.Y, closed_loop_norm=cl_norm,
                      fastest_pole=fast, pole_limit=limit, warnings=notes)


