"""Step metrics of the predictive switching inverter (paper 002's Boolean control).

The 5 % response time and 2 % settling time of :mod:`toolbox.metrics`
ask the response to stay within ``0.05 |delta|`` (``0.02 |delta|``) of its
final value. A linear loop behind an average or SVM inverter does that; the
finite-control-set law of paper 002 (criterion (23)) cannot, by design: it
holds one of eight voltage vectors for a whole period, so its current keeps
an error up to the covering radius of the currents it can reach in one
period plus the dead band of its switching penalty
(:func:`toolbox.verify._checks.fcs_ripple`). When that ripple exceeds 2 % or
5 % of the step the metric is not "slow", it is *undefined* (NaN), and the
``default.finite`` check failed every such design whatever its quality.

For that inverter the two times are therefore measured with the band
``max(b |delta|, ripple)``, ``b`` = 0.05 or 0.02, on the currents sampled at
the controller instants (what the law sees and acts on; inside a period the
current moves along a held vector by construction). The band is the smallest
one the law can be asked to hold; it is the same band ``default.reach``
already uses for this inverter. A law that does not regulate (beta = 0 with
a d step, an absurd gamma whose dead band swallows the step) is still caught:
its band is infinite or larger than the step, which is refused here (NaN
with the band recorded) instead of passing trivially.

The linear inverters are untouched: their metrics stay the kernel's.
"""

from __future__ import annotations

import math

import numpy as np

from toolbox.metrics import STEP_BANDS, band_entry_time

__all__ = ["ripple_band_step_times"]


def ripple_band_step_times(t, y, y0: float, yf: float, t_step: float, t_end: float,
                           ripple: float) -> tuple[dict[str, float], dict[str, float]]:
    """5 % and 2 % times of a switching-law step with the band ``max(b |delta|, ripple)``.

    Parameters
    ----------
    t, y : array_like
        Controller instants (s) and the stepped current there (A).
    y0, yf : float
        Reference before and after the step (A).
    t_step, t_end : float
        Step time and end of the run (s).
    ripple : float
        The law's design ripple on this axis (A), :func:`toolbox.verify._checks.fcs_ripple`.

    Returns
    -------
    times : dict
        ``response_time_5pct`` and ``settling_time_2pct`` (s); NaN when the
        response never stays in its band, or when the band is not smaller than
        the step (the step is not resolved by the law: nothing to measure).
    bands : dict
        The band used for each (A).

    Examples
    --------
    >>> t = np.arange(10) * 1e-3
    >>> y = np.array([0, 0, 6, 9, 11, 9, 11, 9, 11, 9.0])
    >>> times, bands = ripple_band_step_times(t, y, 0.0, 10.0, 1e-3, 1e-2, 1.0)
    >>> times["settling_time_2pct"], bands["settling_time_2pct"]
    (0.002, 1.0)
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    delta = abs(yf - y0)
    times, bands = {}, {}
    for name, b in STEP_BANDS.items():
        tol = max(b * delta, ripple)
        bands[name] = tol
        # a band as wide as the step: the starting point already lies in it
        times[name] = (band_entry_time(t, y, yf, tol, t_step, t_end) if tol < delta
                       else math.nan)
    return times, bands
