"""Kernel part: sensors, references and speed loop of the simulation kernel
(:mod:`toolbox.sim._kernel`), once per controller period: the seeded noise
(splitmix64, uniform or Box-Muller), the sampled and delayed measurements,
the current and speed references, the speed PID.
"""

from __future__ import annotations

import math

import numpy as np

from ._kernel_layout import (SC_CURRENT_DELAY_D, SC_CURRENT_DELAY_Q, SC_CURRENT_GAIN_D,
                             SC_CURRENT_GAIN_Q, SC_CURRENT_NOISE, SC_CURRENT_QUANTUM,
                             SC_F_SIN, SC_GAIN, SC_ID0, SC_ID1, SC_IQ0, SC_IQ1, SC_IQ_AMP,
                             SC_NOISE_KIND, SC_OFFSET, SC_REF_MODE, SC_SPEED0, SC_SPEED1,
                             SC_SPEED_NOISE, SC_T_STEP, SP_IQ_LIMIT, SP_KD, SP_KI, SP_KP,
                             _jit_inline)


# --------------------------------------------------------------------------- RNG
@_jit_inline
def _splitmix(st):
    """splitmix64 step on the 1-element uint64 state array; returns a float in [0, 1)."""
    z = st[0] + np.uint64(0x9E3779B97F4A7C15)
    st[0] = z
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@_jit_inline
def _noise(st, amp, kind):
    """Uniform noise in [-amp, amp] (kind 0) or Gaussian of std amp (kind 1, Box-Muller)."""
    if amp == 0.0:
        return 0.0
    if kind == 0:
        return amp * (2.0 * _splitmix(st) - 1.0)
    u1 = _splitmix(st)
    u2 = _splitmix(st)
    if u1 < 1e-300:
        u1 = 1e-300
    return amp * math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)



# ----------------------------------------------------- sensors and references
@_jit_inline
def _sense(x, rng, SC):
    """Sampled sensors (paper 000: gain/offset/noise on the speed; noise and
    quantisation on the currents); returns (id_m, iq_m, Omega_m)."""
    kind = int(SC[SC_NOISE_KIND])
    i_d_m = x[0] + _noise(rng, SC[SC_CURRENT_NOISE], kind)
    i_q_m = x[1] + _noise(rng, SC[SC_CURRENT_NOISE], kind)
    q = SC[SC_CURRENT_QUANTUM]
    if q > 0.0:
        i_d_m = q * math.floor(i_d_m / q + 0.5)
        i_q_m = q * math.floor(i_q_m / q + 0.5)
    om_m = (1.0 + SC[SC_GAIN]) * x[2] + SC[SC_OFFSET] \
        + _noise(rng, SC[SC_SPEED_NOISE], kind)
    return i_d_m, i_q_m, om_m


@_jit_inline
def _delayed(v, k, nd, buf):
    """``v`` measured ``nd`` periods ago (ring buffer ``buf`` of ``nd + 1``
    samples); 0 before the first one exists (the currents start at 0)."""
    if nd == 0:
        return v
    nb = nd + 1
    buf[k % nb] = v
    if k < nd:
        return 0.0
    return buf[(k - nd) % nb]


@_jit_inline
def _current_sensor(i_d_m, i_q_m, k, buf_d, buf_q, SC):
    """Gain and measurement delay (whole periods) on each measured current
    (paper 002 sect. 5: a gain and a time delay on the state variables
    Phi_d, Phi_q that the predictive law reads)."""
    return (_delayed(i_d_m * SC[SC_CURRENT_GAIN_D], k, int(SC[SC_CURRENT_DELAY_D]), buf_d),
            _delayed(i_q_m * SC[SC_CURRENT_GAIN_Q], k, int(SC[SC_CURRENT_DELAY_Q]), buf_q))


@_jit_inline
def _references(t, SC):
    """Current and speed references at sample time t: (id_ref, iq_ref, speed_ref)."""
    before = t < SC[SC_T_STEP]
    sr = SC[SC_SPEED0] if before else SC[SC_SPEED1]
    if before:
        idr = SC[SC_ID0]
        iqr = SC[SC_IQ0]
    else:
        idr = SC[SC_ID1]
        iqr = SC[SC_IQ1]
    if int(SC[SC_REF_MODE]) == 1:  # sinusoidal torque
        idr = SC[SC_ID1]
        iqr = SC[SC_IQ_AMP] * math.sin(2.0 * math.pi * SC[SC_F_SIN] * t)
    return idr, iqr, sr


@_jit_inline
def _speed_pid(e, e_prev, integ, Tsp, SP):
    """One step of the speed PID with conditional integration (anti-windup).

    Returns (i_q reference, new integral): the integral only moves while the
    output is inside +/- iq_limit.
    """
    integ_new = integ + SP[SP_KI] * e * Tsp
    u = SP[SP_KP] * e + integ_new + SP[SP_KD] * (e - e_prev) / Tsp
    lim = SP[SP_IQ_LIMIT]
    if u > lim:
        u = lim
    elif u < -lim:
        u = -lim
    else:
        integ = integ_new
    return u, integ
