"""Closed-loop metrics: definitions, names and an offline (trace-based) twin.

The kernel accumulates every metric online, at the start of each plant step
(time-weighted by the step length ``dt``), so no trace is needed. The
*response signal* ``y`` is the stepped quantity of the scenario: ``i_q`` (A)
when the q reference steps (also for torque steps), ``i_d`` when only the d
reference steps, the mechanical speed (rad/s) for speed steps. With
``y0``/``yf`` the references before/after the step time ``t_s`` and
``delta = yf - y0``:

``response_time_5pct`` (s)
    Time after ``t_s`` from which ``|y - yf| <= 0.05 |delta|`` holds until the
    end of the run (paper 000's "5 % response time"). 0 if never outside the
    band after ``t_s``; NaN if still outside at the end.
``rise_time_10_90`` (s)
    First time ``(y - y0)/delta >= 0.9`` minus first time it is ``>= 0.1``.
``settling_time_2pct`` (s)
    As the response time, with a +/-2 % band.
``overshoot_pct`` (%)
    ``100 * max((y - yf)/delta, 0)`` after ``t_s``.
``static_error`` (signal unit)
    Mean of ``ref(t) - y(t)`` over the last 10 % of the run (``ref`` is the
    reference actually fed to the loop: a speed loop's ``i_q`` output included).
``final_value``
    Mean of ``y`` over the last 10 % of the run.
``mse_torque`` (N^2 m^2), ``mse_id`` (A^2), ``mse_iq`` (A^2)
    Mean over the whole run of the squared error, paper 002's ``E_Gamma`` and
    ``E_Id``: torque ``T = tf p (flux iq + (Ld-Lq) id iq)`` of the plant against
    the demanded torque ``tf p (flux_c iq_ref + (Ld_c-Lq_c) id_ref iq_ref)``
    (controller model parameters), and ``i_d - i_d,ref``, ``i_q - i_q,ref``.
``commutations_per_s`` (1/s)
    Individual switch commutations per second: each change of a commutation
    cell (one of paper 002's booleans m1, m2, m3) turns one switch off and its
    complement on, i.e. two commutations. This is the count paper 002 calls
    ``Nb_c`` for SVM (12 F_ech: the symmetric pattern 0-k-l-7-l-k-0 changes
    one cell six times per period, i.e. twelve switch commutations; no
    pattern that changes one cell at a time reaches 12 cell changes per
    period). 0 for the average inverter model.
``cell_transitions_per_s`` (1/s)
    Changes of a commutation cell (switch pair) per second: half the above.
    This is the sum of paper 002's criterion term sum_i (Conf_k,i - Conf_k-1,i)^2,
    and the count the paper's predictive-control Nb_c values agree with.
``saturation_time`` (s)
    Total time during which the commanded voltage exceeded the limit
    (counted per controller period).
``final_speed`` (rad/s)
    Mechanical speed at the end of the run.

Step metrics are NaN when the scenario has no step (``delta = 0``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["METRIC_NAMES", "metrics_dict", "step_metrics"]

METRIC_NAMES = (
    "response_time_5pct", "rise_time_10_90", "settling_time_2pct", "overshoot_pct",
    "static_error", "mse_torque", "mse_id", "commutations_per_s",
    "cell_transitions_per_s", "saturation_time", "final_value", "mse_iq",
    "final_speed",
)


def metrics_dict(row) -> dict[str, float]:
    """Name the raw kernel metric vector (see the module docstring for units)."""
    return {name: float(v) for name, v in zip(METRIC_NAMES, row)}


def step_metrics(t, y, y0, yf, t_step, t_end=None):
    """Step-response metrics of a sampled trace, same definitions as the kernel.

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
        ``response_time_5pct``, ``rise_time_10_90``, ``settling_time_2pct``,
        ``overshoot_pct`` (s, s, s, %).
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if t_end is None:
        t_end = t[-1] + (t[-1] - t[-2])
    t_next = np.append(t[1:], t_end)
    delta = yf - y0
    after = t >= t_step - 1e-12
    out = {}
    for name, band in (("response_time_5pct", 0.05), ("settling_time_2pct", 0.02)):
        outside = after & (np.abs(y - yf) > band * abs(delta))
        if not outside.any():
            out[name] = 0.0
        else:
            last = t_next[np.nonzero(outside)[0][-1]]
            out[name] = last - t_step if last < t_end - 1e-12 else float("nan")
    frac = (y - y0) / delta
    i10 = np.nonzero(after & (frac >= 0.1))[0]
    i90 = np.nonzero(after & (frac >= 0.9))[0]
    out["rise_time_10_90"] = (t[i90[0]] - t[i10[0]]) if len(i10) and len(i90) else float("nan")
    over = ((y - yf) / delta)[after]
    out["overshoot_pct"] = 100.0 * max(float(over.max()) if over.size else 0.0, 0.0)
    return out
