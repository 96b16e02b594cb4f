"""Classical margins of a continuous SISO loop ``L = G K`` of
:mod:`toolbox.lti`'s systems, computed exactly: crossings as imaginary-axis
zeros of QZ pencils, ``M_m = 1/||S||_inf`` by SLICOT ab13dd. The grid route
of sampled and delayed loops is ``toolbox.analysis.margins``; the tests
compare the two (``tests/papers/test_003_hinf.py``).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._linalg import balanced, pencil_eigvals
from ._norms import linf_peak
from ._systems import as_statespace, evaluate, series, StateSpace

__all__ = ["LoopMargins", "MARGIN_BAND", "loop_margins", "loop_margins_and_poles"]


def _siso(sys: Any) -> tuple[np.ndarray, ...]:
    """A, B, C, D of a continuous SISO system (or a scalar gain)."""
    g = as_statespace(sys)
    if (g.noutputs, g.ninputs) != (1, 1) or g.discrete:
        raise ValueError(f"loop_margins: a continuous SISO system expected, got "
                         f"{g.noutputs}x{g.ninputs}{' discrete' if g.discrete else ''}")
    return g.A, g.B, g.C, g.D


@dataclass
class LoopMargins:
    """Classical margins of the loop L = G K (paper 003 sect. 3.3, Fig. 7).

    Attributes
    ----------
    gain_margin_db : float
        Gain margin (dB), inf when the phase never crosses -180 deg.
    phase_crossover_rad_s : float
        Frequency of the gain margin (rad/s).
    phase_margin_deg : float
        Phase margin (deg).
    gain_crossover_rad_s : float
        Frequency of the phase margin (rad/s).
    stability_margin : float
        M_m = min |1 + L(jw)| = 1/||S||_inf (peak refined on the grid).
    static_error : float
        1/(1 + L(0)) (0 with an integrator).
    """

    gain_margin_db: float
    phase_crossover_rad_s: float
    phase_margin_deg: float
    gain_crossover_rad_s: float
    stability_margin: float
    static_error: float


#: band in which the crossings are sought (rad/s): that of the grid of
#: :func:`toolbox.analysis.lti_loop_margins`, so both routes see the same crossings
MARGIN_BAND = (1e-3, 1e8)
#: a zero of the crossing function counts as imaginary when |Re| <= this * |zero|
_IMAG_TOL = 1e-6


def _balanced_series(first: tuple,
                     second: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A, B, C, d of ``second * first`` (SISO; the signal passes ``first``
    first): :func:`toolbox.lti.series`, in the coordinates of
    :func:`toolbox.lti.balanced` (powers of two: exact)."""
    L = series(StateSpace(*first), StateSpace(*second))
    if L.nstates == 0:
        return L.A, L.B, L.C, float(L.D[0, 0])
    return (*balanced(L.A, L.B, L.C), float(L.D[0, 0]))


def _imag_axis_zeros(lam: list[complex]) -> list[float]:
    """Frequencies w in :data:`MARGIN_BAND` of the zeros ``lam`` of a
    crossing function on the imaginary axis. The crossing functions below
    are para-Hermitian (even in s), so their zeros are symmetric about the
    imaginary axis and a simple zero on it stays there up to rounding."""
    lo, hi = MARGIN_BAND
    # a few eigenvalues: scalar code beats masked array operations (libm's
    # hypot for the moduli, which may differ from numpy's in the last bit:
    # a zero on the axis is ~1e-12 off it, far from the 1e-6 threshold)
    return sorted(z.imag for z in lam if lo <= z.imag <= hi and abs(z.real) <= _IMAG_TOL * abs(z))


def _crossings(A: np.ndarray, B: np.ndarray, C: np.ndarray,
               d: float) -> tuple[list[float], list[float]]:
    """Gain crossovers (``|L(jw)| = 1``: zeros of ``L(s) L(-s) - 1``) and phase
    crossover candidates (``Im L(jw) = 0``: zeros of ``L(s) - L(-s)``) of the
    SISO loop ``L = (A, B, C, d)``; ``L(-s)`` is realised by ``(-A, -B, C, d)``.

    The zeros are the finite eigenvalues of the QZ pencils ``(M, diag(I, 0))``
    of the system matrices, written directly: ``L(s) L(-s) - 1`` is the series
    connection ``[-A 0 -b; b c A b d; d c c d^2 - 1]``, ``L(s) - L(-s)`` the
    parallel one ``[A 0 b; 0 -A -b; c -c 0]``. (For ``d^2 != 1`` the first
    could be deflated to a standard eigenproblem of order 2n, ~5 us less per
    loop; measured on paper 003's d axis it put a crossover 1.8e-11 from a
    40-digit root where QZ is 1.5e-12 off, so QZ stays.)"""
    n = A.shape[0]
    b, c, minus_A, minus_b = B[:, 0], C[0], -A, -B[:, 0]
    Mg, Mp = np.zeros((2, 2 * n + 1, 2 * n + 1))
    Mg[:n, :n], Mg[:n, -1], Mg[-1, n:-1] = minus_A, minus_b, c
    Mg[n:-1, :n], Mg[n:-1, n:-1], Mg[n:-1, -1] = B * C, A, b * d
    Mg[-1, :n], Mg[-1, -1] = d * c, d * d - 1.0
    Mp[:n, :n], Mp[:n, -1], Mp[-1, :n] = A, b, c
    Mp[n:-1, n:-1], Mp[n:-1, -1], Mp[-1, n:-1] = minus_A, minus_b, -c
    E = np.diag([1.0] * (2 * n) + [0.0])
    return (_imag_axis_zeros(pencil_eigvals(Mg, E)),
            _imag_axis_zeros(pencil_eigvals(Mp, E)))


def _response(A: np.ndarray, B: np.ndarray, C: np.ndarray, d: float,
              w: list[float]) -> list[complex]:
    """``L(jw)`` at a few frequencies (:func:`toolbox.lti.evaluate`, one LU
    solve each)."""
    if not w:
        return []
    return evaluate(A, B, C, np.array([[d]]), 1j * np.asarray(w, float),
                    solve=True)[0, 0].tolist()


def loop_margins(G: Any, K: Any) -> LoopMargins:
    """Margins of L = G K, computed exactly rather than on a grid.

    The crossings are the imaginary-axis zeros of ``L(s) L(-s) - 1`` (gain
    crossovers) and ``L(s) - L(-s)`` (phase crossovers, kept where
    ``Re L < 0``), sought in :data:`MARGIN_BAND`; the headline margins follow
    the rule of :func:`toolbox.analysis.frequency_margins` (python-control's:
    the crossing closest to instability), and
    ``M_m = 1/||S||_inf`` is the L-infinity norm of ``S = 1/(1 + L)``
    (:func:`toolbox.lti.linf_norm`: SLICOT ab13dd, relative tolerance
    1e-10). The tests check the numbers against
    :func:`toolbox.analysis.lti_loop_margins` (the toolbox's grid route,
    20000 points and refinement, ~20 times slower) and python-control.

    Parameters
    ----------
    G, K : LTI system (python-control or toolbox.lti) or float
        Plant and controller, SISO, continuous (read by :func:`as_statespace`).

    Returns
    -------
    LoopMargins
    """
    return loop_margins_and_poles(G, K)[0]


def loop_margins_and_poles(G: Any, K: Any) -> tuple[LoopMargins, np.ndarray, float]:
    """:func:`loop_margins` of ``L = G K``, the closed-loop poles (those of
    ``S = 1/(1 + L)``, whose norm gave ``M_m``) and the frequency of the peak
    of ``|S|`` (rad/s)."""
    A, B, C, d = _balanced_series(_siso(K), _siso(G))
    if A.shape[0] == 0:
        gm_db, w_gm, pm, w_pm = _gain_phase_margins(A, B, C, d)
        return (LoopMargins(gm_db, w_gm, pm, w_pm, abs(1.0 + d), abs(1.0 / (1.0 + d))),
                np.zeros(0, complex), math.inf)
    gm_db, w_gm, pm, w_pm = _gain_phase_margins(A, B, C, d)
    f = 1.0 / (1.0 + d)                              # S = 1/(1 + L)
    fB = f * B
    Acl = A - fB @ C
    peak, w_peak = linf_peak(Acl, fB, -f * C, np.array([[f]]))
    poles = np.linalg.eigvals(Acl)
    if any(abs(z) < 1e-12 for z in np.linalg.eigvals(A).tolist()):   # an integrator: no static error
        ess = 0.0
    else:
        ess = float(abs(1.0 / (1.0 + d - float((C @ np.linalg.solve(A, B))[0, 0]))))
    return LoopMargins(gm_db, w_gm, pm, w_pm, 1.0 / peak, ess), poles, w_peak


def _gain_phase_margins(A: np.ndarray, B: np.ndarray, C: np.ndarray,
                        d: float) -> tuple[float, float, float, float]:
    """(GM dB, its phase crossover, PM deg, its gain crossover) of L = (A, B, C, d),
    inf and nan without crossing."""
    w_gc, w_pc = _crossings(A, B, C, d) if A.shape[0] else ([], [])
    # one call for both sets of crossings (one setup of the complex data); the
    # crossings are few: Python numbers (cmath's phase is libm's atan2, ~0.1 us
    # against ~1.5 us for np.angle's array round trip; the two differ in the
    # last bit on ~7 % of arguments)
    L = _response(A, B, C, d, w_gc + w_pc)
    Lgc, Lpc = L[:len(w_gc)], L[len(w_gc):]
    pms = [(math.degrees(cmath.phase(-x)), w) for x, w in zip(Lgc, w_gc)]
    gms = [(-20 * math.log10(abs(x)), w) for x, w in zip(Lpc, w_pc)
           if x.real < 0 and abs(x.imag) <= 1e-6 * abs(x)]
    gm_db, w_gm = min(gms, key=lambda g: abs(g[0])) if gms else (math.inf, math.nan)
    pm, w_pm = min(pms, key=lambda p: abs(p[0])) if pms else (math.inf, math.nan)
    return float(gm_db), float(w_gm), float(pm), float(w_pm)
