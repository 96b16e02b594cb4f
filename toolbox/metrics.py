"""Step-response metrics of a sampled trace: the one definition every stage uses.

The *response signal* ``y`` steps from the reference ``y0`` to ``yf`` at
``t_step``; ``delta = yf - y0``. Sample ``j`` is taken to hold until
``t[j+1]`` (the last one until ``t_end``).

``response_time_5pct`` (s)
    Time after ``t_step`` from which ``|y - yf| <= 0.05 |delta|`` holds until
    the end of the run (paper 000's "5 % response time"). 0 if never outside
    the band after ``t_step``; NaN if still outside at the end.
``settling_time_2pct`` (s)
    As the response time, with a +/-2 % band.
``rise_time_10_90`` (s)
    First time ``(y - y0)/delta >= 0.9`` minus first time it is ``>= 0.1``
    (both after ``t_step``); NaN if either level is never reached.
``overshoot_pct`` (%)
    ``100 * max((y - yf)/delta, 0)`` after ``t_step``.

A sample that is not a number (a diverged response) counts as outside every
band: a loop that blows up never "settles".

Users: the linear step figures of the analysis (``toolbox.analysis``), the
direct discrete-time design's figures (``toolbox.design.cv_discrete``) and
verification (``toolbox.verify``: the reach check and the switching law's
ripple-band times). The simulator's kernel (``toolbox.sim``) accumulates the
same four metrics online, without traces, for runs whose traces are not kept
(campaigns, long scenarios); ``tests/sim/test_linear.py`` holds the two
routes to each other. This module needs numpy only, so that the analysis can
use it without loading the compiled simulator (toolbox/ARCHITECTURE.md
"Layers").
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["STEP_METRICS", "STEP_BANDS", "band_entry_time", "step_metrics"]

#: The step metrics, in the simulator's order (``toolbox.sim.METRIC_NAMES``).
STEP_METRICS = ("response_time_5pct", "rise_time_10_90", "settling_time_2pct", "overshoot_pct")
#: Band-time metric -> relative band (fraction of ``|delta|``).
STEP_BANDS = {"response_time_5pct": 0.05, "settling_time_2pct": 0.02}


def band_entry_time(t, y, yf: float, tol: float, t_step: float, t_end: float) -> float:
    """Seconds after ``t_step`` from which ``|y - yf| <= tol`` holds until ``t_end``.

    Parameters
    ----------
    t, y : array_like
        Sample times (s) and response; sample ``j`` holds until ``t[j+1]``,
        the last one until ``t_end``.
    yf : float
        Final reference.
    tol : float
        Half-width of the band (signal unit).
    t_step, t_end : float
        Step time and end of the run (s).

    Returns
    -------
    float
        0 when never outside the band after ``t_step``; NaN when still outside
        at the end (a NaN sample counts as outside).

    Examples
    --------
    >>> band_entry_time([0.0, 1.0, 2.0, 3.0], [0.0, 0.5, 0.97, 1.0], 1.0, 0.05, 0.0, 4.0)
    2.0
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    outside = (t >= t_step - 1e-12) & ~(np.abs(y - yf) <= tol)
    if not outside.any():
        return 0.0
    t_next = np.append(t[1:], t_end)
    last = t_next[np.nonzero(outside)[0][-1]]
    return float(last - t_step) if last < t_end - 1e-12 else math.nan


def step_metrics(t, y, y0: float, yf: float, t_step: float,
                 t_end: float | None = None) -> dict[str, float]:
    """The four step metrics of a sampled trace (definitions in the module docstring).

    Parameters
    ----------
    t, y : array_like
        Sample times (s) and response; sample ``j`` is taken to hold until ``t[j+1]``.
    y0, yf : float
        Reference before and after the step.
    t_step : float
        Step time (s).
    t_end : float, optional
        End of the run (s); default ``t[-1] + (t[-1] - t[-2])``.

    Returns
    -------
    dict
        ``response_time_5pct``, ``settling_time_2pct``, ``rise_time_10_90``,
        ``overshoot_pct`` (s, s, s, %), in this order.
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if t_end is None:
        t_end = t[-1] + (t[-1] - t[-2])
    delta = yf - y0
    out = {name: band_entry_time(t, y, yf, band * abs(delta), t_step, t_end)
           for name, band in STEP_BANDS.items()}
    after = t >= t_step - 1e-12
    frac = (y - y0) / delta
    i10 = np.nonzero(after & (frac >= 0.1))[0]
    i90 = np.nonzero(after & (frac >= 0.9))[0]
    out["rise_time_10_90"] = float(t[i90[0]] - t[i10[0]]) if len(i10) and len(i90) else math.nan
    over = ((y - yf) / delta)[after]
    out["overshoot_pct"] = 100.0 * max(float(over.max()) if over.size else 0.0, 0.0)
    return out
