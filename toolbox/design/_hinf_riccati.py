"""Theorem 1 and 2 of paper 003: the Riccati tests and the central controller.

All equation numbers refer to paper 003 (Azaiz et al. 2007), which follows
Glover & Doyle (1988) and Zhou, Doyle & Glover, *Robust and Optimal Control*
(1995), ch. 17 (the general case with D11 != 0): the normalisation of eq
(65)-(67), the Riccati data of eq (10)-(17), the feasibility tests of
Theorem 1 (eq 18-22) and the central controller of Theorem 2 (eq 23-32).
Linear algebra through the documented functions of numpy.linalg and
scipy.linalg (``schur``, ``solve_continuous_are``), options by keyword.

Damaged or wrong equations of the paper, re-derived here:

* eq (28) prints ``C2hat = -D12hat (C2 + F12)``; the correct factor is
  ``D21hat`` (Zhou-Doyle-Glover); in paper 003 both are 1 at gamma = 1, so
  the printed numbers do not reveal it.
* eq (30) prints a factor ``U12`` in ``C1hat``; it is not part of the
  formula (the output rotation is undone on the plant side, not here).
* eq (21) prints ``-(B1 Ds1^T - Y C^T)``; the sign is ``+`` (``L = -(B1
  Ds1^T + Y C^T) Rnj^-1``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla

from ..lti import StateSpace, spectral_norm
from ..errors import DesignInfeasible, SpecError
from ._hinf_assumptions import _check_balanced
from ._hinf_plant import PartitionedPlant, balance_plant

__all__ = ["HinfFeasibility", "hinf_feasibility", "central_controller"]

GAMMA_KEY = "controller.hinf.gamma"


# --------------------------------------------------------------------------
# normalisation eq (65)-(67)
# --------------------------------------------------------------------------
@dataclass(slots=True)
class _Normalised:
    P: PartitionedPlant          # normalised plant, D12 = [0; I], D21 = [0 I], D22 = 0
    R12inv: np.ndarray           # u = R12inv u~
    R21inv: np.ndarray           # y~ = R21inv y


def _normalise(P: PartitionedPlant, svds: tuple[tuple, tuple] | None = None) -> _Normalised:
    """Rotate/scale w, z, u, y so that D12 = [0; I] and D21 = [0 I] (eq 65-67).

    Orthogonal rotations of z and w keep the norm of T_zw; the invertible
    scalings of u and y are undone on the controller (K = R12^-1 K~ R21^-1).
    D22 is set to zero here; it is restored by a loop shift in
    :func:`central_controller`. ``svds``: the full SVDs of D12 and D21 when
    already computed.
    """
    m2, p2 = P.nu, P.ny
    # D12 = U [S;0] V^T, D21 = U21 [S 0] V21^T
    (U, s12, V12t), (U21, s21, V21t) = svds or (np.linalg.svd(P.D12), np.linalg.svd(P.D21))
    Uz = np.concatenate([U[:, m2:], U[:, :m2]], axis=1).T   # Uz D12 = [0; S V^T]
    VwT = np.concatenate([V21t[p2:], V21t[:p2]]).T           # D21 VwT = [0, U S]
    # R12 = S V^T and R21 = U S are inverted from their factors (orthogonal
    # transposes, 1/s), not by an LU of the product
    R12inv, R21inv = V12t.T / s12, U21.T / s21[:, None]
    Pn = P._derived(B1=P.B1 @ VwT, B2=P.B2 @ R12inv, C1=Uz @ P.C1, C2=R21inv @ P.C2,
                    D11=Uz @ P.D11 @ VwT, D12=Uz @ P.D12 @ R12inv,
                    D21=R21inv @ P.D21 @ VwT, D22=np.zeros(P.D22.shape))
    return _Normalised(P=Pn, R12inv=R12inv, R21inv=R21inv)


def _d11_blocks(Pn: PartitionedPlant) -> tuple[np.ndarray, ...]:
    """D1111, D1112, D1121, D1122 of the normalised D11 (Theorem 1)."""
    r, c = Pn.nz - Pn.nu, Pn.nw - Pn.ny
    D = Pn.D11
    return D[:r, :c], D[:r, c:], D[r:, :c], D[r:, c:]


# --------------------------------------------------------------------------
# Riccati equations, eq (14)-(19)
# --------------------------------------------------------------------------
@dataclass(slots=True)
class _Hamiltonian:
    """The gamma-free parts of the Hamiltonian (eq 16/17) of one Riccati equation
    ``a^T X + X a - (X b + s) r^-1 (b^T X + s^T) + q = 0``: with them the
    Hamiltonian at a given r is one solve and one product,

    ``H = [[a, 0], [-q, -a^T]] - [b; -s] r^-1 [s^T, b^T]``

    (whose blocks are ``a - b r^-1 s^T``, ``-b r^-1 b^T``, ``-(q - s r^-1 s^T)``
    and ``-(a - b r^-1 s^T)^T`` for a symmetric r), formed once per plant for the
    whole gamma iteration."""

    a: np.ndarray
    b: np.ndarray
    q: np.ndarray
    s: np.ndarray
    H0: np.ndarray      # [[a, 0], [-q, -a^T]]
    W: np.ndarray       # [b; -s]
    V: np.ndarray       # [s^T, b^T]


def _hamiltonian(a: np.ndarray, b: np.ndarray, q: np.ndarray, s: np.ndarray) -> _Hamiltonian:
    n = a.shape[0]
    H0 = np.zeros((2 * n, 2 * n))
    H0[:n, :n] = a
    H0[n:, :n] = -q                  # faster than np.negative(..., out=) on such sizes
    H0[n:, n:] = -a.T
    return _Hamiltonian(a=a, b=b, q=q, s=s, H0=H0, W=np.concatenate([b, -s]),
                        V=np.concatenate([s.T, b.T], axis=1))


def _ric(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray,
         s: np.ndarray) -> tuple[np.ndarray | None, str]:
    """Stabilising solution of a^T X + X a - (X b + s) r^-1 (b^T X + s^T) + q = 0
    (``r`` symmetric). Returns ``(X, "")`` or ``(None, reason)``; see
    :func:`_ric_h`."""
    return _ric_h(_hamiltonian(a, b, q, s), r)


def _ric_h(h: _Hamiltonian, r: np.ndarray) -> tuple[np.ndarray | None, str]:
    """:func:`_ric` of the equation with gamma-free parts ``h`` at ``r``.

    First the ordered real Schur form of the Hamiltonian (eq 16/17,
    ``scipy.linalg.schur(sort="lhp")``). When that route fails (no n stable
    eigenvalues, or an ill-conditioned basis Z11), scipy's generalised Schur
    method on the extended pencil (``solve_continuous_are``), which does not
    invert the indefinite r, has the last word.
    """
    X, wr, wi = _ric_schur_h(h, r)
    if X is None:
        return _ric_pencil(h, r)
    return _stabilising(X, wr, wi)


def _ric_pencil(h: _Hamiltonian, r: np.ndarray) -> tuple[np.ndarray | None, str]:
    """:func:`_ric_h` by scipy's generalised Schur method on the extended
    pencil (``solve_continuous_are``) alone."""
    a, b, s = h.a, h.b, h.s
    try:
        X = sla.solve_continuous_are(a, b, h.q, r, s=s)
    except (np.linalg.LinAlgError, ValueError):
        return None, ("the Hamiltonian has eigenvalues on the imaginary axis "
                      "or no stabilising solution exists")
    F = np.linalg.solve(r, b.T @ X + s.T)
    ev = np.linalg.eigvals(a - b @ F)
    return _stabilising(_symmetric_part(X), ev.real, ev.imag)


def _stabilising(X: np.ndarray, wr: Any, wi: Any) -> tuple[np.ndarray | None, str]:
    """``(X, "")`` when the closed-loop poles ``wr + j wi`` are stable."""
    # a few poles: scalar code beats array calls (as in _imag_axis_modes)
    wr, wi = wr.tolist(), wi.tolist()
    if wr and max(wr) >= -1e-12 * max(1.0, *map(math.hypot, wr, wi)):
        return None, "the solution is not stabilising"
    return X, ""


def _ric_schur(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray,
               s: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Hamiltonian (eq 16) ordered-Schur solution of the equation of :func:`_ric`
    and the closed-loop poles (see :func:`_ric_schur_h`); ``(None, None)``
    when that route fails."""
    X, wr, wi = _ric_schur_h(_hamiltonian(a, b, q, s), r)
    return (None, None) if X is None else (X, wr + 1j * wi)


def _ric_schur_h(h: _Hamiltonian, r: np.ndarray) -> tuple[np.ndarray | None, ...]:
    """Hamiltonian (eq 16) ordered-Schur solution and the real and imaginary
    parts of the closed-loop poles (the n selected eigenvalues of H, those of
    ``a - b r^-1 (b^T X + s^T)``); ``(None, None, None)`` if it does not exist
    or its basis Z11 is too ill-conditioned to give X = Z21 Z11^-1 accurately
    (1-norm condition number above 1e14). X is symmetrised (rounding
    leaves it slightly asymmetric)."""
    n = h.a.shape[0]
    try:
        rv = np.linalg.solve(r, h.V)                        # r^-1 [s^T, b^T]
    except np.linalg.LinAlgError:                           # singular r: the pencil route
        return None, None, None
    H = h.H0 - h.W @ rv
    if not np.count_nonzero(H[n:, :n]):
        return _ric_zero(H[:n, :n])
    try:
        T, Z, sdim = sla.schur(H, output="real", sort="lhp")
    except (np.linalg.LinAlgError, ValueError):
        return None, None, None
    if sdim != n:
        return None, None, None
    Z11, Z21 = Z[:n, :n], Z[n:, :n]
    # X = Z21 Z11^-1 only from a well-conditioned basis (1-norm condition <= 1e14)
    if not np.linalg.cond(Z11, p=1) <= 1e14:
        return None, None, None
    X = np.linalg.solve(Z11.T, Z21.T).T
    lam = np.linalg.eigvals(T[:n, :n])                      # the n stable eigenvalues of H
    return _symmetric_part(X), lam.real, lam.imag


def _symmetric_part(X: np.ndarray) -> np.ndarray:
    """0.5 (X + X^T) (of a solution X or of its transpose: the same numbers)."""
    X = X + X.T
    X *= 0.5                                  # one temporary fewer
    return X


def _ric_zero(a_cl: np.ndarray) -> tuple[np.ndarray | None, ...]:
    """:func:`_ric_schur_h` when the constant term ``q - s r^-1 s^T`` is exactly
    zero (the Y equation (19) when w reaches y directly, D21 square: paper 003's
    Y is 0): H is then block upper triangular with diagonal blocks
    ``a_cl = a - b r^-1 s^T`` and ``-a_cl^T``, and X = 0 is the stabilising
    solution iff ``a_cl`` is Hurwitz; its eigenvalues are the closed-loop
    poles. One eigenvalue problem of order n instead of the Schur form of
    order 2n; otherwise ``(None, None, None)`` (no stabilising solution)."""
    lam = np.linalg.eigvals(a_cl)
    if not max(lam.real.tolist(), default=-1.0) < 0.0:             # all Re < 0
        return None, None, None
    return np.zeros(a_cl.shape), lam.real, lam.imag


@dataclass(slots=True)
class HinfFeasibility:
    """Outcome of the tests of Theorem 1 of paper 003 at one gamma.

    Attributes
    ----------
    gamma : float
        The level tested.
    feasible : bool
        True when conditions (a) and (b) hold.
    failed : str or None
        ``None`` or one of ``"D11"`` (condition (a)), ``"X_not_stabilising"``,
        ``"X_not_psd"``, ``"Y_not_stabilising"``, ``"Y_not_psd"``,
        ``"rho"`` (rho(XY) >= gamma^2).
    message : str
        Plain-language explanation.
    X, Y : ndarray or None
        Riccati solutions of eq (18)-(19) in the coordinates of the plant
        given (after undoing the internal balancing).
    rho : float
        Spectral radius of X Y (nan when not computed).
    min_eig : float
        Smallest eigenvalue of X (``"X_not_psd"``) or Y (``"Y_not_psd"``), in
        the balanced coordinates of the test (nan otherwise).
    """

    gamma: float
    feasible: bool
    failed: str | None
    message: str
    X: np.ndarray | None = None
    Y: np.ndarray | None = None
    rho: float = float("nan")
    min_eig: float = float("nan")
    _work: Any = field(default=None, repr=False)


def _not_psd(X: np.ndarray, tol: float = 1e-9) -> float | None:
    """None when the symmetric X is >= 0 up to ``tol`` relative to its largest
    eigenvalue (or empty), else its smallest eigenvalue."""
    if not X.size:
        return None
    ev = np.linalg.eigvalsh(X)
    lo, hi = float(ev[0]), float(ev[-1])
    return None if lo >= -tol * max(1.0, -lo, hi) else lo


@dataclass(slots=True)
class _GammaFree:
    """The parts of eq (10)-(17) that do not depend on gamma, formed once per
    plant and reused at every gamma of the iteration."""

    B: np.ndarray       # eq (10)
    C: np.ndarray       # eq (11)
    DtD: np.ndarray     # D1s^T D1s, eq (14) without gamma (D1s of eq 12)
    DDt: np.ndarray     # Ds1 Ds1^T, eq (15) without gamma (Ds1 of eq 13)
    Ew: np.ndarray      # diag(I_m1, 0): eq (14) is DtD - gamma^2 Ew
    Ez: np.ndarray      # diag(I_p1, 0): eq (15) is DDt - gamma^2 Ez
    Hx: _Hamiltonian    # eq (16): a = A, b = B, q = C1^T C1, s = C1^T D1s
    Hy: _Hamiltonian    # eq (17): a = A^T, b = C^T, q = B1 B1^T, s = B1 Ds1^T
    bound: float        # condition (a): max(sigma(D1111 D1112), sigma(D1111; D1121))
    d11: tuple          # D1111, D1112, D1121, D1122 (Theorem 1, eq 24-26)


def _gamma_free(Pn: PartitionedPlant) -> _GammaFree:
    d11 = _d11_blocks(Pn)
    r, c = d11[0].shape
    B = np.concatenate([Pn.B1, Pn.B2], axis=1)
    C = np.concatenate([Pn.C1, Pn.C2])
    D1s = np.concatenate([Pn.D11, Pn.D12], axis=1)
    Ds1 = np.concatenate([Pn.D11, Pn.D21])
    # [D1111 D1112] and [D1111; D1121] are the first rows and columns of D11
    bound = max(spectral_norm(Pn.D11[:r]), spectral_norm(Pn.D11[:, :c]))
    Ew, Ez = np.diag([1.0] * Pn.nw + [0.0] * Pn.nu), np.diag([1.0] * Pn.nz + [0.0] * Pn.ny)
    return _GammaFree(B=B, C=C, DtD=D1s.T @ D1s, DDt=Ds1 @ Ds1.T, Ew=Ew, Ez=Ez,
                      Hx=_hamiltonian(Pn.A, B, Pn.C1.T @ Pn.C1, Pn.C1.T @ D1s),
                      Hy=_hamiltonian(Pn.A.T, C.T, Pn.B1 @ Pn.B1.T, Pn.B1 @ Ds1.T),
                      bound=bound, d11=d11)


def _feasibility_normalised(Pn: PartitionedPlant, gamma: float,
                            gf: _GammaFree | None = None) -> HinfFeasibility:
    """Theorem 1 on an already normalised, balanced plant (``gf``: its
    gamma-free products, formed here when not given)."""
    w = _gamma_free(Pn) if gf is None else gf
    if w.bound >= gamma:
        return HinfFeasibility(gamma, False, "D11",
                               f"condition (a) of Theorem 1 fails: max(sigma(D1111 D1112), "
                               f"sigma(D1111; D1121)) = {w.bound:.6g} >= gamma = {gamma:.6g}")
    g2 = gamma * gamma
    Rnh = w.DtD - g2 * w.Ew                                          # eq (14)
    X, why = _ric_h(w.Hx, Rnh)                                       # eq (16), (18)
    if X is None:
        return HinfFeasibility(gamma, False, "X_not_stabilising",
                               f"the X Riccati equation (18) has no stabilising solution "
                               f"at gamma = {gamma:.6g}: {why}")
    if (low := _not_psd(X)) is not None:
        X2 = _psd_by_pencil(w.Hx, Rnh)
        if X2 is not None:
            X, low = X2, None
    if low is not None:
        return HinfFeasibility(gamma, False, "X_not_psd",
                               f"X of eq (18) is stabilising but not >= 0 at gamma = {gamma:.6g}",
                               X=X, min_eig=low)
    Rnj = w.DDt - g2 * w.Ez                                          # eq (15)
    Y, why = _ric_h(w.Hy, Rnj)                                       # eq (17), (19)
    if Y is None:
        return HinfFeasibility(gamma, False, "Y_not_stabilising",
                               f"the Y Riccati equation (19) has no stabilising solution "
                               f"at gamma = {gamma:.6g}: {why}", X=X)
    # Y = 0 (see _ric_zero) is >= 0 with rho(XY) = 0: no eigenvalue problem for either
    nonzero_y = np.count_nonzero(Y)
    if nonzero_y and (low := _not_psd(Y)) is not None:
        Y2 = _psd_by_pencil(w.Hy, Rnj)
        if Y2 is not None:
            Y, low = Y2, None
    if nonzero_y and low is not None:
        return HinfFeasibility(gamma, False, "Y_not_psd",
                               f"Y of eq (19) is stabilising but not >= 0 at gamma = {gamma:.6g}",
                               X=X, Y=Y, min_eig=low)
    rho = _spectral_radius(X @ Y) if nonzero_y else 0.0
    if rho >= g2:
        return HinfFeasibility(gamma, False, "rho",
                               f"rho(XY) = {rho:.6g} >= gamma^2 = {g2:.6g}",
                               X=X, Y=Y, rho=rho)
    return HinfFeasibility(gamma, True, None, "conditions (a) and (b) of Theorem 1 hold",
                           X=X, Y=Y, rho=rho, _work=(w, Rnh, Rnj))


def _psd_by_pencil(h: _Hamiltonian, r: np.ndarray) -> np.ndarray | None:
    """The pencil route's solution when it is >= 0, else None.

    ``X = Z21 Z11^-1`` from the Hamiltonian's Schur basis loses
    ``cond(Z11)`` digits: on a block-diagonal 2x2 plant (the coupled dq loop
    at standstill, toolbox.design._hinf_coupled) cond(Z11) reaches 1e9 and the
    smallest eigenvalue of an X spanning 9 .. 8e9 comes out at -8e8, a false
    "not >= 0" where SLICOT sb10ad finds the level feasible. A failed
    semi-definiteness test is therefore repeated on the pencil route (which
    does not invert Z11) before the level is declared infeasible."""
    X2, _ = _ric_pencil(h, r)
    return X2 if X2 is not None and _not_psd(X2) is None else None


def _spectral_radius(M: np.ndarray) -> float:
    """max |eigenvalue| of a non-empty real square matrix."""
    return float(np.abs(np.linalg.eigvals(M)).max())


@dataclass(slots=True)
class _Prepared:
    """Balanced and normalised copy of a plant, reused across gammas."""

    P: PartitionedPlant
    t: np.ndarray
    norm: _Normalised
    gf: _GammaFree

    def feasibility(self, gamma: float) -> HinfFeasibility:
        """Theorem 1 at ``gamma`` in balanced, normalised coordinates."""
        return _feasibility_normalised(self.norm.P, gamma, self.gf)


def _prepare(P: PartitionedPlant) -> _Prepared:
    """Check A1-A4, balance and normalise P once (the plant is balanced once and
    that copy serves both the rank tests and the synthesis)."""
    if not isinstance(P, PartitionedPlant):
        raise TypeError(f"expected a PartitionedPlant, got {type(P).__name__}")
    Ps, t = balance_plant(P)
    svds = (np.linalg.svd(Ps.D12), np.linalg.svd(Ps.D21))   # for A2 and the normalisation
    _check_balanced(Ps, d_sv=(svds[0][1], svds[1][1])).raise_if_failed()
    norm = _normalise(Ps, svds)
    return _Prepared(P=P, t=t, norm=norm, gf=_gamma_free(norm.P))

def _unscale_xy(res: HinfFeasibility, t: np.ndarray) -> HinfFeasibility:
    """Map X, Y from balanced coordinates back to those of the given plant."""
    if res.X is not None:
        res.X = res.X / t[:, None] / t[None, :]
    if res.Y is not None:
        res.Y = res.Y * t[:, None] * t[None, :]
    return res


def hinf_feasibility(P: PartitionedPlant, gamma: float) -> HinfFeasibility:
    """Test conditions (a) and (b) of Theorem 1 of paper 003 at ``gamma``.

    The plant is balanced (:func:`balance_plant`) and normalised (eq 65-67);
    then condition (a) on D11, the stabilising solutions X >= 0 and Y >= 0 of
    eq (18)-(19) built from eq (10)-(17), and rho(XY) < gamma^2 are tested in
    this order.

    Parameters
    ----------
    P : PartitionedPlant
        Generalised plant satisfying A1-A4.
    gamma : float
        Performance level, > 0.

    Returns
    -------
    HinfFeasibility
        ``failed`` names the first condition that fails.

    Raises
    ------
    SpecError
        ``gamma`` not a positive number, or A1-A4 violated.
    """
    gamma = _check_gamma(gamma)
    prep = _prepare(P)
    return _unscale_xy(prep.feasibility(gamma), prep.t)


def _check_gamma(gamma: Any) -> float:
    try:
        g = float(gamma)
    except (TypeError, ValueError):
        raise SpecError(GAMMA_KEY, 'a number > 0 or "optimal"', gamma) from None
    if not math.isfinite(g) or g <= 0:
        raise SpecError(GAMMA_KEY, 'a number > 0 or "optimal"', gamma)
    return g


# --------------------------------------------------------------------------
# central controller, Theorem 2, eq (20)-(32)
# --------------------------------------------------------------------------
def _central_normalised(Pn: PartitionedPlant, res: HinfFeasibility) -> tuple[np.ndarray, ...]:
    """Eq (20)-(32) of paper 003 (Zhou-Doyle-Glover general formulae).

    The inverses of eq (24)-(27) enter as linear solves, each solved once for
    all the right-hand sides that need it; with an empty D1111 (paper 003:
    w and y are both scalar) the gamma^2 I - D1111 D1111^T of eq (24)-(26) is
    gamma^2 I exactly and no system is solved for it.
    """
    g2 = res.gamma * res.gamma
    w, Rnh, Rnj = res._work
    X, Y = res.X, res.Y
    m1, m2, p1, p2 = Pn.nw, Pn.nu, Pn.nz, Pn.ny
    D1111, D1112, D1121, D1122 = w.d11
    B, C, A = w.B, w.C, Pn.A
    F = -np.linalg.solve(Rnh, w.Hx.s.T + B.T @ X)                 # eq (20); Hx.s^T = D1s^T C1
    # eq (21): L = -(B1 Ds1^T + Y C^T) Rnj^-1, Rnj symmetric (eq 15); Hy.s = B1 Ds1^T
    L = -np.linalg.solve(Rnj, w.Hy.s.T + C @ Y.T).T
    F12, F2 = F[m1 - p2:m1], F[m1:]
    L12, L2 = L[:, p1 - m2:p1], L[:, p1:]
    # eq (27): Z = (I - Y X / gamma^2)^-1, applied to both B2 + L12 and L2 at once
    ZB = np.linalg.solve(np.eye(A.shape[0]) - (Y @ X) / g2,
                         np.concatenate([Pn.B2 + L12, L2], axis=1))
    if D1111.size:
        r, c = D1111.shape
        # (g2 I - D D^T)^-1 D1112
        Ka = np.linalg.solve(g2 * np.eye(r) - D1111 @ D1111.T, D1112)
        Kb = np.linalg.solve(g2 * np.eye(c) - D1111.T @ D1111, D1121.T)
        D11h = -D1121 @ D1111.T @ Ka - D1122                          # eq (24)
        D12h = np.linalg.cholesky(np.eye(m2) - D1121 @ Kb)      # D12h D12h^T = T2, eq (25)
        T3 = np.eye(p2) - D1112.T @ Ka                                # eq (26)
        B2h = ZB[:, :m2] @ D12h                                       # eq (27)
        B1h = B2h @ np.linalg.solve(D12h, D11h) - ZB[:, m2:]                   # eq (29)
    else:
        # eq (24)-(25) with an empty D1111: T2 = I, so D12h = I and eq (27), (29)
        # lose their products by it (exact: products by an identity round nothing)
        D11h = -D1122                                                 # eq (24)
        T3 = np.eye(p2) - (D1112.T @ D1112) / g2                      # eq (26)
        B2h = ZB[:, :m2]                                              # eq (27)
        B1h = B2h @ D11h - ZB[:, m2:]                                 # eq (29)
    D21h = np.linalg.cholesky(T3).T                         # D21h^T D21h = T3
    C2h = -D21h @ (Pn.C2 + F12)                                       # eq (28), D21h
    S = np.linalg.solve(D21h, C2h)                                    # D21h^-1 C2h of eq (30), (31)
    C1h = F2 + D11h @ S                                      # eq (30), no U12
    Ah = A + B @ F + B1h @ S                                 # eq (31)
    return Ah, B1h, C1h, D11h                                         # eq (32)


def central_controller(P: PartitionedPlant, gamma: float) -> StateSpace:
    """Central H-infinity controller K = [Ahat, B1hat; C1hat, D11hat], eq (32).

    Uses the general Glover-Doyle formulae (eq 20-31, D11 != 0 allowed) on
    the balanced, normalised plant (eq 65-67), then undoes the u/y scalings,
    the D22 loop shift and the state balancing.  Sign convention: u = K y,
    with y = e = r - G u for :func:`augment_mixed_sensitivity`, so K maps the
    current error (A) to the voltage (V).

    Parameters
    ----------
    P : PartitionedPlant
    gamma : float
        Performance level; must be feasible.

    Returns
    -------
    toolbox.lti.StateSpace
        The controller, of the order of P.

    Raises
    ------
    SpecError
        ``gamma`` infeasible (key ``controller.hinf.gamma``): the message
        names the condition of Theorem 1 that failed.
    """
    gamma = _check_gamma(gamma)
    prep = _prepare(P)
    res = prep.feasibility(gamma)
    if not res.feasible:
        raise DesignInfeasible(GAMMA_KEY, "a feasible gamma", gamma, hint=res.message)
    return StateSpace._unchecked(*_controller_from(prep, res))


def _controller_from(prep: _Prepared, res: HinfFeasibility) -> tuple[np.ndarray, ...]:
    """A, B, C, D of the central controller in the coordinates of the given plant."""
    Ah, Bh, Ch, Dh = _central_normalised(prep.norm.P, res)
    # undo u = R12^-1 u~ and y~ = R21^-1 y
    R12inv, R21inv = prep.norm.R12inv, prep.norm.R21inv
    Bh, Ch, Dh = Bh @ R21inv, R12inv @ Ch, R12inv @ Dh @ R21inv
    # undo the state balancing x = T x_s (controller states live in plant coordinates)
    t = prep.t[:, None]
    Ah, Bh, Ch = Ah * (t / prep.t), Bh * t, Ch / prep.t      # exact: powers of two
    D22 = prep.P.D22
    if np.count_nonzero(D22):
        # loop shift u = K0 (y - D22 u): M = (I + Dk D22)^-1, u = M (Ck xk + Dk y)
        M = np.linalg.inv(np.eye(Dh.shape[0]) + Dh @ D22)
        Ah, Bh = Ah - Bh @ D22 @ M @ Ch, Bh @ (np.eye(D22.shape[0]) - D22 @ M @ Dh)
        Ch, Dh = M @ Ch, M @ Dh
    return Ah, Bh, Ch, Dh


