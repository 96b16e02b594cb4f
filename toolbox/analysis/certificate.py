"""Robust stability certificate by a common quadratic Lyapunov function.

Model (continuous time, stated assumptions): the continuous controllers of
both axes (the continuous twin of the executed law, as in
:func:`toolbox.analysis.margins.axis_law`), the dq plant at constant
electrical speed ``omega`` (paper 003 eq (3)-(4)) and the cross-coupling
compensation of the artifact, ``v = u + W i``,
``W = g omega [[0, -Lq_c], [Ld_c, 0]]`` (controller model parameters
``Ld_c, Lq_c``; speed-sensor gain ``g``). Sampling and computation delay are
not in this model by default (use ``delay=True``, below, or the discrete
margins and the sweep).
Back-EMF and its compensation are exogenous constants and do not affect
stability.

Parameter dependence: the closed-loop matrix is **not** affine in
``(R, Ld, Lq, omega)`` (``1/L`` and products appear), but it is affine in the
six coordinates

``theta = (1/Ld, 1/Lq, R/Ld, R/Lq, omega (Lq - g Lq_c)/Ld, omega (Ld - g Ld_c)/Lq)``:

``di_d/dt = -theta_3 i_d + theta_5 i_q + theta_1 u_d``,
``di_q/dt = -theta_4 i_q - theta_6 i_d + theta_2 u_q``.

Each coordinate is multilinear in ``(R, 1/Ld or Ld, Lq, omega, g)`` and
monotone in each, so its range over the parameter box is attained at the
box's corners. The box in ``theta`` spanned by these ranges contains the
image of the parameter box (it ignores the correlations between
coordinates: conservative, never optimistic). ``A(theta)`` being affine, a
common ``P`` with ``A_i' P + P A_i <= -2 alpha P`` at the 64 vertices holds
on the whole ``theta`` box by convexity, hence on the parameter box:
quadratic stability with decay rate ``alpha`` (1/s) for any (even slowly
time-varying) parameters and speed in the box.

With ``delay=True`` the sampling-plus-computation delay ``(d + 1/2) Ts``
enters as a first-order Pade approximant on the commanded voltage (control
law and decoupling); the closed loop is then affine in nine coordinates
``(1/Ld, 1/Lq, R/Ld, R/Lq, w Lq/Ld, w Ld/Lq, g w/Ld, g w/Lq, g w)`` (same
corner argument; up to 512 vertices). This is still a continuous
approximation of the sampled loop, which the robustness sweep evaluates
exactly.

The LMIs are solved with Clarabel (called directly) after a diagonal similarity
(LAPACK dgebal's scaling of the nominal matrix), with ``P >= I`` and
a margin ``eps`` on each vertex LMI, then checked a posteriori with numpy
eigenvalues of the returned ``P`` (a certificate is only reported when that
check passes).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass

import numpy as np

from ..lti import diagonal_scaling
from ..plant import dq_matrices, max_electrical_speed
from ._lmi import (above_identity, lmi_rows, problem_data, solve_by_constraint_generation,
                   solve_feasibility, symmetric_basis, symmetric_matrix)
from ._laws import require_per_axis_laws
from .margins import AXES, axis_law, json_ready

__all__ = ["CertificateResult", "ParameterBox", "closed_loop_matrix",
           "closed_loop_matrix_delay", "point_matrices", "certify",
           "largest_certified_scale"]


@dataclass(frozen=True)
class ParameterBox:
    """Box of true plant parameters and speeds.

    Attributes
    ----------
    R, Ld, Lq : tuple
        ``(low, high)`` in ohm, H, H.
    omega : tuple
        Electrical speed range (rad/s).
    speed_gain : tuple
        Speed-sensor gain range (1).
    """

    R: tuple
    Ld: tuple
    Lq: tuple
    omega: tuple
    speed_gain: tuple = (1.0, 1.0)

    @classmethod
    def around(cls, motor, scale: float, *, R=(0.5, 2.0), L=(0.5, 2.0),
               omega_max: float = 0.0, speed_gain=(1.0, 1.0)) -> "ParameterBox":
        """Box interpolated from the nominal point (``scale`` 0) to the given
        factor ranges and speed range (``scale`` 1)."""
        def f(nom, lo_hi):
            lo, hi = lo_hi
            return (nom * (1 + scale * (lo - 1)), nom * (1 + scale * (hi - 1)))
        return cls(f(motor.R, R), f(motor.Ld, L), f(motor.Lq, L),
                   (-scale * omega_max, scale * omega_max),
                   (1 + scale * (speed_gain[0] - 1), 1 + scale * (speed_gain[1] - 1)))

    def corners(self) -> np.ndarray:
        """All corners ``(R, Ld, Lq, omega, g)`` (32, 5)."""
        return np.array(list(itertools.product(self.R, self.Ld, self.Lq, self.omega,
                                               self.speed_gain)), float)

    def sample(self, n: int, seed: int = 0) -> np.ndarray:
        """``n`` uniform random points plus the corners (for checks)."""
        rng = np.random.default_rng(seed)
        lo = np.array([self.R[0], self.Ld[0], self.Lq[0], self.omega[0], self.speed_gain[0]])
        hi = np.array([self.R[1], self.Ld[1], self.Lq[1], self.omega[1], self.speed_gain[1]])
        return np.vstack([self.corners(), lo + rng.random((n, 5)) * (hi - lo)])


def _plant_entries(points: np.ndarray):
    """The dq plant at parameter points, from :func:`toolbox.plant.dq_matrices`.

    Returns ``A`` (N, 2, 2) and ``B`` (N, 2, 2) of ``di/dt = A(omega) i + B v``
    (paper 003 eq (3)-(4)); the certificate's coordinates are read off these
    entries so that the dq model is written once, in :mod:`toolbox.plant`.
    """
    R, Ld, Lq, om, _ = points.T
    return dq_matrices(R, Ld, Lq, om)


def _coupling(points: np.ndarray, dec) -> np.ndarray:
    """``g omega cross``: the speed the decoupling ``W`` is scaled by (N,)."""
    _, _, _, om, g = points.T
    return (1.0 if dec.cross else 0.0) * g * om


def _theta(points: np.ndarray, dec) -> np.ndarray:
    """The six affine coordinates (module docstring) at parameter points.

    The plant seen by the linear law is ``A + B W`` with the decoupling
    ``W = g omega [[0, -Lq_c], [Ld_c, 0]]``; ``theta`` lists its entries
    ``(B_dd, B_qq, -M_dd, -M_qq, M_dq, -M_qd)`` with ``M = A + B W``.
    """
    A, B = _plant_entries(points)
    h = _coupling(points, dec)
    B_d, B_q = B[:, 0, 0], B[:, 1, 1]
    # (B W)_dq = -h Lq_c B_d, (B W)_qd = h Ld_c B_q
    m_dq = A[:, 0, 1] - h * dec.Lq_c * B_d
    m_qd = A[:, 1, 0] + h * dec.Ld_c * B_q
    return np.stack([B_d, B_q, -A[:, 0, 0], -A[:, 1, 1], m_dq, -m_qd], axis=1)


def _laws(artifact):
    return [axis_law(artifact.axes[k], False) for k in AXES]


def closed_loop_matrix(artifact, theta: np.ndarray) -> np.ndarray:
    """Continuous closed-loop state matrix at coordinates ``theta`` (..., 6).

    States ``[i_d, i_q, x_d, x_q]`` (controller states of each axis).
    Affine in ``theta`` by construction (module docstring).
    """
    theta = np.atleast_2d(theta)
    ld, lq = _laws(artifact)
    nd, nq = ld.n, lq.n
    n = 2 + nd + nq
    N = theta.shape[0]
    a_d, a_q, r_d, r_q, c_d, c_q = theta.T
    A = np.zeros((N, n, n))
    # u = C x + D_m i  (measurement channel of the law)
    Ud = np.zeros((N, n))
    Uq = np.zeros((N, n))
    Ud[:, 0] = ld.D[0, 1]
    Ud[:, 2:2 + nd] = ld.C[0]
    Uq[:, 1] = lq.D[0, 1]
    Uq[:, 2 + nd:] = lq.C[0]
    A[:, 0, :] = a_d[:, None] * Ud
    A[:, 0, 0] += -r_d
    A[:, 0, 1] += c_d
    A[:, 1, :] = a_q[:, None] * Uq
    A[:, 1, 1] += -r_q
    A[:, 1, 0] += -c_q
    A[:, 2:2 + nd, 0] = ld.B[:, 1]
    A[:, 2:2 + nd, 2:2 + nd] = ld.A
    A[:, 2 + nd:, 1] = lq.B[:, 1]
    A[:, 2 + nd:, 2 + nd:] = lq.A
    return A


def _theta_delay(points: np.ndarray, dec) -> np.ndarray:
    """The nine affine coordinates of the Pade-delay model at parameter points:
    the plant entries ``(B_dd, B_qq, -A_dd, -A_qq, A_dq, -A_qd)`` of
    :func:`toolbox.plant.dq_matrices`, then ``h B_dd``, ``h B_qq`` and ``h``
    with ``h = cross g omega`` (the decoupling's speed)."""
    A, B = _plant_entries(points)
    h = _coupling(points, dec)
    B_d, B_q = B[:, 0, 0], B[:, 1, 1]
    return np.stack([B_d, B_q, -A[:, 0, 0], -A[:, 1, 1], A[:, 0, 1], -A[:, 1, 0],
                     h * B_d, h * B_q, h], axis=1)


def closed_loop_matrix_delay(artifact, theta: np.ndarray, tau: float) -> np.ndarray:
    """Closed-loop matrix with a first-order Pade delay ``tau`` (s) per axis.

    The commanded voltage ``v = u + W i`` (control law plus decoupling)
    passes ``(1 - s tau/2)/(1 + s tau/2)``: states ``xi`` with
    ``xi' = (2/tau)(v - xi)``, applied voltage ``2 xi - v``. Affine in the
    nine coordinates ``theta = (1/Ld, 1/Lq, R/Ld, R/Lq, w Lq/Ld, w Ld/Lq,
    g w/Ld, g w/Lq, g w)``; states ``[i_d, i_q, x_d, x_q, xi_d, xi_q]``.
    """
    theta = np.atleast_2d(theta)
    dec = artifact.decoupling
    ld, lq = _laws(artifact)
    nd, nq = ld.n, lq.n
    n = 4 + nd + nq
    N = theta.shape[0]
    a_d, a_q, r_d, r_q, e_d, e_q, f_d, f_q, h = theta.T
    # commanded voltage rows (v = V x), W terms carry g w (coordinate h or f/a)
    Ud = np.zeros((N, n))
    Uq = np.zeros((N, n))
    Ud[:, 0] = ld.D[0, 1]
    Ud[:, 2:2 + nd] = ld.C[0]
    Uq[:, 1] = lq.D[0, 1]
    Uq[:, 2 + nd:2 + nd + nq] = lq.C[0]
    ixd, ixq = 2 + nd + nq, 3 + nd + nq
    A = np.zeros((N, n, n))
    # plant: di_d = -r_d i_d + e_d i_q + a_d (2 xi_d - u_d) + f_d Lq_c i_q
    A[:, 0, :] = -a_d[:, None] * Ud
    A[:, 0, 0] += -r_d
    A[:, 0, 1] += e_d + f_d * dec.Lq_c
    A[:, 0, ixd] += 2 * a_d
    #        di_q = -r_q i_q - e_q i_d + a_q (2 xi_q - u_q) - f_q Ld_c i_d
    A[:, 1, :] = -a_q[:, None] * Uq
    A[:, 1, 1] += -r_q
    A[:, 1, 0] += -e_q - f_q * dec.Ld_c
    A[:, 1, ixq] += 2 * a_q
    A[:, 2:2 + nd, 0] = ld.B[:, 1]
    A[:, 2:2 + nd, 2:2 + nd] = ld.A
    A[:, 2 + nd:2 + nd + nq, 1] = lq.B[:, 1]
    A[:, 2 + nd:2 + nd + nq, 2 + nd:2 + nd + nq] = lq.A
    k = 2.0 / tau
    A[:, ixd, :] = k * Ud
    A[:, ixd, 1] += -k * h * dec.Lq_c
    A[:, ixd, ixd] += -k
    A[:, ixq, :] = k * Uq
    A[:, ixq, 0] += k * h * dec.Ld_c
    A[:, ixq, ixq] += -k
    return A


def point_matrices(artifact, points: np.ndarray, delay: bool = False) -> np.ndarray:
    """Closed-loop matrices at parameter points ``(R, Ld, Lq, omega, g)``
    (with ``delay``: the Pade-delay model of :func:`closed_loop_matrix_delay`,
    ``tau = (delay_samples + 1/2) Ts``)."""
    points = np.atleast_2d(points)
    if delay:
        return closed_loop_matrix_delay(artifact, _theta_delay(points, artifact.decoupling),
                                        _tau(artifact))
    return closed_loop_matrix(artifact, _theta(points, artifact.decoupling))


def _tau(artifact) -> float:
    return (artifact.delay_samples + 0.5) * artifact.sample_time


@dataclass(frozen=True)
class CertificateResult:
    """Outcome of a quadratic-stability search.

    Attributes
    ----------
    certified : bool
        A common Lyapunov matrix was found and verified.
    alpha : float
        Decay rate certified (1/s): every trajectory decays at least as
        ``exp(-alpha t)`` (in the P-norm).
    box : dict
        The parameter box (ohm, H, H, rad/s, 1).
    n_vertices : int
        Vertices of the theta box (64).
    status : str
        Solver status.
    condition_P : float
        Condition number of P (nan if none).
    scale : float
        Box scale factor (for :func:`largest_certified_scale`).
    """

    certified: bool
    alpha: float
    box: dict
    n_vertices: int
    status: str
    condition_P: float
    scale: float = math.nan

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready(asdict(self))


def _vertices(artifact, box: ParameterBox, delay: bool = False) -> np.ndarray:
    f = _theta_delay if delay else _theta
    th = f(box.corners(), artifact.decoupling)
    lo, hi = th.min(axis=0), th.max(axis=0)
    # a coordinate that does not vary contributes one value, not two
    V = np.array(list(itertools.product(*[(a,) if a == b else (a, b) for a, b in zip(lo, hi)])),
                 float)
    if delay:
        return closed_loop_matrix_delay(artifact, V, _tau(artifact))
    return closed_loop_matrix(artifact, V)


def _lmi_data(As: np.ndarray, alpha: float, eps: float = 1e-6):
    """Clarabel's ``(A, b, cones)`` of the vertex LMIs (see :func:`_solve`)."""
    N, n, _ = As.shape
    E = symmetric_basis(n)
    # L_i(E_k) = A_i' E_k + E_k A_i + 2 alpha E_k for all vertices and basis matrices
    AtE = np.einsum("vji,kjl->vkil", As, E)
    L = AtE + np.transpose(AtE, (0, 1, 3, 2)) + 2 * alpha * E[None]
    # P - I >> 0, then -L_i(P) - eps I >> 0 at every vertex
    A_v, b_v = lmi_rows(np.broadcast_to(-eps * np.eye(n), (N, n, n)), -L)
    return problem_data([above_identity(n, E.shape[0])] + list(zip(A_v, b_v)), E.shape[0])


def _solve(As: np.ndarray, alpha: float, eps: float = 1e-6):
    """Solve ``A_i' P + P A_i + 2 alpha P << -eps I`` (every vertex ``A_i``), ``P >> I``.

    The semidefinite program is handed to Clarabel directly (cvxpy's
    canonicalisation was 60 % of the certificate's time and cvxpy's import
    another second; :mod:`toolbox.analysis._lmi`). The unknown ``x`` is the
    upper triangle of ``P``; ``P >> I`` is the cone constraint
    ``svec(P) - svec(I)`` and each vertex LMI the cone constraint
    ``-svec(A_i' E + E A_i + 2 alpha E) x - eps svec(I)`` (Clarabel form
    ``b - A x`` in the PSD triangle cone). These are the matrices cvxpy
    built for the constant-data problem (tested equal), with the same zero
    objective and solver settings (defaults).

    Returns ``(P, status)``; ``P`` is None unless the solver reports
    (almost) solved; a numerical failure is status ``"solver error: ..."``
    (cvxpy raised an exception there).
    """
    x, status = solve_feasibility(*_lmi_data(As, alpha, eps))
    return (None if x is None else symmetric_matrix(x, As.shape[1])), status


def _vertex_slack(As: np.ndarray, P: np.ndarray, alpha: float) -> np.ndarray:
    """Largest eigenvalue of each vertex LMI ``A_i' P + P A_i + 2 alpha P`` (N,)."""
    M = np.transpose(As, (0, 2, 1)) @ P + P @ As + 2 * alpha * P
    return np.linalg.eigvalsh(0.5 * (M + np.transpose(M, (0, 2, 1))))[:, -1]


def _solve_active(As: np.ndarray, alpha: float, guess: np.ndarray | None = None):
    """:func:`_solve` on the vertices that matter, found by constraint generation.

    :func:`toolbox.analysis._lmi.solve_by_constraint_generation`, starting with
    the vertices that a rejected warm start ``guess`` - the certificate of the
    last smaller box - violates most, else those of largest spectral abscissa
    (paper 003's H-infinity boxes need 8 to 12 of their 64 vertices). Its
    verdict is the full solve's; a P from a subset is returned only when it
    holds on every vertex (what :func:`_verified` checks again).

    Returns ``(P, status)`` as :func:`_solve`, on the data ``As`` (normalised
    here by the largest entry of all vertices, as before; ``guess`` in the
    coordinates of ``As``).
    """
    norm = max(1.0, float(np.max(np.abs(As))))
    worst = (_vertex_slack(As, guess, alpha) if guess is not None
             else np.linalg.eigvals(As).real.max(axis=1))
    return solve_by_constraint_generation(
        lambda idx: _solve(As[idx] / norm, alpha / norm),
        lambda P: _vertex_slack(As, P, alpha), np.argsort(-worst))


def _verified(As: np.ndarray, P: np.ndarray, alpha: float) -> bool:
    P = 0.5 * (P + P.T)
    if np.min(np.linalg.eigvalsh(P)) <= 0:
        return False
    return bool(np.max(_vertex_slack(As, P, alpha)) < 0)


def certify(artifact, box: ParameterBox, *, alpha: float = 0.0,
            delay: bool = False) -> CertificateResult:
    """Search a common quadratic Lyapunov function over a parameter box.

    Parameters
    ----------
    artifact : ControllerArtifact
    box : ParameterBox
        True-parameter and speed ranges.
    alpha : float
        Decay rate to certify (1/s); 0 for plain quadratic stability.
    delay : bool
        Include the sampling-plus-computation delay ``(d + 1/2) Ts`` as a
        first-order Pade approximant in the loop (decoupling included):
        nine affine coordinates, up to 512 vertices (slower).

    Returns
    -------
    CertificateResult
    """
    require_per_axis_laws(artifact, "the continuous certificate")
    return _certify(artifact, box, alpha, delay)[0]


def _unstable_vertex(As: np.ndarray, alpha: float) -> bool:
    """Some vertex has an eigenvalue with real part clearly above ``-alpha``.

    Then no ``P > 0`` satisfies its LMI: for an eigenvector ``v`` of ``A_i``
    with eigenvalue ``lambda``, ``v* (A_i' P + P A_i + 2 alpha P) v =
    2 Re(lambda + alpha) v* P v`` is not negative. The margin (1e-9 of the
    largest entry) keeps eigenvalue rounding from deciding.
    """
    lam = np.linalg.eigvals(As).real.max()
    return bool(lam > -alpha + 1e-9 * float(np.max(np.abs(As))))


def _balanced_vertices(artifact, box: ParameterBox, As: np.ndarray, delay: bool):
    """``(T^-1 A_i T, T, T^-1)``: the vertices ``As`` in the coordinates of the
    diagonal similarity ``T`` that balances the box-centre matrix
    (:func:`toolbox.lti.diagonal_scaling`, LAPACK dgebal: conditioning of the
    LMIs; the certificate is ``T^-1 P T^-1`` back in the original ones)."""
    centre = point_matrices(artifact, np.mean(box.corners(), axis=0), delay)[0]
    scale_vec = diagonal_scaling(centre)
    T = np.diag(scale_vec)
    Ti = np.diag(1 / scale_vec)
    return Ti @ As @ T, T, Ti


def _certify(artifact, box: ParameterBox, alpha: float, delay: bool,
             guess: np.ndarray | None = None,
             prescreen: bool = False) -> tuple[CertificateResult, np.ndarray | None]:
    """:func:`certify` plus the Lyapunov matrix in the original coordinates.

    ``guess`` (a P in original coordinates, e.g. from a smaller box) is the
    warm start: when it passes the a posteriori check on this box's
    vertices, it is the certificate and no LMI is solved (status
    ``"warm start"``); else the LMIs are solved as usual. With ``prescreen``
    a box with an unstable vertex (:func:`_unstable_vertex`) is declared not
    certified without a solve (status ``"infeasible (unstable vertex)"``);
    the bisection uses it, where an uncertified box only steers.
    """
    As = _vertices(artifact, box, delay)
    if prescreen and _unstable_vertex(As, alpha):
        return (CertificateResult(False, float(alpha), json_ready(asdict(box)),
                                  int(As.shape[0]), "infeasible (unstable vertex)",
                                  math.nan), None)
    Ab, T, Ti = _balanced_vertices(artifact, box, As, delay)
    Pg = None
    if guess is not None:
        # x_b = T^-1 x: V = x' P0 x = x_b' (T P0 T) x_b
        Pg = T @ guess @ T
        if _verified(Ab, Pg, alpha):
            return (CertificateResult(True, float(alpha), json_ready(asdict(box)),
                                      int(As.shape[0]), "warm start",
                                      float(np.linalg.cond(Pg))), guess)
    P, status = _solve_active(Ab, alpha, Pg)
    ok = P is not None and _verified(Ab, P, alpha)
    result = CertificateResult(bool(ok), float(alpha), json_ready(asdict(box)),
                               int(As.shape[0]), status,
                               float(np.linalg.cond(P)) if P is not None else math.nan)
    return result, (Ti @ P @ Ti if ok else None)


def largest_certified_scale(artifact, motor, drive=None, *, R=(0.5, 2.0), L=(0.5, 2.0),
                            speed_gain=(1.0, 1.0), omega_max: float | None = None,
                            alpha: float = 0.0, tol: float = 0.05,
                            max_scale: float = 1.0, delay: bool = False) -> CertificateResult:
    """Bisection on the box scale factor (0 nominal .. ``max_scale``).

    The box at scale ``k`` is :meth:`ParameterBox.around` (parameter
    deviations and speed range scaled by ``k``). Returns the certificate of
    the largest certified scale (``scale`` attribute; 0 and
    ``certified=False`` if even the nominal point fails).

    Parameters
    ----------
    artifact : ControllerArtifact
        The design.
    motor : Motor
        Nominal plant (centre of the box).
    drive : Drive, optional
        Supplies the speed range when ``omega_max`` is None.
    R, L : tuple of float
        Multiplier ranges of the resistance and of both inductances at scale 1.
    speed_gain : tuple of float
        Speed-sensor gain range at scale 1.
    omega_max : float, optional
        Largest electrical speed (rad/s) at scale 1.
    alpha : float
        Required decay rate (1/s).
    tol : float
        Bisection tolerance on the scale.
    max_scale : float
        Largest scale tried.
    delay : bool
        Include a first-order Pade model of the computation delay.
    """
    require_per_axis_laws(artifact, "the continuous certificate")
    wmax = max_electrical_speed(motor, drive) if omega_max is None else omega_max

    def at(k, guess=None, prescreen=True):
        box = ParameterBox.around(motor, k, R=R, L=L, omega_max=wmax, speed_gain=speed_gain)
        res, P = _certify(artifact, box, alpha, delay, guess, prescreen)
        return CertificateResult(**{**asdict(res), "scale": k}), P

    top, _ = at(max_scale)
    if top.certified:
        return top
    # the nominal result is reported when it fails: solved, never prescreened;
    # elsewhere a box with an unstable vertex is infeasible without a solve
    # (3 of the 6 solves of paper 003's H-infinity bisection)
    nominal, P_best = at(0.0, prescreen=False)
    if not nominal.certified:
        return nominal
    # warm start: the Lyapunov matrix of the largest certified box so far is
    # tried first on the next (larger) box; the boxes are nested, so it often
    # holds there too and the solve is skipped. Only the certified flag steers
    # the bisection, and a P that passes the check is a certificate whichever
    # way it was found.
    lo, hi, best = 0.0, max_scale, nominal
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        r, P = at(mid, P_best)
        if r.certified:
            lo, best, P_best = mid, r, P
        else:
            hi = mid
    return best
