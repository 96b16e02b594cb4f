"""Generalised plant of the H-infinity problem and its S/KS/T augmentation.

Paper 003 (A. Azaiz, Y. Ramdani, A. Meroufel, B. Belabbes, "H-infinity design
of controllers ensuring the regulation of currents of the decoupled field
orientation control applied to a PMS motor", 2007): the partitioned plant of
eq (2)/(64), the mixed-sensitivity augmentation of eq (35)-(40), (50)-(64),
its power-of-two balancing (the data of eq (56)-(63) spans 1e-2 .. 2.7e10)
and the lower LFT ``F_l(P, K)`` that closes the loop.

One step of the pipeline of toolbox/ARCHITECTURE.md "H-infinity numerics":
``_hinf_plant`` -> ``_hinf_assumptions`` -> ``_hinf_riccati`` ->
``_hinf_gamma`` -> ``_hinf_bounds``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..lti import (StateSpace, TransferFunction, balanced_companion, minreal_coeffs,
                    trimmed_coeffs, as_statespace, diagonal_scaling)

__all__ = ["PartitionedPlant", "augment_mixed_sensitivity", "balance_plant", "closed_loop"]

_BLOCKS = ("A", "B1", "B2", "C1", "C2", "D11", "D12", "D21", "D22")


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
        """Return P as a :class:`toolbox.lti.StateSpace`, inputs [w, u], outputs [z, y]."""
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
        size checks of ``__post_init__`` (~15 us) are skipped."""
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
        Internal: the synthesis makes three such copies per call."""
        new = object.__new__(PartitionedPlant)
        new.__dict__.update(self.__dict__, **blocks)    # frozen: no __setattr__ per block
        return new



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
    (:func:`toolbox.lti.minreal_coeffs`, python-control's rule), then
    :func:`toolbox.lti.balanced_companion` gives the controllable canonical
    form, whose states are scaled by powers of two (exact) so that B and C
    have comparable entries (paper 003's w3 has C ~ -2.7e10 for B = 1
    otherwise).
    """
    num, den = trimmed_coeffs(num), trimmed_coeffs(den)
    if not any(den):
        raise ValueError("augment_mixed_sensitivity: zero denominator")
    if len(num) > len(den):
        raise ValueError(f"augment_mixed_sensitivity: expected a proper transfer function, "
                         f"got numerator degree {len(num) - 1} over denominator degree "
                         f"{len(den) - 1}")
    if not any(num):
        return _ss_blocks(0.0)
    num, den = minreal_coeffs(np.array(num), np.array(den))
    return balanced_companion(num.tolist(), den.tolist())


def _ours(K: Any) -> StateSpace:
    """Our ``StateSpace`` of a SISO system (itself when it is one: it keeps the
    poles, zeros and gain computed once, ``StateSpace._poles_zeros``, ``_zpk``)."""
    return K if isinstance(K, StateSpace) else StateSpace._unchecked(*_ss_blocks(K))


def _poles_zeros(K: Any) -> tuple[np.ndarray, np.ndarray]:
    """Poles and invariant zeros of a SISO system (:func:`_ours`)."""
    return _ours(K)._poles_zeros


def _zpk(K: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """Zeros, poles and leading gain of a SISO system (:func:`_ours`)."""
    return _ours(K)._zpk


def augment_mixed_sensitivity(G: Any, w1: Any, w2: Any = None,
                              w3: Any = None) -> PartitionedPlant:
    r"""Build the S/KS/T augmented plant of eq (35)-(40), (50)-(64).

    Signals: w = reference :math:`i_{ref}`, u = voltage, y = e = r - G u and
    z = [w1 e, w2 u, w3 G u] (rows for absent weights are dropped).  State
    ordering follows eq (55): x = [x_G, x_w1, x_w2, x_w3].  The closed loop
    with u = K y is :math:`T_{zw} = [w_1 S;\ w_2 K S;\ w_3 T]`, eq (40).

    Parameters
    ----------
    G : LTI system (python-control or toolbox.lti)
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



def _blocks2x2(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """[[a, b], [c, d]] (``np.block`` costs ~20 us of bookkeeping per call)."""
    return np.concatenate([np.concatenate([a, b], axis=1), np.concatenate([c, d], axis=1)])



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



def closed_loop(P: PartitionedPlant, K: Any) -> StateSpace:
    """Closed loop F_l(P, K) (w -> z), states [x_P, x_K], with u = K y."""
    Ks = as_statespace(K)
    return StateSpace(*_lft(P, (Ks.A, Ks.B, Ks.C, Ks.D)))


def _lft(P: PartitionedPlant, K: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """Matrices of F_l(P, K) for ``K = (Ak, Bk, Ck, Dk)``: u = M (Dk C2 x + Ck xk +
    Dk D21 w), M = (I - Dk D22)^-1 (numpy; python-control's ``lft`` builds named
    systems, ~1.5 ms)."""
    Ak, Bk, Ck, Dk = K
    if np.count_nonzero(P.D22):
        Mi = np.linalg.inv(np.eye(P.nu) - Dk @ P.D22)
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


