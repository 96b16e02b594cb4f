"""Closed-loop metrics of the simulator kernel: definitions and names.

The kernel accumulates every metric online, at the start of each plant step
(time-weighted by the step length ``dt``), so no trace is needed. The
*response signal* ``y`` is the stepped quantity of the scenario: ``i_q`` (A)
when the q reference steps (also for torque steps), ``i_d`` when only the d
reference steps, the mechanical speed (rad/s) for speed steps. With
``y0``/``yf`` the references before/after the step time ``t_s`` and
``delta = yf - y0``:

``response_time_5pct``, ``rise_time_10_90``, ``settling_time_2pct``, ``overshoot_pct``
    The step metrics, defined once in :mod:`toolbox.metrics` (the trace
    route the analysis and verification use); the kernel accumulates them
    online with the same definitions (``tests/sim/test_linear.py``).
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

__all__ = ["METRIC_NAMES", "metrics_dict"]

METRIC_NAMES = (
    "response_time_5pct", "rise_time_10_90", "settling_time_2pct", "overshoot_pct",
    "static_error", "mse_torque", "mse_id", "commutations_per_s",
    "cell_transitions_per_s", "saturation_time", "final_value", "mse_iq",
    "final_speed",
)


def metrics_dict(row) -> dict[str, float]:
    """Name the raw kernel metric vector (see the module docstring for units)."""
    return {name: float(v) for name, v in zip(METRIC_NAMES, row)}

