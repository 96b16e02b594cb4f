"""State-space algebra of the loop analyses (numpy, stacked where useful).

Frequency responses, series connection, closed loop of a law with a plant,
stability tests and zero-order-hold discretisations (single and stacked 2x2).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import expm

from ..lti import StateSpace, balanced, evaluate, pade as lti_pade, series as lti_series, tf2ss
from ..plant import zoh_first_order

if TYPE_CHECKING:
    from ._laws import Law

__all__ = ["freqresp", "FreqResponse", "zoh_axis", "plant_chain", "pade", "series", "closed_loop", "is_stable",
           "zoh_coupled", "zoh_2x2"]


def freqresp(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
             x: np.ndarray) -> np.ndarray:
    """``C (x I - A)^-1 B + D`` at the complex points ``x`` (s or z), shape
    ``(len(x), p, m)``: :func:`toolbox.lti.evaluate` with per-point LU solves
    (the one frequency-response route), in the analysis stage's axis order."""
    return np.moveaxis(evaluate(A, B, C, D, x, solve=True), -1, 0)


class FreqResponse:
    """``C (x I - A)^-1 B + D`` of one system at many points, vectorised.

    The modal sum of :attr:`toolbox.lti.StateSpace.modal` (A diagonalised
    once) for a grid while A's eigenvectors are well conditioned (then within
    ~1e-10 of an LU solve); a nearly defective A (integrator chains, repeated
    poles) keeps per-point LU solves (:meth:`toolbox.lti.StateSpace.evaluate`).
    A SISO system is also evaluated at single points in plain Python
    (:meth:`at`), which the margin refinements call hundreds of times.

    Parameters
    ----------
    A, B, C, D : ndarray
        Real state-space matrices, (n, n), (n, m), (p, n), (p, m).
    """

    def __init__(self, A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray) -> None:
        self.system = StateSpace(A, B, C, D)
        self.modal = self.system.modal
        self._siso = None
        if self.modal is not None and self.system.D.size == 1:
            lam, R = self.modal
            self._siso = (list(zip(R[0, 0].tolist(), lam.tolist())),
                          complex(self.system.D[0, 0]))

    def at(self, x: complex) -> complex:
        """Response of a SISO system at one point ``x`` (a Python complex).

        The modal form is summed in plain Python arithmetic (~2 us, where any
        numpy call costs more); otherwise, or exactly on a pole, one
        LU solve.
        """
        if self._siso is not None:
            try:
                return sum(r / (x - lam) for r, lam in self._siso[0]) + self._siso[1]
            except ZeroDivisionError:           # exactly on a pole
                pass
        return complex(self.system.evaluate([x])[0, 0, 0])

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Response at the complex points ``x``: shape ``(len(x), p, m)``."""
        x = np.asarray(x, complex).reshape(-1)
        if x.size == 1 and self._siso is not None:
            return np.array([[[self.at(complex(x[0]))]]])
        return np.moveaxis(self.system.evaluate(x), -1, 0)


def zoh_axis(R, L, Ts) -> tuple[np.ndarray, np.ndarray]:
    """ZOH discretisation of ``1/(R + s L)``: ``(a, b)`` (broadcasts);
    :func:`toolbox.plant.zoh_first_order`."""
    return zoh_first_order(R, L, Ts)


def plant_chain(a: float, b: float, d: int, Ts: float) -> tuple[np.ndarray, ...]:
    """State space of ``z^-d b/(z - a)``; the current is the first state."""
    n = 1 + d
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    C = np.zeros((1, n))
    A[0, 0] = a
    C[0, 0] = 1.0
    if d == 0:
        B[0, 0] = b
    else:
        A[0, 1] = b          # i+ = a i + b q1
        for j in range(1, d):
            A[j, j + 1] = 1.0  # q_j+ = q_{j+1}
        B[d, 0] = 1.0        # q_d+ = v
    return A, B, C, np.zeros((1, 1))


def pade(tau: float, order: int) -> tuple[np.ndarray, ...]:
    """State space of the ``order`` Pade approximation of ``exp(-s tau)``.

    The controllable canonical form of :func:`toolbox.lti.tf2ss` holds the
    coefficients ``tau^-k`` (1e13 for a third-order 150 us delay), so its
    states are scaled by :func:`toolbox.lti.balanced` (powers of two: exact),
    as python-control's slycot realisation was.
    """
    sys = tf2ss(*lti_pade(tau, order))
    A, B, C, D = (np.array(M) for M in (sys.A, sys.B, sys.C, sys.D))    # writable copies
    if A.size:
        A, B, C = balanced(A, B, C)
    return A, B, C, D


def series(first: tuple, second: tuple) -> tuple[np.ndarray, ...]:
    """``(A, B, C, D)`` of ``second * first`` (signal passes ``first`` then
    ``second``): :func:`toolbox.lti.series` on array tuples."""
    g = lti_series(StateSpace(*first), StateSpace(*second))
    return g.A, g.B, g.C, g.D


def closed_loop(law: Law, plant: tuple) -> tuple[np.ndarray, ...]:
    """Reference -> current closed loop of a law and a strictly proper plant.

    ``plant`` is ``(Ap, Bp, Cp, Dp)`` from voltage (V) to current (A) with
    ``Dp = 0``. States ``[x_law, x_plant]``; returns ``(A, B, C, D)``.
    """
    Ap, Bp, Cp, Dp = plant
    if np.any(Dp):
        raise ValueError("plant must be strictly proper")
    Ak, Bk, Ck, Dk = law.A, law.B, law.C, law.D
    A = np.block([[Ak, Bk[:, 1:2] @ Cp],
                  [Bp @ Ck, Ap + Bp @ Dk[:, 1:2] @ Cp]])
    B = np.vstack([Bk[:, 0:1], Bp @ Dk[:, 0:1]])
    C = np.hstack([np.zeros((1, law.n)), Cp])
    return A, B, C, np.zeros((1, 1))


def is_stable(A: np.ndarray, discrete: bool, tol: float = 1e-9) -> bool:
    """Schur (discrete) or Hurwitz (continuous) test of a state matrix."""
    if A.shape[0] == 0:
        return True
    ev = np.linalg.eigvals(A)
    return bool(np.all(np.abs(ev) < 1 - tol) if discrete else np.all(ev.real < -tol))


def zoh_coupled(Ac: np.ndarray, Bc: np.ndarray, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Stacked ZOH discretisation: ``Ac`` (N, n, n), ``Bc`` (N, n, m).

    Returns ``Phi = exp(A Ts)`` and ``Gamma = int_0^Ts exp(A t) dt B``
    through the exponential of the augmented matrix ``[[A, B], [0, 0]] Ts``.
    """
    N, n, _ = Ac.shape
    m = Bc.shape[2]
    M = np.zeros((N, n + m, n + m))
    M[:, :n, :n] = Ac * Ts
    M[:, :n, n:] = Bc * Ts
    E = expm(M)
    return E[:, :n, :n], E[:, :n, n:]


def zoh_2x2(A: np.ndarray, B: np.ndarray, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form ZOH of stacked 2x2 plants (fast twin of :func:`zoh_coupled`).

    ``exp(A T) = exp(m T) [cosh(D T) I + T sinhc(D T) (A - m I)]`` with
    ``m = tr A / 2``, ``D = sqrt(m^2 - det A)`` (complex) and
    ``sinhc(x) = sinh(x)/x`` (series near 0); ``Gamma = A^-1 (Phi - I) B``,
    valid because ``det A = R^2/(Ld Lq) + omega^2 > 0`` for the dq plant.
    """
    m = 0.5 * (A[:, 0, 0] + A[:, 1, 1])
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    D = np.sqrt((m * m - det).astype(complex))
    x = D * Ts
    small = np.abs(x) < 1e-3
    xs = np.where(small, 1.0, x)
    with np.errstate(over="ignore", invalid="ignore"):
        sinhc = np.where(small, 1 + x * x / 6 + x ** 4 / 120, np.sinh(xs) / xs)
        e = np.exp(m * Ts)
        c0 = np.real(e * np.cosh(x))
        c1 = np.real(e * Ts * sinhc)
    bad = ~(np.isfinite(c0) & np.isfinite(c1))
    if np.any(bad):
        # a fast stiff plant (L/R far below Ts, e.g. R x2 and L x0.5 of a
        # plausible motor at a slow sample time): exp(m T) underflows to 0 while
        # cosh(D T) overflows, 0 x inf = nan. The same coefficients with the
        # exponents added first, exp(m T +- D T), stay finite because
        # |Re D| < |m| (det A > 0); only where the product form failed, so
        # every other number keeps its bits.
        mb, xb = m[bad] * Ts, x[bad]
        with np.errstate(over="ignore", invalid="ignore", under="ignore"):
            ep, em = np.exp(mb + xb), np.exp(mb - xb)
            c0[bad] = np.real(0.5 * (ep + em))
            c1[bad] = np.real(np.where(small[bad], np.exp(mb) * Ts * sinhc[bad],
                                       Ts * (ep - em) / (2 * xs[bad])))
    I = np.eye(2)
    Phi = c0[:, None, None] * I + c1[:, None, None] * (A - m[:, None, None] * I)
    Gam = np.linalg.solve(A, (Phi - I) @ B)
    return Phi, Gam
