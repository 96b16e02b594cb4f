"""Weighting filters for H-infinity mixed-sensitivity design.

The filters of paper 003 (Azaiz et al., "H-infinity design of controllers
ensuring the regulation of currents ... applied to a PMS motor") are given as
explicit rational functions, eq (44)-(49); others are most easily specified by
their low-frequency gain, crossover and high-frequency gain, as MATLAB's
``makeweight`` does.  Every constructor here returns a
:class:`toolbox.lti.TransferFunction` and checks that the weight is usable in
the augmented plant of eq (50)-(64): finite coefficients, proper, stable.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from toolbox.lti import TransferFunction
from toolbox.errors import SpecError

#: Highest makeweight order (see :func:`makeweight`).
MAX_MAKEWEIGHT_ORDER = 10
#: Largest weight gain accepted: the Riccati solutions of the synthesis scale
#: with the square of the weights, and beyond 1e12 (1e24 squared) double
#: precision leaves no digit for the plant's own dynamics (the synthesis then
#: fails with a misleading assumption message instead of a range error).
MAX_WEIGHT_GAIN = 1e12

__all__ = ["weight_from_tf", "weight_from_zpk", "makeweight", "validate_weight"]

_DEFAULT_KEY = "controller.hinf.weights"


def _as_coeffs(values: Sequence[float], key: str, what: str) -> np.ndarray:
    """Turn a coefficient list into a 1-D float array without leading zeros."""
    try:
        arr = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise SpecError(f"{key}.{what}", "a list of numbers", values) from None
    if arr.ndim != 1 or arr.size == 0:
        raise SpecError(f"{key}.{what}", "a non-empty list of numbers", values)
    if not np.all(np.isfinite(arr)):
        raise SpecError(f"{key}.{what}", "finite numbers (no NaN or inf)",
                        arr.tolist())
    nz = np.flatnonzero(arr)
    if nz.size == 0:
        raise SpecError(f"{key}.{what}", "a non-zero polynomial", arr.tolist())
    return arr[nz[0]:]


def validate_weight(w: Any, key: str = _DEFAULT_KEY,
                    allow_integrator: bool = False) -> TransferFunction:
    """Check that a weight is SISO, finite, proper and stable.

    Parameters
    ----------
    w : TransferFunction, python-control system or number
        The weighting filter (dimensionless or in the unit ratio it weights),
        SISO and continuous.
    key : str
        Dotted spec key used in the error message, e.g.
        ``controller.hinf.weights.q.w1``.
    allow_integrator : bool
        Accept poles on the imaginary axis (they violate assumptions A3/A4 of
        paper 003 later, where :func:`toolbox.design._hinf_assumptions.check_assumptions`
        gives the remedy).  Default ``False``.

    Returns
    -------
    TransferFunction
        ``w`` as a :class:`toolbox.lti.TransferFunction` (the same object if
        it was one).

    Raises
    ------
    SpecError
        When ``w`` has NaN/inf coefficients, is improper (more zeros than
        poles) or has a pole with non-negative real part.
    """
    shape = (getattr(w, "noutputs", 1), getattr(w, "ninputs", 1))
    if shape != (1, 1):
        raise SpecError(key, "a SISO weight", f"{shape[0]}x{shape[1]}")
    try:
        w = TransferFunction.from_system(w)
    except (TypeError, ValueError) as err:
        raise SpecError(key, "a SISO continuous transfer function", str(err)) from None
    num = _as_coeffs(w.num, key, "num")
    den = _as_coeffs(w.den, key, "den")
    if num.size > den.size:
        raise SpecError(key, "a proper weight (degree of num <= degree of den)",
                        f"num degree {num.size - 1} > den degree {den.size - 1}",
                        hint="add poles at high frequency, beyond the band of interest")
    poles = np.roots(den)
    bad = poles[poles.real > 0] if allow_integrator else poles[poles.real >= 0]
    if bad.size:
        p = bad[0]
        hint = ("move it to a small negative value, e.g. s + 1e-3 times the crossover"
                if abs(p) == 0 else "weights must be stable")
        raise SpecError(key, "a stable weight (all poles with Re < 0)",
                        f"pole at s = {complex(p):.6g}", hint=hint)
    peak = _peak_gain(num, den, poles)
    if not peak <= MAX_WEIGHT_GAIN:
        raise SpecError(key, f"a weight whose gain stays below {MAX_WEIGHT_GAIN:g}",
                        f"a peak gain of {peak:.3g}",
                        hint="only the ratio of the weights to gamma matters: scale them down")
    return w


def _peak_gain(num: np.ndarray, den: np.ndarray, poles: np.ndarray) -> float:
    """Largest |W(j w)| on a log grid refined at the break frequencies (a peak
    between grid points is at most a few per cent higher: enough for a range check)."""
    roots = np.concatenate([poles, np.roots(num) if num.size > 1 else []])
    breaks = np.abs(roots[np.abs(roots) > 0])
    # s = 0 itself only without an integrator (allow_integrator)
    w = np.concatenate([[0.0] if den[-1] != 0 else [], np.logspace(-6, 12, 181), breaks])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        gain = np.abs(np.polyval(num, 1j * w) / np.polyval(den, 1j * w))
    hf = abs(num[0] / den[0]) if num.size == den.size else 0.0
    return float(max(np.max(gain), hf)) if np.all(np.isfinite(gain)) else math.inf


def weight_from_tf(num: Sequence[float], den: Sequence[float],
                   key: str = _DEFAULT_KEY) -> TransferFunction:
    """Build a weight from polynomial coefficients in s, highest power first.

    Parameters
    ----------
    num, den : sequence of float
        Numerator and denominator coefficients, e.g. eq (44) of paper 003,
        ``w1 = (1/1.51)(s + 177.3493)/(s + 0.0117)`` is
        ``num=[1/1.51, 177.3493/1.51], den=[1, 0.0117]``.
    key : str
        Dotted spec key for error messages.

    Returns
    -------
    TransferFunction

    Raises
    ------
    SpecError
        Bad coefficients, improper or unstable weight.

    Examples
    --------
    >>> w3 = weight_from_tf([1e4, 1.3568e6], [1, 2.7135e6])
    """
    n = _as_coeffs(num, key, "num")
    d = _as_coeffs(den, key, "den")
    return validate_weight(TransferFunction(n, d), key)


def weight_from_zpk(zeros: Sequence[complex], poles: Sequence[complex],
                    gain: float, key: str = _DEFAULT_KEY) -> TransferFunction:
    """Build a weight ``gain * prod(s - z) / prod(s - p)``.

    Parameters
    ----------
    zeros, poles : sequence of complex
        Zeros and poles (rad/s); complex ones must come in conjugate pairs.
    gain : float
        Leading gain (not the DC gain).
    key : str
        Dotted spec key for error messages.

    Returns
    -------
    TransferFunction

    Raises
    ------
    SpecError
        NaN values, unpaired complex roots, improper or unstable weight.
    """
    z = np.asarray(zeros, dtype=complex).ravel()
    p = np.asarray(poles, dtype=complex).ravel()
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(p)) and np.isfinite(gain)):
        raise SpecError(key, "finite zeros, poles and gain",
                        {"zeros": z.tolist(), "poles": p.tolist(), "gain": gain})
    num = np.poly(z) * float(gain) if z.size else np.array([float(gain)])
    den = np.poly(p) if p.size else np.array([1.0])
    for name, c in (("zeros", num), ("poles", den)):
        if np.max(np.abs(np.imag(c))) > 1e-9 * max(1.0, np.max(np.abs(c))):
            raise SpecError(f"{key}.{name}", "complex values in conjugate pairs",
                            (z if name == "zeros" else p).tolist())
    return weight_from_tf(np.real(num), np.real(den), key)


def makeweight(dc_gain: float, crossover_freq: float, crossover_gain: float,
               hf_gain: float, order: int = 1,
               key: str = _DEFAULT_KEY) -> TransferFunction:
    r"""First- or n-th-order weight from three gains, like MATLAB's ``makeweight``.

    The weight has magnitude ``dc_gain`` at s = 0, ``hf_gain`` as
    s -> infinity and ``crossover_gain`` at ``crossover_freq``.  For order 1

    .. math:: w(s) = \frac{h s + \omega_0 d}{s + \omega_0},

    and order n is the n-th power of a first-order weight with gains
    ``dc_gain**(1/n)`` etc. (the magnitudes of the product are those asked).
    With :math:`d=\mathrm{dc}^{1/n}`, :math:`h=\mathrm{hf}^{1/n}`,
    :math:`c=\mathrm{mag}^{1/n}`,
    :math:`\omega_0 = \omega_c \sqrt{(h^2-c^2)/(c^2-d^2)}`.

    Parameters
    ----------
    dc_gain : float
        Low-frequency gain (absolute, not dB), > 0.
    crossover_freq : float
        Frequency where the gain equals ``crossover_gain`` (rad/s), > 0.
    crossover_gain : float
        Gain at ``crossover_freq`` (absolute), strictly between the other two.
    hf_gain : float
        High-frequency gain (absolute), > 0.
    order : int
        Filter order, >= 1.
    key : str
        Dotted spec key for error messages.

    Returns
    -------
    TransferFunction

    Raises
    ------
    SpecError
        Gains not positive and finite, or ``crossover_gain`` not strictly
        between ``dc_gain`` and ``hf_gain``.

    Examples
    --------
    A sensitivity weight in the spirit of eq (44) of paper 003 (|1/w1| = 1 at
    156 rad/s, 1/w1 -> 1.51 at high frequency, static error 1e-4):

    >>> w1 = makeweight(1e4, 156.0, 1.0, 1 / 1.51)
    """
    vals = {"dc_gain": dc_gain, "crossover_freq": crossover_freq,
            "crossover_gain": crossover_gain, "hf_gain": hf_gain}
    for name, v in vals.items():
        if not (isinstance(v, (int, float, np.floating)) and np.isfinite(v) and v > 0):
            raise SpecError(f"{key}.{name}", "a finite number > 0", v)
    if not (isinstance(order, (int, np.integer)) and 1 <= order <= MAX_MAKEWEIGHT_ORDER):
        # the n-th power of a first-order filter is numerically flat beyond 10
        raise SpecError(f"{key}.order", f"an integer >= 1 and <= {MAX_MAKEWEIGHT_ORDER}", order)
    lo, hi = sorted((dc_gain, hf_gain))
    if not lo < crossover_gain < hi:
        raise SpecError(f"{key}.crossover_gain",
                        f"a gain strictly between dc_gain and hf_gain ({lo:g}..{hi:g})",
                        crossover_gain)
    d, h, c = (g ** (1.0 / order) for g in (dc_gain, hf_gain, crossover_gain))
    w0 = crossover_freq * np.sqrt((h * h - c * c) / (c * c - d * d))
    first = TransferFunction([h, w0 * d], [1.0, w0])
    w = first
    for _ in range(order - 1):
        w = w * first
    return validate_weight(w, key)
