"""Norms of :mod:`toolbox._lti`: the L-infinity norm (SLICOT ab13dd) and the
spectral norm of a matrix.
"""

from __future__ import annotations

from math import inf
from typing import Any

import numpy as np

from ._lti_systems import as_statespace


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
