"""The system classes of :mod:`toolbox.lti` (:class:`StateSpace`,
:class:`TransferFunction`), their interconnections (series, parallel,
append, feedback) and the conversions between them and from python-control
systems (one module: the classes' operators and the conversions call each
other).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from sys import modules as sys_modules
from typing import Any

import numpy as np
import scipy.linalg

from ._linalg import invariant_zeros, modal_form, _eigvals, _identity, _solve
from ._poly import minreal_coeffs, poly_roots, _CANCEL_TOL, _poly, _tf2ss_arrays


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

    def evaluate(self, x: Any, solve: bool = False) -> np.ndarray:
        """``C (x I - A)^-1 B + D`` at complex points ``x``: shape ``(p, m, len(x))``
        (:func:`evaluate`, with this system's modal form computed once)."""
        x = np.asarray(x, complex).reshape(-1)
        modal = None if solve or x.size < 2 or self.nstates == 0 else self.modal
        return evaluate(self.A, self.B, self.C, self.D, x, solve=modal is None, modal=modal)

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


def evaluate(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, x: Any,
             solve: bool = False,
             modal: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """``C (x I - A)^-1 B + D`` at complex points ``x``: shape ``(p, m, len(x))``.

    The toolbox's one frequency-response route (``s = j w`` or ``z = e^{j w T}``
    alike). Two evaluations of the same formula:

    * ``solve=False`` (default): the modal sum of :func:`modal_form` serves a
      grid while A's eigenvectors are well conditioned (relative error
      ~cond(V) eps <= ~1e-10); ``modal`` may pass a form computed before. One
      point, or a (nearly) defective A, takes the per-point LU solves.
    * ``solve=True``: one LU solve per point (LAPACK gesv, stacked; relative
      error ~cond(x I - A) eps), for callers that compare two realisations to
      ~1e-10 or evaluate a few points.

    A point exactly on a pole gives inf/nan entries.
    """
    x = np.asarray(x, complex).reshape(-1)
    p, m, n = D.shape[0], D.shape[1], A.shape[0]
    if n == 0:
        return np.repeat(np.asarray(D, complex)[:, :, None], x.size, axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        if not solve and x.size > 1:
            if modal is None:
                modal = modal_form(A, B, C)
            if modal is not None:
                lam, R = modal
                inv = x[None, :] - lam[:, None]                      # (n, N)
                np.divide(1.0, inv, out=inv)     # in place: a grid's (n, N) is large
                if p == m == 1:                  # a product, 2-3x faster than einsum
                    y = R[0, 0] @ inv
                    y += D[0, 0]
                    return y[None, None, :]
                return np.einsum("pmk,kN->pmN", R, inv) + D[:, :, None]
        M = x[:, None, None] * np.eye(n) - A
        try:
            y = np.linalg.solve(M, np.broadcast_to(np.asarray(B, complex), (x.size, n, m)))
        except np.linalg.LinAlgError:
            y = np.stack([_solve_or_inf(Mi, B) for Mi in M])
        return np.moveaxis(C @ y + D, 0, -1)


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
    n1, n = g1.nstates, g1.nstates + g2.nstates
    A = np.zeros((n, n))                    # blocks written in place (np.block: ~10x slower)
    A[:n1, :n1], A[n1:, :n1], A[n1:, n1:] = g1.A, g2.B @ g1.C, g2.A
    B = np.empty((n, g1.ninputs))
    B[:n1], B[n1:] = g1.B, g2.B @ g1.D
    C = np.empty((g2.noutputs, n))
    C[:, :n1], C[:, n1:] = g2.D @ g1.C, g2.C
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


def tf2ss(num: Any, den: Any, dt: float | None = None) -> StateSpace:
    """Controllable canonical realisation of a proper SISO ``num/den``.

    Same form as ``scipy.signal.tf2ss``: ``A`` has ``-den[1:]/den[0]`` as its
    first row, ``B = e1``, ``C = num' - num'_0 den'`` and ``D = num'_0``
    (primes: normalised so that ``den[0] = 1``, ``num`` padded to its degree).
    """
    A, B, C, D = _tf2ss_arrays(_poly(num), _poly(den))
    return static_gain(D, dt) if A.size == 0 else StateSpace(A, B, C, D, dt)


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
