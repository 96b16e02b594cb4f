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

import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import scipy.linalg as sla
import scipy.signal as sig
import control as ct

from ..analysis import lti_loop_margins
from ._hinf_riccati import _ss_blocks

__all__ = [
    "ReductionResult", "reduce_controller", "balanced_truncation", "residualise",
    "replace_integrators", "remove_cancellations", "stable_split",
    "LoopMargins", "loop_margins", "MarginComparison", "compare_margins",
]


# --------------------------------------------------------------------------
# zpk helpers
# --------------------------------------------------------------------------
def _zpk(K: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles and leading gain of a SISO system."""
    Kss = ct.ss(K)
    if Kss.ninputs != 1 or Kss.noutputs != 1:
        raise ValueError(f"expected a SISO controller, got {Kss.noutputs}x{Kss.ninputs}")
    z = np.atleast_1d(Kss.zeros()).astype(complex)
    p = np.atleast_1d(Kss.poles()).astype(complex)
    # leading gain from the value at a test point away from poles and zeros
    s0 = 1j * (1.0 + 3.0 * max([1.0] + [abs(x) for x in np.r_[z, p]]))
    val = complex(Kss(s0))
    k = val * np.prod(s0 - p) / np.prod(s0 - z)
    return z, p, float(k.real)


def _from_zpk(z: np.ndarray, p: np.ndarray, k: float) -> ct.StateSpace:
    """Well-scaled state-space realisation of k prod(s - z)/prod(s - p)."""
    z = _real_conj(z)
    p = _real_conj(p)
    if p.size == 0:
        return ct.ss([], [], [], [[k]])
    A, B, C, D = sig.zpk2ss(z, p, k)
    Mx = np.zeros((A.shape[0] + 1,) * 2)
    Mx[:-1, :-1], Mx[:-1, -1:], Mx[-1:, :-1] = A, B, C
    _, (sc, _) = sla.matrix_balance(Mx, permute=False, separate=True)
    t = 2.0 ** np.round(np.log2(sc[:-1]))
    return ct.ss(A * t[None, :] / t[:, None], B / t[:, None], C * t[None, :], D)


def _as_ss(sys: Any) -> ct.StateSpace:
    """StateSpace of an LTI system or a scalar gain (a SISO transfer function
    through SLICOT td04ad directly, as the synthesis realises its weights)."""
    if np.isscalar(sys):
        return ct.ss([], [], [], [[float(sys)]])
    if isinstance(sys, ct.TransferFunction) and sys.ninputs == 1 and sys.noutputs == 1 \
            and sys.isctime():
        return ct.ss(*_ss_blocks(sys))
    return ct.ss(sys)


def _real_conj(r: np.ndarray) -> np.ndarray:
    """Clean roots: tiny imaginary parts to zero (keeps conjugate pairs)."""
    r = np.asarray(r, complex).copy()
    small = np.abs(r.imag) <= 1e-9 * np.maximum(np.abs(r), 1.0)
    r[small] = r[small].real
    return r


# --------------------------------------------------------------------------
# elementary steps
# --------------------------------------------------------------------------
def remove_cancellations(K: Any, tol: float = 1e-2,
                         keep: Literal["dc", "hf"] = "dc") -> tuple[ct.StateSpace, list[str]]:
    """Remove pole-zero pairs with |z - p| <= tol |p|.

    Each removed factor (s - z)/(s - p) is replaced by a constant: ``z/p``
    (``keep="dc"``: unchanged gain below the pair, the band where the current
    loop works) or 1 (``keep="hf"``: unchanged leading gain, as paper 003 does
    from eq (68) to eq (71); the two differ by |1 - z/p| = 0.14 % there).

    Parameters
    ----------
    K : control.LTI
        SISO controller.
    tol : float
        Relative distance defining a cancellation.
    keep : {"dc", "hf"}
        Which gain to preserve.

    Returns
    -------
    Kr : control.StateSpace
    actions : list of str
        One line per removed pair.
    """
    z, p, k = _zpk(K)
    zl, pl, actions = list(z), [], []
    for pi in sorted(p, key=abs):
        d = [abs(zi - pi) for zi in zl]
        if d and min(d) <= tol * max(abs(pi), 1e-300) and abs(pi) > 0:
            zi = zl.pop(int(np.argmin(d)))
            if keep == "dc":
                k *= (zi / pi).real
            actions.append(f"removed pole {pi:.6g} with zero {zi:.6g} "
                           f"(|z-p|/|p| = {abs(zi - pi) / abs(pi):.2g})")
        else:
            pl.append(pi)
    return _from_zpk(np.array(zl), np.array(pl), k), actions


def replace_integrators(K: Any, tol: float) -> tuple[ct.StateSpace, list[str]]:
    """Replace poles with |p| < tol (rad/s) by exact integrators, eq (71)-(72).

    The leading gain is kept, as in paper 003 (eq 68 -> 71: 49.70 stays
    49.7026, pole -0.01174 becomes s).  The loop gain above |p| is unchanged
    and the static error becomes exactly zero.

    Parameters
    ----------
    K : control.LTI
        SISO controller.
    tol : float
        Magnitude below which a pole is taken as an integrator (rad/s).

    Returns
    -------
    Kr : control.StateSpace
    actions : list of str
    """
    z, p, k = _zpk(K)
    small = np.abs(p) < tol
    actions = [f"replaced pole {pi:.6g} by an integrator" for pi in p[small] if pi != 0]
    p = p.copy()
    p[small] = 0.0
    return _from_zpk(z, p, k), actions


def stable_split(K: Any, tol: float = 1e-12) -> tuple[ct.StateSpace, ct.StateSpace]:
    """Additive split K = K_s + K_u into stable part and the rest.

    Ordered real Schur form, then a Sylvester equation block-diagonalises A.
    Poles with Re p >= -tol * max|p| go to K_u (integrators included); the
    feedthrough stays in K_s.

    Parameters
    ----------
    K : control.LTI
    tol : float
        Relative margin defining "stable".

    Returns
    -------
    Ks, Ku : control.StateSpace
    """
    Kss = ct.ss(K)
    A, B, C, D = (np.asarray(x, float) for x in (Kss.A, Kss.B, Kss.C, Kss.D))
    n = A.shape[0]
    if n == 0:
        return Kss, ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[0.0]])
    lim = tol * max(1.0, float(np.max(np.abs(np.linalg.eigvals(A)))))
    T, U, ns = sla.schur(A, output="real", sort=lambda x, y: x < -lim)
    A11, A12, A22 = T[:ns, :ns], T[:ns, ns:], T[ns:, ns:]
    X = sla.solve_sylvester(A11, -A22, -A12)         # A11 X - X A22 + A12 = 0
    Bt, Ct = U.T @ B, C @ U
    B1 = Bt[:ns] - X @ Bt[ns:]
    C2 = Ct[:, ns:] + Ct[:, :ns] @ X
    Ks = ct.ss(A11, B1, Ct[:, :ns], D)
    Ku = ct.ss(A22, Bt[ns:], C2, np.zeros_like(D))
    return Ks, Ku


def _gramian_factor(M: np.ndarray) -> np.ndarray:
    """L with L L^T = M for a symmetric positive semidefinite M."""
    w, V = np.linalg.eigh(0.5 * (M + M.T))
    return V * np.sqrt(np.clip(w, 0.0, None))[None, :]


def balanced_truncation(K: Any, order: int) -> tuple[ct.StateSpace, np.ndarray, float]:
    r"""Square-root balanced truncation of a stable system.

    Gramians :math:`AP + PA^T + BB^T = 0`, :math:`A^TQ + QA + C^TC = 0`
    (scipy ``solve_continuous_lyapunov`` on diagonally balanced data),
    :math:`L_Q^T L_P = U\Sigma V^T`, projections
    :math:`T_r = L_P V_r \Sigma_r^{-1/2}`, :math:`W_r = L_Q U_r \Sigma_r^{-1/2}`.
    Error bound :math:`\|K - K_r\|_\infty \le 2\sum_{i>r}\sigma_i`.

    Parameters
    ----------
    K : control.LTI
        Stable system.
    order : int
        States kept.

    Returns
    -------
    Kr : control.StateSpace
    hsv : ndarray
        Hankel singular values, decreasing.
    bound : float
        2 * sum of the discarded Hankel singular values.
    """
    Kss = ct.ss(K)
    A, B, C, D = (np.asarray(x, float) for x in (Kss.A, Kss.B, Kss.C, Kss.D))
    n = A.shape[0]
    if np.any(np.linalg.eigvals(A).real >= 0):
        raise ValueError("balanced_truncation: K must be stable; split it with stable_split")
    Mx = np.zeros((n + 1, n + 1))
    Mx[:n, :n], Mx[:n, n:], Mx[n:, :n] = A, B[:, :1], C[:1, :]
    _, (sc, _) = sla.matrix_balance(Mx, permute=False, separate=True)
    t = 2.0 ** np.round(np.log2(sc[:n]))
    A, B, C = A * t[None, :] / t[:, None], B / t[:, None], C * t[None, :]
    Lp = _gramian_factor(sla.solve_continuous_lyapunov(A, -B @ B.T))
    Lq = _gramian_factor(sla.solve_continuous_lyapunov(A.T, -C.T @ C))
    U, hsv, Vt = np.linalg.svd(Lq.T @ Lp)
    r = int(min(max(order, 0), np.count_nonzero(hsv > hsv[0] * 1e-14) if hsv.size else 0))
    sr = 1.0 / np.sqrt(hsv[:r])
    Tr = Lp @ Vt[:r].T * sr[None, :]
    Wr = Lq @ U[:, :r] * sr[None, :]
    Kr = ct.ss(Wr.T @ A @ Tr, Wr.T @ B, C @ Tr, D)
    return Kr, hsv, float(2.0 * np.sum(hsv[r:]))


def residualise(K: Any, fast: float) -> tuple[ct.StateSpace, list[str]]:
    """Singular-perturbation reduction of modes with |p| > fast (rad/s).

    The fast block of the (block-diagonalised) modal form is set to its
    steady state: Ar = A11 - A12 A22^-1 A21, ..., Dr = D - C2 A22^-1 B2, so
    the DC gain is kept exactly.

    Parameters
    ----------
    K : control.LTI
    fast : float
        Threshold (rad/s).

    Returns
    -------
    Kr : control.StateSpace
    actions : list of str
    """
    Kss = ct.ss(K)
    A, B, C, D = (np.asarray(x, float) for x in (Kss.A, Kss.B, Kss.C, Kss.D))
    if A.shape[0] == 0:
        return Kss, []
    ev = np.linalg.eigvals(A)
    T, U, ns = sla.schur(A, output="real", sort=lambda x, y: abs(complex(x, y)) <= fast)
    if ns == A.shape[0]:
        return Kss, []
    A11, A12, A22 = T[:ns, :ns], T[:ns, ns:], T[ns:, ns:]
    X = sla.solve_sylvester(A11, -A22, -A12)
    Bt, Ct = U.T @ B, C @ U
    B1, B2 = Bt[:ns] - X @ Bt[ns:], Bt[ns:]
    C1, C2 = Ct[:, :ns], Ct[:, ns:] + Ct[:, :ns] @ X
    Dr = D - C2 @ np.linalg.solve(A22, B2)
    gone = ev[np.abs(ev) > fast]
    return ct.ss(A11, B1, C1, Dr), [f"residualised fast mode(s) {', '.join(f'{g:.4g}' for g in gone)}"]


# --------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------
@dataclass
class ReductionResult:
    """Outcome of :func:`reduce_controller`.

    Attributes
    ----------
    K : control.StateSpace
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

    K: ct.StateSpace
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
    K : control.LTI
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
    Kc = ct.ss(K)
    n0 = Kc.nstates
    acts: list[str] = []
    hsv, bound = None, None
    if cancel_tol is not None:
        Kc, a = remove_cancellations(Kc, cancel_tol)
        acts += a
    if fast is not None:
        Kc, a = residualise(Kc, fast)
        acts += a
    if integrator_tol is not None:
        Kc, a = replace_integrators(Kc, integrator_tol)
        acts += a
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
            Kc = ct.parallel(Kr, Ku) if Ku.nstates else Kr
            acts.append(f"balanced truncation of the stable part to {keep} states "
                        f"(error bound {bound:.3g})")
        else:
            raise ValueError(f"reduce_controller: unknown method {method!r}")
    return ReductionResult(K=Kc, order_before=n0, order_after=Kc.nstates,
                           hankel_sv=hsv, error_bound=bound, actions=acts)


# --------------------------------------------------------------------------
# margins before / after
# --------------------------------------------------------------------------
@dataclass
class LoopMargins:
    """Classical margins of the loop L = G K (paper 003 sect. 3.3, Fig. 7).

    Attributes
    ----------
    gain_margin_db : float
        Gain margin (dB), inf when the phase never crosses -180 deg.
    phase_crossover_rad_s : float
        Frequency of the gain margin (rad/s).
    phase_margin_deg : float
        Phase margin (deg).
    gain_crossover_rad_s : float
        Frequency of the phase margin (rad/s).
    stability_margin : float
        M_m = min |1 + L(jw)| = 1/||S||_inf (peak refined on the grid).
    static_error : float
        1/(1 + L(0)) (0 with an integrator).
    """

    gain_margin_db: float
    phase_crossover_rad_s: float
    phase_margin_deg: float
    gain_crossover_rad_s: float
    stability_margin: float
    static_error: float


def loop_margins(G: Any, K: Any, freqs: np.ndarray | None = None) -> LoopMargins:
    """Margins of L = G K from the toolbox's one margins API.

    :func:`toolbox.analysis.lti_loop_margins` (refined crossings, the same
    numbers as python-control ``stability_margins``) plus the static error.

    Parameters
    ----------
    G, K : control.LTI
        Plant (A/V) and controller (V/A).
    freqs : ndarray, optional
        Frequency grid (rad/s); default that of
        :func:`~toolbox.analysis.lti_loop_margins` (1e-3 .. 1e8 rad/s).

    Returns
    -------
    LoopMargins
    """
    L = _as_ss(G) * _as_ss(K)
    m = lti_loop_margins(L, None if freqs is None else np.asarray(freqs, float))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dc = complex(L(0)) if not np.any(np.abs(L.poles()) < 1e-12) else np.inf
    ess = 0.0 if not np.isfinite(abs(dc)) else float(abs(1.0 / (1.0 + dc)))
    return LoopMargins(m.gain_margin_db, m.phase_crossover_rad_s, m.phase_margin_deg,
                       m.gain_crossover_rad_s, m.stability_margin, ess)


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
    always flagged.

    Parameters
    ----------
    G, K, Kr : control.LTI
        Plant, full and reduced controllers.
    max_loss : float
        Allowed relative loss, default 0.1 (10 %).

    Returns
    -------
    MarginComparison
    """
    a, b = loop_margins(G, K), loop_margins(G, Kr)
    flags = []
    pairs = {"gain margin": (10 ** (a.gain_margin_db / 20), 10 ** (b.gain_margin_db / 20)),
             "phase margin": (a.phase_margin_deg, b.phase_margin_deg),
             "stability margin M_m": (a.stability_margin, b.stability_margin)}
    for name, (x, y) in pairs.items():
        if np.isfinite(x) and not y >= (1 - max_loss) * x:
            flags.append(f"{name} fell from {x:.4g} to {y:.4g} (> {100 * max_loss:g} % loss)")
    cl = ct.feedback(_as_ss(G) * _as_ss(Kr), 1)
    if np.any(np.real(cl.poles()) >= 0):
        flags.append("the reduced controller destabilises the loop")
    return MarginComparison(a, b, max_loss, flags)
