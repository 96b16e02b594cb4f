"""Realisations of an axis law that the C header executes.

Two forms are produced from an artifact axis (``AxisController.law``, the
discrete two-input system ``[i_ref, i_meas] -> v``):

* ``"sos"`` for one-degree-of-freedom laws (``B[:, 1] == -B[:, 0]`` and
  ``D[0, 1] == -D[0, 0]``): second-order sections of the error controller in
  the coefficient layout of CMSIS-DSP ``arm_biquad_cascade_df2T_f32``
  (``{b0, b1, b2, a1, a2}`` per stage, a1 and a2 NEGATED with respect to
  scipy's denominator ``[1, a1, a2]``) followed by an output gain;
* ``"ss"`` for two-input laws: the state-space law itself after an exact
  power-of-two diagonal balancing (``scipy.linalg.matrix_balance``).

Both come with their equivalent state-space matrices *in the coordinates
the C code uses* (for the SOS form: the transposed-direct-form-II states
``[s1, s2]`` of each stage in order), so the anti-windup vector of the
artifact can be mapped into them and error bounds can be computed on the
arithmetic actually executed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.signal

__all__ = ["Realisation", "realise_axis", "is_one_dof"]


@dataclass(frozen=True, eq=False)
class Realisation:
    """One axis law as executed by the header.

    Attributes
    ----------
    form : str
        ``"sos"`` or ``"ss"``.
    A, B, C, D : ndarray
        Equivalent state-space matrices in the executed coordinates
        (n x n, n x 2, 1 x n, 1 x 2); inputs ``[i_ref, i_meas]`` (A), output V.
    aw : ndarray
        Back-calculation vector (n,) in the same coordinates (zeros if none).
    sos : ndarray or None
        For ``"sos"``: stages x 6 in scipy layout ``[b0, b1, b2, 1, a1, a2]``.
    gain : float
        For ``"sos"``: output gain (V/A); 1 otherwise.
    """

    form: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    aw: np.ndarray
    sos: np.ndarray | None = None
    gain: float = 1.0

    @property
    def order(self) -> int:
        return self.A.shape[0]

    def cmsis_coefficients(self) -> np.ndarray:
        """Stages x 5 ``{b0, b1, b2, -a1, -a2}`` (CMSIS df2T sign convention)."""
        if self.sos is None:
            return np.zeros((0, 5))
        s = self.sos
        return np.column_stack([s[:, 0], s[:, 1], s[:, 2], -s[:, 4], -s[:, 5]])


def is_one_dof(B: np.ndarray, D: np.ndarray, rtol: float = 1e-12) -> bool:
    """True when the law is ``v = K (i_ref - i_meas)`` (channels opposite)."""
    scale = max(float(np.max(np.abs(B), initial=0.0)), float(np.max(np.abs(D))), 1e-300)
    return bool(np.all(np.abs(B[:, 0] + B[:, 1]) <= rtol * scale)
                and abs(D[0, 0] + D[0, 1]) <= rtol * scale)


def _cascade(sos: np.ndarray, gain: float) -> tuple[np.ndarray, ...]:
    """State space of the df2T cascade, states ``[s1_1, s2_1, s1_2, ...]``.

    Stage k (scipy signs, a = [1, a1, a2]): ``y = b0 u + s1``,
    ``s1' = b1 u - a1 y + s2``, ``s2' = b2 u - a2 y``.
    """
    m = sos.shape[0]
    n = 2 * m
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    # running expression of the current stage input as  cx @ x + du * u
    cx = np.zeros(n)
    du = 1.0
    for k, (b0, b1, b2, _, a1, a2) in enumerate(sos):
        i = 2 * k
        # y_k = b0 * in + s1_k
        yx = b0 * cx
        yx[i] += 1.0
        yu = b0 * du
        # s1' = b1 in - a1 y + s2 ; s2' = b2 in - a2 y
        A[i] = b1 * cx - a1 * yx
        A[i, i + 1] += 1.0
        B[i, 0] = b1 * du - a1 * yu
        A[i + 1] = b2 * cx - a2 * yx
        B[i + 1, 0] = b2 * du - a2 * yu
        cx, du = yx, yu
    return A, B, gain * cx.reshape(1, n), np.array([[gain * du]])


def _similarity(A1, B1, C1, A2, B2, C2) -> np.ndarray | None:
    """T with ``x1 = T x2`` (T A2 = A1 T, T B2 = B1, C1 T = C2), or None."""
    n = A1.shape[0]
    eye = np.eye(n)
    # vec(T A2 - A1 T) = (A2^T kron I - I kron A1) vec(T)   (column-major vec)
    M = np.vstack([np.kron(A2.T, eye) - np.kron(eye, A1),
                   np.kron(B2.T, eye),
                   np.kron(eye, C1)])
    rhs = np.concatenate([np.zeros(n * n), B1.ravel(order="F"), C2.ravel(order="F")])
    scale = np.maximum(np.linalg.norm(M, axis=1), 1e-300)
    sol, *_ = np.linalg.lstsq(M / scale[:, None], rhs / scale, rcond=None)
    T = sol.reshape(n, n, order="F")
    resid = np.linalg.norm(M @ sol - rhs) / max(np.linalg.norm(rhs), 1e-300)
    if not np.isfinite(resid) or resid > 1e-8 or np.linalg.cond(T) > 1e12:
        return None
    return T


def _sos_realisation(A, B, C, D, aw) -> Realisation | None:
    n = A.shape[0]
    b1 = B[:, :1]
    d = float(D[0, 0])
    if n == 0:
        return Realisation("sos", np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)),
                           np.array([[d, -d]]), np.zeros(0), np.zeros((0, 6)), d)
    z, p, k = scipy.signal.ss2zpk(A, b1, C, np.array([[d]]))
    z = z[np.isfinite(z)]
    if z.size != p.size:
        # strictly proper (D = 0, e.g. ZOH): scipy's zpk2sos would drop the
        # numerator delay; such laws are exported in state-space form
        return None
    sos = scipy.signal.zpk2sos(z, p, 1.0, pairing="nearest")
    Ac, Bc, Cc, Dc = _cascade(sos, float(k))
    # the s2 state of a first-order stage (b2 = a2 = 0) stays at zero: leave it
    # out of the similarity (its anti-windup entry is zero)
    live = np.flatnonzero(np.any(Ac != 0, axis=1) | (Bc[:, 0] != 0))
    if live.size != n:
        return None
    T = _similarity(A, b1, C, Ac[np.ix_(live, live)], Bc[live], Cc[:, live])
    if T is None:
        return None
    aw_c = np.zeros(Ac.shape[0])
    aw_c[live] = np.linalg.solve(T, aw)
    return Realisation("sos", Ac, np.hstack([Bc, -Bc]), Cc,
                       np.hstack([Dc, -Dc]), aw_c, sos, float(k))


def realise_axis(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                 aw: np.ndarray | None, prefer_sos: bool = True) -> Realisation:
    """The realisation the header executes for one axis law.

    Parameters
    ----------
    A, B, C, D : ndarray
        Discrete law ``[i_ref, i_meas] -> v`` (A, V).
    aw : ndarray or None
        Back-calculation vector (n,) or None.
    prefer_sos : bool
        Use second-order sections when the law is one-degree-of-freedom.

    Returns
    -------
    Realisation
        SOS form when possible (1-DOF and an invertible similarity to the
        cascade exists), else the balanced state-space form.
    """
    n = A.shape[0]
    aw = np.zeros(n) if aw is None else np.asarray(aw, float).reshape(n)
    if prefer_sos and is_one_dof(B, D):
        real = _sos_realisation(A, B, C, D, aw)
        if real is not None:
            return real
    if n:
        _, (scale, perm) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
        S = scale                                  # powers of two: exact
        A = A * (1.0 / S)[:, None] * S[None, :]
        B = B / S[:, None]
        C = C * S[None, :]
        aw = aw / S
    return Realisation("ss", A, B, C, D, aw)
