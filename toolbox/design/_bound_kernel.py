"""Compiled search of the weight-bound grid, eq (41)-(43) of paper 003 (issue 13).

:func:`worst_points` serves :func:`toolbox.design._hinf_riccati.weight_bound_check`:
the grid index where each weighted closed-loop function ``|w_i F_i(j w)|``
(``F`` = S, KS, T) is largest. In numpy that is ~35 passes over arrays of 4000
complex numbers (~200 us, a seventh of a warm q-axis design, issue 13). Here
the grid is taken in blocks that stay in the L1 cache, each factor
``gain * prod(s - roots)`` is real arithmetic the compiler vectorises, and the
ratios are compared squared (no complex division, no ``hypot``): ~50 us.

Squares halve the exponent range. The caller runs this only when every
factor's modulus is known a priori to lie within [1e-43, 1e43] on the grid,
so that every square and product of squares formed here is a normal number
(within [1e-258, 1e258]), except for ``|c|^2 = |gd kd + gn kn|^2``, which can
cancel (``1 + G K`` near 0): its smallest value is returned for the caller to
check.

Imported on first use, so that ``import toolbox.design`` does not import numba.
No ``fastmath``: plain IEEE operations in a fixed order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["worst_points"]

#: points per block: the block's 16 arrays of doubles (32 KB) stay in L1
_BLOCK = 256


@njit(cache=True, error_model="numpy")
def _factor(w: np.ndarray, roots: np.ndarray, gain: float,
            re: np.ndarray, im: np.ndarray) -> None:
    """``gain * prod(s - roots)`` at ``s = j w`` into ``re + j im``."""
    for i in range(w.size):
        re[i] = gain
        im[i] = 0.0
    for r in roots:                               # times (s - r) = -Re r + j (w - Im r)
        a = -r.real
        for i in range(w.size):
            b = w[i] - r.imag
            x, y = re[i], im[i]
            re[i] = x * a - y * b
            im[i] = x * b + y * a


@njit(cache=True, error_model="numpy")
def worst_points(w, roots, starts, gains, which):
    """Grid index of the largest ``|w_j F_j|`` for each bound ``j``.

    Parameters
    ----------
    w : ndarray (N,)
        Frequencies (rad/s).
    roots : ndarray of complex
        Roots of all factors, those of factor ``f`` in ``roots[starts[f]:starts[f + 1]]``.
    starts : ndarray of int (m + 1,)
    gains : ndarray (m,)
        Factor ``f`` is ``gains[f] * prod(s - its roots)``: 0-3 the numerator
        and denominator of G, then of K; then the numerator and denominator of
        each bound's weight.
    which : ndarray of int (nb,)
        Function of each bound: 0 for S (``gd kd/c``), 1 for KS (``gd kn/c``),
        2 for T (``gn kn/c``), ``c = gd kd + gn kn``.

    Returns
    -------
    at : ndarray of int (nb,)
        Index of each bound's largest ratio (the first, on a tie).
    c2_min : float
        Smallest ``|c|^2`` on the grid.
    """
    n, nb = w.size, which.size
    re, im = np.empty((6, _BLOCK)), np.empty((6, _BLOCK))
    sq = np.empty((4, _BLOCK))                    # |c|^2, |gd kd|^2, |gd kn|^2, |gn kn|^2
    r2 = np.empty(_BLOCK)
    at = np.zeros(nb, np.int64)
    best = np.full(nb, -1.0)
    c2_min = np.inf
    for i0 in range(0, n, _BLOCK):
        m = min(_BLOCK, n - i0)
        wb = w[i0:i0 + m]
        for f in range(4):                        # gn, gd, kn, kd
            _factor(wb, roots[starts[f]:starts[f + 1]], gains[f], re[f, :m], im[f, :m])
        for i in range(m):
            gnr, gni, gdr, gdi = re[0, i], im[0, i], re[1, i], im[1, i]
            knr, kni, kdr, kdi = re[2, i], im[2, i], re[3, i], im[3, i]
            sr, si = gdr * kdr - gdi * kdi, gdr * kdi + gdi * kdr
            qr, qi = gdr * knr - gdi * kni, gdr * kni + gdi * knr
            tr, ti = gnr * knr - gni * kni, gnr * kni + gni * knr
            cr, ci = sr + tr, si + ti
            sq[0, i] = cr * cr + ci * ci
            sq[1, i] = sr * sr + si * si
            sq[2, i] = qr * qr + qi * qi
            sq[3, i] = tr * tr + ti * ti
        c2_min = min(c2_min, sq[0, :m].min())
        for j in range(nb):
            f = 4 + 2 * j
            _factor(wb, roots[starts[f]:starts[f + 1]], gains[f], re[4, :m], im[4, :m])
            _factor(wb, roots[starts[f + 1]:starts[f + 2]], gains[f + 1], re[5, :m], im[5, :m])
            fj = sq[1 + which[j]]
            for i in range(m):
                r2[i] = ((fj[i] * (re[4, i] * re[4, i] + im[4, i] * im[4, i]))
                         / (sq[0, i] * (re[5, i] * re[5, i] + im[5, i] * im[5, i])))
            k = np.argmax(r2[:m])
            if r2[k] > best[j]:
                best[j] = r2[k]
                at[j] = i0 + k
    return at, c2_min
