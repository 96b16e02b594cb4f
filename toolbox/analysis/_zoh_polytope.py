"""The sampled loop's plant over one cell, as a polytope: steps 1-3 of the
soundness argument of the sampled certificate (the argument is written out
once, complete, in the docstring of :mod:`toolbox.analysis._sampled_certificate`).

Holds the coordinates ``Theta`` of the ZOH model (``X = Ts A(w)``,
``b = Ts diag(B)``) and their box over a cell (step 1), the linearisation of
``exp`` and ``Psi`` at its centre with the remainder bound ``rho`` (step 2),
the linear parts of ``Phi`` and ``Gamma`` at the box's corners, and the
polygon containing the placement rotation's ``(cos delta, sin delta)``
(steps 1 and 3). The closed-loop corner matrices built from them
(``_vertices``), the LMIs and the cells are the certificate's.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import expm

from ..plant import dq_matrices
from ._coupled import placement_error

if TYPE_CHECKING:
    from ._sampled_certificate import SampledBox

def _theta(points: np.ndarray, Ts: float) -> np.ndarray:
    """``(X00, X01, X10, X11, b_d, b_q)`` with ``X = Ts A(w)``, ``b = Ts diag(B)``
    from :func:`toolbox.plant.dq_matrices` at points ``(R, Ld, Lq, w, ...)``."""
    A, B = dq_matrices(points[:, 0], points[:, 1], points[:, 2], points[:, 3])
    if np.any(B[:, 0, 1] != 0) or np.any(B[:, 1, 0] != 0):
        raise ValueError("the sampled certificate assumes a diagonal input matrix B")
    X = Ts * A
    return np.stack([X[:, 0, 0], X[:, 0, 1], X[:, 1, 0], X[:, 1, 1],
                     Ts * B[:, 0, 0], Ts * B[:, 1, 1]], axis=1)


@dataclass(frozen=True)
class _ZohLinearisation:
    """``exp`` and ``Psi`` linearised at ``X_c`` with the remainder bound ``rho``
    on ``||[Phi - Phi_lin, Psi - Psi_lin]||_2`` over ``||X - X_c||_2 <= dev``
    (module docstring, step 2)."""

    Xc: np.ndarray     # (2, 2)
    eZ: np.ndarray     # exp([[X_c, I], [0, 0]]) (4, 4)
    dZ: np.ndarray     # its Frechet derivatives along the four entries of X (4, 4, 4)
    rho: float

    @classmethod
    def at(cls, Xc: np.ndarray, dev: float) -> "_ZohLinearisation":
        """Linearisation at ``Xc`` valid for ``||X - Xc||_2 <= dev``."""
        # Z = [[X, I], [0, 0]]: exp(Z) = [[exp X, Psi(X)], [0, I]]
        Z = np.zeros((4, 4))
        Z[:2, :2] = Xc
        Z[:2, 2:] = np.eye(2)
        # D exp_Z[E] is the top-right block of exp([[Z, E], [0, Z]])
        big = np.zeros((4, 8, 8))
        for j in range(4):
            big[j, :4, :4] = Z
            big[j, 4:, 4:] = Z
            big[j, j // 2, 4 + j % 2] = 1.0
        a = float(np.linalg.norm(Xc, 2))
        rho = math.sqrt(2.0) * math.exp(a) * (math.expm1(dev) - dev)
        return cls(np.array(Xc, float), expm(Z), expm(big)[:, :4, 4:], rho)

    def parts(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear parts ``Phi_lin``, ``Psi_lin`` (N, 2, 2) at ``X`` (N, 2, 2)."""
        D = (X - self.Xc).reshape(-1, 4)
        Phi = self.eZ[:2, :2] + np.einsum("vj,jab->vab", D, self.dZ[:, :2, :2])
        Psi = self.eZ[:2, 2:] + np.einsum("vj,jab->vab", D, self.dZ[:, :2, 2:])
        return Phi, Psi


def _theta_box(cell: SampledBox, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """``Theta``: ranges of the six coordinates over the cell (step 1)."""
    th = _theta(cell.corners(), Ts)
    return th.min(axis=0), th.max(axis=0)


def _linearisation(cell: SampledBox, Ts: float) -> _ZohLinearisation:
    """Linearisation at the centre of ``Theta``, valid on all of ``Theta``."""
    lo, hi = _theta_box(cell, Ts)
    Xv = np.array(list(itertools.product(*zip(lo[:4], hi[:4]))), float).reshape(-1, 2, 2)
    Xc = (0.5 * (lo + hi))[:4].reshape(2, 2)
    # ||X - X_c|| is convex in X: its maximum over the box is at a corner
    dev = float(np.max(np.linalg.norm(Xv - Xc, 2, axis=(1, 2))))
    return _ZohLinearisation.at(Xc, dev)


def _zoh_polytope(cell: SampledBox, Ts: float):
    """Linear parts of ``Phi`` and ``Gamma`` at the 64 corners of ``Theta`` and
    the remainder bound (module docstring, steps 1-3).

    Returns ``(Phi (64, 2, 2), Gamma (64, 2, 2), b (64, 2, 2) diagonal, rho)``.
    """
    lo, hi = _theta_box(cell, Ts)
    lin = _linearisation(cell, Ts)
    V = np.array(list(itertools.product(*zip(lo, hi))), float)          # (64, 6)
    Phi, Psi = lin.parts(V[:, :4].reshape(-1, 2, 2))
    b = np.zeros((V.shape[0], 2, 2))
    b[:, 0, 0], b[:, 1, 1] = V[:, 4], V[:, 5]
    return Phi, Psi @ b, b, lin.rho


def _placement_polygon(artifact, cell: SampledBox) -> tuple[float, np.ndarray]:
    """``(eps_c, Q)``: the centre of the placement error's range over the cell
    and the vertices ``Q`` (m, 2) of a polygon containing every
    ``(cos delta, sin delta)``, ``delta = eps - eps_c`` (module docstring,
    step 3).

    ``eps = t_c (g w + o) - (d + 1/2) Ts w``
    (:func:`~toolbox.analysis._coupled.placement_error`) is multi-affine in
    ``(w, g, o)``: its range over the cell is attained at the cell's
    corners. With ``D`` the half-width: ``D = 0`` gives the single vertex
    ``(1, 0)`` (no extra corners); ``0 < D < pi`` the trapezoid bounded by
    the chord at ``cos D`` and the tangents at ``delta = -D, 0, D``,
    vertices ``(cos D, +/-sin D)`` and ``(1, +/-tan(D/2))``; ``D >= pi`` the
    square ``[-1, 1]^2``.
    """
    c = cell.corners()
    d = int(artifact.delay_samples)
    wm = c[:, 4] * c[:, 3] + c[:, 5]
    eps = placement_error(artifact.decoupling, artifact.sample_time, d, c[:, 3], wm)
    lo, hi = float(np.min(eps)), float(np.max(eps))
    eps_c = 0.5 * (lo + hi)
    if hi == lo:
        return eps_c, np.array([[1.0, 0.0]])
    # widened by far more than the rounding of eps (a difference of two terms
    # that may nearly cancel), eps_c and D
    terms = max(float(np.max(np.abs(artifact.decoupling.delay_compensation_time * wm))),
                float(np.max(np.abs((d + 0.5) * artifact.sample_time * c[:, 3]))))
    D = 0.5 * (hi - lo) + 1e-12 * terms
    if D >= math.pi:
        return eps_c, np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, -1.0], [1.0, 1.0]])
    t = math.tan(0.5 * D)
    return eps_c, np.array([[math.cos(D), -math.sin(D)], [math.cos(D), math.sin(D)],
                            [1.0, -t], [1.0, t]])
