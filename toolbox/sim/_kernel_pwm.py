"""Switching inverter models of the simulation kernel over one controller
period: the centred space-vector pattern and the regular-sampled triangle
carrier with min-max injection (the plant integrated between switchings).
"""

from __future__ import annotations

import math

import numpy as np

from ._inverter import bit_changes, state_vector, svm_times
from ._kernel_layout import DP_HALF_PERIODS, DP_R_HEX, DP_TS, _A_CELLS, _SQ3_2, _jit, _jit_variant
from ._kernel_plant import _to_ab
from ._kernel_steps import _advance


@_jit_variant
def _svm_period(x, t, vd, vq, phi, conf, h, pl, t_load, mech, acc, omega0, acc_m,
                refs, mset, DP, flux):
    """One period of space-vector modulation, paper 002 eq (21)-(22): the symmetric
    centred pattern 0-k-l-7-l-k-0 (six cell commutations) of ``v_dq`` placed at
    the angle ``phi``, the plant integrated segment by segment. Returns (time,
    state, inverter state at the end). ``flux``: the kernel's variant flag
    of a saturated motor (``_kernel_steps._advance_n``)."""
    Ts = DP[DP_TS]
    r_hex = DP[DP_R_HEX]
    va, vb = _to_ab(vd, vq, math.cos(phi), math.sin(phi))
    st1, st2, t1, t2, t0 = svm_times(va, vb, r_hex, Ts)
    seq_s = (0, st1, st2, 7, st2, st1, 0)
    seq_t = (0.25 * t0, 0.5 * t1, 0.5 * t2, 0.5 * t0, 0.5 * t2, 0.5 * t1, 0.25 * t0)
    for j in range(7):
        stj = seq_s[j]
        acc_m[_A_CELLS] += bit_changes(conf, stj)
        conf = stj
        vx, vy = state_vector(stj, r_hex)
        t, x = _advance(x, t, vx, vy, 1, seq_t[j], h, pl, t_load, mech, acc, omega0,
                        acc_m, refs, mset, flux)
    return t, x, conf


@_jit
def _duties(va, vb, r_hex):
    """Leg duty cycles (d_a, d_b, d_c) in [0, 1] of the stationary-frame voltage
    (va, vb) by min-max (zero-sequence) injection: the regular-sampled carrier
    equivalent of the centred space-vector pattern (``state_vector`` inverted,
    the common offset chosen so that max and min duty are symmetric about 1/2)."""
    xa = va / r_hex * (2.0 / 3.0)
    xb = (-0.5 * va + _SQ3_2 * vb) / r_hex * (2.0 / 3.0)
    xc = (-0.5 * va - _SQ3_2 * vb) / r_hex * (2.0 / 3.0)
    off = 0.5 - 0.5 * (max(xa, xb, xc) + min(xa, xb, xc))
    return (min(max(xa + off, 0.0), 1.0), min(max(xb + off, 0.0), 1.0),
            min(max(xc + off, 0.0), 1.0))


@_jit_variant
def _carrier_half(x, t, dts, rising, conf, th_dur, h, pl, t_load, mech, acc, omega0,
                  acc_m, refs, mset, r_hex, flux):
    """One half period ``th_dur`` of the symmetric triangle carrier.

    A leg is on while its duty exceeds the carrier. Falling half (carrier
    1 -> 0, ``rising`` False): leg x turns on at ``(1 - d_x) th_dur``; rising
    half: it turns off at ``d_x th_dur``. Legs at duty 0 or 1 do not switch.
    The plant is integrated segment by segment between the switching
    instants; returns (time, state, inverter state at the end).
    """
    start = np.int64(0)  # not the literal 0: it compiled a version of each callee
    for leg in range(3):
        d = dts[leg]
        if (rising and d > 0.0) or (not rising and d >= 1.0):
            start |= 4 >> leg
    acc_m[_A_CELLS] += bit_changes(conf, start)
    conf = start
    # switching instants of legs a, b, c, visited in increasing order
    ta = dts[0] * th_dur if rising else (1.0 - dts[0]) * th_dur
    tb = dts[1] * th_dur if rising else (1.0 - dts[1]) * th_dur
    tc = dts[2] * th_dur if rising else (1.0 - dts[2]) * th_dur
    t_prev = 0.0
    for _ in range(3):
        leg = 0
        tj = ta
        if tb < tj:
            leg = 1
            tj = tb
        if tc < tj:
            leg = 2
            tj = tc
        if leg == 0:
            ta = math.inf
        elif leg == 1:
            tb = math.inf
        else:
            tc = math.inf
        if tj <= 0.0 or tj >= th_dur:
            continue
        vx, vy = state_vector(conf, r_hex)
        t, x = _advance(x, t, vx, vy, 1, tj - t_prev, h, pl, t_load, mech, acc, omega0,
                        acc_m, refs, mset, flux)
        t_prev = tj
        conf ^= 4 >> leg
        acc_m[_A_CELLS] += 1
    vx, vy = state_vector(conf, r_hex)
    t, x = _advance(x, t, vx, vy, 1, th_dur - t_prev, h, pl, t_load, mech, acc, omega0,
                    acc_m, refs, mset, flux)
    return t, x, conf


@_jit_variant
def _carrier_period(x, t, k, vd, vq, phi, conf, h, pl, t_load, mech, acc, omega0,
                    acc_m, refs, mset, DP, flux):
    """One controller period of carrier-based PWM at ``drive.switching_frequency``:
    ``half_periods`` half periods of a symmetric triangle carrier whose peak
    falls on the first sampling instant (regular sampling, duties loaded at
    the sample and held over the period, as the shadow registers of a PWM
    timer). The voltage is placed in the stationary frame at the angle
    ``phi``, as :func:`_svm_period` does; with two half periods per sample the
    pattern is the centred 0-k-l-7-l-k-0 of that model. Returns (time, state,
    inverter state at the end)."""
    Ts = DP[DP_TS]
    r_hex = DP[DP_R_HEX]
    n = int(DP[DP_HALF_PERIODS])
    va, vb = _to_ab(vd, vq, math.cos(phi), math.sin(phi))
    dts = _duties(va, vb, r_hex)
    th_dur = Ts / n
    for i in range(n):
        rising = (k * n + i) % 2 == 1
        t, x, conf = _carrier_half(x, t, dts, rising, conf, th_dur, h, pl, t_load, mech,
                                   acc, omega0, acc_m, refs, mset, r_hex, flux)
    return t, x, conf

