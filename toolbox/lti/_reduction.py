"""Model reduction of :mod:`toolbox.lti`'s systems: additive stable/unstable
split, square-root balanced truncation (Moore 1981; Laub et al. 1987) and
singular-perturbation residualisation (Liu & Anderson 1989). The policy of
which reduction a controller gets lives with its design method
(``toolbox.design``, paper 003 eq (71)-(72)).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
import scipy.linalg as sla

from ._linalg import state_scaling
from ._systems import as_statespace, StateSpace

__all__ = ["stable_split", "balanced_truncation", "residualise"]


def _block_diagonal(A: np.ndarray, B: np.ndarray, C: np.ndarray,
                    first: Callable[[float, float], bool]) -> tuple[int, tuple, tuple]:
    """``(n1, (A1, B1, C1), (A2, B2, C2))``: the system split into two decoupled
    parts, the eigenvalues selected by ``first(re, im)`` in part 1.

    Ordered real Schur form ``A = U T U^T`` (scipy.linalg.schur, ``sort``), then
    the Sylvester equation ``T11 X - X T22 + T12 = 0`` block-diagonalises T;
    ``(A1, B1, C1) + (A2, B2, C2)`` has the transfer function of (A, B, C).
    """
    T, U, ns = sla.schur(A, output="real", sort=first)
    A11, A12, A22 = T[:ns, :ns], T[:ns, ns:], T[ns:, ns:]
    X = sla.solve_sylvester(A11, -A22, -A12)         # A11 X - X A22 + A12 = 0
    Bt, Ct = U.T @ B, C @ U
    return (ns, (A11, Bt[:ns] - X @ Bt[ns:], Ct[:, :ns]),
            (A22, Bt[ns:], Ct[:, ns:] + Ct[:, :ns] @ X))


def stable_split(K: Any, tol: float = 1e-12) -> tuple[StateSpace, StateSpace]:
    """Additive split K = K_s + K_u into stable part and the rest.

    Ordered real Schur form, then a Sylvester equation block-diagonalises A.
    Poles with Re p >= -tol * max|p| go to K_u (integrators included); the
    feedthrough stays in K_s.

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
    tol : float
        Relative margin defining "stable".

    Returns
    -------
    Ks, Ku : toolbox.lti.StateSpace
    """
    Kss = as_statespace(K)
    A, B, C, D = (np.asarray(x, float) for x in (Kss.A, Kss.B, Kss.C, Kss.D))
    n = A.shape[0]
    if n == 0:
        return Kss, StateSpace(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[0.0]])
    lim = tol * max(1.0, float(np.max(np.abs(np.linalg.eigvals(A)))))
    ns, (A11, B1, C1), (A22, B2, C2) = _block_diagonal(A, B, C, lambda x, y: x < -lim)
    Ks = StateSpace(A11, B1, C1, D)
    Ku = StateSpace(A22, B2, C2, np.zeros_like(D))
    return Ks, Ku


def _gramian_factor(M: np.ndarray) -> np.ndarray:
    """L with L L^T = M for a symmetric positive semidefinite M."""
    w, V = np.linalg.eigh(0.5 * (M + M.T))
    return V * np.sqrt(np.clip(w, 0.0, None))[None, :]


def balanced_truncation(K: Any, order: int) -> tuple[StateSpace, np.ndarray, float]:
    r"""Square-root balanced truncation of a stable system.

    Gramians :math:`AP + PA^T + BB^T = 0`, :math:`A^TQ + QA + C^TC = 0`
    (scipy ``solve_continuous_lyapunov`` on diagonally balanced data),
    :math:`L_Q^T L_P = U\Sigma V^T`, projections
    :math:`T_r = L_P V_r \Sigma_r^{-1/2}`, :math:`W_r = L_Q U_r \Sigma_r^{-1/2}`.
    Error bound :math:`\|K - K_r\|_\infty \le 2\sum_{i>r}\sigma_i`.

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
        Stable system.
    order : int
        States kept.

    Returns
    -------
    Kr : toolbox.lti.StateSpace
    hsv : ndarray
        Hankel singular values, decreasing.
    bound : float
        2 * sum of the discarded Hankel singular values.
    """
    Kss = as_statespace(K)
    A, B, C, D = (np.asarray(x, float) for x in (Kss.A, Kss.B, Kss.C, Kss.D))
    if np.any(np.linalg.eigvals(A).real >= 0):
        raise ValueError("balanced_truncation: K must be stable; split it with stable_split")
    t = state_scaling(A, B[:, :1], C[:1, :])
    A, B, C = A * t[None, :] / t[:, None], B / t[:, None], C * t[None, :]
    Lp = _gramian_factor(sla.solve_continuous_lyapunov(A, -B @ B.T))
    Lq = _gramian_factor(sla.solve_continuous_lyapunov(A.T, -C.T @ C))
    U, hsv, Vt = np.linalg.svd(Lq.T @ Lp)
    r = int(min(max(order, 0), np.count_nonzero(hsv > hsv[0] * 1e-14) if hsv.size else 0))
    sr = 1.0 / np.sqrt(hsv[:r])
    Tr = Lp @ Vt[:r].T * sr[None, :]
    Wr = Lq @ U[:, :r] * sr[None, :]
    Kr = StateSpace(Wr.T @ A @ Tr, Wr.T @ B, C @ Tr, D)
    return Kr, hsv, float(2.0 * np.sum(hsv[r:]))


def residualise(K: Any, fast: float) -> tuple[StateSpace, list[str]]:
    """Singular-perturbation reduction of modes with |p| > fast (rad/s).

    The fast block of the (block-diagonalised) modal form is set to its
    steady state: Ar = A11 - A12 A22^-1 A21, ..., Dr = D - C2 A22^-1 B2, so
    the DC gain is kept exactly.

    Parameters
    ----------
    K : LTI system (python-control or toolbox.lti)
    fast : float
        Threshold (rad/s).

    Returns
    -------
    Kr : toolbox.lti.StateSpace
    actions : list of str
    """
    Kss = as_statespace(K)
    A, B, C, D = (np.asarray(x, float) for x in (Kss.A, Kss.B, Kss.C, Kss.D))
    if A.shape[0] == 0:
        return Kss, []
    ev = np.linalg.eigvals(A)
    ns, (A11, B1, C1), (A22, B2, C2) = _block_diagonal(
        A, B, C, lambda x, y: abs(complex(x, y)) <= fast)
    if ns == A.shape[0]:
        return Kss, []
    Dr = D - C2 @ np.linalg.solve(A22, B2)
    gone = ev[np.abs(ev) > fast]
    return StateSpace(A11, B1, C1, Dr), [f"residualised fast mode(s) {', '.join(f'{g:.4g}' for g in gone)}"]
