"""Controller order reduction for the H-infinity current controllers.

Paper 003 (Azaiz et al.) reduces the 4th-order central controllers of eq (68)
and (70) to the 3rd-order controllers of eq (71)-(72) by (i) dropping the
pole-zero pair that the w3 weight leaves near -2.7e6 rad/s (q) / -1.155e6 rad/s
(d) and (ii) replacing the slow pole inherited from w1 (-0.0117 / -0.0040
rad/s) by an exact integrator.  This module does those steps and, when a
target order is still not reached, balanced truncation (square-root method,
with the Hankel singular values and the 2 * sum error bound) or singular
perturbation (residualisation of fast modes, keeps the DC gain).
:func:`compare_margins` then checks that the loop G K keeps its margins.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..lti import (LoopMargins, StateSpace, as_statespace, balanced_companion,
                    balanced_truncation, loop_margins as lti_loop_margins,
                    loop_margins_and_poles, parallel, residualise, stable_split)
from ._hinf_plant import _ss_blocks, _zpk

__all__ = [
    "ReductionResult", "reduce_controller", "replace_integrators", "remove_cancellations",
    "loop_margins", "MarginComparison", "compare_margins",
]


# --------------------------------------------------------------------------
# zpk helpers
# --------------------------------------------------------------------------
def _from_zpk(z: np.ndarray, p: np.ndarray, k: float) -> StateSpace:
    """Well-scaled state-space realisation of k prod(s - z)/prod(s - p)."""
    return StateSpace._unchecked(*_zpk_realisation(z, p, k))     # fresh float arrays


def _zpk_realisation(z: np.ndarray, p: np.ndarray, k: float) -> tuple[np.ndarray, ...]:
    """A, B, C, D of k prod(s - z)/prod(s - p): scipy.signal's ``zpk2ss``
    (the controllable canonical form of :func:`toolbox.lti.tf2ss`) without its
    argument handling (~0.3 ms a call), then the diagonal balancing
    of :func:`toolbox.lti.balanced`: the same numbers, from the polynomials'
    coefficients as Python floats (:func:`toolbox.lti.balanced_companion`,
    ~10 array calls instead of ~30)."""
    if p.size == 0:
        return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[float(k)]])
    den = _poly_from_roots(_real_conj(p))
    n = len(den) - 1
    num = _poly_from_roots(_real_conj(z))
    if len(num) > n + 1:
        raise ValueError(f"improper transfer function ({len(num) - 1} zeros, {n} poles)")
    A, B, C, D = balanced_companion([float(k) * v for v in num], den)
    return A.copy(), B.copy(), C.copy(), D


def _poly_from_roots(r: list[complex]) -> list[float]:
    """Coefficients of ``prod(s - r_i)``, highest power first, real for a
    conjugate-closed set (those of a real system, as :func:`_real_conj`
    leaves them): a linear factor per real root and the real quadratic
    ``s^2 - Re(x + y) s + Re(x y)`` per pair ``x, y`` (``y = conj(x)`` up to
    rounding: the zeros from a QZ pencil, :func:`toolbox.lti.invariant_zeros`, differ
    in the last bits; exact conjugates give ``-2 Re(x)`` and ``|x|^2``), in
    Python floats (a few roots: ~1 us where ``np.poly``'s ``np.convolve`` per
    root took ~4-8). As accurate as ``np.poly``'s complex products, whose
    imaginary parts cancel only up to rounding, or more: over 3000 random
    sets of 2-6 roots within 1e-3..1e7 rad/s, the coefficients' relative
    error against a 60-digit product is 1.1e-16 median and 5e-16 at worst,
    ``np.poly``'s 1.2e-16 and 3.9e-13. A complex root without a partner
    within 1e-6 (relative) is not that of a real system: ValueError."""
    partners = iter(_conjugate_partners(r))
    a = [1.0]
    for x in r:
        if x.imag == 0.0:                            # times (s - x)
            m = -x.real
            a = [a[0]] + [u + m * v for u, v in zip(a[1:], a)] + [m * a[-1]]
        elif x.imag > 0.0:                           # times (s - x)(s - y); y skipped
            y = next(partners)
            p1, p2 = -(x.real + y.real), x.real * y.real - x.imag * y.imag
            a += [0.0, 0.0]
            a = [a[0], a[1] + p1 * a[0]] + [u + p1 * v + p2 * w for u, v, w in zip(a[2:], a[1:], a)]
    return a


def _conjugate_partners(r: list[complex]) -> list[complex]:
    """For each root above the real axis, in order, the root below it nearest
    its conjugate; ValueError when the set is not conjugate-closed up to 1e-6
    (relative)."""
    upper = [x for x in r if x.imag > 0.0]
    lower = [x for x in r if x.imag < 0.0]
    if len(upper) != len(lower):
        raise ValueError(f"roots {r} are not closed under conjugation: not those of a real "
                         f"transfer function")
    out = []
    for x in upper:
        d = [abs(x - y.conjugate()) for y in lower]
        j = d.index(min(d))
        if d[j] > 1e-6 * max(1.0, abs(x)):
            raise ValueError(f"roots {r} are not closed under conjugation: not those of a real "
                             f"transfer function")
        out.append(lower.pop(j))
    return out


def _real_conj(r: np.ndarray) -> list[complex]:
    """Clean roots: tiny imaginary parts to zero (keeps conjugate pairs)."""
    return [complex(x.real, 0.0) if abs(x.imag) <= 1e-9 * max(abs(x), 1.0) else x
            for x in np.asarray(r, complex).tolist()]


# --------------------------------------------------------------------------
# elementary steps
# --------------------------------------------------------------------------
def remove_cancellations(K: Any, tol: float = 1e-2,
                         keep: Literal["dc", "hf"] = "dc") -> tuple[StateSpace, list[str]]:
    """Remove pole-zero pairs with |z - p| <= tol |p|.

    Each removed factor (s - z)/(s - p) is replaced by a constant: ``z/p``
    (``keep="dc"``: unchanged gain below the pair, the band where the current
    loop works) or 1 (``keep="hf"``: unchanged leading gain, as paper 003 does
    from eq (68) to eq (71); the two differ by |1 - z/p| = 0.14 % there).

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
        SISO controller.
    tol : float
        Relative distance defining a cancellation.
    keep : {"dc", "hf"}
        Which gain to preserve.

    Returns
    -------
    Kr : toolbox.lti.StateSpace
    actions : list of str
        One line per removed pair.
    """
    Kz, actions = _cancel(_zpk(K), tol, keep)
    return _from_zpk(*Kz), actions


def _cancel(Kz: tuple, tol: float, keep: str) -> tuple[tuple, list[str]]:
    """:func:`remove_cancellations` on ``(zeros, poles, gain)``."""
    z, p, k = Kz
    # a few roots: Python numbers (numpy scalars' arithmetic costs several times more)
    zl, pl, actions = np.asarray(z, complex).tolist(), [], []
    for pi in sorted(np.asarray(p, complex).tolist(), key=abs):
        d = [abs(zi - pi) for zi in zl]
        if d and min(d) <= tol * max(abs(pi), 1e-300) and abs(pi) > 0:
            zi = zl.pop(d.index(min(d)))
            if keep == "dc":
                k *= (np.complex128(zi) / pi).real    # numpy's division, as before
            actions.append(f"removed pole {pi:.6g} with zero {zi:.6g} "
                           f"(|z-p|/|p| = {abs(zi - pi) / abs(pi):.2g})")
        else:
            pl.append(pi)
    return (np.array(zl, complex), np.array(pl, complex), k), actions


def replace_integrators(K: Any, tol: float) -> tuple[StateSpace, list[str]]:
    """Replace poles with |p| < tol (rad/s) by exact integrators, eq (71)-(72).

    The leading gain is kept, as in paper 003 (eq 68 -> 71: 49.70 stays
    49.7026, pole -0.01174 becomes s).  The loop gain above |p| is unchanged
    and the static error becomes exactly zero.

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
        SISO controller.
    tol : float
        Magnitude below which a pole is taken as an integrator (rad/s).

    Returns
    -------
    Kr : toolbox.lti.StateSpace
    actions : list of str
    """
    Kz, actions = _integrators(_zpk(K), tol)
    return _from_zpk(*Kz), actions


def _integrators(Kz: tuple, tol: float) -> tuple[tuple, list[str]]:
    """:func:`replace_integrators` on ``(zeros, poles, gain)``."""
    z, p, k = Kz
    pl = np.asarray(p, complex).tolist()             # a few poles: Python numbers
    actions = [f"replaced pole {pi:.6g} by an integrator" for pi in pl if 0 < abs(pi) < tol]
    return (z, np.array([0j if abs(pi) < tol else pi for pi in pl], complex), k), actions


# --------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------
@dataclass
class ReductionResult:
    """Outcome of :func:`reduce_controller`.

    Attributes
    ----------
    K : toolbox.lti.StateSpace
        Reduced controller (V/A).
    order_before, order_after : int
        Number of states before and after.
    hankel_sv : ndarray or None
        Hankel singular values of the stable part when balanced truncation ran.
    error_bound : float or None
        2 * sum of the discarded Hankel singular values (balanced truncation
        step only; None otherwise).
    actions : list of str
        What was done, in order.
    """

    K: StateSpace
    order_before: int
    order_after: int
    hankel_sv: np.ndarray | None = None
    error_bound: float | None = None
    actions: list[str] = field(default_factory=list)


def reduce_controller(K: Any, order: int | None = None,
                      method: Literal["balanced", "residualise"] = "balanced",
                      integrator_tol: float | None = None, cancel_tol: float | None = 1e-2,
                      fast: float | None = None) -> ReductionResult:
    """Reduce a controller as paper 003 sect. 3.5 does, then further if asked.

    Steps, in order: remove near pole-zero cancellations (``cancel_tol``),
    residualise modes faster than ``fast`` rad/s, replace poles with
    |p| < ``integrator_tol`` by integrators (eq 71-72), and finally, while the
    order exceeds ``order``, balanced truncation of the stable part (or
    residualisation of the fastest modes with ``method="residualise"``).

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
        SISO controller.
    order : int, optional
        Target number of states.
    method : {"balanced", "residualise"}
        Method for the last step.
    integrator_tol : float, optional
        Pole magnitude (rad/s) below which a pole becomes an integrator.
    cancel_tol : float or None
        Relative pole-zero distance for cancellations; None skips.
    fast : float, optional
        Residualise modes with |p| above this (rad/s).

    Returns
    -------
    ReductionResult

    Examples
    --------
    Eq (68) -> eq (71) of paper 003:

    >>> # res = reduce_controller(Kq, integrator_tol=0.1)   # 4 -> 3 states
    """
    Kc = as_statespace(K)
    n0 = Kc.nstates
    acts: list[str] = []
    hsv, bound = None, None
    Kz = None                       # the zpk form while the steps work on it
    if cancel_tol is not None:
        Kz, a = _cancel(_zpk(Kc), cancel_tol, "dc")
        acts += a
    if fast is not None:
        Kc, a = residualise(_from_zpk(*Kz) if Kz is not None else Kc, fast)
        Kz = None
        acts += a
    if integrator_tol is not None:
        Kz, a = _integrators(Kz if Kz is not None else _zpk(Kc), integrator_tol)
        acts += a
    if Kz is not None:
        Kc = _from_zpk(*Kz)
    if order is not None and Kc.nstates > order:
        if method == "residualise":
            mags = np.sort(np.abs(Kc.poles()))
            Kc, a = residualise(Kc, float(mags[order - 1]) * (1 + 1e-9) if order > 0 else 0.0)
            acts += a
        elif method == "balanced":
            Ks, Ku = stable_split(Kc)
            keep = max(order - Ku.nstates, 0)
            if keep < Ku.nstates and order < Ku.nstates:
                warnings.warn(f"reduce_controller: {Ku.nstates} unstable/integrating "
                              f"states kept; order {order} not reachable", RuntimeWarning)
            Kr, hsv, bound = balanced_truncation(Ks, keep)
            Kc = parallel(Kr, Ku) if Ku.nstates else Kr
            acts.append(f"balanced truncation of the stable part to {keep} states "
                        f"(error bound {bound:.3g})")
        else:
            raise ValueError(f"reduce_controller: unknown method {method!r}")
    return ReductionResult(K=Kc, order_before=n0, order_after=Kc.nstates,
                           hankel_sv=hsv, error_bound=bound, actions=acts)


# --------------------------------------------------------------------------
# margins before / after
# --------------------------------------------------------------------------
def loop_margins(G: Any, K: Any) -> LoopMargins:
    """:func:`toolbox.lti.loop_margins` of ``L = G K`` (exact crossings,
    ``M_m`` by SLICOT ab13dd), with transfer functions realised as the
    H-infinity design realises them (cancellation, then the balanced companion
    form: :func:`toolbox.design._hinf_plant._ss_blocks`).

    Parameters
    ----------
    G, K : LTI system (python-control or toolbox.lti) or float
        Plant (A/V) and controller (V/A), SISO.

    Returns
    -------
    LoopMargins
    """
    return lti_loop_margins(StateSpace(*_ss_blocks(G)), StateSpace(*_ss_blocks(K)))


@dataclass
class MarginComparison:
    """Margins of G K before and after reduction.

    Attributes
    ----------
    full, reduced : LoopMargins
    max_loss : float
        Allowed relative loss (e.g. 0.1 for 10 %).
    flags : list of str
        One line per margin that lost more than ``max_loss``; empty when
        the reduction kept the margins.
    """

    full: LoopMargins
    reduced: LoopMargins
    max_loss: float
    flags: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when no margin lost more than ``max_loss``."""
        return not self.flags


def compare_margins(G: Any, K: Any, Kr: Any, max_loss: float = 0.1) -> MarginComparison:
    """Flag margins of G Kr that are worse than those of G K by > ``max_loss``.

    Gain margin is compared in absolute ratio (not dB), phase margin in
    degrees, M_m as is.  A reduced controller that destabilises the loop is
    always flagged (a closed-loop pole with Re >= 0: the poles of ``S``,
    which the norm giving M_m computed).

    Parameters
    ----------
    G, K, Kr : LTI system (python-control or toolbox.lti)
        Plant, full and reduced controllers.
    max_loss : float
        Allowed relative loss, default 0.1 (10 %).

    Returns
    -------
    MarginComparison
    """
    g = StateSpace(*_ss_blocks(G))
    a = lti_loop_margins(g, StateSpace(*_ss_blocks(K)))
    b, poles, _ = loop_margins_and_poles(g, StateSpace(*_ss_blocks(Kr)))
    flags = []
    pairs = {"gain margin": (10 ** (a.gain_margin_db / 20), 10 ** (b.gain_margin_db / 20)),
             "phase margin": (a.phase_margin_deg, b.phase_margin_deg),
             "stability margin M_m": (a.stability_margin, b.stability_margin)}
    for name, (x, y) in pairs.items():
        if math.isfinite(x) and not y >= (1 - max_loss) * x:
            flags.append(f"{name} fell from {x:.4g} to {y:.4g} (> {100 * max_loss:g} % loss)")
    if np.count_nonzero(poles.real >= 0):
        flags.append("the reduced controller destabilises the loop")
    return MarginComparison(a, b, max_loss, flags)
