"""Minimal realisation of :mod:`toolbox.lti`'s state-space systems (staircase
reduction of the unreachable and unobservable parts).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._systems import as_statespace, StateSpace


def _reachable(A: np.ndarray, B: np.ndarray, tol: float) -> tuple[int, np.ndarray]:
    """Dimension and orthogonal basis of the reachable subspace of ``(A, B)``.

    Staircase algorithm (Varga 1981, "Minimal realization procedures based on
    balancing and related techniques"; the reduction SLICOT ``TB01UD``
    performs): each step keeps the directions in which the newest input block
    has singular values above ``tol`` and passes the rest on. Returns
    ``(r, T)`` with T orthogonal (n x n) and the first r columns spanning the
    reachable subspace, so ``T^T A T`` is block upper triangular.
    """
    n = A.shape[0]
    T = np.eye(n)
    done = 0                                   # states known reachable
    block = B
    while done < n:
        U, sv, _ = np.linalg.svd(block, full_matrices=True)
        rank = int(np.sum(sv > tol))
        if rank == 0:
            break
        T[:, done:] = T[:, done:] @ U          # reached directions first
        if done + rank == n:
            return n, T
        At = T.T @ A @ T
        block = At[done + rank:, done:done + rank]
        done += rank
    return done, T


def minreal(sys: Any, tol: float | None = None) -> StateSpace:
    """Remove the unreachable, then the unobservable states of a system.

    Rank decisions are absolute: a singular value at most ``tol`` counts as
    zero (default ``sqrt(eps) max(|A|, |B|, |C|)``, 2-norms: the round-off
    of a similarity transform with a condition number up to ~1e6 stays
    below it); scale B and C first when their units differ from A's. The transfer function is unchanged; the
    kept coordinates are orthogonal projections of the original ones.
    """
    g = as_statespace(sys)
    n = g.nstates
    if n == 0:
        return g
    if tol is None:
        tol = np.sqrt(np.finfo(float).eps) * max(np.linalg.norm(M, 2)
                                                 for M in (g.A, g.B, g.C) if M.size)
    r, T = _reachable(g.A, g.B, tol)
    Tr = T[:, :r]
    A, B, C = Tr.T @ g.A @ Tr, Tr.T @ g.B, g.C @ Tr
    o, S = _reachable(A.T, C.T, tol)           # observable = reachable of the dual
    So = S[:, :o]
    return StateSpace(So.T @ A @ So, So.T @ B, C @ So, g.D, g.dt)
