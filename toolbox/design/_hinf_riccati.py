"""H-infinity mixed-sensitivity synthesis by the Glover-Doyle Riccati formulae.

All equation numbers refer to paper 003: A. Azaiz, Y. Ramdani, A. Meroufel,
B. Belabbes, "H-infinity design of controllers ensuring the regulation of
currents of the decoupled field orientation control applied to a PMS motor"
(2007), which follows Glover & Doyle (1988) and Zhou, Doyle & Glover, *Robust
and Optimal Control* (1995), ch. 17 (the general case with D11 != 0).

Pipeline (a row of verbs):

``augment_mixed_sensitivity`` (eq 35-40, 50-64) -> ``check_assumptions``
(A1-A4) -> ``hinf_feasibility`` (Theorem 1, eq 10-22 after the normalisation
of eq 65-67) -> ``central_controller`` (Theorem 2, eq 23-32) ->
``gamma_iteration`` (bisection) -> ``synthesize`` (back-off, realisability,
recomputed norm) -> ``weight_bound_check`` (eq 41-43).

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

import itertools
import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import scipy.linalg as sla
from scipy.linalg.lapack import (dgecon as _dgecon, dgees as _dgees, dgeev as _dgeev,
                                 dgesdd as _dgesdd, dgesv as _dgesv, dlange as _dlange,
                                 dpotrf as _dpotrf,
                                 dsyevd as _dsyevd, dtrsen as _dtrsen, zgesdd as _zgesdd)

from .._lti import (StateSpace, TransferFunction, _balanced_companion, _identity,
                    _leading_identity, _linf_norm, _minreal_coeffs, _roots, _solve,
                    _spectral_norm, _svd, _trimmed, as_statespace, diagonal_scaling)
from ..errors import DesignInfeasible, SpecError

__all__ = [
    "PartitionedPlant", "augment_mixed_sensitivity", "check_assumptions",
    "AssumptionReport", "balance_plant", "HinfFeasibility", "hinf_feasibility",
    "central_controller", "gamma_iteration", "HinfResult", "synthesize",
    "pole_limit", "effective_poles", "fastest_pole_modulus", "WeightBound",
    "weight_bound_check", "GammaBelowOptimum",
]

_GAMMA_KEY = "controller.hinf.gamma"


class GammaBelowOptimum(DesignInfeasible):
    """A fixed ``gamma`` below the best achievable one (Theorem 1 fails).

    Carries the failed condition as data so callers branch on the class and
    read :attr:`condition`, never on message text (issue 11 item 10).

    Attributes
    ----------
    condition : str
        The condition of Theorem 1 that failed (words, for the message).
    best : float
        Best achievable gamma of this problem (nan if unknown).
    axis : str
        ``"d"`` or ``"q"`` once :func:`toolbox.design.hinf.design_hinf_axis`
        located it (empty before).
    """

    condition: str = ""
    best: float = float("nan")
    axis: str = ""

    def _copy(self, key: str, file: str | None) -> "GammaBelowOptimum":
        new = super()._copy(key, file)
        new.condition, new.best = self.condition, self.best
        return new


# --------------------------------------------------------------------------
# partitioned plant, eq (2) and (64)
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class PartitionedPlant:
    r"""Generalised plant P of eq (2)/(64) of paper 003.

    .. math::
        \dot x = A x + B_1 w + B_2 u,\quad
        z = C_1 x + D_{11} w + D_{12} u,\quad
        y = C_2 x + D_{21} w + D_{22} u

    Parameters
    ----------
    A, B1, B2, C1, C2, D11, D12, D21, D22 : array_like
        Real blocks (float).  Empty blocks may be given with shape ``(k, 0)``
        or ``(0, k)``.

    Raises
    ------
    ValueError
        A block has the wrong size; the message names the block, the size
        expected and the size received.
    """

    A: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    C1: np.ndarray
    C2: np.ndarray
    D11: np.ndarray
    D12: np.ndarray
    D21: np.ndarray
    D22: np.ndarray
    state_labels: tuple[str, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "state_labels", tuple(self.state_labels))
        for name in _BLOCKS:
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.ndim < 2:
                arr = arr.reshape(1, -1) if arr.size else arr.reshape(0, 0)
            object.__setattr__(self, name, arr)
        self._check_finite()
        n = self.A.shape[0]
        nw, nu = self.B1.shape[1], self.B2.shape[1]
        nz, ny = self.C1.shape[0], self.C2.shape[0]
        expect = {"A": (n, n), "B1": (n, nw), "B2": (n, nu), "C1": (nz, n),
                  "C2": (ny, n), "D11": (nz, nw), "D12": (nz, nu),
                  "D21": (ny, nw), "D22": (ny, nu)}
        for name, shape in expect.items():
            got = getattr(self, name).shape
            if got != shape:
                raise ValueError(f"PartitionedPlant: block {name} must be "
                                 f"{shape[0]}x{shape[1]} (from A, B1, B2, C1, C2), "
                                 f"got {got[0]}x{got[1]}")
        if self.state_labels and len(self.state_labels) != n:
            raise ValueError(f"PartitionedPlant: state_labels must have {n} entries, "
                             f"got {len(self.state_labels)}")

    @property
    def nx(self) -> int:
        """Number of states."""
        return self.A.shape[0]

    @property
    def nw(self) -> int:
        """Number of exogenous inputs w (m1)."""
        return self.B1.shape[1]

    @property
    def nu(self) -> int:
        """Number of control inputs u (m2)."""
        return self.B2.shape[1]

    @property
    def nz(self) -> int:
        """Number of performance outputs z (p1)."""
        return self.C1.shape[0]

    @property
    def ny(self) -> int:
        """Number of measurements y (p2)."""
        return self.C2.shape[0]

    def to_statespace(self) -> StateSpace:
        """Return P as a :class:`toolbox._lti.StateSpace`, inputs [w, u], outputs [z, y]."""
        B = np.hstack([self.B1, self.B2])
        C = np.vstack([self.C1, self.C2])
        D = np.block([[self.D11, self.D12], [self.D21, self.D22]])
        return StateSpace(self.A, B, C, D)

    def replace(self, **blocks: Any) -> "PartitionedPlant":
        """Return a copy with some blocks replaced."""
        data = {k: getattr(self, k) for k in _BLOCKS}
        data["state_labels"] = self.state_labels
        data.update(blocks)
        return PartitionedPlant(**data)

    def _check_finite(self) -> None:
        """ValueError naming the first block with a NaN or inf entry: one
        finiteness test of all the entries (nine tests cost ~15 us), the
        culprit sought only when it fails."""
        if not np.isfinite(np.concatenate([getattr(self, k).ravel() for k in _BLOCKS])).all():
            name = next(k for k in _BLOCKS if not np.isfinite(getattr(self, k)).all())
            raise ValueError(f"PartitionedPlant: block {name} has NaN or inf entries")

    @classmethod
    def _from_system_matrix(cls, S: np.ndarray, nx: int, nw: int, nz: int,
                            state_labels: tuple[str, ...]) -> "PartitionedPlant":
        """The plant whose blocks are views of its system matrix
        ``S = [[A, B1, B2], [C1, D11, D12], [C2, D21, D22]]`` (float, assembled
        here: the augmentation). Only the finiteness of the entries, which come
        from the caller's weights, is tested, once on S; the conversions and
        size checks of ``__post_init__`` (~15 us) are skipped (issue 13)."""
        n, m1, p1 = nx, nw, nz
        new = object.__new__(cls)
        new.__dict__.update(                 # frozen: no __setattr__ per block
            A=S[:n, :n], B1=S[:n, n:n + m1], B2=S[:n, n + m1:],
            C1=S[n:n + p1, :n], D11=S[n:n + p1, n:n + m1], D12=S[n:n + p1, n + m1:],
            C2=S[n + p1:, :n], D21=S[n + p1:, n:n + m1], D22=S[n + p1:, n + m1:],
            state_labels=state_labels)
        if not np.isfinite(S).all():
            new._check_finite()              # names the block
        return new

    def _derived(self, **blocks: np.ndarray) -> "PartitionedPlant":
        """Copy with some blocks replaced by float arrays computed from valid ones
        (similarity, rotation, scaling): same sizes by construction, so the
        checks of ``__post_init__`` (tens of microseconds, per copy) are skipped.
        Internal: the synthesis makes three such copies per call (issue 13)."""
        new = object.__new__(PartitionedPlant)
        new.__dict__.update(self.__dict__, **blocks)    # frozen: no __setattr__ per block
        return new


# --------------------------------------------------------------------------
# LAPACK called directly: the matrices here have order <= ~12, where numpy's and
# scipy's wrappers (argument checks, dispatch) cost 3-10 times the LAPACK work
# itself (issue 13). Inputs must be finite float arrays (they are built here).
# Their options go by position (f2py matches a keyword by string comparison
# against each name, ~0.1 us apiece): the order is the wrapper's signature,
# e.g. ``dgeev(a, compute_vl, compute_vr)``, ``dgesdd(a, compute_uv,
# full_matrices)``, ``dsyevd(a, compute_v)``, ``dpotrf(a, lower, clean)``.
# --------------------------------------------------------------------------
def _inv(A: np.ndarray) -> np.ndarray:
    """A^-1 (LAPACK dgesv on the identity, as numpy's ``inv``)."""
    return _solve(A, _identity(A.shape[0]))


def _svdvals(M: np.ndarray) -> np.ndarray:
    """Singular values, decreasing (LAPACK dgesdd, as numpy's ``svd``)."""
    if M.size == 0:
        return np.zeros(0)
    # complex at an imaginary-axis mode (A - j w I) in the A1-A4 rank tests
    _, s, _, info = (_zgesdd if M.dtype.kind == "c" else _dgesdd)(M, 0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgesdd failed (info {info})")
    return s


def _cholesky(M: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor (LAPACK dpotrf, as numpy's ``cholesky``)."""
    if M.size == 0:
        return M.copy()
    c, info = _dpotrf(M, 1, 1)
    if info != 0:
        raise np.linalg.LinAlgError(f"matrix not positive definite (dpotrf info {info})")
    return c


#: maximum of a non-empty array: the ufunc's reduce, without ``ndarray.max``'s
#: Python-level dispatch (~1 us a call, several per gamma)
_amax = np.maximum.reduce

_BLOCKS = ("A", "B1", "B2", "C1", "C2", "D11", "D12", "D21", "D22")


def _ss_blocks(sys: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A, B, C, D of a SISO system or a scalar gain."""
    if isinstance(sys, (int, float, np.floating)):
        return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[float(sys)]])
    if isinstance(sys, StateSpace):
        s = sys                  # ours (float arrays): no transfer-function test, ~2 us
    elif (coeffs := _tf_coeffs(sys)) is not None:
        return _tf_realisation(*coeffs)
    else:
        s = sys if all(hasattr(sys, m) for m in "ABCD") else as_statespace(sys)
    if np.shape(s.D) != (1, 1):
        raise ValueError(f"augment_mixed_sensitivity: expected a SISO system, "
                         f"got {np.shape(s.D)[0]}x{np.shape(s.D)[1]}")
    return (np.asarray(s.A, float), np.asarray(s.B, float),
            np.asarray(s.C, float), np.asarray(s.D, float))


def _tf_coeffs(sys: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """``(num, den)`` of a SISO transfer function (ours, python-control's or
    any object with ``num[0][0]`` and ``den[0][0]``, read without importing
    python-control); None for anything else."""
    if isinstance(sys, TransferFunction):
        return sys.num, sys.den
    if (hasattr(sys, "num") and hasattr(sys, "den") and not hasattr(sys, "A")
            and len(sys.num) == 1 and len(sys.num[0]) == 1):
        return np.atleast_1d(sys.num[0][0]), np.atleast_1d(sys.den[0][0])
    return None


def _tf_realisation(num: Any, den: Any) -> tuple[np.ndarray, ...]:
    """Minimal realisation (A, B, C, D) of the proper SISO ``num/den``.

    Common roots of num and den are cancelled first
    (:func:`toolbox._lti._minreal_coeffs`, python-control's rule), then
    :func:`toolbox._lti._balanced_companion` gives the controllable canonical
    form, whose states are scaled by powers of two (exact) so that B and C
    have comparable entries (paper 003's w3 has C ~ -2.7e10 for B = 1
    otherwise).
    """
    num, den = _trimmed(num), _trimmed(den)
    if not any(den):
        raise ValueError("augment_mixed_sensitivity: zero denominator")
    if len(num) > len(den):
        raise ValueError(f"augment_mixed_sensitivity: expected a proper transfer function, "
                         f"got numerator degree {len(num) - 1} over denominator degree "
                         f"{len(den) - 1}")
    if not any(num):
        return _ss_blocks(0.0)
    num, den = _minreal_coeffs(np.array(num), np.array(den))
    return _balanced_companion(num.tolist(), den.tolist())


def augment_mixed_sensitivity(G: Any, w1: Any, w2: Any = None,
                              w3: Any = None) -> PartitionedPlant:
    r"""Build the S/KS/T augmented plant of eq (35)-(40), (50)-(64).

    Signals: w = reference :math:`i_{ref}`, u = voltage, y = e = r - G u and
    z = [w1 e, w2 u, w3 G u] (rows for absent weights are dropped).  State
    ordering follows eq (55): x = [x_G, x_w1, x_w2, x_w3].  The closed loop
    with u = K y is :math:`T_{zw} = [w_1 S;\ w_2 K S;\ w_3 T]`, eq (40).

    Parameters
    ----------
    G : LTI system (python-control or toolbox._lti)
        SISO plant, e.g. eq (34) :math:`G_q = 1/(r_s + L_q s)` (A/V).
    w1, w2, w3 : control.LTI or float or None
        Weights on S, KS, T; ``w2``/``w3`` may be ``None``.

    Returns
    -------
    PartitionedPlant

    Examples
    --------
    >>> import control as ct
    >>> s = ct.tf('s')
    >>> P = augment_mixed_sensitivity(1 / (0.6 + 2.8e-3 * s),
    ...                               (s + 177.3493) / 1.51 / (s + 0.0117), 0.5, None)
    >>> P.nx, P.nz
    (2, 2)
    """
    Ag, Bg, Cg, Dg = _ss_blocks(G)
    ng = Ag.shape[0]
    ws = [(name, _ss_blocks(w)) for name, w in (("w1", w1), ("w2", w2), ("w3", w3))
          if w is not None]
    n, nz = ng + sum(m[0].shape[0] for _, m in ws), len(ws)
    # the system matrix [[A, B1, B2], [C1, D11, D12], [C2, D21, D22]] filled in place
    # (columns x, w, u): one array instead of nine blocks and their concatenations
    S = np.zeros((n + nz + 1, n + 2))
    S[:ng, :ng] = Ag
    S[:ng, n + 1:] = Bg
    # the weights' inputs as rows over [x, w, u]: the error e = r - (Cg xg + Dg u),
    # which is also y (the last row), u, and the plant output Cg xg + Dg u
    e = S[n + nz:]
    e[:, :ng], e[:, n], e[:, n + 1:] = -Cg, 1.0, -Dg
    u = np.zeros((1, n + 2))
    u[:, n + 1] = 1.0
    yg = np.zeros((1, n + 2))
    yg[:, :ng], yg[:, n + 1:] = Cg, Dg
    inputs = {"w1": e, "w2": u, "w3": yg}
    labels = ["G"] * ng
    i0 = ng
    for k, (name, (Aw, Bw, Cw, Dw)) in enumerate(ws):
        i1 = i0 + Aw.shape[0]
        v = inputs[name]
        S[i0:i1, i0:i1] = Aw
        S[i0:i1] += Bw * v                   # x_w' = Aw x_w + Bw (its input)
        z = S[n + k:n + k + 1]
        z += Dw * v                          # z_k = Cw x_w + Dw (its input), added to
        z[:, i0:i1] += Cw                    # zeros: a zero entry is +0 as a matmul's sum
        labels += [name] * (i1 - i0)
        i0 = i1
    return PartitionedPlant._from_system_matrix(S, n, 1, nz, tuple(labels))


# --------------------------------------------------------------------------
# assumptions A1-A4
# --------------------------------------------------------------------------
@dataclass
class AssumptionReport:
    """Outcome of :func:`check_assumptions`.

    Attributes
    ----------
    ok : bool
        All of A1-A4 hold.
    problems : list of str
        One plain-language message per violated assumption, with a remedy.
    """

    ok: bool
    problems: list[str] = field(default_factory=list)

    def raise_if_failed(self, key: str = "controller.hinf.weights") -> None:
        """Raise :class:`SpecError` listing the problems, if any."""
        if not self.ok:
            raise SpecError(key, "weights for which assumptions A1-A4 of the "
                            "H-infinity problem hold", "; ".join(self.problems))


def _imag_axis_modes(A: np.ndarray, tol: float) -> list[complex]:
    """Eigenvalues of A within ``tol`` (relative to max(1, the largest |eigenvalue|))
    of the imaginary axis."""
    if A.shape[0] == 0:
        return []
    wr, wi, _, _, info = _dgeev(A, 0, 0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgeev failed (info {info})")
    wr, wi = wr.tolist(), wi.tolist()       # a few: scalar code beats array calls
    lim = tol * max(1.0, *map(math.hypot, wr, wi))
    return [complex(a, b) for a, b in zip(wr, wi) if abs(a) <= lim]


def _rank_defect(M: np.ndarray, tol: float, sv: np.ndarray | None = None) -> bool:
    """True when the tall-or-square matrix M loses column rank (a row-rank test
    passes the transpose: its singular values are those of the conjugate
    transpose, so no conjugated copy is made); ``sv``: M's singular values
    when already computed."""
    if M.shape[1] == 0:
        return False
    if M.shape[0] < M.shape[1]:
        return True
    sv = (_svdvals(M) if sv is None else sv).tolist()   # Python floats: no numpy scalars
    hi, lo = sv[0], sv[-1]
    return lo <= tol * max(hi, 1e-300)


def _blame_mode(P: PartitionedPlant, lam: complex) -> str:
    """Name the block (plant or weight) whose states own eigenvalue lam."""
    if not P.state_labels:
        return "a weight or the plant"
    w, V = np.linalg.eig(P.A)
    k = int(np.argmin(np.abs(w - lam)))
    idx = int(np.argmax(np.abs(V[:, k])))
    return P.state_labels[idx]


def _blocks2x2(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """[[a, b], [c, d]] (``np.block`` costs ~20 us of bookkeeping per call)."""
    return np.concatenate([np.concatenate([a, b], axis=1), np.concatenate([c, d], axis=1)])


def _where(lam: complex) -> str:
    return "s = 0" if abs(lam) < 1e-12 else f"s = {complex(0, lam.imag):.4g}"


def check_assumptions(P: PartitionedPlant, tol: float = 1e-12) -> AssumptionReport:
    """Check assumptions A1-A4 of paper 003 (Glover-Doyle) on P.

    A1: (A, B2) stabilisable and (A, C2) detectable.  A2: D12 full column
    rank and D21 full row rank (eq 65-67 then normalise them to [0; I] and
    [0 I]).  A3/A4: [A - jwI, B2; C1, D12] full column rank and
    [A - jwI, B1; C2, D21] full row rank for all w.  For a mixed-sensitivity
    plant these can only fail at imaginary-axis modes of A (a weight or plant
    pole on the axis), which is where they are tested, plus w = 0.

    Parameters
    ----------
    P : PartitionedPlant
    tol : float
        Relative tolerance for "on the imaginary axis" and for rank tests.

    Returns
    -------
    AssumptionReport
        One message per failure, naming the assumption, the culprit and the
        remedy, e.g. "w1 has a pole at s = 0: move it to a small negative
        value".
    """
    return _check_balanced(balance_plant(P)[0], tol)


def _check_balanced(P: PartitionedPlant, tol: float = 1e-12,
                    d_sv: tuple[np.ndarray, np.ndarray] | None = None) -> AssumptionReport:
    """:func:`check_assumptions` on a plant already balanced by :func:`balance_plant`
    (rank tests on equilibrated data); ``d_sv``: the singular values of D12 and
    D21 when already computed (by the SVDs the normalisation uses)."""
    problems: list[str] = []
    n = P.nx
    modes = _imag_axis_modes(P.A, tol)
    for lam in modes:
        M = P.A - 1j * lam.imag * np.eye(n)
        src, where = _blame_mode(P, lam), _where(lam)
        if _rank_defect(np.concatenate([M, P.B2], axis=1).T, tol):
            problems.append(f"A1 fails (not stabilisable): {src} has a pole at {where} "
                            f"that u cannot move: move it to a small negative value")
        if _rank_defect(np.vstack([M, P.C2]), tol):
            problems.append(f"A1 fails (not detectable): {src} has a pole at {where} "
                            f"that y does not see: move it to a small negative value "
                            f"(e.g. 1e-4 times the crossover frequency)")
    for lam in modes + [0j]:
        M = P.A - 1j * lam.imag * np.eye(n) if lam.imag else P.A   # real at s = 0
        if _rank_defect(_blocks2x2(M, P.B2, P.C1, P.D12), tol):
            problems.append(f"A3 fails: the weighted plant has an invariant zero at "
                            f"{_where(lam)}: move the pole or zero of w2/w3 (or of G) off "
                            f"the imaginary axis")
        if _rank_defect(_blocks2x2(M, P.B1, P.C2, P.D21).T, tol):
            problems.append(f"A4 fails: {_blame_mode(P, lam) if modes else 'the plant'} "
                            f"gives a rank loss at {_where(lam)}: move its pole to a small "
                            f"negative value")
    s12, s21 = (None, None) if d_sv is None else d_sv
    if _rank_defect(P.D12, tol, s12):
        problems.append("A2 fails: D12 has not full column rank: give the control weight "
                        "w2 a non-zero high-frequency gain (u must be weighted directly)")
    if _rank_defect(P.D21.T, tol, s21):
        problems.append("A2 fails: D21 has not full row rank: the measurement must contain "
                        "the exogenous input directly (y = r - G u gives D21 = 1)")
    problems = list(dict.fromkeys(problems))       # a message once, in order
    return AssumptionReport(ok=not problems, problems=problems)


# --------------------------------------------------------------------------
# scaling of badly conditioned data (C1 ~ 2.7e10 in eq 59)
# --------------------------------------------------------------------------
def balance_plant(P: PartitionedPlant) -> tuple[PartitionedPlant, np.ndarray]:
    """Diagonal state scaling x = T x_s that equilibrates P (powers of two).

    Paper 003's q-axis data (eq 56-63) spans 1e-2 .. 2.7e10; the Riccati
    solution X then spans 1 .. 1.4e14 (see the printed X).  A state
    similarity changes neither the transfer matrix nor the H-infinity
    problem; the controller found for the scaled plant is mapped back with
    :func:`_unscale_controller` (exact, since T holds powers of two).

    Parameters
    ----------
    P : PartitionedPlant

    Returns
    -------
    Ps : PartitionedPlant
        The scaled plant (A_s = T^-1 A T, B_s = T^-1 B, C_s = C T).
    t : ndarray
        The diagonal of T.
    """
    n = P.nx
    if n == 0:
        return P, np.ones(0)
    m1, p1 = P.nw, P.nz
    m, p = m1 + P.nu, p1 + P.ny
    M = np.zeros((n + max(m, p),) * 2)
    M[:n, :n] = P.A
    M[:n, n:n + m1] = P.B1
    M[:n, n + m1:n + m] = P.B2
    M[n:n + p1, :n] = P.C1
    M[n + p1:n + p, :n] = P.C2
    t = diagonal_scaling(M)[:n]                  # powers of two
    ti = (1.0 / t)[:, None]                  # exact: t holds powers of two
    Ps = P._derived(A=P.A * (ti * t), B1=P.B1 * ti, B2=P.B2 * ti, C1=P.C1 * t, C2=P.C2 * t)
    return Ps, t


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
    (U, s12, V12t), (U21, s21, V21t) = svds or (_svd(P.D12), _svd(P.D21))
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
def _no_select(wr: float, wi: float) -> bool:
    """The selector scipy's dgees wrapper requires (unused: no sorting there)."""
    return False


@dataclass(slots=True)
class _Hamiltonian:
    """The gamma-free parts of the Hamiltonian (eq 16/17) of one Riccati equation
    ``a^T X + X a - (X b + s) r^-1 (b^T X + s^T) + q = 0``: with them the
    Hamiltonian at a given r is one solve and one product,

    ``H = [[a, 0], [-q, -a^T]] - [b; -s] r^-1 [s^T, b^T]``

    (whose blocks are ``a - b r^-1 s^T``, ``-b r^-1 b^T``, ``-(q - s r^-1 s^T)``
    and ``-(a - b r^-1 s^T)^T`` for a symmetric r), formed once per plant for the
    whole gamma iteration (issue 13)."""

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

    First the ordered real Schur form of the Hamiltonian (eq 16/17), one LAPACK
    ``dgees`` call sized for these problems (order <= ~10; scipy's
    ``solve_continuous_are`` spends ~0.8 ms per call in argument validation and
    the extended-pencil QZ, issue 13). When that route fails (no n stable
    eigenvalues, or an ill-conditioned basis Z11), scipy's generalised Schur
    method on the extended pencil, which does not invert the indefinite r, has
    the last word.
    """
    X, wr, wi = _ric_schur_h(h, r)
    if X is None:
        a, b, s = h.a, h.b, h.s
        try:
            X = sla.solve_continuous_are(a, b, h.q, r, s=s)
        except (np.linalg.LinAlgError, ValueError):
            return None, ("the Hamiltonian has eigenvalues on the imaginary axis "
                          "or no stabilising solution exists")
        F = np.linalg.solve(r, b.T @ X + s.T)
        ev = np.linalg.eigvals(a - b @ F)
        wr, wi = ev.real, ev.imag
        X = _symmetric_part(X)
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
    (1-norm condition estimate above 1e14). X is symmetrised (rounding
    leaves it slightly asymmetric)."""
    n = h.a.shape[0]
    try:
        rv = _solve(r, h.V)                                 # r^-1 [s^T, b^T]
    except np.linalg.LinAlgError:                           # singular r: the pencil route
        return None, None, None
    H = h.H0 - h.W @ rv
    if not np.count_nonzero(H[n:, :n]):   # count_nonzero: no Python-level dispatch
        return _ric_zero(H[:n, :n])
    # unsorted Schur form, then dtrsen moves the stable eigenvalues first: what
    # dgees's own sorting does, without a Python callback per eigenvalue
    T, _, wr, wi, Z, _, info = _dgees(_no_select, H, 1, 0)       # compute_v, sort_t
    if info != 0:
        return None, None, None
    _, Z, wr, wi, sdim, _, _, info = _dtrsen((wr < 0.0).astype(np.int32), T, Z, "N",
                                             overwrite_t=1, overwrite_q=1)
    if info != 0 or sdim != n:
        return None, None, None
    Z11t = Z[:n, :n].T
    # X^T = Z11^-T Z21^T; dgesv keeps the LU factors for the condition estimate
    lu, _, Xt, info = _dgesv(Z11t, Z[n:, :n].T)
    if info != 0:
        return None, None, None
    rcond, _ = _dgecon(lu, _dlange("1", Z11t))
    if not rcond >= 1e-14:
        return None, None, None
    return _symmetric_part(Xt), wr[:n], wi[:n]


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
    wr, wi, _, _, info = _dgeev(a_cl, 0, 0)
    if info != 0 or not max(wr.tolist(), default=-1.0) < 0.0:      # all Re < 0
        return None, None, None
    return np.zeros(a_cl.shape), wr, wi


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
    _x_eig: Any = field(default=None, repr=False)   # X's eigenvalues and vectors (_Boundary)


def _not_psd(X: np.ndarray) -> float | None:
    """:func:`_psd_defect` of the eigenvalues of a symmetric X."""
    return _psd_defect(_eigh(X)[0]) if X.size else None


def _psd_defect(ev: np.ndarray, tol: float = 1e-9) -> float | None:
    """None when the (ascending, non-empty) eigenvalues ``ev`` are >= 0 up to
    ``tol`` relative to the largest, else the smallest (kept for the gamma
    iteration's prediction, :class:`_Boundary`)."""
    ev = ev.tolist()                            # Python floats: no numpy scalar arithmetic
    lo, hi = ev[0], ev[-1]
    return None if lo >= -tol * max(1.0, -lo, hi) else lo


def _eigh(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and eigenvectors of a symmetric X (LAPACK
    dsyevd; the vectors cost ~1 us more on these orders and serve
    :class:`_Boundary`)."""
    lam, U, info = _dsyevd(X, 1)
    if info != 0:
        raise np.linalg.LinAlgError(f"dsyevd failed (info {info})")
    return lam, U


@dataclass(slots=True)
class _GammaFree:
    """The parts of eq (10)-(17) that do not depend on gamma, formed once per
    plant and reused at every gamma of the iteration (issue 13)."""

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
    bound = max(_spectral_norm(Pn.D11[:r]), _spectral_norm(Pn.D11[:, :c]))
    m, p = Pn.nw + Pn.nu, Pn.nz + Pn.ny
    Ew, Ez = _leading_identity(m, m, Pn.nw), _leading_identity(p, p, Pn.nz)
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
    x_eig = _eigh(X) if X.size else None
    if x_eig is not None and (low := _psd_defect(x_eig[0])) is not None:
        return HinfFeasibility(gamma, False, "X_not_psd",
                               f"X of eq (18) is stabilising but not >= 0 at gamma = {gamma:.6g}",
                               X=X, min_eig=low, _x_eig=x_eig)
    Rnj = w.DDt - g2 * w.Ez                                          # eq (15)
    Y, why = _ric_h(w.Hy, Rnj)                                       # eq (17), (19)
    if Y is None:
        return HinfFeasibility(gamma, False, "Y_not_stabilising",
                               f"the Y Riccati equation (19) has no stabilising solution "
                               f"at gamma = {gamma:.6g}: {why}", X=X)
    # Y = 0 (see _ric_zero) is >= 0 with rho(XY) = 0: no eigenvalue problem for either
    nonzero_y = np.count_nonzero(Y)
    if nonzero_y and (low := _not_psd(Y)) is not None:
        return HinfFeasibility(gamma, False, "Y_not_psd",
                               f"Y of eq (19) is stabilising but not >= 0 at gamma = {gamma:.6g}",
                               X=X, Y=Y, min_eig=low)
    rho = _spectral_radius(X @ Y) if nonzero_y else 0.0
    if rho >= g2:
        return HinfFeasibility(gamma, False, "rho",
                               f"rho(XY) = {rho:.6g} >= gamma^2 = {g2:.6g}",
                               X=X, Y=Y, rho=rho)
    return HinfFeasibility(gamma, True, None, "conditions (a) and (b) of Theorem 1 hold",
                           X=X, Y=Y, rho=rho, _work=(w, Rnh, Rnj), _x_eig=x_eig)


def _spectral_radius(M: np.ndarray) -> float:
    """max |eigenvalue| of a non-empty real square matrix (LAPACK dgeev)."""
    wr, wi, _, _, info = _dgeev(M, 0, 0)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgeev failed (info {info})")
    return float(_amax(np.hypot(wr, wi)))


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
    svds = (_svd(Ps.D12), _svd(Ps.D21))          # for both A2 and the normalisation
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
        raise SpecError(_GAMMA_KEY, 'a number > 0 or "optimal"', gamma) from None
    if not math.isfinite(g) or g <= 0:
        raise SpecError(_GAMMA_KEY, 'a number > 0 or "optimal"', gamma)
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
    F = -_solve(Rnh, w.Hx.s.T + B.T @ X)                 # eq (20); Hx.s^T = D1s^T C1
    # eq (21): L = -(B1 Ds1^T + Y C^T) Rnj^-1, Rnj symmetric (eq 15); Hy.s = B1 Ds1^T
    L = -_solve(Rnj, w.Hy.s.T + C @ Y.T).T
    F12, F2 = F[m1 - p2:m1], F[m1:]
    L12, L2 = L[:, p1 - m2:p1], L[:, p1:]
    # eq (27): Z = (I - Y X / gamma^2)^-1, applied to both B2 + L12 and L2 at once
    ZB = _solve(_identity(A.shape[0]) - (Y @ X) / g2, np.concatenate([Pn.B2 + L12, L2], axis=1))
    if D1111.size:
        r, c = D1111.shape
        Ka = _solve(g2 * _identity(r) - D1111 @ D1111.T, D1112)         # (g2 I - D D^T)^-1 D1112
        Kb = _solve(g2 * _identity(c) - D1111.T @ D1111, D1121.T)
        D11h = -D1121 @ D1111.T @ Ka - D1122                          # eq (24)
        D12h = _cholesky(_identity(m2) - D1121 @ Kb)            # D12h D12h^T = T2, eq (25)
        T3 = _identity(p2) - D1112.T @ Ka                                # eq (26)
        B2h = ZB[:, :m2] @ D12h                                       # eq (27)
        B1h = B2h @ _solve(D12h, D11h) - ZB[:, m2:]                   # eq (29)
    else:
        # eq (24)-(25) with an empty D1111: T2 = I, so D12h = I and eq (27), (29)
        # lose their products by it (exact: products by an identity round nothing)
        D11h = -D1122                                                 # eq (24)
        T3 = _identity(p2) - (D1112.T @ D1112) / g2                      # eq (26)
        B2h = ZB[:, :m2]                                              # eq (27)
        B1h = B2h @ D11h - ZB[:, m2:]                                 # eq (29)
    D21h = _cholesky(T3).T                                   # D21h^T D21h = T3
    C2h = -D21h @ (Pn.C2 + F12)                                       # eq (28), D21h
    S = _solve(D21h, C2h)                                    # D21h^-1 C2h of eq (30), (31)
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
    toolbox._lti.StateSpace
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
        raise DesignInfeasible(_GAMMA_KEY, "a feasible gamma", gamma, hint=res.message)
    return StateSpace._unchecked(*_controller_from(prep, res))


def _controller_from(prep: _Prepared, res: HinfFeasibility) -> tuple[np.ndarray, ...]:
    """A, B, C, D of the central controller in the coordinates of the given plant."""
    Ah, Bh, Ch, Dh = _central_normalised(prep.norm.P, res)
    # undo u = R12^-1 u~ and y~ = R21^-1 y
    Bh, Ch, Dh = Bh @ prep.norm.R21inv, prep.norm.R12inv @ Ch, prep.norm.R12inv @ Dh @ prep.norm.R21inv
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


# --------------------------------------------------------------------------
# gamma iteration
# --------------------------------------------------------------------------
def gamma_iteration(P: PartitionedPlant, tol: float = 1e-4,
                    gamma_max: float | None = None) -> float:
    """Smallest feasible gamma by bisection on Theorem 1 (relative tolerance).

    The lower end of the bracket is the D11 bound of condition (a) (no
    controller can do better); the upper end starts at max(1, 2 * lower)
    and doubles until feasible.  Bisection stops when
    ``(hi - lo) <= tol * hi``; the feasible end ``hi`` is returned, so the
    result is feasible and at most ``tol`` (relative) above the optimum.

    Parameters
    ----------
    P : PartitionedPlant
    tol : float
        Relative tolerance on gamma, default 1e-4.
    gamma_max : float, optional
        Give up above this level (default 1e8).

    Returns
    -------
    float
        gamma_opt (within ``tol``), dimensionless.

    Raises
    ------
    SpecError
        No feasible gamma up to ``gamma_max`` (key ``controller.hinf.gamma``).
    """
    return _gamma_iteration(_prepare(P), tol, gamma_max)


def _gamma_iteration(prep: _Prepared, tol: float, gamma_max: float | None) -> float:
    """:func:`gamma_iteration` on a prepared plant.

    Returns the answer of the plain bisection with fewer Riccati solutions
    (issue 13): feasibility is monotone in gamma (a level above an achievable
    one is achievable), so a midpoint above a level already found feasible is
    feasible and one below a level found infeasible is not. :func:`_narrow`
    first brackets the optimum by interpolation; the bisection then replays
    its midpoints and solves the Riccati equations only for those the
    bracket [a, b] leaves undecided. The first midpoint is tested before the
    upper end: when it is feasible, so is the upper end (one test fewer, the
    usual case: gamma_opt is rarely above 3/4 of the first upper end).
    """
    lo = prep.gf.bound
    top = 1e8 if gamma_max is None else float(gamma_max)
    hi = min(max(1.0, 2.0 * lo), top)
    seen = _Boundary()
    a = lo                                   # the highest level known infeasible
    if lo < hi:
        mid = 0.5 * (lo + hi)
        seen.add(res := prep.feasibility(mid))
        if res.feasible:
            return _bisect(prep, *_narrow(prep, lo, hi, lo, mid, seen, tol), tol)
        a = mid
    while not (res := prep.feasibility(hi)).feasible:
        if hi >= top:
            raise DesignInfeasible(_GAMMA_KEY, f"a problem feasible for some gamma <= {top:g}",
                            hint="no controller reaches it: raise gamma_max or relax "
                                 "the weights w1/w3")
        seen.add(res)
        a = hi
        lo, hi = hi, min(2.0 * hi, top)
    seen.add(res)
    return _bisect(prep, *_narrow(prep, lo, hi, a, hi, seen, tol), tol)


def _bisect(prep: _Prepared, lo: float, hi: float, a: float, b: float, tol: float) -> float:
    """The bisection of :func:`gamma_iteration` from [lo, hi], testing only the
    midpoints the known bracket [a, b] (a infeasible, b feasible) leaves open."""
    while True:
        lo, hi = _walk(lo, hi, a, b, tol)
        if hi - lo <= tol * hi:
            return hi                            # all decided: the last bracket's top
        mid = 0.5 * (lo + hi)
        a, b = (a, mid) if prep.feasibility(mid).feasible else (mid, b)


#: tests :func:`_narrow` may spend (the gallery's H-infinity designs need 4 to 8
#: tests in all, 68 over their 10 iterations where the extrapolation from
#: infeasible levels alone needed 92; the bisection then goes on from the
#: bracket reached)
_NARROW_STEPS = 10


class _Boundary:
    """What the tested levels say about where the optimal gamma lies.

    Each condition of Theorem 1 that fails below the optimum has a number
    that goes through zero about linearly in ``1/gamma^2`` at its boundary
    (gamma enters the Riccati data of eq (14)-(17) as ``gamma^-2``):
    ``1/lambda`` for the eigenvalue of X (or Y) that runs off to infinity
    there (X^-1 is smooth through the boundary; the eigenvalue is the
    negative one below it, the same eigenvector's above it), ``1 -
    rho(XY)/gamma^2`` for the coupling condition. The X eigenvalue is the
    usual boundary (paper 003's Y is 0); it is the one whose feasible
    levels are used too, so that the optimum is interpolated between levels
    on both sides of it rather than extrapolated from one side. Before any
    level has failed, the second-order step from the lowest feasible level
    (:func:`_taylor_level`) predicts it.
    """

    def __init__(self) -> None:
        self.low: list[tuple] = []       # infeasible: (gamma, condition, value, eigenvector)
        self.high: list[list] = []       # feasible: [gamma, result, the entry of ``low``
                                         #   matched last, the value, the Taylor level]
        self.top: tuple | None = None    # the highest of ``low``
        self.guess: float | None = None  # the last Taylor level predicted

    def add(self, res: HinfFeasibility) -> None:
        """Record a tested level."""
        if res.feasible:
            if res._x_eig is not None:
                self.high.append([res.gamma, res, None, 0.0, None])
            return
        if res.failed == "X_not_psd":
            lam, U = res._x_eig
            entry = (res.gamma, "X", 1.0 / lam[0].item(), U[:, 0])
        elif res.failed == "Y_not_psd":
            entry = (res.gamma, "Y", 1.0 / res.min_eig, None)
        elif res.failed == "rho":
            entry = (res.gamma, "rho", 1.0 - res.rho / res.gamma ** 2, None)
        else:
            return
        self.low.append(entry)
        if self.top is None or entry[0] > self.top[0]:
            self.top = entry

    def predict(self, a: float, b: float) -> float | None:
        """The optimum (between the levels a, infeasible, and b, feasible)
        interpolated from the three levels nearest to [a, b] of the family of
        the highest infeasible level with data (inverse quadratic
        interpolation in ``1/gamma^2``; the line through the two nearest when
        that leaves the bracket). The X family counts the feasible levels too,
        with the value of the eigenvalue whose eigenvector is nearest that of
        the highest infeasible level. Before any level with data failed:
        :func:`_taylor_level` from the lowest feasible level (the previous
        one's while it lies in [a, b]). None (or nan) without a prediction."""
        if self.top is None:
            if not self.high:
                return None
            low = min(self.high, key=_first)
            if low[4] is None:
                # the last prediction while the bracket still holds it (the level
                # just found feasible is the top of its cell: the next test is the
                # cell below either way), else the Taylor level from this one
                last = self.guess
                low[4] = last if last is not None and a < last < b else _taylor_level(low[1])
                self.guess = low[4]
            return low[4]
        cond = self.top[1]
        near = sorted([(a - g, g, v) for g, c, v, _ in self.low if c == cond]
                      + ([(h[0] - b, h[0], h) for h in self.high] if cond == "X" else []),
                      key=_first)[:3]
        if len(near) < 2:
            return None
        pts = [(g ** -2, v if isinstance(v, float) else self._matched(v)) for _, g, v in near]
        (x1, f1), (x2, f2) = pts[:2]
        if len(pts) == 3 and f1 != f2 and (f3 := pts[2][1]) != f1 and f3 != f2:
            x = (x1 * f2 * f3 / ((f1 - f2) * (f1 - f3)) + x2 * f1 * f3 / ((f2 - f1) * (f2 - f3))
                 + pts[2][0] * f1 * f2 / ((f3 - f1) * (f3 - f2)))
            if b ** -2 < x < a ** -2:
                return x ** -0.5
        if f1 == f2:
            return None
        x = x1 - f1 * (x2 - x1) / (f2 - f1)
        return x ** -0.5 if x > 0.0 else None

    def _matched(self, high: list) -> float:
        """``1/lambda`` of the eigenvalue of a feasible level's X whose
        eigenvector is nearest the highest infeasible level's (kept until
        that level changes)."""
        if high[2] is not self.top:
            lam, U = high[1]._x_eig
            x = lam[int(np.abs(self.top[3] @ U).argmax())].item()
            high[2:4] = self.top, (1.0 / x if x else math.inf)     # inf: no prediction
        return high[3]


def _taylor_level(res: HinfFeasibility) -> float:
    """The level where ``1/lambda`` of the eigenvalue of X nearest to running
    off to infinity (the smallest Newton step ``lambda/lambda'``) reaches zero
    by its second-order Taylor polynomial in ``x = 1/gamma^2``, from a
    feasible level towards the X boundary of :class:`_Boundary`; Newton's
    level when that polynomial has no root, nan when no eigenvalue grows.

    Eq (18) differentiated in x (``r = DtD - Ew/x``, eq 14; ``r' = Ew/x^2``,
    ``r'' = -2 Ew/x^3``) is the Lyapunov equation
    ``Acl' X' + X' Acl + F' r' F = 0``, ``F = r^-1 (B' X + S')``,
    ``Acl = A - B F``; differentiated again, with ``F' = r^-1 P``,
    ``P = B' X' - r' F``: ``Acl' X'' + X'' Acl = 2 P' r^-1 P - F' r'' F``
    (the same operator, checked against differences of X' at nearby levels).
    An eigenvalue moves by ``lambda' = u' X' u`` and ``lambda'' = u' X'' u +
    2 sum_j (u_j' X' u)^2 / (lambda - lambda_j)``, and the root of
    ``1/lambda``'s polynomial is ``dx = 2 lambda / (lambda' + sqrt(2 lambda
    lambda'' - 3 lambda'^2))`` (Newton's ``lambda/lambda'`` when the
    second-order term vanishes). Measured against the optimum to 1e-11 from
    the first level tested: paper 003's q axis (eq 44-46, from 1.04 times
    the optimum) 9e-6 above it where Newton's step fell 2e-4 below, so that
    the bisection cell predicted (tol 1e-4) is the optimum's: 3 feasibility
    tests instead of 4 (issue 13); from farther (the d axis of
    ``003_azaiz2007_hinf_optimal``, 1.37 times) 2 % below."""
    w, Rnh, _ = res._work
    h, X = w.Hx, res.X
    n = X.shape[0]
    g2 = res.gamma * res.gamma
    F = _solve(Rnh, h.s.T + h.b.T @ X)
    At = (h.a - h.b @ F).T
    eye = _identity(n)
    # the row-major vec of Acl' X' + X' Acl, kron(At, I) + kron(I, At) by broadcasting
    # (np.kron costs ~20 us here): a Lyapunov equation of order 4-6 is one solve
    L = (At[:, None, :, None] * eye[None, :, None, :]
         + eye[:, None, :, None] * At[None, :, None, :]).reshape(n * n, n * n)
    r1 = w.Ew * (g2 * g2)                                              # r'
    FrF = F.T @ r1 @ F
    Xd = _solve(L, -FrF.reshape(-1, 1)).reshape(n, n)                  # X'
    Pm = h.b.T @ Xd - r1 @ F
    Xdd = _solve(L, (2.0 * (Pm.T @ _solve(Rnh, Pm) + g2 * FrF)).reshape(-1, 1)).reshape(n, n)
    lam, U = res._x_eig
    Ud = U.T @ Xd @ U                          # lambda' on the diagonal
    lam, d1 = lam.tolist(), Ud.diagonal().tolist()
    steps = [(v / d, k) for k, (v, d) in enumerate(zip(lam, d1)) if v > 0.0 and d > 0.0]
    if not steps:
        return math.nan
    step, k = min(steps)
    v, d, row = lam[k], d1[k], Ud[k].tolist()
    dd = (U[:, k] @ Xdd @ U[:, k]).item() + 2.0 * sum(
        row[j] ** 2 / (v - lam[j]) for j in range(n) if j != k and lam[j] != v)
    disc = 2.0 * v * dd - 3.0 * d * d
    if disc >= 0.0:
        step = 2.0 * v / (d + math.sqrt(disc))
    return (1.0 / g2 + step) ** -0.5


def _first(entry: tuple) -> float:
    return entry[0]


def _narrow(prep: _Prepared, lo: float, hi: float, a: float, b: float, seen: _Boundary,
            tol: float) -> tuple[float, float, float, float]:
    """A bracket [a, b] of the optimal gamma (a infeasible, b feasible, both
    known from tests) that decides the midpoints of the bisection of
    :func:`gamma_iteration` from [lo, hi] (none falls inside it), returned
    with the bracket of that bisection reached (:func:`_walk`).

    The tests are levels of that bisection: after every test
    :meth:`_Boundary.predict` predicts the optimum from all the levels tested,
    and the undecided end of the bisection's last bracket around the
    prediction (:func:`_cell`) is tested, the upper first; two hits decide
    the whole bisection. Its next undecided midpoint is tested when there is
    no prediction inside the bracket [a, b].
    """
    for _ in range(_NARROW_STEPS):
        lo, hi = _walk(lo, hi, a, b, tol)
        if hi - lo <= tol * hi:
            break
        c = 0.5 * (lo + hi)
        guess = seen.predict(a, b)
        if guess is not None and a < guess < b:
            below, top = _cell(lo, hi, a, b, guess, tol)
            c = top if top < b else below if below > a else c
        seen.add(res := prep.feasibility(c))
        a, b = (a, c) if res.feasible else (c, b)
    return lo, hi, a, b


def _walk(lo: float, hi: float, a: float, b: float, tol: float) -> tuple[float, float]:
    """The bracket the bisection from [lo, hi] (tolerance ``tol``) reaches
    through the midpoints the known levels a (infeasible) and b (feasible)
    decide: its midpoint is undecided, or it is the last (``hi - lo <= tol
    hi``). As a and b only tighten, the walk resumes from the bracket it
    reached (~14 levels in Python, ~3 us, per test otherwise)."""
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        if a < mid < b:
            break
        lo, hi = (lo, mid) if mid >= b else (mid, hi)
    return lo, hi


def _cell(lo: float, hi: float, a: float, b: float, guess: float,
          tol: float) -> tuple[float, float]:
    """The last bracket of the bisection from [lo, hi] if the optimum were
    ``guess`` (a < guess < b): its levels from ``guess`` up feasible."""
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if mid >= b or (mid > a and mid >= guess) else (mid, hi)
    return lo, hi


# --------------------------------------------------------------------------
# realisability of the controller at a sample time
# --------------------------------------------------------------------------
def pole_limit(sample_time: float, factor: float = 1.0) -> float:
    """Largest controller pole magnitude realisable at ``sample_time`` (rad/s).

    The limit is ``factor * pi / sample_time``, the Nyquist frequency: a
    controller running every ``sample_time`` seconds cannot represent
    dynamics faster than that (Tustin maps such a pole next to z = -1, ZOH
    next to z = 0, and the discrete controller is then badly conditioned and
    no longer behaves like the design).  For Ts = 1e-4 s this is 31 416 rad/s,
    above the q-axis crossover (145 rad/s) by a factor of 200.

    Parameters
    ----------
    sample_time : float
        Controller period (s), > 0.
    factor : float
        Multiplier of the Nyquist frequency, default 1.

    Returns
    -------
    float
        Limit (rad/s).
    """
    if not (np.isfinite(sample_time) and sample_time > 0):
        raise SpecError("drive.sample_time", "a number > 0 (s)", sample_time)
    return float(factor * np.pi / sample_time)


def effective_poles(K: Any, cancel_tol: float = 1e-2) -> np.ndarray:
    """Poles of K that are not nearly cancelled by a zero.

    A pole p counts as cancelled when a zero z has |z - p| <= cancel_tol * |p|
    (default 1 %): the pair then changes |K| by at most about 1 % at every
    frequency and can be removed without effect (see
    :func:`toolbox.design._reduction.remove_cancellations`).  In paper 003,
    eq (68), the pole 2.717e6 faces the zero 2.714e6 (0.1 % apart).

    Parameters
    ----------
    K : LTI system (python-control or toolbox._lti)
        SISO controller.
    cancel_tol : float
        Relative distance below which a pole-zero pair is a cancellation.

    Returns
    -------
    ndarray of complex
        The remaining poles (rad/s).
    """
    return _effective_poles(*_poles_zeros(K), cancel_tol)


def _ours(K: Any) -> StateSpace:
    """Our ``StateSpace`` of a SISO system (itself when it is one: it keeps the
    poles, zeros and gain computed once, ``StateSpace._poles_zeros``, ``_zpk``)."""
    return K if isinstance(K, StateSpace) else StateSpace._unchecked(*_ss_blocks(K))


def _poles_zeros(K: Any) -> tuple[np.ndarray, np.ndarray]:
    """Poles and invariant zeros of a SISO system (:func:`_ours`)."""
    return _ours(K)._poles_zeros


def _effective_poles(poles: np.ndarray, zeros: np.ndarray, cancel_tol: float) -> np.ndarray:
    """:func:`effective_poles` of the given poles and zeros."""
    # Python complex numbers: the same differences and moduli (libm's hypot)
    # as numpy's scalars, at a third of their cost (numpy's vectorised hypot
    # on arrays would differ in the last bit; its scalars do not)
    z = zeros.tolist()
    keep = []
    for pi in sorted(poles.tolist(), key=abs):
        d = [abs(zi - pi) for zi in z]
        if d and min(d) <= cancel_tol * max(abs(pi), 1e-300):
            z.pop(d.index(min(d)))
        else:
            keep.append(pi)
    return np.array(keep, dtype=complex)


def _zpk(K: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles and leading gain of a SISO system (:func:`_ours`)."""
    return _ours(K)._zpk


def fastest_pole_modulus(K: Any) -> float:
    """Largest ``|s|`` of the controller's effective poles (rad/s), 0 if none.

    Compared with :func:`pole_limit` (``pi/Ts``) to decide whether ``K`` can
    be discretised at the sample time (paper 003 sect. 4 trap at the optimum).
    """
    ep = _effective_poles(*_poles_zeros(K), 1e-2)
    return float(_amax(np.abs(ep))) if ep.size else 0.0


# --------------------------------------------------------------------------
# synthesis with back-off and a posteriori checks
# --------------------------------------------------------------------------
@dataclass
class HinfResult:
    """Everything :func:`synthesize` found.

    Attributes
    ----------
    K : toolbox._lti.StateSpace
        Central controller, error (A) -> voltage (V).
    gamma : float
        Level the controller was designed for.
    gamma_opt : float or None
        Optimal level from :func:`gamma_iteration` (None for a fixed gamma).
    backoff : float
        Relative back-off finally used (0 for a fixed gamma).
    X, Y : ndarray
        Riccati solutions of eq (18)-(19) at ``gamma``.
    closed_loop_norm : float
        ||F_l(P, K)||_inf recomputed (LFT + :func:`toolbox._lti.linf_norm`).
    fastest_pole : float
        Largest |pole| of K that is not nearly cancelled (rad/s).
    pole_limit : float or None
        Realisability limit used (rad/s), None without a sample time.
    warnings : list of str
        Every oddity found (also issued through ``warnings.warn``).
    """

    K: StateSpace
    gamma: float
    gamma_opt: float | None
    backoff: float
    X: np.ndarray
    Y: np.ndarray
    closed_loop_norm: float
    fastest_pole: float
    pole_limit: float | None
    warnings: list[str] = field(default_factory=list)


def closed_loop(P: PartitionedPlant, K: Any) -> StateSpace:
    """Closed loop F_l(P, K) (w -> z), states [x_P, x_K], with u = K y."""
    Ks = as_statespace(K)
    return StateSpace(*_lft(P, (Ks.A, Ks.B, Ks.C, Ks.D)))


def _lft(P: PartitionedPlant, K: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """Matrices of F_l(P, K) for ``K = (Ak, Bk, Ck, Dk)``: u = M (Dk C2 x + Ck xk +
    Dk D21 w), M = (I - Dk D22)^-1 (numpy; python-control's ``lft`` builds named
    systems, ~1.5 ms, issue 13)."""
    Ak, Bk, Ck, Dk = K
    if np.count_nonzero(P.D22):
        Mi = _inv(_identity(P.nu) - Dk @ P.D22)
        Ux, Uk, Uw = Mi @ Dk @ P.C2, Mi @ Ck, Mi @ Dk @ P.D21    # u = Ux x + Uk xk + Uw w
        Yx, Yk, Yw = P.C2 + P.D22 @ Ux, P.D22 @ Uk, P.D21 + P.D22 @ Uw
        Ak = Ak + Bk @ Yk
    else:
        # D22 = 0 (a strictly proper plant): M = I and y = C2 x + D21 w, the
        # same numbers without the ~10 products by I and 0 (~10 us)
        Ux, Uk, Uw = Dk @ P.C2, Ck, Dk @ P.D21
        Yx, Yw = P.C2, P.D21
    A = _blocks2x2(P.A + P.B2 @ Ux, P.B2 @ Uk, Bk @ Yx, Ak)
    B = np.concatenate([P.B1 + P.B2 @ Uw, Bk @ Yw])
    C = np.concatenate([P.C1 + P.D12 @ Ux, P.D12 @ Uk], axis=1)
    return A, B, C, P.D11 + P.D12 @ Uw


def hinf_norm(sys: Any) -> float:
    """H-infinity norm (:func:`toolbox._lti.linf_norm`, the algorithm of SLICOT
    ab13dd behind python-control's ``norm``), inf when unstable or with a pole
    on the imaginary axis."""
    A, B, C, D = (np.asarray(m, float) for m in (sys.A, sys.B, sys.C, sys.D))
    return _hinf_norm(A, B, C, D)


def _hinf_norm(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray) -> float:
    n = A.shape[0]
    if n == 0:
        return _spectral_norm(D)
    # the poles the norm computed on the way (no second eigenvalue problem; an
    # unstable system, the rare case, still gets its finite L-infinity norm first);
    # a mixed-sensitivity loop usually peaks at w = 0 (w1 nearly integrates: both
    # axes of paper 003), where the first Hamiltonian then certifies the norm
    norm, _, poles = _linf_norm(A, B, C, D, peak_at_zero=True)
    # a pole with Re >= 0 or within np.isclose's 1e-8 of the axis: Re >= -1e-8
    return float("inf") if _amax(poles.real) >= -1e-8 else norm


def synthesize(P: PartitionedPlant, gamma: float | Literal["optimal"] = "optimal",
               backoff: float = 0.05, sample_time: float | None = None,
               tol: float = 1e-4, max_backoff: float = 2.0) -> HinfResult:
    """Design the central H-infinity controller, refusing unrealisable ones.

    With ``gamma="optimal"`` the optimum is found by :func:`gamma_iteration`
    and the controller is designed at ``(1 + backoff) * gamma_opt``: at the
    optimum itself the central controller of paper 003's q axis has a pole
    that runs off to minus infinity (python-control's ``mixsyn`` returns one
    near -6e9 .. -2e10 rad/s).  With a ``sample_time`` the back-off is then
    doubled until no (non-cancelled) controller pole is faster than
    :func:`pole_limit`; if ``max_backoff`` is reached a warning says so.
    Finally the closed-loop norm is recomputed independently and a mismatch
    with gamma is reported.

    Parameters
    ----------
    P : PartitionedPlant
    gamma : float or "optimal"
        Fixed level (e.g. 1 as in paper 003 sect. 3.3) or "optimal".
    backoff : float
        Initial relative back-off for "optimal", >= 0 (default 0.05).
    sample_time : float, optional
        Controller period (s) for the realisability test.
    tol : float
        Relative tolerance of the gamma iteration.
    max_backoff : float
        Largest back-off tried.

    Returns
    -------
    HinfResult

    Raises
    ------
    SpecError
        A fixed gamma below the optimum (key ``controller.hinf.gamma``; the
        message names the failed condition and gives the best achievable
        gamma), a bad ``backoff`` or violated assumptions A1-A4.
    """
    if not (isinstance(backoff, (int, float)) and math.isfinite(backoff) and backoff >= 0):
        raise SpecError("controller.hinf.backoff", "a number >= 0", backoff)
    prep = _prepare(P)
    notes: list[str] = []
    limit = pole_limit(sample_time) if sample_time is not None else None
    if isinstance(gamma, str):
        if gamma != "optimal":
            raise SpecError(_GAMMA_KEY, 'a number > 0 or "optimal"', gamma)
        gamma_opt = _gamma_iteration(prep, tol, None)
        b = float(backoff)
        while True:
            res = prep.feasibility((1.0 + b) * gamma_opt)
            K = StateSpace._unchecked(*_controller_from(prep, res)) if res.feasible else None
            fast = fastest_pole_modulus(K) if K is not None else math.inf
            ok = limit is None or fast <= limit
            if (K is not None and ok) or b >= max_backoff:
                break
            b = min(max(2.0 * b, 0.01), max_backoff)
        if K is None:
            raise DesignInfeasible(_GAMMA_KEY, "a feasible gamma", (1 + b) * gamma_opt,
                            hint=res.message)
    else:
        g = _check_gamma(gamma)
        res = prep.feasibility(g)
        if not res.feasible:
            best = _gamma_iteration(prep, tol, None)
            err = GammaBelowOptimum(_GAMMA_KEY, f"gamma >= the best achievable {best:.4g}", g,
                                    hint=f"{res.message}; set gamma above {best:.4g} or "
                                         "\"optimal\"")
            err.condition, err.best = res.message, best
            raise err
        K, gamma_opt, b = StateSpace._unchecked(*_controller_from(prep, res)), None, 0.0
        fast = fastest_pole_modulus(K)
    if limit is not None and fast > limit:
        notes.append(f"controller pole at |s| = {fast:.4g} rad/s exceeds the realisability "
                     f"limit pi/Ts = {limit:.4g} rad/s"
                     + (f" even with back-off {b:g}" if gamma_opt is not None else "")
                     + ": raise gamma (back-off) or lower the high-frequency weights")
    cl_norm = _hinf_norm(*_lft(P, (K.A, K.B, K.C, K.D)))
    if not cl_norm <= res.gamma * (1 + 1e-6) + 1e-12:
        notes.append(f"recomputed closed-loop norm {cl_norm:.6g} exceeds the design "
                     f"gamma {res.gamma:.6g}: the Riccati solution is inaccurate")
    for msg in notes:
        warnings.warn(msg, RuntimeWarning, stacklevel=2)
    prep_res = _unscale_xy(res, prep.t)
    return HinfResult(K=K, gamma=res.gamma, gamma_opt=gamma_opt, backoff=b,
                      X=prep_res.X, Y=prep_res.Y, closed_loop_norm=cl_norm,
                      fastest_pole=fast, pole_limit=limit, warnings=notes)


# --------------------------------------------------------------------------
# weight bounds, eq (41)-(43)
# --------------------------------------------------------------------------
@dataclass
class WeightBound:
    """Worst ratio of a closed-loop function to its bound, eq (41)-(43).

    Attributes
    ----------
    name : str
        ``"S"``, ``"KS"`` or ``"T"``.
    worst_ratio : float
        max over the grid of |F(jw)| |w_i(jw)| (< 1 means the bound holds).
    worst_freq : float
        Frequency of the worst ratio (rad/s).
    """

    name: str
    worst_ratio: float
    worst_freq: float


#: default grid of :func:`weight_bound_check` (rad/s), read-only and built once
_BOUND_GRID = np.logspace(-4, 9, 4000)
_BOUND_GRID.flags.writeable = False
#: the compiled search's result stands when every factor's modulus on the grid
#: lies within exp(+-_FACTOR_LOG_BOUND) (~1e+-43, known a priori) and
#: |c|^2 = |gd kd + gn kn|^2 = |1 + G K|^2 |gd kd|^2 is at least _C2_MIN there:
#: its squares and their products are then normal numbers
#: (toolbox/design/_bound_kernel.py)
_FACTOR_LOG_BOUND = 99.0
_C2_MIN = 1e-200


@dataclass(frozen=True, slots=True)
class _Factor:
    """``gain * prod(s - roots)``, the numerator or denominator of a SISO
    response, evaluated with one rounding per factor: as accurate as the
    roots (the synthesis computed the controller's already,
    :func:`fastest_pole_modulus`; a first-order weight's root is one
    division). Measured on paper 003's q-axis controller at 109 of the 4000
    grid points against a 40-digit evaluation of its realisation: relative
    error 5e-15 median, 3e-12 at worst, where the modal sum of
    :meth:`toolbox._lti.StateSpace.evaluate` lost 2e-10 median (issue 13)."""

    gain: float
    roots: list[complex]

    def at(self, s: complex) -> complex:
        """The value at one point (Python complex numbers, the kernel's order)."""
        v = complex(self.gain)
        for r in self.roots:
            v *= s - r
        return v

    def on_grid(self, s: np.ndarray) -> np.ndarray:
        """The values at the points ``s`` (the operations of :meth:`at`)."""
        v = np.full(s.size, complex(self.gain))
        for r in self.roots:
            v *= s - r
        return v

    def log_range(self, w_lo: float, w_hi: float) -> tuple[float, float]:
        """Natural logarithms of a lower and an upper bound of ``|f(j w)|`` for
        ``w_lo <= w <= w_hi`` (``-inf`` where it may vanish): ``|j w - r|``
        lies between the distance from ``r`` to that segment of the imaginary
        axis and ``max|w| + |r|``."""
        if self.gain == 0.0:
            return -math.inf, -math.inf
        w_max = max(abs(w_lo), abs(w_hi))
        lo = hi = math.log(abs(self.gain))
        for r in self.roots:
            d = math.hypot(r.real, max(0.0, w_lo - r.imag, r.imag - w_hi))
            lo += math.log(d) if d > 0.0 else -math.inf
            hi += math.log(w_max + abs(r))
        return lo, hi


def _factors(sys: Any) -> tuple[_Factor, _Factor]:
    """Numerator and denominator of a SISO transfer function (ours or
    python-control's: its polynomials' roots, a first-order one's by one
    division), a number, or a state-space system (its zeros, poles and gain,
    :func:`_zpk`)."""
    if (coeffs := _tf_coeffs(sys)) is not None:
        return tuple(_Factor(c[0], _roots(np.array(c)).tolist()) for c in map(_trimmed, coeffs))
    if np.isscalar(sys):
        return _Factor(float(sys), []), _Factor(1.0, [])
    z, p, k = _zpk(sys)
    return _Factor(k, z.tolist()), _Factor(1.0, p.tolist())


#: the closed-loop function of each bound in terms of G = gn/gd and K = kn/kd
#: (1 + G K = c/(gd kd), c = gd kd + gn kn): S = gd kd/c, K S = gd kn/c, T = gn kn/c
_BOUND_FUNCTIONS = {"S": (1, 3), "KS": (1, 2), "T": (0, 2)}


def weight_bound_check(G: Any, K: Any, w1: Any, w2: Any = None, w3: Any = None,
                       freqs: np.ndarray | None = None) -> dict[str, WeightBound]:
    """Check |S| < 1/|w1|, |KS| < 1/|w2|, |T| < 1/|w3| (eq 41-43 of paper 003).

    Every system is a numerator and a denominator ``gain * prod(s - roots)``
    (:class:`_Factor`). The worst grid point of each bound is found by a
    compiled pass over the grid (:mod:`toolbox.design._bound_kernel`, issue
    13: ~50 us where numpy's ~35 passes over 4000 complex numbers took
    ~200 us), or by numpy when the factors' moduli are not known to keep that
    pass's squares in range (a controller of order ~5 or more at 1e9 rad/s:
    :data:`_FACTOR_LOG_BOUND`); the ratio there is evaluated by
    :meth:`_Factor.at`.

    Parameters
    ----------
    G, K : LTI system (python-control or toolbox._lti)
        Plant (A/V) and controller (V/A).
    w1, w2, w3 : control.LTI or float or None
        Weights; ``None`` skips the function.
    freqs : ndarray, optional
        Grid (rad/s); default 4000 log-spaced points from 1e-4 to 1e9 rad/s,
        which brackets every pole/zero of paper 003's weights (1e-2 .. 1e7).

    Returns
    -------
    dict of str to WeightBound
        Keys ``"S"``, ``"KS"``, ``"T"`` for the weights given.
    """
    w = _BOUND_GRID if freqs is None else np.asarray(freqs, float).ravel()
    loop = [*_factors(G), *_factors(K)]                         # gn, gd, kn, kd
    bounds = {name: _factors(wt) for name, wt in (("S", w1), ("KS", w2), ("T", w3))
              if wt is not None}
    at = _worst_points_compiled(w, loop, bounds)
    if at is None:
        at = _worst_points_numpy(w, loop, bounds)
    out = {}
    for name, i in zip(bounds, at):
        s = 1j * float(w[i])
        v = [f.at(s) for f in loop]
        (a, b), (n, d) = _BOUND_FUNCTIONS[name], bounds[name]
        ratio = abs((v[a] * v[b] * n.at(s)) / ((v[1] * v[3] + v[0] * v[2]) * d.at(s)))
        out[name] = WeightBound(name, ratio, float(w[i]))
    return out


def _worst_points_compiled(w: np.ndarray, loop: list[_Factor],
                           bounds: dict[str, tuple[_Factor, _Factor]]) -> list[int] | None:
    """The grid index of each bound's worst ratio by the compiled pass, None
    when its squares are not known to stay in range."""
    if not bounds or w.size == 0:
        return None
    factors = loop + [f for pair in bounds.values() for f in pair]
    w_lo, w_hi = (w[0], w[-1]) if w is _BOUND_GRID else (float(w.min()), float(w.max()))
    if not all(-_FACTOR_LOG_BOUND <= lo and hi <= _FACTOR_LOG_BOUND
               for lo, hi in (f.log_range(w_lo, w_hi) for f in factors)):
        return None
    from ._bound_kernel import worst_points

    at, c2_min = worst_points(
        w, np.array([r for f in factors for r in f.roots], complex),
        np.array(list(itertools.accumulate([len(f.roots) for f in factors], initial=0))),
        np.array([f.gain for f in factors]),
        np.array([list(_BOUND_FUNCTIONS).index(name) for name in bounds]))
    return at.tolist() if c2_min >= _C2_MIN else None


def _worst_points_numpy(w: np.ndarray, loop: list[_Factor],
                        bounds: dict[str, tuple[_Factor, _Factor]]) -> list[int]:
    """:func:`_worst_points_compiled` by numpy over the whole grid (complex
    quotients and moduli: no squares to leave the range)."""
    s = 1j * w
    v = [f.on_grid(s) for f in loop]                            # gn, gd, kn, kd
    c = v[1] * v[3] + v[0] * v[2]
    out = []
    for name, (n, d) in bounds.items():
        a, b = _BOUND_FUNCTIONS[name]
        out.append(int(np.abs((v[a] * v[b] * n.on_grid(s)) / (c * d.on_grid(s))).argmax()))
    return out
