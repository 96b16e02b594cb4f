"""Realisations of an axis law that the C header executes.

Two forms are produced from an artifact axis (``AxisController.law``, the
discrete two-input system ``[i_ref, i_meas] -> v``):

* ``"sos"`` for one-degree-of-freedom laws (``B[:, 1] == -B[:, 0]`` and
  ``D[0, 1] == -D[0, 0]``): second-order sections of the error controller in
  the coefficient layout of CMSIS-DSP ``arm_biquad_cascade_df2T_f32``
  (``{b0, b1, b2, a1, a2}`` per stage, a1 and a2 NEGATED with respect to
  scipy's denominator ``[1, a1, a2]``) followed by an output gain;
* ``"ss"`` for two-input laws: the state-space law itself after an exact
  power-of-two diagonal balancing (:func:`toolbox.lti.diagonal_scaling`).

Both come with their equivalent state-space matrices *in the coordinates
the C code uses* (for the SOS form: the transposed-direct-form-II states
``[s1, s2]`` of each stage in order), so the anti-windup vector of the
artifact can be mapped into them and error bounds can be computed on the
arithmetic actually executed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lti import StateSpace, diagonal_scaling, ss2zpk

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


# -- scipy.signal.zpk2sos(z, p, 1.0, pairing="nearest"), digital --------------
# scipy.signal is not imported for it: importing it costs ~0.4 s of every
# `cct design`. The port keeps scipy's operations (same sections,
# same floating-point numbers: tests/export/test_sos.py compares with ==) for
# the case used here, equal numbers of zeros and poles.
def _cplxreal(z: np.ndarray, tol: float = 100 * np.finfo(float).eps) -> tuple[np.ndarray, ...]:
    """Complex roots with positive imaginary part (pairs averaged) and real
    roots, each sorted as ``scipy.signal._filter_design._cplxreal`` does."""
    z = np.atleast_1d(z)
    if z.size == 0:
        return z, z
    z = z[np.lexsort((abs(z.imag), z.real))]
    real = abs(z.imag) <= tol * abs(z)
    zr = z[real].real
    if len(zr) == len(z):
        return np.array([]), zr
    z = z[~real]
    zp, zn = z[z.imag > 0], z[z.imag < 0]
    if len(zp) != len(zn):
        raise ValueError("Array contains complex value with no matching conjugate.")
    same_real = np.diff(zp.real) <= tol * abs(zp[:-1])
    diffs = np.diff(np.concatenate(([0], same_real, [0])))
    for start, stop in zip(np.nonzero(diffs > 0)[0], np.nonzero(diffs < 0)[0] + 1):
        for chunk in (zp[start:stop], zn[start:stop]):
            chunk[...] = chunk[np.lexsort([abs(chunk.imag)])]
    if any(abs(zp - zn.conj()) > tol * abs(zn)):
        raise ValueError("Array contains complex value with no matching conjugate.")
    return (zp + zn.conj()) / 2, zr


def _nearest_idx(fro: np.ndarray, to: complex, which: str) -> int:
    """Index of the element of ``fro`` nearest ``to`` (of the kind ``which``)."""
    order = np.argsort(np.abs(fro - to))
    if which == "any":
        return order[0]
    mask = np.isreal(fro[order])
    if which == "complex":
        mask = ~mask
    return order[np.nonzero(mask)[0][0]]


def _section(z: list, p: list) -> np.ndarray:
    """One second-order section ``[b0, b1, b2, 1, a1, a2]`` from <= 2 zeros and poles."""
    sos = np.zeros(6)
    b, a = np.atleast_1d(1.0 * np.poly(z)), np.atleast_1d(np.poly(p))
    sos[3 - len(b):3] = b
    sos[6 - len(a):6] = a
    return sos


def _worst(p: np.ndarray) -> int:
    """The pole nearest the unit circle."""
    return int(np.argmin(np.abs(1 - np.abs(p))))


def zpk2sos_nearest(z: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Unit-gain second-order sections of a digital filter: the poles nearest
    the unit circle last, each paired with its nearest zeros (scipy's
    ``pairing="nearest"``; its steps and special cases in the same order)."""
    p = np.concatenate((p, np.zeros(max(len(z) - len(p), 0))))
    z = np.concatenate((z, np.zeros(max(len(p) - len(z), 0))))
    n_sections = (len(p) + 1) // 2
    if len(p) % 2 == 1:
        p, z = np.concatenate((p, [0.0])), np.concatenate((z, [0.0]))
    z, p = np.concatenate(_cplxreal(z)), np.concatenate(_cplxreal(p))
    sos = np.zeros((n_sections, 6))
    for si in range(n_sections - 1, -1, -1):
        i = _worst(p)
        p1, p = p[i], np.delete(p, i)
        if np.isreal(p1) and np.isreal(p).sum() == 0:        # the last real pole
            i = _nearest_idx(z, p1, "real")
            z1, z = z[i], np.delete(z, i)
            sos[si] = _section([z1, 0], [p1, 0])
        elif (len(p) + 1 == len(z) and not np.isreal(p1)
              and np.isreal(p).sum() == 1 and np.isreal(z).sum() == 1):
            # one real pole and one real zero left: they must end up together
            i = _nearest_idx(z, p1, "complex")
            z1, z = z[i], np.delete(z, i)
            sos[si] = _section([z1, z1.conj()], [p1, p1.conj()])
        else:
            if np.isreal(p1):
                real = np.flatnonzero(np.isreal(p))
                i = real[_worst(p[real])]
                p2, p = p[i], np.delete(p, i)
            else:
                p2 = p1.conj()
            if len(z) == 0:
                sos[si] = _section([], [p1, p2])
                continue
            i = _nearest_idx(z, p1, "any")
            z1, z = z[i], np.delete(z, i)
            if not np.isreal(z1):
                sos[si] = _section([z1, z1.conj()], [p1, p2])
            elif len(z) == 0:
                sos[si] = _section([z1], [p1, p2])
            else:
                i = _nearest_idx(z, p1, "real")
                z2, z = z[i], np.delete(z, i)
                sos[si] = _section([z1, z2], [p1, p2])
    return sos


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
    z, p, k = ss2zpk(StateSpace(A, b1, C, np.array([[d]])))
    z = z[np.isfinite(z)]
    if z.size != p.size:
        # strictly proper (D = 0, e.g. ZOH): zpk2sos would drop the numerator
        # delay; such laws are exported in state-space form
        return None
    sos = zpk2sos_nearest(z, p)
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
        S = diagonal_scaling(A)                    # powers of two: exact
        A = A * (1.0 / S)[:, None] * S[None, :]
        B = B / S[:, None]
        C = C * S[None, :]
        aw = aw / S
    return Realisation("ss", A, B, C, D, aw)
