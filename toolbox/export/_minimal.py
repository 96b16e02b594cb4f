"""Minimal, round-off-free realisation of an axis law before export.

Design routes (Riccati solutions, Tustin maps, similarity transforms) leave
entries of order ``eps * norm`` where the exact law has zeros (e.g. the row of
an integrator: ``[-1e-14, 1, -9e-16]``), and may carry states that neither
input nor the anti-windup path reaches (a cancelled pole-zero pair). Counted
as coefficients, such entries make the dynamic range of a coefficient set
look like 1e14 and refuse a sound controller.

:func:`minimal_law` therefore

1. balances the law with an exact power-of-two diagonal similarity
   (:func:`toolbox.lti.diagonal_scaling`, LAPACK ``gebal``) so that one
   threshold fits every row;
2. sets to zero every entry of ``A``, ``[B aw]``, ``C`` below
   ``ROUNDOFF_REL`` times the norm of its block (1e-10: four orders above the
   1e-14 round-off seen in practice, six below any coefficient that matters
   at float32 precision, 6e-8);
3. removes unreachable/unobservable states of the system
   ``(A, [B aw], C, [D 0])`` with :func:`toolbox.lti.minreal` (orthogonal
   staircase, the reduction of SLICOT ``TB01PD``) at a tolerance relative to
   the system norm. The anti-windup vector is an
   input here, so the reduced law equals the executed law *including* the
   back-calculation path, not only its linear part;
4. accepts the result only if its frequency response equals the original one
   on every channel (``[i_ref, i_meas, dv] -> v``) within ``EQUIV_RTOL``, and
   otherwise returns the law unchanged. Cleaning can therefore never change
   what is executed beyond round-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lti import StateSpace, diagonal_scaling, evaluate, minreal

__all__ = ["MinimalLaw", "minimal_law", "ROUNDOFF_REL", "EQUIV_RTOL"]

ROUNDOFF_REL = 1e-10
EQUIV_RTOL = 1e-7
_N_GRID = 200


@dataclass(frozen=True, eq=False)
class MinimalLaw:
    """An axis law after round-off cleaning and minimal realisation.

    Attributes
    ----------
    A, B, C, D : ndarray
        Law ``[i_ref, i_meas] -> v`` (n x n, n x 2, 1 x n, 1 x 2).
    aw : ndarray
        Back-calculation vector (n,) in the same coordinates.
    removed_states : int
        States removed by the minimal realisation.
    zeroed : int
        Entries set to zero as round-off.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    aw: np.ndarray
    removed_states: int = 0
    zeroed: int = 0


def _response(A, Bx, C, Dx, z: np.ndarray) -> np.ndarray:
    """(len(z), m) frequency response of the first output of ``(A, Bx, C, Dx)``
    at the points z (:func:`toolbox.lti.evaluate`, one LU solve per point)."""
    return evaluate(A, Bx, C[:1], Dx[:1], z, solve=True)[0].T


def _equivalent(orig: tuple, new: tuple) -> bool:
    """True when both systems have the same response on every channel.

    Grid: 200 points from 1e-4 x Nyquist to Nyquist on the unit circle (an
    integrator at z = 1 is excluded by the lower end). Tolerance ``EQUIV_RTOL``
    relative to the channel's largest magnitude on the grid plus the point's
    own magnitude: round-off cleaning changes the response by ~1e-10.
    """
    z = np.exp(1j * np.pi * np.logspace(-4, 0, _N_GRID))
    with np.errstate(all="ignore"):
        try:
            h0 = _response(*orig, z)
            h1 = _response(*new, z)
        except np.linalg.LinAlgError:
            return False
    if not (np.all(np.isfinite(h0)) and np.all(np.isfinite(h1))):
        return False
    scale = np.max(np.abs(h0), axis=0, initial=0.0)
    return bool(np.all(np.abs(h1 - h0) <= EQUIV_RTOL * (np.abs(h0) + 1e-3 * scale) + 1e-300))


#: Largest entry magnitude handed to the cleaning (float32 would overflow long before).
CLEANABLE_MAX = 1e30
#: Largest ||A|| of a discrete law worth realising minimally: a sound law's
#: (balanced) state matrix has eigenvalues in the unit disc and entries of order 1.
A_NORM_MAX = 1e6


def _zero_small(M: np.ndarray) -> tuple[np.ndarray, int]:
    """M with entries below ROUNDOFF_REL x its 2-norm set to zero."""
    if M.size == 0:
        return M, 0
    thr = ROUNDOFF_REL * float(np.linalg.norm(M, 2))
    small = (np.abs(M) < thr) & (M != 0)
    out = M.copy()
    out[small] = 0.0
    return out, int(small.sum())


def _balance(A, Bx, C):
    """Exact power-of-two diagonal similarity (no permutation)."""
    if A.shape[0] == 0:
        return A, Bx, C
    scale = diagonal_scaling(A)
    return A * (1.0 / scale)[:, None] * scale[None, :], Bx / scale[:, None], C * scale[None, :]


def _minreal(A, Bx, C, Dx, ts: float):
    """:func:`toolbox.lti.minreal` on the law with unit-norm input and output
    maps, or None when no state goes.

    Reachability and observability do not depend on the scale of B and C (nor
    on D), so they are normalised first: the rank decisions then use a
    tolerance relative to A alone.
    """
    n = A.shape[0]
    norm_a = float(np.linalg.norm(A, 2)) if n else 0.0
    if n == 0 or not np.isfinite(norm_a) or norm_a > A_NORM_MAX:
        return None
    b_scale = float(np.linalg.norm(Bx, 2)) or 1.0
    c_scale = float(np.linalg.norm(C, 2)) or 1.0
    with np.errstate(all="ignore"):
        try:
            red = minreal(StateSpace(A, Bx / b_scale, C / c_scale, np.zeros_like(Dx), ts),
                          tol=ROUNDOFF_REL * max(norm_a, 1.0))
        except np.linalg.LinAlgError:          # SVD did not converge: keep the full law
            return None
    if red.nstates >= n:
        return None
    return red.A, red.B * b_scale, red.C * c_scale, Dx


def minimal_law(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                aw: np.ndarray | None, sample_time: float) -> MinimalLaw:
    """Round-off-free minimal realisation of an axis law (see module docstring).

    Parameters
    ----------
    A, B, C, D : ndarray
        Discrete law ``[i_ref, i_meas] -> v``.
    aw : ndarray or None
        Back-calculation vector (n,), None for none.
    sample_time : float
        Controller period (s), for the discrete system.

    Returns
    -------
    MinimalLaw
        The cleaned law; the original one when cleaning would change the
        input-output map (including the anti-windup channel) by more than
        ``EQUIV_RTOL``.
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    B = np.asarray(B, float).reshape(n, 2)
    C = np.asarray(C, float).reshape(1, n)
    D = np.asarray(D, float).reshape(1, 2)
    aw = np.zeros(n) if aw is None else np.asarray(aw, float).reshape(n)
    Bx = np.column_stack([B, aw])
    Dx = np.column_stack([D, [[0.0]]])
    original = MinimalLaw(A, B, C, D, aw)
    if n == 0 or not all(np.all(np.abs(m) < CLEANABLE_MAX) for m in (A, Bx, C, D)):
        # non-finite or absurd entries (tampered file): no rank decision is
        # meaningful on them; the range check refuses the law
        return original
    Ab, Bb, Cb = _balance(A, Bx, C)
    Ac, z1 = _zero_small(Ab)
    # B and aw are cleaned as separate blocks: their scales differ (A/V vs 1)
    Bc, z2 = _zero_small(Bb[:, :2])
    awc, z3 = _zero_small(Bb[:, 2:])
    Cc, z4 = _zero_small(Cb)
    Bxc = np.column_stack([Bc, awc])
    cand = (Ac, Bxc, Cc, Dx)
    red = _minreal(*cand, sample_time)
    if red is not None and _equivalent((A, Bx, C, Dx), red):
        # minreal's coordinates carry fresh round-off: clean them once more
        Ar, Brx, Cr, _ = _balance(*red[:3]) + (Dx,)
        Ar, _ = _zero_small(Ar)
        Brx = np.column_stack([_zero_small(Brx[:, :2])[0], _zero_small(Brx[:, 2:])[0]])
        Cr, _ = _zero_small(Cr)
        if _equivalent((A, Bx, C, Dx), (Ar, Brx, Cr, Dx)):
            cand = (Ar, Brx, Cr, Dx)
    if not _equivalent((A, Bx, C, Dx), cand):
        return original
    Af, Bxf, Cf, _ = cand
    return MinimalLaw(Af, Bxf[:, :2], Cf, D, Bxf[:, 2], n - Af.shape[0], z1 + z2 + z3 + z4)
