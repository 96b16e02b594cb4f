"""Online step and error metrics of the simulation kernel: their constants,
the accumulators updated at every plant step and the metrics computed from
them at the end of a run (definitions: :mod:`toolbox.sim._metrics`).
"""

from __future__ import annotations

import math

import numpy as np

from ._kernel_layout import (M_CELL_TRANSITIONS_PER_S, M_COMMUTATIONS_PER_S, M_FINAL_SPEED,
                             M_FINAL_VALUE, M_MSE_ID, M_MSE_IQ, M_MSE_TORQUE, M_OVERSHOOT_PCT,
                             M_RESPONSE_TIME_5PCT, M_RISE_TIME_10_90, M_SATURATION_TIME,
                             M_SETTLING_TIME_2PCT, M_STATIC_ERROR, N_METRICS, SC_DURATION, SC_ID0,
                             SC_ID1, SC_IQ0, SC_IQ1, SC_SIGNAL, SC_SPEED0, SC_SPEED1, SC_T_STEP,
                             _A_CELLS, _A_FINAL, _A_OUT2, _A_OUT5, _A_SAT, _A_SQID, _A_SQIQ,
                             _A_SQT, _A_STAT, _A_STATT, _A_T10, _A_T90, _A_YEXT, _jit, _jit_inline)
from ._kernel_plant import _torque


# ---------------------------------------------------------------- online metrics
@_jit
def _metric_setup(SC):
    """Constants of the step metrics: (signal, y0, yf, steady-state start, t_step).

    signal 0 follows i_q, 1 i_d, 2 the speed; the steady state is the last 10 %.
    """
    sig = int(SC[SC_SIGNAL])
    if sig == 0:
        y0 = SC[SC_IQ0]
        yf = SC[SC_IQ1]
    elif sig == 1:
        y0 = SC[SC_ID0]
        yf = SC[SC_ID1]
    else:
        y0 = SC[SC_SPEED0]
        yf = SC[SC_SPEED1]
    return sig, y0, yf, 0.9 * SC[SC_DURATION] - 1e-12, SC[SC_T_STEP] - 1e-12


@_jit_inline
def _load_acc(acc_m):
    """The accumulators :func:`_accumulate` updates (slots ``_A_OUT5`` ..
    ``_A_SQIQ``) as a tuple: local values that LLVM keeps in registers over a
    run of plant steps, where the array's elements were loaded and stored at
    every step and could only be updated by branches."""
    return (acc_m[_A_OUT5], acc_m[_A_OUT2], acc_m[_A_T10], acc_m[_A_T90], acc_m[_A_YEXT],
            acc_m[_A_SQT], acc_m[_A_SQID], acc_m[_A_STAT], acc_m[_A_STATT],
            acc_m[_A_FINAL], acc_m[_A_SQIQ])


@_jit_inline
def _store_acc(acc_m, m):
    """Write back the tuple of :func:`_load_acc`."""
    (acc_m[_A_OUT5], acc_m[_A_OUT2], acc_m[_A_T10], acc_m[_A_T90], acc_m[_A_YEXT],
     acc_m[_A_SQT], acc_m[_A_SQID], acc_m[_A_STAT], acc_m[_A_STATT],
     acc_m[_A_FINAL], acc_m[_A_SQIQ]) = m


@_jit_inline
def _accumulate(m, i_d, i_q, om, t, dt, pl, refs, mset):
    """Online metrics at the start of a plant step of length dt (time-weighted):
    the accumulators ``m`` (:func:`_load_acc`) updated."""
    return _accumulate_torque(m, i_d, i_q, om, _torque(pl, i_d, i_q), t, dt, refs, mset)


@_jit_inline
def _accumulate_torque(m, i_d, i_q, om, torque, t, dt, refs, mset):
    """:func:`_accumulate` with the torque given (a saturated motor's, from its flux)."""
    out5, out2, t10, t90, yext, sqt, sqid, stat, statt, final, sqiq = m
    idr, iqr, sr, tref = refs
    sig, y0, yf, t_stat, t_step = mset
    e_t = torque - tref
    sqt += e_t * e_t * dt
    e_id = i_d - idr
    sqid += e_id * e_id * dt
    e_iq = i_q - iqr
    sqiq += e_iq * e_iq * dt
    if sig == 0:
        y = i_q
        r = iqr
    elif sig == 1:
        y = i_d
        r = idr
    else:
        y = om
        r = sr
    if t >= t_stat:
        stat += (r - y) * dt
        final += y * dt
        statt += dt
    delta = yf - y0
    if t >= t_step and delta != 0.0:
        dev = abs(y - yf)
        if dev > 0.05 * abs(delta):
            out5 = t + dt
        if dev > 0.02 * abs(delta):
            out2 = t + dt
        # 90 % reached implies 10 % reached: no division once both are known
        if t90 < 0.0:
            frac = (y - y0) / delta
            if frac >= 0.1 and t10 < 0.0:
                t10 = t
            if frac >= 0.9:
                t90 = t
        # the overshoot (y - yf)/delta is monotone in y: keep the extreme y
        # in the direction of the step and divide once (:func:`_overshoot`)
        if (y > yext) if delta > 0.0 else (y < yext):
            yext = y
    return out5, out2, t10, t90, yext, sqt, sqid, stat, statt, final, sqiq


# ---------------------------------------------------------------------- metrics
@_jit
def _overshoot(y_ext, yf, delta):
    """``max((y - yf)/delta, 0)`` over the run from the extreme ``y_ext`` of y
    in the direction of the step (``yf`` if y never passed it).

    Equal, bit for bit, to the maximum of the per-step quotients: correctly
    rounded subtraction and division are monotone, so the quotient of the
    extreme is the extreme of the quotients; ``y_ext == yf`` gives +0 (the
    quotient would be -0 for a negative step).
    """
    if y_ext == yf or math.isnan(delta):  # nan: no quotient ever exceeded 0
        return 0.0
    return (y_ext - yf) / delta


@_jit
def _finalise(acc_m, n_per, Ts, om_final, t_step, mset):
    """Metrics (order of ``_metrics.METRIC_NAMES``) from the accumulators."""
    M = np.full(N_METRICS, np.nan)
    total = n_per * Ts
    if acc_m[_A_OUT5] < 0.0:
        M[M_RESPONSE_TIME_5PCT] = 0.0
    elif acc_m[_A_OUT5] < total - 1e-12:
        M[M_RESPONSE_TIME_5PCT] = acc_m[_A_OUT5] - t_step
    if acc_m[_A_T10] >= 0.0 and acc_m[_A_T90] >= 0.0:
        M[M_RISE_TIME_10_90] = acc_m[_A_T90] - acc_m[_A_T10]
    if acc_m[_A_OUT2] < 0.0:
        M[M_SETTLING_TIME_2PCT] = 0.0
    elif acc_m[_A_OUT2] < total - 1e-12:
        M[M_SETTLING_TIME_2PCT] = acc_m[_A_OUT2] - t_step
    M[M_OVERSHOOT_PCT] = 100.0 * _overshoot(acc_m[_A_YEXT], mset[2], mset[2] - mset[1])
    if acc_m[_A_STATT] > 0.0:
        M[M_STATIC_ERROR] = acc_m[_A_STAT] / acc_m[_A_STATT]
        M[M_FINAL_VALUE] = acc_m[_A_FINAL] / acc_m[_A_STATT]
    if total > 0.0:
        M[M_MSE_TORQUE] = acc_m[_A_SQT] / total
        M[M_MSE_ID] = acc_m[_A_SQID] / total
        M[M_MSE_IQ] = acc_m[_A_SQIQ] / total
        M[M_COMMUTATIONS_PER_S] = 2.0 * acc_m[_A_CELLS] / total
        M[M_CELL_TRANSITIONS_PER_S] = acc_m[_A_CELLS] / total
    M[M_SATURATION_TIME] = acc_m[_A_SAT]
    M[M_FINAL_SPEED] = om_final
    if mset[2] - mset[1] == 0.0:  # no step: the step metrics are undefined
        M[M_RESPONSE_TIME_5PCT] = np.nan
        M[M_RISE_TIME_10_90] = np.nan
        M[M_SETTLING_TIME_2PCT] = np.nan
        M[M_OVERSHOOT_PCT] = np.nan
    return M

