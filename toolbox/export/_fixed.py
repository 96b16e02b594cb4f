"""Fixed-point (Q31) plan of an axis law, and worst-case error bounds.

Scaling (all signals are Q31 words, i.e. value / 2**31 in [-1, 1)):

* inputs ``i / I_BASE``, ``Omega_m / W_BASE``; outputs ``v / V_BASE``; states
  ``x_i / S_i``. Every base is a power of two (A, rad/s, V, state units) at or
  above a rigorous bound of the signal, so nothing overflows:
  currents up to ``I_MAX`` (``motor.max_current``), speed up to ``W_MAX``
  (``drive.max_speed``, else the larger of ``motor.rated_speed`` and twice
  the speed at which the back-EMF reaches the voltage limit); the input bases
  reach ``PLAUSIBLE_MARGIN`` x these ranges (the plausible ranges, so the
  step tells an implausible sample from one it clamps); the states from the
  anti-windup recursion ``x+ = (A - aw C) x + (B - aw D) u + aw (v_sat - v_dec)``
  which holds in and out of saturation, with ``|v_sat| <= V_MAX`` and the
  decoupling voltage ``|v_dec| <= D_MAX``: ``|x| <= sum_k |F^k G| [U; V]``
  (computed as a rigorous upper bound by doubling, finite only when
  ``F = A - aw C`` is Schur).
* each coefficient set (a row of ``[A B aw]``, the output row ``[C D]`` and
  each decoupling coefficient) is an int32 mantissa vector ``m`` with one
  shift ``F``: ``c = m / 2**F``, ``|m| < 2**(31 - g)`` with ``g`` guard bits
  (``2**g`` >= number of terms), so the int64 accumulator of ``sum m_j x_j``
  cannot overflow; the result is ``(acc + 2**(F-1)) >> F`` then clamped to
  int32 (the clamp never acts when the bounds hold).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._plausible import PLAUSIBLE_MARGIN

__all__ = ["FixedAxis", "FixedPlan", "l1_state_bound", "plan_fixed", "horizon_bound",
           "propagate_bound", "float32_local_errors", "fixed_local_errors"]

U32 = 2.0 ** -24           # unit roundoff of IEEE float32
Q31_LSB = 2.0 ** -31


def _pow2_at_least(x: float) -> float:
    """Smallest power of two >= x (x > 0), 1 for x <= 0."""
    if not x > 0:
        return 1.0
    return float(2.0 ** math.ceil(math.log2(x * (1.0 + 1e-12))))


def l1_state_bound(F: np.ndarray, G: np.ndarray, amp: np.ndarray,
                   max_doublings: int = 48) -> np.ndarray | None:
    """Upper bound of ``sum_k |F^k G| amp`` (elementwise), or None if infinite.

    Doubling: ``S_2K <= S_K + |F^K| S_K``; once ``rho(|F^K|) < 1/2`` the tail
    is bounded by ``(I - |F^K|)^-1 S_K`` (a Neumann series).
    """
    n = F.shape[0]
    if n == 0:
        return np.zeros(0)
    S = np.abs(G) @ amp
    P = F.copy()
    for _ in range(max_doublings):
        aP = np.abs(P)
        if max(abs(np.linalg.eigvals(aP))) < 0.5:
            return np.linalg.solve(np.eye(n) - aP, S)
        with np.errstate(over="ignore", invalid="ignore"):
            S = S + aP @ S
            P = P @ P
        if not np.all(np.isfinite(P)) or not np.all(np.isfinite(S)):
            return None
    return None


@dataclass
class FixedAxis:
    """Q31 data of one axis (normalised coordinates).

    Attributes
    ----------
    S : ndarray
        State scales (state units per full scale).
    rows : list of (ndarray, int)
        Mantissas and shift of each state row ``[A_n | B_n | aw_n]``.
    out : (ndarray, int)
        Mantissas and shift of the output row ``[C_n | D_n]``.
    An, Bn, Cn, Dn, awn : ndarray
        Exact normalised matrices.
    Aq, Bq, Cq, Dq, awq : ndarray
        Their quantised values ``m / 2**F``.
    """

    S: np.ndarray
    rows: list
    out: tuple
    An: np.ndarray
    Bn: np.ndarray
    Cn: np.ndarray
    Dn: np.ndarray
    awn: np.ndarray
    Aq: np.ndarray
    Bq: np.ndarray
    Cq: np.ndarray
    Dq: np.ndarray
    awq: np.ndarray


@dataclass
class FixedPlan:
    """Bases and quantised coefficients of the Q31 variant.

    Attributes
    ----------
    I_BASE, V_BASE, W_BASE : float
        Full scales of currents (A), voltages (V) and mechanical speed (rad/s).
    I_MAX, W_MAX, V_MAX : float
        The input ranges the scaling guarantees, and the voltage limit (V).
    axes : dict
        ``{"d": FixedAxis, "q": FixedAxis}``.
    dec : dict
        Decoupling coefficients ``name -> (mantissa, shift, exact value)``.
    vmax_q31 : int
        ``V_MAX / V_BASE`` in Q31.
    guard : int
        Largest number of guard bits used by a coefficient set.
    """

    I_BASE: float
    V_BASE: float
    W_BASE: float
    I_MAX: float
    W_MAX: float
    V_MAX: float
    axes: dict
    dec: dict
    vmax_q31: int
    guard: int
    notes: list = field(default_factory=list)


def _quantise_row(c: np.ndarray, guard: int) -> tuple[np.ndarray, int] | None:
    """Mantissas and shift for one coefficient set, None if too large."""
    mx = float(np.max(np.abs(c), initial=0.0))
    if mx == 0.0:
        return np.zeros(c.size, dtype=np.int64), 31
    e = math.ceil(math.log2(mx * (1.0 + 1e-12)))      # mx <= 2**e
    F = 31 - guard - e
    if F < 0:
        return None
    F = min(F, 62)
    m = np.round(c * 2.0 ** F).astype(np.int64)
    lim = 2 ** (31 - guard)
    if np.any(np.abs(m) >= lim):                        # rounding reached the limit
        F -= 1
        m = np.round(c * 2.0 ** F).astype(np.int64)
    return m, F


def plan_fixed(reals: dict, *, I_MAX: float, W_MAX: float,
               V_MAX: float, dec_coeffs: dict) -> tuple[FixedPlan | None, str]:
    """Choose bases, state scales and Q31 coefficient sets.

    Parameters
    ----------
    reals : dict
        ``{"d": Realisation, "q": Realisation}``.
    I_MAX, W_MAX, V_MAX : float
        Current range (A), mechanical speed range (rad/s), voltage limit (V).
    dec_coeffs : dict
        Physical decoupling coefficients: ``dd`` (V per (rad/s * A), multiplies
        ``Omega_m * i_q`` in v_d), ``dq`` (multiplies ``Omega_m * i_d`` in v_q),
        ``de`` (V per rad/s, multiplies ``Omega_m`` in v_q).

    Returns
    -------
    (FixedPlan or None, str)
        The plan, or None and the reason it cannot be made.
    """
    # the input words reach the plausible ranges (PLAUSIBLE_MARGIN x the
    # ranges), so the step can tell an implausible sample from a clamped one
    I_BASE = _pow2_at_least(PLAUSIBLE_MARGIN * I_MAX)
    W_BASE = _pow2_at_least(PLAUSIBLE_MARGIN * W_MAX)
    D_MAX = {"d": abs(dec_coeffs["dd"]) * W_MAX * I_MAX,
             "q": abs(dec_coeffs["dq"]) * W_MAX * I_MAX + abs(dec_coeffs["de"]) * W_MAX}
    X = {}
    v_bound = V_MAX
    for ax, r in reals.items():
        F = r.A - np.outer(r.aw, r.C[0])
        G = np.hstack([r.B - np.outer(r.aw, r.D[0]), r.aw.reshape(-1, 1)])
        amp = np.array([I_MAX, I_MAX, V_MAX + D_MAX[ax]])
        xb = l1_state_bound(F, G, amp)
        if xb is None:
            return None, (f"axis {ax}: the state of the law has no finite bound "
                          "(A - aw C is not Schur: an integrator without back-calculation "
                          "anti-windup, or a controller zero on the unit circle)")
        X[ax] = xb
        v_bound = max(v_bound, float(np.abs(r.C[0]) @ xb + np.abs(r.D[0]).sum() * I_MAX
                                     + D_MAX[ax]))
    V_BASE = _pow2_at_least(v_bound)
    axes = {}
    guard_used = 0
    for ax, r in reals.items():
        n = r.order
        S = np.array([_pow2_at_least(v) for v in X[ax]]) if n else np.zeros(0)
        Si = 1.0 / S if n else S
        An = r.A * Si[:, None] * S[None, :]
        Bn = r.B * Si[:, None] * I_BASE
        awn = r.aw * Si * V_BASE
        Cn = r.C * S[None, :] / V_BASE
        Dn = r.D * I_BASE / V_BASE
        nterms = n + 3
        guard = max(1, math.ceil(math.log2(nterms)))
        guard_used = max(guard_used, guard)
        rows, Aq, Bq, awq = [], np.zeros_like(An), np.zeros_like(Bn), np.zeros_like(awn)
        for i in range(n):
            row = np.concatenate([An[i], Bn[i], [awn[i]]])
            qr = _quantise_row(row, guard)
            if qr is None:
                return None, f"axis {ax}: state row {i} has a coefficient >= 2**{31 - guard}"
            m, Fsh = qr
            rows.append((m, Fsh))
            qv = m / 2.0 ** Fsh
            Aq[i], Bq[i], awq[i] = qv[:n], qv[n:n + 2], qv[n + 2]
        qo = _quantise_row(np.concatenate([Cn[0], Dn[0]]), guard)
        if qo is None:
            return None, f"axis {ax}: output row has a coefficient >= 2**{31 - guard}"
        qv = qo[0] / 2.0 ** qo[1]
        axes[ax] = FixedAxis(S, rows, qo, An, Bn, Cn, Dn, awn, Aq, Bq,
                             qv[:n].reshape(1, n), qv[n:].reshape(1, 2), awq)
    dec = {}
    norm = {"dd": W_BASE * I_BASE / V_BASE, "dq": W_BASE * I_BASE / V_BASE,
            "de": W_BASE / V_BASE}
    for name, c in dec_coeffs.items():
        value = c * norm[name]
        qr = _quantise_row(np.array([value]), 1)
        if qr is None:
            return None, f"decoupling coefficient {name} too large for Q31"
        dec[name] = (int(qr[0][0]), qr[1], value)
    vmax_q31 = int(math.floor(V_MAX / V_BASE * 2.0 ** 31))
    return FixedPlan(I_BASE, V_BASE, W_BASE, I_MAX, W_MAX, V_MAX, axes, dec,
                     vmax_q31, guard_used), ""


def horizon_bound(plan: FixedPlan, n: int) -> dict:
    """Worst-case Q31 output error (V) over ``n`` periods from equal states.

    Every input anywhere in its range (|u_n| <= I_MAX / I_BASE, states within
    their bounds |x_n| <= 1, speed <= W_MAX), unsaturated; local errors as in
    :func:`fixed_local_errors` with those worst-case magnitudes, propagated
    by :func:`propagate_bound`.

    Parameters
    ----------
    plan : FixedPlan
        The Q31 plan.
    n : int
        Number of periods.

    Returns
    -------
    dict
        ``{"d": V, "q": V}``.
    """
    lsb = 2.0 ** -31
    un = plan.I_MAX / plan.I_BASE
    wn = plan.W_MAX / plan.W_BASE
    dec_err = {"d": 0.0, "q": 0.0}
    for name, ax, prod in (("dd", "d", wn * un), ("dq", "q", wn * un), ("de", "q", wn)):
        m, F, val = plan.dec[name]
        dec_err[ax] += abs(m / 2.0 ** F - val) * prod + abs(m / 2.0 ** F) * 0.5 * lsb + 0.5 * lsb
    out = {}
    for ax, fa in plan.axes.items():
        k = fa.An.shape[0]
        xn = np.ones((n, k))
        u = np.full((n, 2), un)
        dx, dy = fixed_local_errors(fa, xn, u, np.full(n, dec_err[ax]))
        out[ax] = float(plan.V_BASE * propagate_bound(fa.Aq, fa.Cq, dx, dy).max())
    return out


def _fftconvolve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Full linear convolution of two real 1-D arrays by FFT.

    ``scipy.signal.fftconvolve`` without importing scipy.signal (~0.4 s of
    every ``cct design``): the same scipy.fft transforms at the same
    length, so the same numbers (tests/export/test_propagate_bound.py).
    """
    from scipy.fft import irfft, next_fast_len, rfft  # lazy: scipy.fft, 43 modules

    if a.size == 1 or b.size == 1:          # scipy multiplies directly (no transform)
        return a * b
    size = a.size + b.size - 1
    L = next_fast_len(size, real=True)
    return irfft(rfft(a, L) * rfft(b, L), L)[:size]


def propagate_bound(A: np.ndarray, C: np.ndarray, delta_x: np.ndarray,
                    delta_y: np.ndarray) -> np.ndarray:
    """Worst-case output error of a linear recursion with local errors.

    ``e[k+1] = A e[k] + delta_x[k]``, ``err_y[k] <= |C| |e[k]| + delta_y[k]``,
    bounded elementwise with exact powers: ``|e[k]| <= sum_j |A^(k-1-j)| delta_x[j]``.

    Parameters
    ----------
    A, C : ndarray
        Executed recursion (n x n, 1 x n).
    delta_x : ndarray
        (N, n) local state errors (absolute, >= 0).
    delta_y : ndarray
        (N,) local output errors.

    Returns
    -------
    ndarray
        (N,) bound on the output error.
    """
    N, n = delta_x.shape
    out = np.array(delta_y, float).copy()
    if n == 0:
        return out
    powers = np.empty((N, n, n))
    P = np.eye(n)
    for m in range(N):
        powers[m] = np.abs(P)
        P = P @ A
    aC = np.abs(C[0])
    # g[m] = |C| |A^m| (row vector)
    g = np.einsum("j,mjk->mk", aC, powers)
    # out[k] += sum_{i<k} g[k-1-i] . delta_x[i]: a convolution, by FFT (the direct
    # double sum is O(N^2): 0.02 s at Ts = 1e-7 is 2e5 periods, hours), widened
    # by the FFT's rounding so that it stays an upper bound
    conv = np.zeros(N)
    for j in range(n):
        conv += _fftconvolve(g[:, j], delta_x[:, j])[:N]
    scale = float(np.abs(g).max(initial=0.0) * np.abs(delta_x).sum())
    out[1:] += np.maximum(conv[:N - 1], 0.0) + 1e-12 * scale
    return out


def float32_local_errors(real, x: np.ndarray, u: np.ndarray, dec_abs: np.ndarray,
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Local rounding errors of the float32 header arithmetic along a trajectory.

    ``gamma = (chain + 2) u32`` per value, with ``chain`` the longest chain of
    roundings that forms it (``n + 2`` products and sums in the state-space
    form; ``3 (stages + 1)`` in the SOS cascade, whose expanded rows carry the
    intermediate stage outputs), plus one rounding of each coefficient and
    input. First-order worst case (Higham, Accuracy and Stability, eq 3.5).

    Parameters
    ----------
    real : Realisation
        Executed realisation.
    x : ndarray
        (N, n) exact state trajectory in the executed coordinates.
    u : ndarray
        (N, 2) inputs ``[i_ref, i_meas]`` (A).
    dec_abs : ndarray
        (N,) sum of the absolute values of the decoupling terms (V).

    Returns
    -------
    (ndarray, ndarray)
        ``delta_x`` (N, n) and ``delta_y`` (N,) (state units, V).
    """
    n = real.order
    chain = 3 * (n // 2 + 1) if real.form == "sos" else n + 2
    gam = (chain + 2) * U32
    aA, aB, aC, aD = (np.abs(m) for m in (real.A, real.B, real.C, real.D))
    dx = gam * (np.abs(x) @ aA.T + np.abs(u) @ aB.T) if n else np.zeros((len(u), 0))
    dy = gam * (np.abs(x) @ aC[0] + np.abs(u) @ aD[0]) + 8 * U32 * (dec_abs + 0.0)
    vtot = np.abs(x @ real.C[0] + u @ real.D[0]) + dec_abs
    dy = dy + 2 * U32 * vtot
    return dx, dy


def fixed_local_errors(fa: FixedAxis, xn: np.ndarray, un: np.ndarray,
                       dec_err: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local errors of the Q31 arithmetic in normalised units (full scale 1).

    Coefficient quantisation ``|A_q - A_n| |x| + |B_q - B_n| |u|``, input
    quantisation ``|B_q| 2**-32`` (round to nearest Q31), result rounding
    ``2**-32`` per row; output likewise, plus the decoupling error.
    """
    n = fa.An.shape[0]
    half = 0.5 * Q31_LSB
    if n:
        dx = (np.abs(xn) @ np.abs(fa.Aq - fa.An).T + np.abs(un) @ np.abs(fa.Bq - fa.Bn).T
              + half * np.abs(fa.Bq).sum(axis=1)[None, :] + half)
    else:
        dx = np.zeros((len(un), 0))
    dy = (np.abs(xn) @ np.abs(fa.Cq - fa.Cn)[0] + np.abs(un) @ np.abs(fa.Dq - fa.Dn)[0]
          + half * np.abs(fa.Dq).sum() + half + dec_err + 2 * Q31_LSB)
    return dx, dy
