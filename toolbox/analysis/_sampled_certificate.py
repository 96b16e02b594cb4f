"""Robust-stability certificate of the sampled coupled dq loop as executed.

The continuous certificate (:mod:`toolbox.analysis.certificate`) ignores the
sampling and the computation delay, so it can certify a box on which the
executed loop is unstable (paper 002's PI: ``Kp Ts / L`` reaches 3.6 at
half the inductance). This certificate is about the loop the robustness
sweep and the simulator run: :func:`toolbox.analysis.margins.coupled_closed_loop`
(ZOH plant at constant speed, the executed discrete laws of both axes, the
decoupling with the controller's parameters and the measured speed, the
delay line of ``delay_samples`` periods, and the voltage placement: the
commanded voltage enters through ``Gamma R(eps)``,
``eps = t_c w_m - (d + 1/2) Ts w``, toolbox/ARCHITECTURE.md "The digital
loop"; the back-EMF, an input that does not affect stability, through
``Gamma``).

Uncertainty: true ``R``, ``Ld``, ``Lq``, electrical speed ``w``, and the
measured speed ``w_m = g w + o`` of the decoupling (sensor gain ``g`` and
offset ``o``), each in an interval (:class:`SampledBox`); constant in time.

Soundness argument (every step is an over-bound, none an approximation):

1. *Coordinates.* The continuous plant enters the ZOH model only through
   ``X = Ts A(w)`` (4 entries) and ``b = Ts diag(B)`` (2 entries), from
   :func:`toolbox.plant.dq_matrices`: ``Phi = exp(X)``,
   ``Gamma = Psi(X) diag(b)`` with ``Psi(X) = sum_k X^k/(k+1)!``. Each
   entry (``Ts R/Ld``, ``Ts w Lq/Ld``, ``Ts/Ld``, ...) is monotone in each
   physical parameter, so its range over a cell is attained at the cell's
   16 corners; the box ``Theta`` of these ranges contains the cell's image.
   The placement error ``eps = t_c (g w + o) - (d + 1/2) Ts w``
   (:func:`~toolbox.analysis._coupled.placement_error`) is multi-affine in
   ``(w, g, o)``, so its range ``[eps_c - h, eps_c + h]`` over the cell is
   attained at the corners too; ``R(eps) = R(eps_c) (cos delta I + sin delta J)``,
   ``J = [[0, -1], [1, 0]]``, ``|delta| <= h``, and ``(cos delta, sin delta)``
   lies in the trapezoid ``Q`` with vertices ``(cos h, +/-sin h)``,
   ``(1, +/-tan(h/2))`` (bounded by the chord and the arc's tangents at
   ``delta = -h, 0, h``; valid for ``h < pi``, the square ``[-1, 1]^2``
   beyond; ``h`` widened by 1e-12 of the terms of ``eps`` for rounding).
   When ``eps`` is constant over the cell (``h = 0``: the default
   ``t_c = (d + 1/2) Ts`` without speed-sensor error gives ``eps = 0``
   exactly) ``Q`` is the point ``(1, 0)``.
2. *Linearisation with a remainder.* At the centre ``X_c`` of ``Theta``,
   ``exp(X_c + D) = exp(X_c) + Dexp[D] + r`` and likewise for ``Psi`` with
   the Frechet derivatives (block-triangular exponentials, exact), and
   ``||r_Phi||, ||r_Psi|| <= e^a (e^b - 1 - b)``, ``a = ||X_c||_2``,
   ``b = max ||X - X_c||_2`` over ``Theta`` (the series terms with two or
   more factors ``D``; the norm is convex, so its maximum over ``Theta`` is
   at a corner). Hence ``[r_Phi, r_Psi]`` has 2-norm at most
   ``rho = sqrt(2) e^a (e^b - 1 - b)``.
3. *Polytope.* With the linear parts, the closed-loop matrix is multi-affine
   in (the ``X`` coordinates, the ``b`` coordinates, ``w_m``) and affine in
   ``(cos delta, sin delta)``: the loop is affine in ``(Phi, Gamma_v)`` and,
   through the decoupling, in ``w_m``
   (:func:`~toolbox.analysis._coupled.coupled_state_matrix`), and
   ``Gamma_v,lin = Psi_lin diag(b) R(eps_c) (cos delta I + sin delta J)``, a
   product of factors each depending on one group of coordinates. Treating
   ``w_m`` and ``(cos delta, sin delta)`` as free in their ranges (ignoring
   their tie to ``w``, ``g``, ``o`` and the arc) only enlarges the set.
   A function multi-affine on a box times a polygon (affine in the polygon's
   point) is a convex combination of its values at the products of the box's
   corners and the polygon's vertices (the box's multi-affine weights times
   any convex weights of the point in the polygon; the same weights for all
   factors), so ``A_cl = sum_i l_i A_i + U r V x`` with the 64 x 2 x ``m``
   corner matrices ``A_i`` (``m`` = 4 vertices of ``Q``, 1 when ``h = 0``),
   ``U`` the current rows, ``r = [r_Phi, r_Psi]`` and
   ``V x = [i; diag(b) R(eps) u]`` (``u``: the commanded voltage's state map,
   so ``R(eps) u`` is the voltage applied in the rotor frame, on which the
   remainder ``r_Psi diag(b)`` acts); ``V`` is affine in the same
   coordinates, so ``V = sum_i l_i V_i`` with the same weights.
4. *Lyapunov with the S-procedure.* For ``w = r V x``, ``|w| <= rho |V x|``;
   if ``P > 0``, ``lam >= 0`` satisfy at every corner
   ``[[P - lam rho^2 V_i'V_i, 0, A_i'P], [0, lam I, U'P], [P A_i, P U, P]] > 0``
   then ``x'(.)x`` decreases along ``x+ = A_i x + U w`` for all such ``w``
   (Schur complement of the S-procedure inequality). That inequality is
   jointly matrix-convex in ``(A, V)`` (``[A U]'P[A U] + lam rho^2 V'V``),
   so it holds for every convex combination ``(sum l_i A_i, sum l_i V_i)``,
   hence for every plant, measured speed and placement error of the cell and
   every remainder: every frozen set of the cell has a Schur closed loop (in
   fact the cell is quadratically stable).
5. *Cells and check.* The speed range is split into cells (a Lyapunov
   matrix per cell: the certificate is for constant speed, as the sweep's
   loops are). The LMIs are handed to Clarabel directly
   (:mod:`toolbox.analysis._lmi`) and solved by constraint
   generation over the corners (its verdict is the full solve's), and every
   corner inequality is re-checked with numpy eigenvalues of the returned
   ``P, lam`` (a cell counts as certified only when that check passes).
   Warm starts (a smaller box's ``P``, the mirror image of the opposite
   speed cell's: ``(w, w_m) -> (-w, -w_m)`` maps ``eps`` to ``-eps`` and
   ``R(-eps) = S2 R(eps) S2``, ``S2 = diag(1, -1)``, the same similarity)
   pass the same check or are not used. A corner's LMI rows are assembled
   when it first enters a solve (constraint generation needs a few).

Steps 1-3's over-bounds of the plant over a cell (``Theta``, the linearisation
and its remainder, the placement polygon) are computed in
:mod:`toolbox.analysis._zoh_polytope`; the corner matrices, the LMIs and the
cells (steps 3-5) here.

The box at scale ``k`` interpolates from the nominal point (``k = 0``) to the
given ranges (``k = 1``); the bisection on ``k`` reports the largest certified
scale and, at the smallest refused scale, the "first uncertified corner": the
corner of the refused cell with the largest exact spectral radius (``unstable``
when that radius is >= 1, i.e. a true counterexample). The delay is the
design's (``delay_samples``); a set with another delay is not covered.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from ..lti import diagonal_scaling
from ..artifact import json_ready
from ..plant import max_electrical_speed
from ._coupled import coupled_closed_loop, coupled_state_matrix, rotation
from ._laws import AXES, axis_law, require_per_axis_laws
from ._lmi import (ACTIVE_STEP, above_identity, lmi_rows, problem_data,
                   solve_by_constraint_generation, solve_feasibility, symmetric_basis,
                   symmetric_matrix)
from ._sampling import DEFAULT_BOX, DEFAULT_RANGES
# steps 1-3; _vertices looks them up in this module (tests replace _placement_polygon
# here); _theta, _theta_box, _linearisation are re-exported for the tests
from ._zoh_polytope import (_linearisation, _placement_polygon, _theta,  # noqa: F401
                            _theta_box, _zoh_polytope)

__all__ = ["SampledBox", "SampledCertificate", "certify_sampled",
           "largest_certified_sampled_scale"]

#: strict margin of the vertex LMIs (the data are normalised to order 1)
_EPS = 1e-7
#: corner matrices per cell without placement error: the 2^6 corners of Theta times
#: the two measured-speed ends (times the placement polygon's 4 vertices when the
#: placement error varies over the cell)
_N_VERTICES = 2 ** 6 * 2


@dataclass(frozen=True)
class SampledBox:
    """True parameters, true speed and speed-sensor errors of the sampled certificate.

    Attributes
    ----------
    R, Ld, Lq : tuple
        ``(low, high)`` in ohm, H, H.
    omega : tuple
        True electrical speed range (rad/s).
    speed_gain : tuple
        Speed-sensor gain ``g`` range (1).
    speed_offset : tuple
        Speed-sensor offset ``o`` range (electrical rad/s); measured ``g w + o``.
    """

    R: tuple
    Ld: tuple
    Lq: tuple
    omega: tuple
    speed_gain: tuple = (1.0, 1.0)
    speed_offset: tuple = (0.0, 0.0)

    @classmethod
    def around(cls, motor, scale: float, *, R=DEFAULT_BOX["R"], L=DEFAULT_BOX["Ld"],
               omega_max: float = 0.0, speed_gain=(1.0, 1.0),
               speed_offset=(0.0, 0.0)) -> "SampledBox":
        """Box interpolated from the nominal point (``scale`` 0) to the factor
        ranges, ``|w| <= omega_max`` and the sensor ranges (``scale`` 1)."""
        def f(nom, lo_hi):
            lo, hi = lo_hi
            return (nom * (1 + scale * (lo - 1)), nom * (1 + scale * (hi - 1)))
        return cls(f(motor.R, R), f(motor.Ld, L), f(motor.Lq, L),
                   (-scale * omega_max, scale * omega_max), f(1.0, speed_gain),
                   (scale * speed_offset[0], scale * speed_offset[1]))

    def corners(self) -> np.ndarray:
        """All corners ``(R, Ld, Lq, w, g, o)`` (64, 6)."""
        return np.array(list(itertools.product(self.R, self.Ld, self.Lq, self.omega,
                                               self.speed_gain, self.speed_offset)), float)

    def measured_speed(self) -> tuple[float, float]:
        """Range of ``g w + o`` (bilinear: attained at corners)."""
        c = self.corners()
        wm = c[:, 4] * c[:, 3] + c[:, 5]
        return float(wm.min()), float(wm.max())

    def speed_cells(self, n: int) -> list["SampledBox"]:
        """The box with its speed range split into ``n`` equal cells, the
        fastest cells first (where a certificate usually fails)."""
        if self.omega[0] == self.omega[1]:
            return [self]          # one speed: one cell (the nominal point at scale 0)
        edges = np.linspace(self.omega[0], self.omega[1], n + 1)
        cells = [SampledBox(self.R, self.Ld, self.Lq, (float(a), float(b)), self.speed_gain,
                            self.speed_offset) for a, b in zip(edges[:-1], edges[1:])]
        return sorted(cells, key=lambda c: -max(abs(c.omega[0]), abs(c.omega[1])))

    def contains(self, R, Ld, Lq, omega, speed_gain=1.0, speed_offset=0.0) -> np.ndarray:
        """Which points lie in the box (bool array, bounds inclusive)."""
        def inside(v, lo_hi):
            return (np.asarray(v) >= lo_hi[0]) & (np.asarray(v) <= lo_hi[1])
        return (inside(R, self.R) & inside(Ld, self.Ld) & inside(Lq, self.Lq)
                & inside(omega, self.omega) & inside(speed_gain, self.speed_gain)
                & inside(speed_offset, self.speed_offset))


@dataclass(frozen=True)
class SampledCertificate:
    """Largest box on which the sampled coupled loop is certified stable.

    Attributes
    ----------
    certified : bool
        Some box (scale > 0, or the nominal point at scale 0) is certified.
    scale : float
        Largest certified box scale (0 nominal .. ``max_scale``).
    box : dict
        The certified :class:`SampledBox` (ohm, H, H, electrical rad/s, 1,
        electrical rad/s).
    speed_range_rad_s : list
        Certified true electrical speed range (rad/s).
    speed_range_mech_rad_s : list
        The same range in mechanical rad/s (``speed_range_rad_s / pole_pairs``;
        the spec's ``max_speed`` is mechanical).
    pole_pairs : int
        Pole pairs of the motor (electrical = ``pole_pairs`` x mechanical).
    delay_samples : int
        Computation delay of the certified loop (the design's).
    speed_cells : int
        Speed cells (one Lyapunov matrix each).
    n_vertices : int
        Corner matrices per cell, the largest over the certified cells (64
        plant coordinates x 2 measured speeds, x 4 vertices of the placement
        polygon when the placement error varies over the cell).
    remainder_bound : float
        Largest linearisation remainder ``rho`` of the certified cells.
    condition_P : float
        Largest condition number of the cells' Lyapunov matrices.
    first_uncertified : dict or None
        At the smallest refused scale: ``scale``, ``reason``, the refused
        cell's worst ``corner`` (scale factors ``R``, ``Ld``, ``Lq``,
        ``speed_gain``, offset ``speed_offset_rad_s``, ``omega_rad_s``),
        its exact ``spectral_radius`` and ``unstable`` (radius >= 1);
        None when the whole requested box is certified.
    basis : str
        What the certificate is about.
    """

    certified: bool
    scale: float
    box: dict
    speed_range_rad_s: list
    speed_range_mech_rad_s: list
    pole_pairs: int
    delay_samples: int
    speed_cells: int
    n_vertices: int
    remainder_bound: float
    condition_P: float
    first_uncertified: dict | None = None
    basis: str = field(default=(
        "sampled coupled dq loop as executed (ZOH plant, computation delay, decoupling with "
        "the controller's parameters and the measured speed, voltage placement Gamma R(eps)): "
        "common quadratic Lyapunov "
        "function per speed cell over a polytope containing the exact ZOH model "
        "(linearisation plus a norm-bounded remainder, S-procedure)"))

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready(asdict(self))


@dataclass(frozen=True)
class _CellOutcome:
    certified: bool
    reason: str
    rho: float
    condition_P: float
    worst_corner: np.ndarray      # (R, Ld, Lq, w, g, o) of the largest exact radius
    worst_radius: float
    n_vertices: int = _N_VERTICES  # corner matrices of the cell's polytope


def _laws(artifact) -> dict:
    return {k: axis_law(artifact.axes[k], True) for k in AXES}


def _vertices(artifact, laws, cell: SampledBox):
    """Corner matrices ``A_i`` (N, n, n), ``V_i`` (N, 4, n) and ``rho`` (steps 1-3).

    ``N = 64 x 2 x m``: the corners of ``Theta``, the two measured-speed ends
    and the ``m`` vertices of the placement polygon (:func:`_placement_polygon`;
    ``m = 1`` when the placement error is constant over the cell)."""
    Ts, d = artifact.sample_time, int(artifact.delay_samples)
    Phi, Gam, b, rho = _zoh_polytope(cell, Ts)
    wm = np.array(cell.measured_speed())
    eps_c, Q = _placement_polygon(artifact, cell)
    # R(eps) = R(eps_c) (cos delta I + sin delta J) at the polygon's vertices
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    Rot = rotation(eps_c)[0] @ (Q[:, 0, None, None] * np.eye(2) + Q[:, 1, None, None] * J)
    k, m = Phi.shape[0], Q.shape[0]
    Phi, Gam, b = (np.repeat(M, 2 * m, axis=0) for M in (Phi, Gam, b))
    wm = np.tile(np.repeat(wm, m), k)
    Rot = np.tile(Rot, (2 * k, 1, 1))
    dec = artifact.decoupling
    # the commanded voltage enters through Gamma R(eps) (coupled_closed_loop)
    A = coupled_state_matrix(laws, dec, d, Phi, Gam @ Rot, wm)
    n = A.shape[-1]
    zero = np.zeros_like(Phi)
    # the commanded voltage's state map: the current rows' gain on Gamma R(eps)
    S = (coupled_state_matrix(laws, dec, d, zero, np.broadcast_to(np.eye(2), Phi.shape), wm)
         - coupled_state_matrix(laws, dec, d, zero, zero, wm))[:, :2, :]
    V = np.zeros((A.shape[0], 4, n))
    V[:, 0, 0] = V[:, 1, 1] = 1.0
    # the rotated (applied) voltage scaled by b: the remainder's Psi factor multiplies it
    V[:, 2:, :] = b @ Rot @ S
    return A, V, rho


def _corner_matrices(A, G, U, P, lam) -> np.ndarray:
    """``[A_i U]' P [A_i U] - diag(P - lam G_i, lam I)`` (N, n+2, n+2): negative
    definite at every corner is step 4's condition (its Schur complement with
    respect to ``P > 0``)."""
    AU = np.concatenate([A, np.broadcast_to(U, (A.shape[0],) + U.shape)], axis=2)
    M = np.transpose(AU, (0, 2, 1)) @ P @ AU
    n = A.shape[-1]
    M[:, :n, :n] -= P - lam * G
    M[:, n:, n:] -= lam * np.eye(U.shape[1])
    return 0.5 * (M + np.transpose(M, (0, 2, 1)))


def _corner_slack(A, G, U, P, lam) -> np.ndarray:
    """Largest eigenvalue of each corner matrix, relative to its size (N,)."""
    ev = np.linalg.eigvalsh(_corner_matrices(A, G, U, P, lam))
    return ev[:, -1] / np.max(np.abs(ev), axis=-1)


def _worst_eig(A, G, U, P, lam) -> float:
    """Largest eigenvalue over the corners, relative to the matrices' size."""
    return float(np.max(_corner_slack(A, G, U, P, lam)))


#: a corner's inequality holds when its relative slack is below -_CHECK_MARGIN
_CHECK_MARGIN = 1e-12


def _verified(A, G, U, P, lam) -> bool:
    """A posteriori check of step 4 with numpy eigenvalues: ``P > 0``, ``lam >= 0``
    and every corner matrix negative definite."""
    P = 0.5 * (P + P.T)
    if not lam >= 0 or np.min(np.linalg.eigvalsh(P)) <= 0:
        return False
    return _worst_eig(A, G, U, P, lam) < -_CHECK_MARGIN


def _multiplier(A, G, U, P) -> float:
    """The S-procedure multiplier for a given ``P`` (warm start): the corners'
    largest eigenvalue is convex in ``lam``, so a golden-section search on
    ``log lam`` (unimodal) finds its minimiser."""
    lo, hi = -12.0, 12.0
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    f = lambda s: _worst_eig(A, G, U, P, 10.0 ** s)  # noqa: E731
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = f(a), f(b)
    for _ in range(40):
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = f(a)
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = f(b)
    return 10.0 ** (a if fa < fb else b)


def _lmi_blocks(A, G, U):
    """Clarabel rows of step 4's LMIs, assembled once per cell
    (:mod:`toolbox.analysis._lmi`): unknowns ``x = [upper triangle of P, lam]``.

    Returns ``(P >> I block, corner blocks (A (N, s, m+1), b (N, s)))``;
    corner ``i`` is ``-M_i(P, lam) - eps I >> 0`` with the corner matrix
    ``M_i`` of :func:`_corner_matrices`, linear in ``(P, lam)``.
    """
    N, n, _ = A.shape
    m = U.shape[1]
    E = symmetric_basis(n)
    ui, uj = np.triu_indices(n)
    AU = np.concatenate([A, np.broadcast_to(U, (N, n, m))], axis=2)
    # M_i(E_k) = [A_i U]' E_k [A_i U] - diag(E_k, 0); M_i(lam) = diag(G_i, -I).
    # E_k = e_u e_v' + e_v e_u' (u < v) or e_u e_u': the first term is the
    # outer product of rows u and v of [A_i U]
    C = np.zeros((N, E.shape[0] + 1, n + m, n + m))
    outer = AU[:, ui, :, None] * AU[:, uj, None, :]
    C[:, :-1] = outer + np.swapaxes(outer, -1, -2) * (ui != uj)[None, :, None, None]
    C[:, :-1, :n, :n] -= E[None]
    C[:, -1, :n, :n] = G
    C[:, -1, n:, n:] = -np.eye(m)
    corners = lmi_rows(np.broadcast_to(-_EPS * np.eye(n + m), (N, n + m, n + m)), -C)
    return above_identity(n, E.shape[0] + 1), corners


def _solve_lmi(A, G, U, order: np.ndarray, step: int = ACTIVE_STEP):
    """``(P, lam, status)`` of step 4's corner LMIs (Clarabel, called directly),
    by constraint generation over the corners, most likely binding first
    (``order``, ``step`` corners added per round; all at once when ``step``
    is at least their number); P None when the solver finds none. ``P >= I``
    fixes the scale. A P is returned only when it holds at every corner, and
    the verdict is then the solve over all corners'
    (:func:`toolbox.analysis._lmi.solve_by_constraint_generation`)."""
    n = A.shape[-1]
    n_x = n * (n + 1) // 2 + 1
    identity = above_identity(n, n_x)
    rows: dict = {}     # corner -> its rows, assembled when the corner first enters a solve

    def solve(idx):
        new = [i for i in idx if i not in rows]
        if new:
            _, (Ac, bc) = _lmi_blocks(A[new], G[new], U)
            rows.update(zip(new, zip(Ac, bc)))
        x, status = solve_feasibility(*problem_data(
            [identity] + [rows[i] for i in idx], n_x, nonneg=[n_x - 1]))
        return (None if x is None else (symmetric_matrix(x[:-1], n), float(x[-1]))), status

    sol, status = solve_by_constraint_generation(
        solve, lambda s: _corner_slack(A, G, U, *s), order, margin=_CHECK_MARGIN, step=step)
    return (None, 0.0, status) if sol is None else (*sol, status)


def _distinct_corners(A, G) -> np.ndarray:
    """Indices of the distinct corner pairs ``(A_i, G_i)`` (in their order): the
    box is degenerate in the coordinates that do not vary (all of them at
    scale 0), and a repeated corner is a repeated LMI."""
    flat = np.concatenate([A.reshape(A.shape[0], -1), G.reshape(G.shape[0], -1)], axis=1)
    return np.sort(np.unique(flat, axis=0, return_index=True)[1])


def _exact_corners(artifact, laws, cell: SampledBox) -> tuple[np.ndarray, np.ndarray]:
    """Exact spectral radii of the sampled loop at the cell's 64 corners."""
    c = cell.corners()
    loop = coupled_closed_loop(laws, artifact.decoupling, artifact.sample_time,
                               int(artifact.delay_samples), R=c[:, 0], Ld=c[:, 1], Lq=c[:, 2],
                               omega=c[:, 3], omega_meas=c[:, 4] * c[:, 3] + c[:, 5])
    return c, loop.spectral_radius()


@dataclass(frozen=True)
class _CellLMI:
    """Step 4's data of one cell: the distinct corner matrices ``A`` (N, n, n),
    ``G = rho^2 V'V`` and ``U`` after the diagonal similarity ``x = diag(t) x_b``
    (for conditioning), the corners' spectral radii and the remainder bound."""

    A: np.ndarray
    G: np.ndarray
    U: np.ndarray
    t: np.ndarray
    radii: np.ndarray
    rho: float
    n_vertices: int


def _cell_lmi(artifact, laws, cell: SampledBox) -> _CellLMI:
    """The corner data of a cell (steps 1-4), balanced, repeated corners dropped."""
    A, V, rho = _vertices(artifact, laws, cell)
    n_vertices = A.shape[0]
    G = rho ** 2 * np.transpose(V, (0, 2, 1)) @ V
    n = A.shape[-1]
    U = np.zeros((n, 2))
    U[0, 0] = U[1, 1] = 1.0
    # diagonal similarity x = T x_b from the mean corner matrix, for conditioning
    t = diagonal_scaling(np.mean(A, axis=0))
    keep = _distinct_corners(A, G)
    A, G = A[keep], G[keep]
    return _CellLMI(A * t[None, None, :] / t[None, :, None],
                    G * t[None, :, None] * t[None, None, :], U / t[:, None], t,
                    np.max(np.abs(np.linalg.eigvals(A)), axis=1), rho, n_vertices)


def _mirror_signs(laws, delay_samples: int) -> np.ndarray:
    """``S = diag(s)`` that maps the loop at ``(w, w_m)`` to the loop at
    ``(-w, -w_m)``: ``S A S``. Flipping the sign of ``i_q`` does
    (``dq_matrices``: ``S2 A(w) S2 = A(-w)``, and the decoupling likewise), with
    the q axis's law states and delayed voltages (the state order of
    :func:`~toolbox.analysis._coupled.coupled_state_matrix`)."""
    nd, nq = laws["d"].n, laws["q"].n
    s = np.ones(2 + nd + nq + 2 * delay_samples)
    s[1] = -1.0
    s[2 + nd:2 + nd + nq] = -1.0
    s[2 + nd + nq + 1::2] = -1.0
    return s


def _mirror(cell: SampledBox) -> SampledBox:
    """The cell of opposite speeds and sensor offsets."""
    return SampledBox(cell.R, cell.Ld, cell.Lq, (-cell.omega[1], -cell.omega[0]),
                      cell.speed_gain, (-cell.speed_offset[1], -cell.speed_offset[0]))


def _certify_cell(artifact, laws, cell: SampledBox, guesses: Sequence[tuple] = ()
                  ) -> tuple[_CellOutcome, np.ndarray | None, float]:
    """Outcome of one cell, its Lyapunov matrix (original coordinates, or None)
    and multiplier.

    ``guesses``: ``(P, lam)`` pairs tried first, in order - the mirror image
    of the opposite cell's certificate (an exact symmetry up to rounding, see
    :func:`_mirror_signs`; ``lam`` kept) and a Lyapunov matrix of a smaller
    nested cell (``lam`` None: its best multiplier). The LMIs are solved
    only when all fail the check. Either way a cell is certified only by the
    numpy check of step 4.
    """
    corners, radius = _exact_corners(artifact, laws, cell)
    i = int(np.argmax(radius))
    worst = (corners[i], float(radius[i]))
    if radius[i] >= 1.0 - 1e-9:
        return _CellOutcome(False, "a corner of the cell is unstable", math.nan, math.nan,
                            *worst), None, 0.0
    c = _cell_lmi(artifact, laws, cell)
    # step 4's corner inequality implies A_i' P A_i < P: a corner matrix of the
    # polytope that is not Schur makes the LMIs infeasible, no need to solve them
    if np.max(c.radii) >= 1.0:
        return _CellOutcome(False, "a corner of the polytope over the cell is unstable", c.rho,
                            math.nan, *worst, c.n_vertices), None, 0.0
    # constraint generation starts with the corners a rejected warm start
    # violates most, else with the least stable ones
    order = np.argsort(-c.radii)
    for guess, lam in guesses:
        Pg = guess * c.t[:, None] * c.t[None, :]
        lam = _multiplier(c.A, c.G, c.U, Pg) if lam is None else lam
        if _verified(c.A, c.G, c.U, Pg, lam):
            return (_CellOutcome(True, "warm start", c.rho, float(np.linalg.cond(Pg)), *worst,
                                 c.n_vertices), guess, lam)
        order = np.argsort(-_corner_slack(c.A, c.G, c.U, Pg, lam))
    P, lam, status = _solve_lmi(c.A, c.G, c.U, order)
    if P is None:
        return _CellOutcome(False, f"no Lyapunov matrix found ({status})", c.rho, math.nan,
                            *worst, c.n_vertices), None, 0.0
    if not _verified(c.A, c.G, c.U, P, lam):
        return _CellOutcome(False, "the solver's Lyapunov matrix fails the numpy check", c.rho,
                            math.nan, *worst, c.n_vertices), None, 0.0
    return (_CellOutcome(True, status, c.rho, float(np.linalg.cond(P)), *worst, c.n_vertices),
            P / c.t[:, None] / c.t[None, :], lam)


def certify_sampled(artifact, box: SampledBox, *, speed_cells: int = 2,
                    guesses: dict | None = None) -> tuple[bool, list[_CellOutcome]]:
    """Certify the sampled coupled loop on a box (module docstring).

    Parameters
    ----------
    artifact : ControllerArtifact
    box : SampledBox
    speed_cells : int
        Speed cells, each with its own Lyapunov matrix.
    guesses : dict, optional
        ``{cell index: P}`` warm starts, updated with the matrices found
        (the bisection passes the same dict from box to box).

    Returns
    -------
    (bool, list)
        Whether every cell is certified, and the outcome of each cell tried
        (fastest first; stops at the first refused cell).
    """
    require_per_axis_laws(artifact, "the sampled certificate")
    laws = _laws(artifact)
    signs = _mirror_signs(laws, int(artifact.delay_samples))
    guesses = {} if guesses is None else guesses
    certified: dict = {}       # cell -> (P, lam) of this box, for its mirror image
    outcomes = []
    for k, cell in enumerate(box.speed_cells(speed_cells)):
        tries = []
        if _mirror(cell) in certified:
            P, lam = certified[_mirror(cell)]
            tries.append((signs[:, None] * P * signs[None, :], lam))
        if guesses.get(k) is not None:
            tries.append((guesses[k], None))
        out, P, lam = _certify_cell(artifact, laws, cell, tries)
        outcomes.append(out)
        if not out.certified:
            return False, outcomes
        guesses[k] = P
        certified[cell] = (P, lam)
    return True, outcomes


def _corner_dict(motor, corner: np.ndarray, radius: float) -> dict:
    R, Ld, Lq, w, g, o = (float(v) for v in corner)
    return {"R": R / motor.R, "Ld": Ld / motor.Ld, "Lq": Lq / motor.Lq, "omega_rad_s": w,
            "speed_gain": g, "speed_offset_rad_s": o, "spectral_radius": radius,
            "unstable": bool(radius >= 1.0 - 1e-9)}


def largest_certified_sampled_scale(artifact, motor, drive=None, *, R=DEFAULT_BOX["R"],
                                    L=DEFAULT_BOX["Ld"],
                                    speed_gain=DEFAULT_RANGES["speed_gain"][:2],
                                    speed_offset=DEFAULT_RANGES["speed_offset"][:2],
                                    omega_max: float | None = None, speed_cells: int = 2,
                                    tol: float = 0.05,
                                    max_scale: float = 1.0) -> SampledCertificate:
    """Bisection on the box scale of the sampled-loop certificate.

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant (centre of the box).
    drive : Drive, optional
        Supplies the speed range when ``omega_max`` is None
        (:func:`toolbox.plant.max_electrical_speed`).
    R, L : tuple
        Factor ranges of the resistance and of both inductances at scale 1
        (default the robustness sweep's, x0.5..x2).
    speed_gain : tuple
        Speed-sensor gain range at scale 1 (default the sweep's, 0.9..1.1).
    speed_offset : tuple
        Speed-sensor offset range at scale 1, **mechanical** rad/s as in the
        sweep (default +/-10).
    omega_max : float, optional
        Largest electrical speed at scale 1 (rad/s).
    speed_cells : int
        Speed cells per box.
    tol : float
        Bisection tolerance on the scale.
    max_scale : float
        Largest scale tried.

    Returns
    -------
    SampledCertificate
    """
    wmax = max_electrical_speed(motor, drive) if omega_max is None else omega_max
    off = tuple(motor.pole_pairs * v for v in speed_offset)
    guesses: dict = {}

    def box(k):
        return SampledBox.around(motor, k, R=R, L=L, omega_max=wmax, speed_gain=speed_gain,
                                 speed_offset=off)

    def at(k):
        return certify_sampled(artifact, box(k), speed_cells=speed_cells, guesses=guesses)

    def refused(k, outcomes):
        o = outcomes[-1]
        return {"scale": k, "reason": o.reason,
                "corner": _corner_dict(motor, o.worst_corner, o.worst_radius)}

    def result(k, outcomes, first):
        b = box(k)
        ok = [o for o in outcomes if o.certified]
        return SampledCertificate(
            certified=bool(outcomes and all(o.certified for o in outcomes)), scale=k,
            box=json_ready(asdict(b)), speed_range_rad_s=list(b.omega),
            speed_range_mech_rad_s=[w / motor.pole_pairs for w in b.omega],
            pole_pairs=int(motor.pole_pairs),
            delay_samples=int(artifact.delay_samples), speed_cells=speed_cells,
            n_vertices=max((o.n_vertices for o in ok), default=_N_VERTICES),
            remainder_bound=max((o.rho for o in ok), default=math.nan),
            condition_P=max((o.condition_P for o in ok), default=math.nan),
            first_uncertified=first)

    ok_top, out_top = at(max_scale)
    if ok_top:
        return result(max_scale, out_top, None)
    ok0, out0 = at(0.0)
    if not ok0:
        return result(0.0, out0, refused(0.0, out0))
    lo, hi, best, first = 0.0, max_scale, out0, refused(max_scale, out_top)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        ok, out = at(mid)
        if ok:
            lo, best = mid, out
        else:
            hi, first = mid, refused(mid, out)
    return result(lo, best, first)
