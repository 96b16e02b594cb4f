"""Assumptions A1-A4 of the H-infinity problem (paper 003, after Glover-Doyle).

Rank tests on the balanced generalised plant (:mod:`._hinf_plant`): A1
stabilisability and detectability, A2 the rank of D12 and D21, A3/A4 no
invariant zero on the imaginary axis; each failure is reported in words with
its culprit (plant or weight) and a remedy.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import SpecError
from ._hinf_plant import PartitionedPlant, _blocks2x2, balance_plant

__all__ = ["AssumptionReport", "check_assumptions"]


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
    lam = np.linalg.eigvals(A)
    lim = tol * max(1.0, float(np.abs(lam).max()))
    return [complex(z) for z in lam if abs(z.real) <= lim]


def _rank_defect(M: np.ndarray, tol: float, sv: np.ndarray | None = None) -> bool:
    """True when the tall-or-square matrix M loses column rank (a row-rank test
    passes the transpose: its singular values are those of the conjugate
    transpose, so no conjugated copy is made); ``sv``: M's singular values
    when already computed."""
    if M.shape[1] == 0:
        return False
    if M.shape[0] < M.shape[1]:
        return True
    sv = (np.linalg.svd(M, compute_uv=False) if sv is None else sv).tolist()
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


