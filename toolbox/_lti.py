"""The toolbox's own linear time-invariant systems (numpy and scipy.linalg only).

``import control`` pulls scipy.signal and matplotlib.pyplot (0.8-1.0 s of
every ``cct design``), while the toolbox needs only a handful of
operations on small systems: this module provides them. python-control stays
the independent route of the tests (``tests/test_lti.py``) and what users may
pass in: :func:`as_statespace` duck-types its ``StateSpace`` and
``TransferFunction`` objects without importing it, and
:meth:`StateSpace.to_control` hands a system back (lazy import).

Conventions follow python-control so that ported code reads the same:

* ``dt is None`` means continuous time; a discrete system has ``dt > 0`` (s).
* ``g2 * g1`` is the series connection "``g1`` then ``g2``", with the states
  of ``g1`` first (python-control's order); ``g1 + g2`` the parallel one
  (states of ``g1`` first); ``feedback(g, h, sign=-1)`` closes
  ``u = r + sign * h y`` around ``g``.
* :func:`c2d` reproduces ``scipy.signal.cont2discrete`` operation by
  operation (the route of ``control.sample_system`` without pre-warping), so
  that discretised laws are the same floating-point numbers as before.
* Polynomials are coefficient sequences, highest power first.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache
from math import hypot, inf
from sys import modules as sys_modules
from typing import Any, Sequence

import numpy as np
import scipy.linalg
from scipy.linalg.lapack import (dgebal as _dgebal, dgeev as _dgeev,
                                 dgesdd as _dgesdd, dgesdd_lwork as _dgesdd_lwork_query,
                                 dgesv as _dgesv, dggev as _dggev, zgesv as _zgesv)

__all__ = ["StateSpace", "TransferFunction", "as_statespace", "tf2ss", "ss2tf", "ss2zpk", "c2d",
           "pade", "acker", "minreal", "series", "parallel", "feedback", "append", "static_gain",
           "linf_norm", "linf_peak", "invariant_zeros", "pencil_eigvals", "balanced",
           "balanced_blocks", "balanced_companion", "state_scaling", "diagonal_scaling",
           "modal_form", "minreal_coeffs", "trimmed_coeffs", "poly_roots", "spectral_norm",
           "C2D_METHODS"]

#: Discretisation methods of :func:`c2d` (python-control / scipy names); the
#: generalised bilinear transform of each is ``_GBT_ALPHA``.
_GBT_ALPHA = {"tustin": 0.5, "bilinear": 0.5, "euler": 0.0, "forward_diff": 0.0,
              "backward_diff": 1.0}
C2D_METHODS = ("zoh", "foh", *_GBT_ALPHA)

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


def _matrix(value: Any, name: str) -> np.ndarray:
    """A read-only 2-D float copy of ``value`` (scalars and vectors promoted)."""
    arr = np.array(value, dtype=float)
    if arr.ndim > 2:
        raise ValueError(f"{name} must be at most 2-D, got shape {arr.shape}")
    if arr.ndim < 2:
        arr = arr.reshape(1, -1) if arr.size else arr.reshape(0, 0)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class StateSpace:
    """``x' = A x + B u, y = C x + D u`` (continuous) or ``x+ = ...`` (discrete).

    Parameters
    ----------
    A, B, C, D : array_like
        (n, n), (n, m), (p, n), (p, m); stored as read-only float arrays. A
        static gain has ``n = 0`` (give A as ``np.zeros((0, 0))`` and B, C
        with the matching zero dimension, or use :func:`static_gain`).
    dt : float or None
        Sample time (s) of a discrete system; None for continuous time.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float | None = None

    @classmethod
    def _unchecked(cls, A: np.ndarray, B: np.ndarray, C: np.ndarray,
                   D: np.ndarray) -> "StateSpace":
        """A continuous system of float arrays of consistent shapes that the
        caller has just computed and hands over (made read-only here, not
        copied): the checks and copies of the constructor cost ~4 us, and the
        H-infinity synthesis builds several small systems per design."""
        new = object.__new__(cls)
        for k, v in zip("ABCD", (A, B, C, D)):
            v.flags.writeable = False
            object.__setattr__(new, k, v)
        object.__setattr__(new, "dt", None)
        return new

    def __post_init__(self) -> None:
        A, B, C, D = (_matrix(getattr(self, k), k) for k in "ABCD")
        n = A.shape[0]
        if A.shape != (n, n):
            raise ValueError(f"A must be square, got shape {A.shape}")
        if n == 0:
            # python-control style empty blocks: take the I/O sizes from D
            B, C = B.reshape(0, D.shape[1]), C.reshape(D.shape[0], 0)
        if B.shape[0] != n or C.shape[1] != n or D.shape != (C.shape[0], B.shape[1]):
            raise ValueError(f"inconsistent shapes A {A.shape}, B {B.shape}, C {C.shape}, "
                             f"D {D.shape}")
        dt = self.dt
        if dt is not None:
            dt = float(dt)
            if not (np.isfinite(dt) and dt > 0):
                raise ValueError(f"dt must be None (continuous) or > 0, got {self.dt!r}")
        for k, v in zip("ABCD", (A, B, C, D)):
            object.__setattr__(self, k, v)
        object.__setattr__(self, "dt", dt)

    # -- sizes -----------------------------------------------------------
    @property
    def nstates(self) -> int:
        return self.A.shape[0]

    @property
    def ninputs(self) -> int:
        return self.B.shape[1]

    @property
    def noutputs(self) -> int:
        return self.C.shape[0]

    @property
    def discrete(self) -> bool:
        """True for a discrete-time system (``dt`` set)."""
        return self.dt is not None

    def __repr__(self) -> str:
        kind = f"dt={self.dt}" if self.discrete else "continuous"
        return (f"StateSpace(n={self.nstates}, inputs={self.ninputs}, "
                f"outputs={self.noutputs}, {kind})")

    # -- analysis --------------------------------------------------------
    def poles(self) -> np.ndarray:
        """Eigenvalues of A (s-plane or z-plane)."""
        return np.linalg.eigvals(self.A) if self.nstates else np.zeros(0, complex)

    @cached_property
    def modal(self) -> tuple[np.ndarray, np.ndarray] | None:
        """:func:`modal_form` of the system (computed once), None without states."""
        return modal_form(self.A, self.B, self.C) if self.nstates else None

    @cached_property
    def _poles_zeros(self) -> tuple[np.ndarray, np.ndarray]:
        """Poles (dgeev) and invariant zeros (:func:`invariant_zeros`) of a SISO system,
        computed once:
        the H-infinity synthesis tests its controller's fastest pole with them
        and the order reduction starts from the same zeros and poles."""
        return _eigvals(self.A), invariant_zeros(self.A, self.B, self.C, self.D)

    @cached_property
    def _zpk(self) -> tuple[np.ndarray, np.ndarray, float]:
        """Zeros, poles and leading gain of a SISO system, computed once: the
        H-infinity weight-bound check and the order reduction both start from
        them. The gain is the value at a test point away from the
        poles and zeros, divided by their factors there."""
        p, z = self._poles_zeros
        s0 = 1j * (1.0 + 3.0 * max([1.0] + [abs(x) for x in z.tolist() + p.tolist()]))
        val = complex(self.D[0, 0])
        if self.nstates:
            val += complex((self.C @ _solve(s0 * _identity(self.nstates) - self.A, self.B))[0, 0])
        k = val * np.prod(s0 - p) / np.prod(s0 - z)
        return z, p, float(k.real)

    def evaluate(self, x: Any) -> np.ndarray:
        """``C (x I - A)^-1 B + D`` at complex points ``x``: shape ``(p, m, len(x))``.

        The modal sum (:attr:`modal`) serves a grid while A's eigenvectors are
        well conditioned; otherwise, and for one point, an LU solve per point.
        A point exactly on a pole gives inf/nan entries.
        """
        x = np.asarray(x, complex).reshape(-1)
        p, m, n = self.noutputs, self.ninputs, self.nstates
        if n == 0:
            return np.repeat(self.D.astype(complex)[:, :, None], x.size, axis=2)
        with np.errstate(divide="ignore", invalid="ignore"):
            if x.size > 1 and self.modal is not None:
                lam, R = self.modal
                inv = x[None, :] - lam[:, None]                      # (n, N)
                np.divide(1.0, inv, out=inv)     # in place: a grid's (n, N) is large
                if p == m == 1:                  # a product, 2-3x faster than einsum
                    y = R[0, 0] @ inv
                    y += self.D[0, 0]
                    return y[None, None, :]
                return np.einsum("pmk,kN->pmN", R, inv) + self.D[:, :, None]
            M = x[:, None, None] * np.eye(n) - self.A
            try:
                y = np.linalg.solve(M, np.broadcast_to(self.B.astype(complex), (x.size, n, m)))
            except np.linalg.LinAlgError:
                y = np.stack([_solve_or_inf(Mi, self.B) for Mi in M])
            return np.moveaxis(self.C @ y + self.D, 0, -1)

    def __call__(self, x: Any) -> Any:
        """Response at complex point(s) ``x`` as python-control's ``sys(x)``:
        a SISO system gives a scalar or a 1-D array, else ``(p, m[, N])``."""
        scalar = np.ndim(x) == 0
        out = self.evaluate(x)
        if self.noutputs == self.ninputs == 1:
            out = out[0, 0]
        return out[..., 0] if scalar else out

    def freqresp(self, omega: Any) -> np.ndarray:
        """Frequency response at ``omega`` (rad/s): shape ``(p, m, len(omega))``.

        Evaluated at ``j omega`` (continuous) or ``exp(j omega dt)`` (discrete).
        """
        w = np.asarray(omega, float).reshape(-1)
        return self.evaluate(np.exp(1j * w * self.dt) if self.discrete else 1j * w)

    def dcgain(self) -> np.ndarray:
        """Steady-state gain ``G(0)`` (continuous) or ``G(1)`` (discrete), (p, m)."""
        return self.evaluate([1.0 if self.discrete else 0.0])[:, :, 0].real

    # -- interconnections (python-control operator conventions) ----------
    def __neg__(self) -> "StateSpace":
        return StateSpace(self.A, self.B, -self.C, -self.D, self.dt)

    def __mul__(self, other: Any) -> "StateSpace":
        """``self * other``: ``other`` first, then ``self``."""
        return series(_operand(other, self, "right"), self)

    def __rmul__(self, other: Any) -> "StateSpace":
        return series(self, _operand(other, self, "left"))

    def __add__(self, other: Any) -> "StateSpace":
        return parallel(self, _operand(other, self, "parallel"))

    def __radd__(self, other: Any) -> "StateSpace":
        return parallel(_operand(other, self, "parallel"), self)

    def __sub__(self, other: Any) -> "StateSpace":
        return parallel(self, -_operand(other, self, "parallel"))

    def __rsub__(self, other: Any) -> "StateSpace":
        return parallel(_operand(other, self, "parallel"), -self)

    def __getitem__(self, key: tuple) -> "StateSpace":
        """Subsystem ``sys[outputs, inputs]`` (ints or slices; states kept)."""
        rows, cols = (k if isinstance(k, slice) else slice(k, k + 1) for k in key)
        return StateSpace(self.A, self.B[:, cols], self.C[rows, :], self.D[rows, cols], self.dt)

    def feedback(self, other: Any = 1.0, sign: int = -1) -> "StateSpace":
        """:func:`feedback` of ``self`` with ``other`` in the return path."""
        return feedback(self, other, sign)

    def to_control(self) -> Any:
        """The same system as a ``control.StateSpace`` (imports python-control)."""
        import control

        if self.discrete:
            return control.ss(self.A, self.B, self.C, self.D, self.dt)
        return control.ss(self.A, self.B, self.C, self.D)


def _solve_or_inf(M: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``M^-1 B``, or inf where M is singular (a point exactly on a pole)."""
    try:
        return np.linalg.solve(M, B.astype(complex))
    except np.linalg.LinAlgError:
        return np.full(B.shape, np.inf + 0j)


def static_gain(D: Any, dt: float | None = None) -> StateSpace:
    """A memoryless system ``y = D u``."""
    D = np.atleast_2d(np.asarray(D, float))
    return StateSpace(np.zeros((0, 0)), np.zeros((0, D.shape[1])), np.zeros((D.shape[0], 0)),
                      D, dt)


def _operand(value: Any, like: StateSpace, role: str) -> StateSpace:
    """Promote a scalar or matrix operand of an interconnection with ``like``.

    A scalar becomes ``k I`` of the size the connection needs (python-control
    semantics: ``2 * G`` scales every channel).
    """
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        size = {"right": like.ninputs, "left": like.noutputs}.get(role)
        if size is None:                               # parallel: y = k u needs p == m
            size = like.ninputs
            if like.ninputs != like.noutputs:
                return static_gain(np.full((like.noutputs, like.ninputs), float(value)), like.dt)
        return static_gain(float(value) * np.eye(size), like.dt)
    sys = as_statespace(value)
    if sys.nstates == 0 and sys.dt is None and like.dt is not None:
        sys = StateSpace(sys.A, sys.B, sys.C, sys.D, like.dt)
    return sys


def _common_dt(a: StateSpace, b: StateSpace) -> float | None:
    """The sample time of a connection of ``a`` and ``b`` (static gains adapt)."""
    if a.nstates == 0 and a.dt is None:
        return b.dt
    if b.nstates == 0 and b.dt is None:
        return a.dt
    if a.dt != b.dt:
        raise ValueError(f"cannot connect systems with dt={a.dt} and dt={b.dt}")
    return a.dt


def series(first: Any, second: Any) -> StateSpace:
    """``second * first``: the output of ``first`` drives ``second``.

    States are ``[x_first; x_second]``.
    """
    g1, g2 = as_statespace(first), as_statespace(second)
    if g1.noutputs != g2.ninputs:
        raise ValueError(f"series: {g1.noutputs} outputs into {g2.ninputs} inputs")
    n1, n2 = g1.nstates, g2.nstates
    A = np.block([[g1.A, np.zeros((n1, n2))], [g2.B @ g1.C, g2.A]])
    B = np.vstack([g1.B, g2.B @ g1.D])
    C = np.hstack([g2.D @ g1.C, g2.C])
    return StateSpace(A, B, C, g2.D @ g1.D, _common_dt(g1, g2))


def parallel(g1: Any, g2: Any) -> StateSpace:
    """``g1 + g2`` (same input, outputs added); states ``[x1; x2]``."""
    a, b = as_statespace(g1), as_statespace(g2)
    if (a.ninputs, a.noutputs) != (b.ninputs, b.noutputs):
        raise ValueError(f"parallel: shapes {a.noutputs}x{a.ninputs} and "
                         f"{b.noutputs}x{b.ninputs} differ")
    return StateSpace(scipy.linalg.block_diag(a.A, b.A), np.vstack([a.B, b.B]),
                      np.hstack([a.C, b.C]), a.D + b.D, _common_dt(a, b))


def append(*systems: Any) -> StateSpace:
    """Block-diagonal connection: inputs and outputs stacked, states in order."""
    gs = [as_statespace(g) for g in systems]
    dts = {g.dt for g in gs if g.nstates or g.dt is not None}    # static gains adapt
    if len(dts) > 1:
        raise ValueError(f"append: systems with different sample times {sorted(map(str, dts))}")
    dt = dts.pop() if dts else None
    return StateSpace(scipy.linalg.block_diag(*[g.A for g in gs]),
                      scipy.linalg.block_diag(*[g.B for g in gs]),
                      scipy.linalg.block_diag(*[g.C for g in gs]),
                      scipy.linalg.block_diag(*[g.D for g in gs]), dt)


def feedback(plant: Any, other: Any = 1.0, sign: int = -1) -> StateSpace:
    """Closed loop ``y = G u1``, ``u1 = r + sign * H y``: ``r -> y``.

    ``other`` (H) may be a scalar (``k I``), a matrix or a system. The
    algebraic loop is solved with ``F = I - sign D_G D_H`` (error when
    singular). States are ``[x_G; x_H]``.
    """
    G = as_statespace(plant)
    H = _operand(other, G, "left") if np.isscalar(other) else as_statespace(other)
    if (H.ninputs, H.noutputs) != (G.noutputs, G.ninputs):
        raise ValueError(f"feedback: H must be {G.ninputs}x{G.noutputs}, "
                         f"got {H.noutputs}x{H.ninputs}")
    dt = _common_dt(G, H)
    F = np.eye(G.noutputs) - sign * G.D @ H.D
    Fi_C = np.linalg.solve(F, np.hstack([G.C, sign * G.D @ H.C]))   # y in terms of x
    Fi_D = np.linalg.solve(F, G.D)                                  # y in terms of r
    U_x = np.hstack([np.zeros((G.ninputs, G.nstates)), sign * H.C]) + sign * H.D @ Fi_C
    U_r = np.eye(G.ninputs) + sign * H.D @ Fi_D
    A = scipy.linalg.block_diag(G.A, H.A) + np.vstack([G.B @ U_x, H.B @ Fi_C])
    B = np.vstack([G.B @ U_r, H.B @ Fi_D])
    return StateSpace(A, B, Fi_C, Fi_D, dt)


# -- transfer functions -------------------------------------------------------
def trimmed_coeffs(coeffs: Any) -> list[float]:
    """The coefficients of a polynomial as Python floats without leading zeros
    (zero -> ``[0.0]``): the small transfer functions of a design need no array."""
    p = np.asarray(coeffs, dtype=float).reshape(-1).tolist()
    i = next((k for k, c in enumerate(p) if c), None)
    return [0.0] if i is None else p[i:]


def _poly(coeffs: Any) -> np.ndarray:
    """:func:`trimmed_coeffs` as a fresh 1-D float array."""
    return np.array(trimmed_coeffs(coeffs))


def poly_roots(p: np.ndarray) -> np.ndarray:
    """Roots of a trimmed polynomial; a first-order one without ``np.roots``'s
    companion-matrix eigenvalues (weights are mostly first-order)."""
    if p.size <= 1:
        return np.zeros(0, complex)
    if p.size == 2:
        return np.array([-p[1] / p[0]], complex)
    return np.roots(p)


#: Relative distance below which a pole and a zero of a
#: :class:`TransferFunction` cancel (python-control's ``minreal`` default).
_CANCEL_TOL = float(np.sqrt(np.finfo(float).eps))


def minreal_coeffs(num: np.ndarray, den: np.ndarray,
                    tol: float = _CANCEL_TOL) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`TransferFunction.minreal` on trimmed coefficients: the same
    ``num`` and ``den`` objects when nothing cancels, else new trimmed ones
    (the H-infinity augmentation realises four transfer functions per axis
    and needs no object of them)."""
    if num.size == 1 or den.size == 1:
        return num, den                        # no zero or no pole: nothing to cancel
    if num.size == 2 and den.size == 2:        # one zero, one pole (most weights): scalars
        (n0, n1), (d0, d1) = num.tolist(), den.tolist()
        z, p = -n1 / n0, -d1 / d0               # the roots poly_roots gives, as floats
        return (num[:1], den[:1]) if abs(p - z) <= tol * max(1.0, abs(z)) else (num, den)
    zeros = list(poly_roots(num)) if num.any() else []
    poles = list(poly_roots(den))
    kept = []
    for z in zeros:
        near = [i for i, p in enumerate(poles) if abs(p - z) <= tol * max(1.0, abs(z))]
        if near:
            poles.pop(min(near, key=lambda i: abs(poles[i] - z)))
        else:
            kept.append(z)
    if len(kept) == len(zeros):
        return num, den
    return (_poly(num[0] * np.real(np.poly(kept)) if kept else num[:1]),
            _poly(den[0] * np.real(np.poly(poles))))


def tf2ss(num: Any, den: Any, dt: float | None = None) -> StateSpace:
    """Controllable canonical realisation of a proper SISO ``num/den``.

    Same form as ``scipy.signal.tf2ss``: ``A`` has ``-den[1:]/den[0]`` as its
    first row, ``B = e1``, ``C = num' - num'_0 den'`` and ``D = num'_0``
    (primes: normalised so that ``den[0] = 1``, ``num`` padded to its degree).
    """
    A, B, C, D = _tf2ss_arrays(_poly(num), _poly(den))
    return static_gain(D, dt) if A.size == 0 else StateSpace(A, B, C, D, dt)


def _tf2ss_arrays(num: np.ndarray, den: np.ndarray) -> tuple[np.ndarray, ...]:
    """A, B, C, D of :func:`tf2ss` for trimmed 1-D float polynomials (no
    system object: the H-infinity augmentation realises four transfer
    functions per axis and keeps only the arrays)."""
    if not den.any():
        raise ValueError("tf2ss: zero denominator")
    if num.size > den.size:
        raise ValueError(f"tf2ss: improper transfer function (numerator degree "
                         f"{num.size - 1} > denominator degree {den.size - 1})")
    num = np.concatenate([np.zeros(den.size - num.size), num]) / den[0]
    den = den / den[0]
    n = den.size - 1
    D = np.array([[num[0]]])
    A = np.zeros((n, n))
    A[:1] = -den[1:]                                # the first row (none when n = 0)
    A.reshape(-1)[n::n + 1] = 1.0                   # the subdiagonal (a view)
    B = np.zeros((n, 1))
    B[:1] = 1.0
    C = (num[1:] - num[0] * den[1:]).reshape(1, n)
    return A, B, C, D


def ss2tf(sys: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(num, den)`` of a SISO system, with ``den`` monic of degree n.

    ``den = det(s I - A)`` and ``num = det(s I - A + B C) + (D - 1) den``
    (the identity behind ``scipy.signal.ss2tf``): no states are cancelled, so
    a non-minimal system gives common roots in num and den.
    """
    g = as_statespace(sys)
    if (g.noutputs, g.ninputs) != (1, 1):
        raise ValueError(f"ss2tf needs a SISO system, got {g.noutputs}x{g.ninputs}")
    d = float(g.D[0, 0])
    if g.nstates == 0:
        return np.array([d]), np.array([1.0])
    den = np.poly(g.A)
    num = np.poly(g.A - g.B @ g.C) + (d - 1.0) * den
    return num, den


#: Numerator coefficients at most this large (after normalising the
#: denominator to be monic) are round-off of a leading zero (scipy's rule in
#: ``scipy.signal.normalize``).
_NUM_ZERO = 1e-14


def ss2zpk(sys: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles and gain of a SISO system, as ``scipy.signal.ss2zpk``.

    Roots of :func:`ss2tf`'s polynomials; leading numerator coefficients of
    magnitude <= 1e-14 are dropped as round-off (``ss2tf`` leaves them where
    the relative degree exceeds the number of exact cancellations), silently
    where scipy warns ``BadCoefficients``. The gain is the leading numerator
    coefficient (the denominator is monic).
    """
    num, den = ss2tf(sys)
    lead = np.flatnonzero(np.abs(num) > _NUM_ZERO)
    num = num[lead[0]:] if lead.size else num[-1:]
    k = num[0]
    return np.roots(num / k), np.roots(den), float(k)


def as_statespace(sys: Any) -> StateSpace:
    """Our :class:`StateSpace` from a system of any supported kind.

    Accepts our own systems (returned as is), scalars and matrices (arrays
    or nested lists: static gains), objects with ``A, B, C, D`` attributes
    and an optional ``dt`` (python-control ``StateSpace``,
    :class:`toolbox.artifact.StateSpaceData`) and objects with ``num``/``den``
    indexable as ``[i][j]`` (python-control ``TransferFunction``, SISO or
    MIMO), without importing python-control: a python-control transfer
    function is realised by python-control (already imported, since the
    object exists), others by :func:`tf2ss`. python-control's ``dt = 0``
    means continuous.
    """
    if isinstance(sys, StateSpace):
        return sys
    if isinstance(sys, TransferFunction):
        return sys.to_statespace()
    if isinstance(sys, (int, float, np.integer, np.floating)) and not isinstance(sys, bool):
        return static_gain([[float(sys)]])
    if isinstance(sys, (np.ndarray, list)):
        return static_gain(sys)
    dt = _read_dt(getattr(sys, "dt", None))
    if all(hasattr(sys, k) for k in "ABCD"):
        return StateSpace(sys.A, sys.B, sys.C, sys.D, dt)
    if hasattr(sys, "num") and hasattr(sys, "den"):
        control = sys_modules.get("control")
        if control is not None and isinstance(sys, control.TransferFunction):
            # python-control is imported (the object exists): its own
            # realisation (SLICOT td04ad), so that a user's transfer function
            # gives the same states as before this module existed
            ss = control.ss(sys)
            return StateSpace(ss.A, ss.B, ss.C, ss.D, dt)
        return _tf_to_ss(sys, dt)
    raise TypeError(f"cannot read {type(sys).__name__} as a linear system")


@dataclass(frozen=True, eq=False)
class TransferFunction:
    """A continuous SISO transfer function ``num(s) / den(s)``.

    The form in which weighting filters are written (paper 003 eq (44)-(49)):
    products and sums stay exact polynomials, the response is evaluated from
    the coefficients and :meth:`to_statespace` realises it (:func:`tf2ss`).

    Parameters
    ----------
    num, den : array_like
        Coefficients in s, highest power first; stored as read-only 1-D float
        arrays without leading zeros (``den`` must not be zero).
    """

    num: np.ndarray
    den: np.ndarray

    def __post_init__(self) -> None:
        num, den = _poly(self.num), _poly(self.den)
        if not den.any():
            raise ValueError("TransferFunction: zero denominator")
        for k, v in (("num", num), ("den", den)):
            v.setflags(write=False)
            object.__setattr__(self, k, v)

    @classmethod
    def from_system(cls, sys: Any) -> "TransferFunction":
        """The transfer function of a SISO system of any supported kind.

        Ours (returned as is), a number, a python-control ``TransferFunction``
        (its ``num[0][0]``, ``den[0][0]``, read without importing it) or any
        system :func:`as_statespace` reads (:func:`ss2tf`: no cancellation).
        """
        if isinstance(sys, TransferFunction):
            return sys
        if isinstance(sys, (int, float, np.integer, np.floating)) and not isinstance(sys, bool):
            return cls([float(sys)], [1.0])
        if hasattr(sys, "num") and hasattr(sys, "den") and not hasattr(sys, "A"):
            if len(sys.num) != 1 or len(sys.num[0]) != 1:
                raise ValueError(f"TransferFunction: expected a SISO system, got "
                                 f"{len(sys.num)}x{len(sys.num[0])}")
            if _read_dt(getattr(sys, "dt", None)) is not None:
                raise ValueError("TransferFunction: expected a continuous system")
            return cls(sys.num[0][0], sys.den[0][0])
        g = as_statespace(sys)
        if g.discrete:
            raise ValueError("TransferFunction: expected a continuous system")
        return cls(*ss2tf(g))

    def __repr__(self) -> str:
        return f"TransferFunction(num={self.num.tolist()}, den={self.den.tolist()})"

    # -- analysis --------------------------------------------------------
    @property
    def order(self) -> int:
        """Degree of the denominator."""
        return self.den.size - 1

    @property
    def proper(self) -> bool:
        """Numerator degree at most the denominator's."""
        return self.num.size <= self.den.size

    def poles(self) -> np.ndarray:
        """Roots of the denominator."""
        return poly_roots(self.den)

    def zeros(self) -> np.ndarray:
        """Roots of the numerator (none for a constant or zero numerator)."""
        return poly_roots(self.num) if self.num.any() else np.zeros(0, complex)

    def __call__(self, x: Any) -> Any:
        """``num(x) / den(x)`` at complex point(s) ``x`` (scalar or array)."""
        x = np.asarray(x, complex)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.polyval(self.num, x) / np.polyval(self.den, x)
        return out[()] if out.ndim == 0 else out

    def freqresp(self, omega: Any) -> np.ndarray:
        """Response at ``j omega`` (rad/s), shape ``(1, 1, len(omega))`` as
        :meth:`StateSpace.freqresp`."""
        return self(1j * np.asarray(omega, float).reshape(-1))[None, None, :]

    def hf_gain(self) -> float:
        """``|W(j inf)|``: 0 when strictly proper (``inf`` when improper)."""
        if self.num.size < self.den.size or not self.num.any():
            return 0.0
        return abs(self.num[0] / self.den[0]) if self.proper else float("inf")

    # -- algebra ---------------------------------------------------------
    def __neg__(self) -> "TransferFunction":
        return TransferFunction(-self.num, self.den)

    def __mul__(self, other: Any) -> "TransferFunction":
        o = TransferFunction.from_system(other)
        return TransferFunction(np.polymul(self.num, o.num), np.polymul(self.den, o.den))

    __rmul__ = __mul__

    def __add__(self, other: Any) -> "TransferFunction":
        o = TransferFunction.from_system(other)
        num = np.polyadd(np.polymul(self.num, o.den), np.polymul(o.num, self.den))
        return TransferFunction(num, np.polymul(self.den, o.den))

    __radd__ = __add__

    def __sub__(self, other: Any) -> "TransferFunction":
        return self + (-TransferFunction.from_system(other))

    def inverse(self) -> "TransferFunction":
        """``den / num`` (error for a zero numerator)."""
        if not self.num.any():
            raise ValueError("TransferFunction: the inverse of zero")
        return TransferFunction(self.den, self.num)

    def minreal(self, tol: float = _CANCEL_TOL) -> "TransferFunction":
        """Cancel the poles and zeros closer than ``tol max(1, |z|)`` (the
        rule of python-control's transfer-function ``minreal``); unchanged
        coefficients when nothing cancels (roots are not re-expanded)."""
        num, den = minreal_coeffs(self.num, self.den, tol)
        return self if num is self.num else TransferFunction(num, den)

    def to_statespace(self) -> StateSpace:
        """Controllable canonical realisation (:func:`tf2ss`)."""
        return tf2ss(self.num, self.den)

    def to_control(self) -> Any:
        """The same transfer function as a ``control.TransferFunction``
        (imports python-control)."""
        import control

        return control.tf(self.num, self.den)


def _read_dt(dt: Any) -> float | None:
    """python-control's ``dt`` (0/None continuous, True unspecified) as ours."""
    if dt is None or dt is False or dt == 0:
        return None
    if dt is True:
        raise ValueError("a discrete system with unspecified sample time (dt=True)")
    return float(dt)


def _tf_to_ss(tf: Any, dt: float | None) -> StateSpace:
    """Realise a (MIMO) transfer function entry by entry.

    SISO: :func:`tf2ss`. MIMO: the block-diagonal union of the entries'
    realisations (not minimal; the toolbox's MIMO systems are built in state
    space, this serves users' inputs).
    """
    p, m = len(tf.num), len(tf.num[0])
    entries = [[tf2ss(tf.num[i][j], tf.den[i][j], dt) for j in range(m)] for i in range(p)]
    if p == m == 1:
        return entries[0][0]
    A = scipy.linalg.block_diag(*[e.A for row in entries for e in row])
    n = A.shape[0]
    B, C, D = np.zeros((n, m)), np.zeros((p, n)), np.zeros((p, m))
    k = 0
    for i in range(p):
        for j in range(m):
            e = entries[i][j]
            B[k:k + e.nstates, j] = e.B[:, 0]
            C[i, k:k + e.nstates] = e.C[0]
            D[i, j] = e.D[0, 0]
            k += e.nstates
    return StateSpace(A, B, C, D, dt)


# -- discretisation, delay, pole placement ------------------------------------
def c2d(sys: Any, dt: float, method: str = "zoh") -> StateSpace:
    """Discretise a continuous system at sample time ``dt``.

    ``method`` is ``zoh``, ``foh`` or a generalised bilinear transform
    (``tustin``/``bilinear``, ``euler``/``forward_diff``, ``backward_diff``).
    The formulas of ``scipy.signal.cont2discrete`` (``control.sample_system``
    without pre-warping), with numpy's solves for the bilinear transforms:
    the same numbers within rounding (``tests/test_lti.py``).
    """
    g = as_statespace(sys)
    if g.discrete:
        raise ValueError("c2d: the system is already discrete")
    dt = float(dt)
    a, b, c, d = g.A, g.B, g.C, g.D
    n, m = b.shape
    if method == "zoh":
        em = np.vstack([np.hstack([a, b]), np.zeros((m, n + m))])
        ms = scipy.linalg.expm(dt * em)[:n, :]
        return StateSpace(ms[:, :n], ms[:, n:], c, d, dt)
    if method == "foh":
        em_upper = scipy.linalg.block_diag(np.block([a, b]) * dt, np.eye(m))
        em = np.block([[em_upper], [np.zeros((m, n + 2 * m))]])
        ms = scipy.linalg.expm(em)
        ms11, ms12, ms13 = ms[:n, :n], ms[:n, n:n + m], ms[:n, n + m:]
        return StateSpace(ms11, ms12 - ms13 + ms11 @ ms13, c, d + c @ ms13, dt)
    if method in _GBT_ALPHA:
        alpha = _GBT_ALPHA[method]
        ima = np.eye(n) - alpha * dt * a
        # numpy's solve: scipy 1.17's batched one costs 0.1-4 ms a call here
        ad = np.linalg.solve(ima, np.eye(n) + (1.0 - alpha) * dt * a)
        bd = np.linalg.solve(ima, dt * b)
        cd = np.linalg.solve(ima.transpose(), c.transpose()).transpose()
        return StateSpace(ad, bd, cd, d + alpha * np.dot(c, bd), dt)
    raise ValueError(f"c2d: unknown method {method!r}; one of {list(C2D_METHODS)}")


def pade(T: float, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """``(num, den)`` of the order-``n`` Pade approximation of ``exp(-s T)``.

    Golub and Van Loan's accumulated coefficients (the recurrence of
    ``control.pade``), normalised so that ``den[0] = 1``.
    """
    if T < 0 or n < 0:
        raise ValueError(f"pade: need T >= 0 and n >= 0, got T={T}, n={n}")
    if T == 0:
        return np.array([1.0]), np.array([1.0])
    num, den = np.zeros(n + 1), np.zeros(n + 1)
    num[-1] = den[-1] = 1.0
    cn = cd = 1.0
    for k in range(1, n + 1):
        cn *= -T * (n - k + 1) / (2 * n - k + 1) / k
        cd *= T * (n - k + 1) / (2 * n - k + 1) / k
        num[-k - 1], den[-k - 1] = cn, cd
    return num / den[0], den / den[0]


def acker(A: Any, B: Any, poles: Sequence[complex]) -> np.ndarray:
    """Ackermann's gain K (1 x n) placing ``eig(A - B K)`` at ``poles``.

    ``K = e_n^T ctrb(A, B)^-1 p(A)`` with ``p`` the monic polynomial of the
    poles (single input). Raises ValueError when (A, B) is not controllable.
    """
    A, B = np.atleast_2d(np.asarray(A, float)), np.asarray(B, float).reshape(-1, 1)
    n = A.shape[0]
    ctrb = np.zeros((n, n))
    ctrb[:, :1] = B
    for k in range(1, n):                  # A^k B by repeated products, as control.ctrb
        ctrb[:, k:k + 1] = A @ ctrb[:, k - 1:k]
    if np.linalg.matrix_rank(ctrb) != n:
        raise ValueError("System not reachable; pole placement invalid")
    p = np.real(np.poly(poles))
    pmat = sum(p[n - i] * np.linalg.matrix_power(A, i) for i in range(n + 1))
    return np.linalg.solve(ctrb, pmat)[-1:, :]


# -- minimal realisation -------------------------------------------------------
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


# -- norms ---------------------------------------------------------------------
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
