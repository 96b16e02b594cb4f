"""Compiled passes over the robustness sweep's stacked loops.

:func:`grid_pass` serves :func:`toolbox.analysis._siso.grid_margins`,
:func:`plant_factors` the sweep's loops (``toolbox.analysis.robustness``).

The robustness sweep hands ``grid_margins`` thousands of loops of a thousand
points; in numpy each full-size quantity (``|1 + L|^2``, ``|1 - L|^2/|1 + L|^2``,
their row extrema, the sign-change masks of ``|L| - 1`` and ``Im L``) is a pass
over memory of its own, together 70 % of ``grid_margins``' time. This
kernel does them in one pass with the same IEEE operations in the same order
(no ``fastmath``: no fused multiply-add, no reassociation), so its numbers are
numpy's bit for bit (tested). ``|L|`` itself stays numpy's ``abs`` (its
``hypot`` is not the textbook formula).

Imported on first use, so that ``import toolbox.analysis`` does not import numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["grid_pass", "plant_factors"]


@njit(cache=True, error_model="numpy")
def grid_pass(re: np.ndarray, im: np.ndarray, mag: np.ndarray):
    """Row extrema and crossing cells of loops ``L = re + j im`` (n, Nw).

    Returns
    -------
    one2_min : ndarray
        ``min_w |1 + L|^2`` per row (n,), ``(1 + re)^2 + im^2``.
    ratio_max : ndarray
        ``max_w |1 - L|^2/|1 + L|^2`` per row (n,).
    gain_cells, phase_cells : ndarray of bool
        (n, Nw - 1): ``|L| - 1`` (``mag - 1``), respectively ``Im L``,
        changes sign strictly between columns ``k`` and ``k + 1``.

    A NaN makes its row's extrema NaN, as ``numpy.min``/``max``, and starts
    or ends no crossing.
    """
    n, nw = re.shape
    one2_min = np.empty(n)
    ratio_max = np.empty(n)
    gain_cells = np.zeros((n, nw - 1), np.bool_)
    phase_cells = np.zeros((n, nw - 1), np.bool_)
    for i in range(n):
        lo = np.inf
        hi = -np.inf
        for k in range(nw):
            r = re[i, k]
            m = im[i, k]
            m2 = m * m
            p = 1.0 + r
            one2 = p * p + m2
            q = 1.0 - r
            ratio = (q * q + m2) / one2
            if one2 < lo or one2 != one2:
                lo = one2
            if ratio > hi or ratio != ratio:
                hi = ratio
            if k:
                a0, a1 = mag[i, k - 1], mag[i, k]
                gain_cells[i, k - 1] = (a0 > 1.0 and a1 < 1.0) or (a0 < 1.0 and a1 > 1.0)
                b0 = im[i, k - 1]
                phase_cells[i, k - 1] = (b0 > 0.0 and m < 0.0) or (b0 < 0.0 and m > 0.0)
        one2_min[i] = lo
        ratio_max[i] = hi
    return one2_min, ratio_max, gain_cells, phase_cells


@njit(cache=True, error_model="numpy")
def plant_factors(zr: np.ndarray, qi: np.ndarray, a: np.ndarray, b: np.ndarray):
    """``z - a`` conjugated and ``b/|z - a|^2`` of first-order plants ``b/(z - a)``.

    ``zr``, ``qi`` (Nw,) are ``Re z``, ``Im z``; ``a``, ``b`` (n,). Returns the
    complex ``qr - j qi`` with ``qr = zr - a`` (n, Nw) and the real
    ``b/(qr^2 + qi^2)`` (n, Nw): numpy's ``zr - a``, ``qr - 1j qi`` and
    ``b/(qr * qr + qi * qi)`` bit for bit, in one pass (signed zeros included:
    the imaginary part is ``0.0 - qi``, as numpy's complex subtraction gives).
    """
    n, nw = a.size, zr.size
    conj = np.empty((n, nw), np.complex128)
    scale = np.empty((n, nw))
    for i in range(n):
        for k in range(nw):
            qr = zr[k] - a[i]
            conj[i, k] = complex(qr, 0.0 - qi[k])
            scale[i, k] = b[i] / (qr * qr + qi[k] * qi[k])
    return conj, scale
