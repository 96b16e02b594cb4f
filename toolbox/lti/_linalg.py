"""Matrix kernels of :mod:`toolbox.lti`: diagonal scaling and balancing, the
modal form, LAPACK calls without numpy's dispatch (eigen-decomposition,
solves, SVD), pencil eigenvalues and invariant zeros.
"""

from __future__ import annotations

from functools import lru_cache
from math import hypot

import numpy as np
import scipy.linalg
from scipy.linalg.lapack import (dgebal as _dgebal, dgeev as _dgeev, dgesdd as _dgesdd,
                                 dgesdd_lwork as _dgesdd_lwork_query, dgesv as _dgesv,
                                 dggev as _dggev, zgesv as _zgesv)


#: Largest condition number of the eigenvector matrix for which a frequency
#: response is evaluated as a modal sum (relative error ~cond(V) eps, so
#: <= ~1e-10); a nearly defective A takes per-point LU solves instead.
_MODAL_COND_MAX = 1e6


def diagonal_scaling(M: np.ndarray) -> np.ndarray:
    """Diagonal scaling of LAPACK dgebal without permutation, as
    ``scipy.linalg.matrix_balance(M, permute=False, separate=True)``: exact
    powers of two (dgebal multiplies by its radix ``SCLFAC = 2``), so that
    ratios of them are exact and need no rounding."""
    _, _, _, scale, info = _dgebal(M, scale=1, permute=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgebal failed (info {info})")
    return scale


def state_scaling(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Powers of two ``t`` such that ``x = diag(t) x_b`` equilibrates
    ``[A B; C 0]`` (dgebal), taken relative to the input/output's own scale so
    that B and C are equilibrated as well: controllers come back in the
    plant's coordinates with entries over ~12 decades, and a companion-form
    realisation has B = e1 against C up to ~1e10."""
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:], M[n:, :n] = A, B, C
    scale = diagonal_scaling(M)
    return scale[:n] / scale[n]                  # exact: powers of two


def balanced(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(A, B, C)`` in the coordinates of :func:`state_scaling` (exact: powers of two)."""
    t = state_scaling(A, B, C)
    return A * t[None, :] / t[:, None], B / t[:, None], C * t[None, :]


def balanced_blocks(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A, B, C of the SISO system matrix ``M = [[A, B], [C, 0]]`` in the
    coordinates of :func:`balanced` (the same powers of two, so the same
    numbers), as views of one scaled copy of ``M``: for a caller that wrote
    the system matrix itself, one array operation for the three blocks
    instead of a system matrix rebuilt by :func:`state_scaling` and three
    scalings."""
    n = M.shape[0] - 1
    if n:
        t = diagonal_scaling(M)
        t = t / t[n]                                 # exact: powers of two; t[n] = 1
        M = M * t[None, :] / t[:, None]
    return M[:n, :n], M[:n, n:], M[n:, :n]


def balanced_companion(num: list[float], den: list[float]) -> tuple[np.ndarray, ...]:
    """A, B, C, D of :func:`tf2ss`'s controllable canonical form of the proper
    ``num/den`` (trimmed Python floats, ``den[0] != 0``) in the coordinates of
    :func:`balanced`: the same numbers as ``balanced(*tf2ss(num, den)[:3])``,
    with the system matrix ``[[A, B], [C, 0]]`` written once from the
    coefficients (``-den[1:]`` on A's first row, ones below its diagonal,
    ``B = e1``, ``C = num[1:] - num[0] den[1:]``, normalised by ``den[0]``) and
    scaled by :func:`balanced_blocks`. A, B, C are views of that matrix."""
    n, d0 = len(den) - 1, den[0]
    num = [v / d0 for v in [0.0] * (n + 1 - len(num)) + num]
    den = [v / d0 for v in den]
    M = np.zeros((n + 1, n + 1))
    if n:
        M[0, :n] = [-v for v in den[1:]]
        M.reshape(-1)[n + 1:n * (n + 1):n + 2] = 1.0     # A's subdiagonal
        M[0, n] = 1.0
        M[n, :n] = [u - num[0] * v for u, v in zip(num[1:], den[1:])]
    return (*balanced_blocks(M), np.array([[num[0]]]))


def modal_form(A: np.ndarray, B: np.ndarray,
               C: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Poles ``lam`` (n,) and residues ``R`` (p, m, n) with
    ``C (x I - A)^-1 B = sum_k R[:, :, k] / (x - lam_k)``, or None when A is
    (nearly) defective.

    One eigen-decomposition ``A = V diag(lam) V^-1`` then serves every point:
    O(N n) array work instead of N LU factorisations (20000 points of a
    5-state loop: ~1 ms instead of ~13 ms; python-control's per-frequency
    SLICOT ``tb05ad`` takes ~40 ms). The sum loses about
    ``cond(V) eps`` relative accuracy, so it is offered only while
    ``n ||V^-1||_1`` (eig's columns have unit 2-norm, so this bounds
    ``cond_2(V)`` from above, without an SVD) is at most
    :data:`_MODAL_COND_MAX`; otherwise callers solve per point.
    """
    lam, V = _eig(A)
    # V^-1 by LAPACK gesv on the identity, as numpy's ``inv`` (without its
    # ~3 us of dispatch); V is real when every eigenvalue is
    _, _, Vi, info = (_zgesv if V.dtype.kind == "c" else _dgesv)(V, _identity(A.shape[0]))
    if info != 0:                                    # defective A
        return None
    # "not <=": eigenvectors of a matrix with a nan entry (dgeev returns them
    # without complaint, numpy's eig refused it) take the per-point solves too
    if not A.shape[0] * np.abs(Vi).sum(0).max() <= _MODAL_COND_MAX:
        return None
    return lam, (C @ V)[:, None, :] * (Vi @ B).T[None, :, :]


def _eig(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.linalg.eig(A)`` of a real square matrix: LAPACK dgeev (scipy's
    build: ~8 us for order 5 against numpy's ~12 us around the same routine;
    the last bits may differ between the two builds, ~1e-15), with
    numpy's conventions: real ``lam`` and ``V`` when every eigenvalue is real,
    else complex ones, a conjugate pair's vectors ``vr[:, j] +- i vr[:, j+1]``
    assembled from dgeev's packed real columns."""
    wr, wi, _, vr, info = _dgeev(A, compute_vl=0, compute_vr=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgeev failed (info {info})")
    # C-ordered as numpy's (products round differently on another layout); a
    # few columns: scalar code and basic slices beat masked array operations
    imag = wi.tolist()
    if not any(imag):
        return wr, np.ascontiguousarray(vr)
    V = np.array(vr, complex, order="C")
    for j, x in enumerate(imag):
        if x > 0.0:                              # a pair: dgeev gives its positive part first
            V[:, j].imag = vr[:, j + 1]
            V[:, j + 1] = V[:, j].conj()
    return wr + 1j * wi, V


def _solve(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A^-1 B (LAPACK dgesv, zgesv for a complex A, without numpy's ~4 us of
    dispatch); LinAlgError when A is exactly singular."""
    _, _, x, info = (_zgesv if A.dtype.kind == "c" else _dgesv)(A, B)
    if info != 0:
        raise np.linalg.LinAlgError(f"singular matrix (gesv info {info})")
    return x


def _identity(n: int) -> np.ndarray:
    """Read-only identity of order n, made once (``np.eye`` builds one in
    Python, ~1 us, and the small systems here need several per call)."""
    return _leading_identity(n, n, n)


@lru_cache(maxsize=64)
def _leading_identity(rows: int, cols: int, k: int) -> np.ndarray:
    """Read-only ``rows x cols`` matrix with ones on the first ``k`` diagonal
    entries, zeros elsewhere: ``diag(I_k, 0)``, the right-hand matrix of a
    system pencil and the gamma-weighted blocks of the H-infinity Riccati data."""
    E = np.zeros((rows, cols))
    E[np.arange(k), np.arange(k)] = 1.0
    E.flags.writeable = False
    return E


def _svd(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``np.linalg.svd(M)`` of a real matrix (full U and V^T): LAPACK dgesdd
    with numpy's workspace and layout, without its ~4 us of dispatch. It is
    scipy's LAPACK build, not numpy's: the bits agree on the gallery's plants
    (outputs unchanged) but need not on every matrix."""
    U, s, Vt, info = _dgesdd(M, compute_uv=1, full_matrices=1, lwork=_dgesdd_lwork(*M.shape))
    if info != 0:
        raise np.linalg.LinAlgError(f"dgesdd failed (info {info})")
    # C-ordered as numpy's (products round differently on another layout)
    return np.ascontiguousarray(U), s, np.ascontiguousarray(Vt)


@lru_cache(maxsize=32)
def _dgesdd_lwork(m: int, n: int) -> int:
    """Optimal dgesdd workspace (full U and V^T) for an m x n matrix."""
    work, info = _dgesdd_lwork_query(m, n, compute_uv=1, full_matrices=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgesdd workspace query failed (info {info})")
    return max(int(work), 1)


def _eigvals(A: np.ndarray) -> np.ndarray:
    """Eigenvalues of a real square matrix (LAPACK dgeev)."""
    if A.shape[0] == 0:
        return np.zeros(0, complex)
    wr, wi, _, _, info = _dgeev(A, compute_vl=0, compute_vr=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgeev failed (info {info})")
    return wr + 1j * wi


def pencil_eigvals(M: np.ndarray, N: np.ndarray) -> list[complex]:
    """Finite generalised eigenvalues of (M, N) (LAPACK dggev; the infinite
    ones, |beta| <= 1e-13 |alpha|, are dropped) as Python numbers (a pencil of a small system
    has a dozen eigenvalues: scalar code beats the nine array operations of
    the filter and the quotients). The quotients are numpy's ``alpha / beta``
    bit for bit (its complex division by a real ``beta`` multiplies by
    ``1 / beta``); the moduli of the finiteness test are libm's ``hypot``,
    which may differ from numpy's vectorised one in the last bit, far from
    the test's margin (an infinite eigenvalue has |beta| ~ eps |alpha| or 0)."""
    ar, ai, beta, _, _, _, info = _dggev(M, N, compute_vl=0, compute_vr=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dggev failed (info {info})")
    out = []
    for re, im, b in zip(ar.tolist(), ai.tolist(), beta.tolist()):
        if abs(b) > 1e-13 * hypot(re, im):
            r = 1.0 / b
            out.append(complex(re * r, im * r))
    return out


def invariant_zeros(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Invariant zeros of a SISO system: the finite eigenvalues of the system
    pencil ``([A B; C D], diag(I, 0))`` (QZ), after a power-of-two diagonal
    scaling of its states (exact, :func:`balanced`: one input and one output)
    that evens the entries of controllers spanning many decades; the infinite
    eigenvalues (relative degree) are dropped."""
    if B.shape[1] != 1 or C.shape[0] != 1:
        raise ValueError(f"invariant_zeros: a SISO system expected, got {C.shape[0]} outputs and "
                         f"{B.shape[1]} inputs")
    n = A.shape[0]
    if n == 0:
        return np.zeros(0, complex)
    A, B, C = balanced(A, B, C)
    M = np.zeros((n + C.shape[0], n + B.shape[1]))
    M[:n, :n], M[:n, n:], M[n:, :n], M[n:, n:] = A, B, C, D
    return np.array(pencil_eigvals(M, _leading_identity(*M.shape, n)), complex)
