"""Norms of :mod:`toolbox.lti`: the L-infinity and H-infinity norms (SLICOT
ab13dd), the H2
norm (a Lyapunov equation, scipy.linalg) and the spectral norm of a matrix.
"""

from __future__ import annotations

from math import inf
from typing import Any

import numpy as np
import scipy.linalg

from ._systems import as_statespace


def linf_norm(sys: Any, tol: float = 1e-10) -> float:
    """``sup_w sigma_max(G(j w))`` of a continuous system (L-infinity norm).

    SLICOT ``ab13dd`` through slycot (Bruinsma & Steinbuch 1990, the routine
    behind python-control's ``norm``; states equilibrated first), imported on
    first use. Unstable systems are allowed (the norm on the imaginary axis);
    a pole on the imaginary axis gives ``inf``. ``tol``: ab13dd's relative
    accuracy.
    """
    g = as_statespace(sys)
    return linf_peak(g.A, g.B, g.C, g.D, tol)[0]


def hinf_norm(sys: Any, stability_tol: float = 1e-8) -> float:
    """H-infinity norm of a continuous system: :func:`linf_norm` (SLICOT
    ab13dd) when every pole has ``Re < -stability_tol``, else ``inf``
    (unstable, or a pole on the imaginary axis within ``stability_tol``)."""
    g = as_statespace(sys)
    if g.nstates and np.linalg.eigvals(g.A).real.max() >= -stability_tol:
        return inf
    return linf_peak(g.A, g.B, g.C, g.D)[0]


def linf_peak(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
               tol: float = 1e-10) -> tuple[float, float]:
    """:func:`linf_norm` of the float realisation ``(A, B, C, D)`` and a
    frequency (rad/s) where the response attains it (ab13dd's ``fpeak``;
    ``inf`` for a norm reached only as w -> inf)."""
    n = A.shape[0]
    if n == 0 or D.size == 0:
        return spectral_norm(D), inf
    from slycot import ab13dd

    A, B, C, D = (np.array(m, dtype=float, order="F") for m in (A, B, C, D))
    gpeak, fpeak = ab13dd("C", "I", "S", "D", n, B.shape[1], C.shape[0], A,
                          np.eye(n), B, C, D, tol)
    return float(gpeak), float(fpeak)


def spectral_norm(M: np.ndarray) -> float:
    """Largest singular value of a matrix (0 when empty); a row or column is
    its 2-norm, a scalar its modulus."""
    if M.shape == (1, 1):
        return abs(M[0, 0].item())
    if M.shape[0] == 1 or M.shape[1] == 1:           # a row or column: sigma_max = 2-norm
        sq = M * M if M.dtype.kind == "f" else M.real * M.real + M.imag * M.imag
        return float(np.sqrt(sq.sum()))
    return float(np.linalg.norm(M, 2)) if M.size else 0.0


def h2_norm(sys: Any) -> float:
    """``||G||_2`` of a stable continuous system: ``sqrt(trace(C P C^T))``
    with the controllability Gramian ``A P + P A^T + B B^T = 0``
    (scipy.linalg.solve_continuous_lyapunov, Bartels-Stewart; Zhou, Doyle &
    Glover, Lemma 4.4). ``inf`` when D is not zero or A is not Hurwitz (the
    integral diverges); 0 without states and D = 0.
    """
    g = as_statespace(sys)
    if g.discrete:
        raise ValueError("h2_norm: a continuous system expected")
    if np.any(g.D):
        return inf
    if g.nstates == 0:
        return 0.0
    if not np.all(np.linalg.eigvals(g.A).real < 0.0):
        return inf
    P = scipy.linalg.solve_continuous_lyapunov(g.A, -g.B @ g.B.T)
    return float(np.sqrt(max(np.trace(g.C @ P @ g.C.T), 0.0)))
