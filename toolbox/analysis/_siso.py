"""The one margins API of the toolbox: classical and disk margins of a SISO loop.

Every margin the toolbox reports comes from here:

* :func:`frequency_margins` - a loop given as a function ``w -> L(jw)``
  (or ``L(e^{jwTs})``) on a dense grid, every crossing and peak refined
  (Brent root finding on ``log|L|`` and ``Im L``, bounded scalar search for
  the peaks); used by the per-axis analysis
  (:func:`toolbox.analysis.margins.axis_margins`);
* :func:`lti_loop_margins` - the same for an LTI loop (a
  :class:`toolbox.lti.StateSpace` or a python-control system; continuous or
  discrete); used by the H-infinity order-reduction guard;
* :func:`grid_margins` - a response already sampled on a grid, possibly
  stacked (N loops x Nw points), with linear interpolation between grid
  points instead of refinement; used by the robustness sweep (thousands of
  loops at once) and meant for plotted data.

Naming (toolbox/ARCHITECTURE.md "MARGINS", same as python-control
``stability_margins``): ``gain_margin_db`` is read at the **phase crossover**
(``angle L = -180 deg``, ``phase_crossover_rad_s``), ``phase_margin_deg`` at
the **gain crossover** (``|L| = 1``, ``gain_crossover_rad_s``). With several
crossings the headline margins are those closest to instability
(python-control's rule: the gain margin of smallest ``|log GM|``, the phase
margin of smallest ``|PM|``).

Disk margins: Seiler, Packard, Gahinet, "An introduction to disk margins",
IEEE Control Systems Magazine 40(5), 2020: for skew ``sigma`` the loop
tolerates every gain and phase variation in
``D(alpha, sigma) = {(2 + (1 - sigma) delta)/(2 - (1 + sigma) delta) : |delta| < alpha}``
with ``alpha = 1/max_w |S + (sigma - 1)/2|``; ``sigma = 0`` is the balanced
disk margin ``1/||(S - T)/2||_inf``.
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..lti import as_statespace
from ._scalar import bounded_minimum, brentq
from ._statespace import FreqResponse

__all__ = ["MARGIN_KEYS", "FrequencyMargins", "disk_variations", "log_grid",
           "frequency_margins", "lti_loop_margins", "grid_margins", "SKEWS"]

#: The MARGINS keys of controller.json (toolbox/ARCHITECTURE.md), in contract order.
MARGIN_KEYS = ("gain_margin_db", "gain_crossover_rad_s", "phase_margin_deg",
               "phase_crossover_rad_s", "disk_margin", "stability_margin",
               "sensitivity_peak", "bandwidth_rad_s", "static_error")

#: Disk skews evaluated by :func:`frequency_margins` (-1: T-based, 0: balanced, 1: S-based).
SKEWS = (-1.0, -0.5, 0.0, 0.5, 1.0)


@dataclass(frozen=True)
class FrequencyMargins:
    """Frequency-domain margins of one SISO loop ``L``.

    Attributes
    ----------
    gain_margin_db : float
        At the phase crossover closest to instability; inf without one.
    phase_crossover_rad_s : float
        Where the gain margin is read (rad/s); nan without one.
    phase_margin_deg : float
        At the gain crossover closest to instability; inf without one.
    gain_crossover_rad_s : float
        Where the phase margin is read (rad/s); nan without one.
    sensitivity_peak : float
        ``||S||_inf``, ``S = 1/(1 + L)``.
    stability_margin : float
        ``M_m = min_w |1 + L| = 1/||S||_inf`` (paper 003 sect. 3.3).
    complementary_peak : float
        ``||T||_inf``, ``T = L/(1 + L)``.
    disk_margin : float
        Balanced disk margin ``alpha`` (skew 0).
    delay_margin_s : float
        ``min PM/w_gc`` over the gain crossovers (s); 0 for a negative PM.
    gain_margins_db, phase_margins_deg : list
        Every crossing found, ``[value, frequency]``, by frequency.
    skewed_disk_margins : list of dict
        ``{skew, alpha, gain_low, gain_high, phase_deg}`` for :data:`SKEWS`.
    """

    gain_margin_db: float
    phase_crossover_rad_s: float
    phase_margin_deg: float
    gain_crossover_rad_s: float
    sensitivity_peak: float
    stability_margin: float
    complementary_peak: float
    disk_margin: float
    delay_margin_s: float
    gain_margins_db: list = field(default_factory=list)
    phase_margins_deg: list = field(default_factory=list)
    skewed_disk_margins: list = field(default_factory=list)


def disk_variations(alpha: float, skew: float = 0.0) -> tuple[float, float, float]:
    """Gain and phase variations guaranteed by a disk margin.

    Parameters
    ----------
    alpha : float
        Disk margin (dimensionless).
    skew : float
        Disk skew ``sigma`` (0 balanced, 1 for S, -1 for T).

    Returns
    -------
    gain_low, gain_high : float
        Real-axis intercepts of ``D(alpha, sigma)`` (gain factors).
    phase_deg : float
        Largest ``theta`` with ``exp(j theta)`` in the disk (deg), from
        ``cos theta = (1 + g_low g_high)/(g_low + g_high)`` (90 deg when the
        disk is a half plane, 180 when it contains the unit circle).
    """
    lo = max((1 - 0.5 * alpha * (1 - skew)) / (1 + 0.5 * alpha * (1 + skew)), 0.0)
    den = 1 - 0.5 * alpha * (1 + skew)
    hi = (1 + 0.5 * alpha * (1 - skew)) / den if den > 0 else math.inf
    if not math.isfinite(hi):
        return lo, hi, 90.0 if den == 0 else 180.0
    c = (1 + lo * hi) / (lo + hi) if lo + hi != 0 else -2.0
    phase = math.degrees(math.acos(c)) if abs(c) <= 1 else (180.0 if c < -1 else 0.0)
    return float(lo), float(hi), phase


@functools.lru_cache(maxsize=32)
def log_grid(w_lo: float, w_hi: float, n: int, discrete: bool) -> np.ndarray:
    """Logarithmic frequency grid (rad/s); in discrete time its last point is
    exactly ``w_hi`` (the Nyquist frequency) so that ``L(-1)`` is evaluated.

    Read-only and cached: every margin computation of a design asks for the
    same 20000-point grid (~0.5 ms of ``logspace`` each time)."""
    w = np.logspace(math.log10(w_lo), math.log10(w_hi), n)
    if discrete:
        w[-1] = w_hi
    w.flags.writeable = False
    return w


def _roots_in_grid(fun: Callable[[float], float], w: np.ndarray, vals: np.ndarray) -> list[float]:
    """Refined zeros of ``fun`` at sign changes of ``vals`` on ``w``."""
    out = []
    idx = np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0]
    for i in idx:
        try:
            u = brentq(lambda lw: fun(math.exp(lw)), math.log(w[i]), math.log(w[i + 1]),
                       xtol=1e-13, rtol=1e-13)
        except ValueError:
            continue
        out.append(math.exp(u))
    out += [float(w[i]) for i in np.nonzero(vals == 0)[0]]
    return sorted(out)


def _peak(fun: Callable[[float], float], w: np.ndarray, vals: np.ndarray) -> tuple[float, float]:
    """Maximum of ``fun`` (scalar of w) refined around the grid maximum."""
    i = int(np.nanargmax(vals))
    lo, hi = math.log(w[max(i - 1, 0)]), math.log(w[min(i + 1, len(w) - 1)])
    best_w, best = float(w[i]), float(vals[i])
    if hi > lo:
        lw, neg = bounded_minimum(lambda lw: -fun(math.exp(lw)), lo, hi, xatol=1e-10)
        if -neg > best:
            best_w, best = math.exp(lw), float(-neg)
    return best, best_w


def frequency_margins(loop: Callable[[np.ndarray], np.ndarray], w: np.ndarray, *,
                      nyquist: bool = False,
                      loop_at: Callable[[float], complex] | None = None) -> FrequencyMargins:
    """Margins of a loop given by its frequency response function.

    Parameters
    ----------
    loop : callable
        ``w -> L`` (complex array of the same length), w in rad/s.
    w : ndarray
        Increasing grid (rad/s), dense enough to separate crossings (a
        crossing pair inside one grid cell is missed; 6000 log points per
        12 decades keep cells below 0.5 %).
    nyquist : bool
        Discrete loop whose last grid point is the Nyquist frequency: a real
        negative ``L(-1)`` is a phase crossover even without a sign change.
    loop_at : callable, optional
        ``w -> L`` at one frequency (float -> complex), the same loop: the
        refinements evaluate it a few hundred times, where a one-point array
        call of ``loop`` costs ten times more (default: ``loop`` itself).

    Returns
    -------
    FrequencyMargins
    """
    if loop_at is None:
        loop_at = lambda x: complex(loop(np.array([x]))[0])  # noqa: E731
    with np.errstate(divide="ignore", invalid="ignore"):
        return _frequency_margins(loop, loop_at, np.asarray(w, float), nyquist)


def _frequency_margins(loop, L1, w: np.ndarray, nyquist: bool) -> FrequencyMargins:
    Lw = loop(w)
    # gain crossovers (|L| = 1) -> phase margins
    pms = [[math.degrees(np.angle(-L1(x))), x]
           for x in _roots_in_grid(lambda x: math.log(abs(L1(x))), w, np.log(np.abs(Lw)))]
    # phase crossovers (Im L = 0, Re L < 0) -> gain margins
    wpc = _roots_in_grid(lambda x: L1(x).imag, w, Lw.imag)
    # L(-1) of a loop with a zero at z = -1 (Tustin) is rounding noise of any
    # sign, not a phase crossover: it counts only above 1e-14 of the loop's peak
    if (nyquist and abs(Lw[-1].imag) <= 1e-9 * abs(Lw[-1]) and w[-1] not in wpc
            and abs(Lw[-1]) > 1e-14 * np.max(np.abs(Lw), initial=0.0, where=np.isfinite(Lw))):
        wpc.append(float(w[-1]))
    gms = []
    for x in wpc:
        Lx = L1(x)
        if Lx.real < 0 and abs(Lx.imag) <= 1e-6 * abs(Lx):
            gms.append([-20 * math.log10(abs(Lx)), x])
    gm_db, w_gm = min(gms, key=lambda g: abs(g[0])) if gms else (math.inf, math.nan)
    if pms:
        pm, w_pm = min(pms, key=lambda p: abs(p[0]))
        delay_margin = min((math.radians(p) / x if p > 0 else 0.0) for p, x in pms)
    else:
        pm, w_pm, delay_margin = math.inf, math.nan, math.inf

    S = lambda x: 1.0 / (1.0 + L1(x))  # noqa: E731
    Sw = 1.0 / (1.0 + Lw)
    s_peak, _ = _peak(lambda x: abs(S(x)), w, np.abs(Sw))
    t_peak, _ = _peak(lambda x: abs(1 - S(x)), w, np.abs(Lw * Sw))
    skewed = []
    for sigma in SKEWS:
        # skew 1 is |S| itself: the same search as s_peak, not run twice
        peak = s_peak if sigma == 1.0 else _peak(lambda x: abs(S(x) + 0.5 * (sigma - 1)), w,
                                                 np.abs(Sw + 0.5 * (sigma - 1)))[0]
        alpha = 1.0 / peak
        lo, hi, ph = disk_variations(alpha, sigma)
        skewed.append({"skew": sigma, "alpha": alpha, "gain_low": lo, "gain_high": hi,
                       "phase_deg": ph})
    balanced = next(d for d in skewed if d["skew"] == 0.0)
    return FrequencyMargins(
        gain_margin_db=float(gm_db), phase_crossover_rad_s=float(w_gm),
        phase_margin_deg=float(pm), gain_crossover_rad_s=float(w_pm),
        sensitivity_peak=float(s_peak), stability_margin=float(1.0 / s_peak),
        complementary_peak=float(t_peak), disk_margin=float(balanced["alpha"]),
        delay_margin_s=float(delay_margin),
        gain_margins_db=sorted(gms, key=lambda g: g[1])[:8],
        phase_margins_deg=sorted(pms, key=lambda p: p[1])[:8], skewed_disk_margins=skewed)


def lti_loop_margins(L: Any, w: np.ndarray | None = None, *,
                     n_grid: int = 20000) -> FrequencyMargins:
    """Margins of an LTI loop ``L`` (continuous or discrete).

    Parameters
    ----------
    L : toolbox.lti.StateSpace, python-control LTI, or anything
        :func:`toolbox.lti.as_statespace` reads (without importing
        python-control; a transfer function is realised in controllable
        canonical form). The loop transfer (SISO), e.g. ``G * K``.
    w : ndarray, optional
        Grid (rad/s). Default: ``n_grid`` log points from 1e-3 rad/s to
        1e8 rad/s (continuous) or to the Nyquist frequency ``pi/dt``
        (discrete); 20000 points over 11 decades keep each cell below 0.13 %,
        so crossings closer than that are the only ones that can be missed.
    n_grid : int
        Size of the default grid.

    Returns
    -------
    FrequencyMargins
        Same numbers as :func:`control.stability_margins` (checked in the
        tests), plus the disk margins.
    """
    sys = as_statespace(L)
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    if D.shape != (1, 1):
        raise ValueError(f"lti_loop_margins: expected a SISO loop, got {D.shape[0]} outputs x "
                         f"{D.shape[1]} inputs")
    dt = sys.dt
    discrete = dt is not None
    if w is None:
        w = log_grid(1e-3, math.pi / dt if discrete else 1e8, n_grid, discrete)
    else:
        discrete = discrete and math.isclose(float(w[-1]), math.pi / dt)

    fr = FreqResponse(A, B, C, D)   # Hessenberg form once, for the grid and the refinements

    def response(x: np.ndarray) -> np.ndarray:
        # FreqResponse silences its own division by zero on a pole; no
        # warnings.catch_warnings here (~10 us for each of ~90 refinement calls)
        pts = np.exp(1j * x * dt) if dt is not None else 1j * np.asarray(x, float)
        return fr(pts)[:, 0, 0]

    def response_at(x: float) -> complex:
        return fr.at(cmath.exp(1j * x * dt) if dt is not None else 1j * x)

    return frequency_margins(response, np.asarray(w, float), nyquist=discrete,
                             loop_at=response_at)


def grid_margins(w: np.ndarray, response: np.ndarray, *, nyquist: bool = False) -> dict[str, np.ndarray]:
    """Margins of loops sampled on a grid, stacked, without refinement.

    Crossings are located by sign changes between grid points and the loop is
    interpolated linearly inside the cell (fast for thousands of loops; the
    error is of the order of the cell's change of ``L``, so callers that need
    the exact value recompute it with :func:`frequency_margins`).

    Parameters
    ----------
    w : ndarray
        Grid (rad/s), (Nw,). Kept for the signature's clarity and checks.
    response : ndarray
        ``L`` on the grid, (Nw,) or (N, Nw).
    nyquist : bool
        The last point is the Nyquist frequency of a discrete loop: a real
        negative ``L(-1)`` counts as a phase crossover.

    Returns
    -------
    dict
        ``gain_margin_db``, ``phase_margin_deg`` (closest to instability,
        inf without crossing), ``stability_margin`` (``min |1 + L|``) and
        ``disk_margin`` (balanced), each (N,) or scalar-shaped like the input.
    """
    Lw = np.asarray(response, complex)
    single = Lw.ndim == 1
    Lw = np.atleast_2d(Lw)
    if Lw.shape[-1] != np.size(w):
        raise ValueError(f"grid_margins: response has {Lw.shape[-1]} points, grid {np.size(w)}")
    with np.errstate(divide="ignore", invalid="ignore"):
        out = _grid_margins(Lw, nyquist)
    return {k: v[0] for k, v in out.items()} if single else out


def _grid_margins(Lw: np.ndarray, nyquist: bool) -> dict[str, np.ndarray]:
    # thousands of loops of a thousand points each; every full-size
    # quantity is made in one compiled pass (_grid_kernel, numpy's numbers bit for
    # bit), the complex divisions replaced by real arithmetic, and everything
    # else is evaluated only at the crossing cells
    from ._grid_kernel import grid_pass  # lazy: numba + JIT kernel, 211 modules

    re, im = Lw.real, Lw.imag
    mag = np.abs(Lw)
    one2_min, ratio_max, gain_cells, phase_cells = grid_pass(re, im, mag)
    sm = np.sqrt(one2_min)                                 # min |1 + L|
    # |S - 1/2| = |1 - L|/(2 |1 + L|), S = 1/(1 + L)
    dm = 2.0 / np.sqrt(ratio_max)
    n = Lw.shape[0]
    # phase margins at |L| = 1 crossings (sign changes of log |L|)
    r, c = _cells(gain_cells)
    lg0, lg1 = np.log(mag[r, c]), np.log(mag[r, c + 1])
    t = lg0 / (lg0 - lg1)
    Lc = Lw[r, c] + t * (Lw[r, c + 1] - Lw[r, c])
    pm = _closest(n, r, c, np.degrees(np.angle(-Lc)))
    # gain margins at Im L = 0, Re L < 0
    r, c = _cells(phase_cells)
    t2 = im[r, c] / (im[r, c] - im[r, c + 1])
    rc = re[r, c] + t2 * (re[r, c + 1] - re[r, c])
    neg = rc < 0
    r, c, gm = r[neg], c[neg], -20 * np.log10(np.abs(rc[neg]))
    if nyquist:  # L(-1) is real: a phase crossover when negative
        k = np.nonzero(re[:, -1] < 0)[0]
        r = np.concatenate([r, k])
        c = np.concatenate([c, np.full(k.size, Lw.shape[1] - 1)])
        gm = np.concatenate([gm, -20 * np.log10(np.abs(re[k, -1]))])
    return {"gain_margin_db": _closest(n, r, c, gm), "phase_margin_deg": pm,
            "stability_margin": sm, "disk_margin": dm}


def _cells(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, cols)`` of the True cells of a 2-D mask, row by row: ``flatnonzero``
    (a 2-D ``np.nonzero`` cost ten times more)."""
    return np.divmod(np.flatnonzero(mask), mask.shape[1])


def _closest(n: int, rows: np.ndarray, cols: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Per row of ``n``, the value of smallest magnitude among the entries
    ``(rows, cols, values)`` (the first column on a tie); inf for a row
    without entries (NaN values are no entries)."""
    ok = ~np.isnan(values)
    rows, cols, values = rows[ok], cols[ok], values[ok]
    out = np.full(n, np.inf)
    order = np.lexsort((cols, np.abs(values), rows))
    first = order[np.unique(rows[order], return_index=True)[1]]
    v = values[first]
    out[rows[first]] = np.where(np.isinf(v), np.inf, v)
    return out
