"""Inverter models used by the simulation kernel (numba-compiled helpers).

Three models share the stationary (alpha, beta) frame and the rotor dq frame
(electrical angle ``theta``; ``v_d = v_alpha cos(theta) + v_beta sin(theta)``,
``v_q = -v_alpha sin(theta) + v_beta cos(theta)``):

* voltage limits of the average model: circle of radius ``v_max`` or the exact
  SVM hexagon of vertex radius ``r_hex`` (the inscribed circle radius is
  ``r_hex * sqrt(3) / 2``);
* space-vector modulation, Cormerais 2002 eq (21)-(22): ``V T = T0 V0 + Tk Vk + Tl Vl``,
  ``T = T0 + Tk + Tl``, with the symmetric centred pattern ``0-k-l-7-l-k-0``;
* the 8 inverter states of the Boolean predictive control (paper 002 eq (12)-(13)).

Inverter state index ``i`` is the integer of the binary number ``m1 m2 m3``
(paper 002): bit 2 is cell C1 (phase a), bit 1 is C2 (phase b), bit 0 is C3.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["STATE_BITS", "ACTIVE_ORDER"]

# (m1, m2, m3) of inverter state i = 4*m1 + 2*m2 + m3 (paper 002 numbering).
STATE_BITS = np.array([[(i >> 2) & 1, (i >> 1) & 1, i & 1] for i in range(8)],
                      dtype=np.int64)
# Active states ordered by the angle of their voltage vector: 0, 60, ..., 300 deg.
# a=100 (4), ab=110 (6), b=010 (2), bc=011 (3), c=001 (1), ca=101 (5).
ACTIVE_ORDER = np.array([4, 6, 2, 3, 1, 5], dtype=np.int64)

_SQ3_2 = math.sqrt(3.0) / 2.0


@njit(cache=True)
def state_vector(state, r_hex):
    """(v_alpha, v_beta) of inverter ``state`` for hexagon vertex radius ``r_hex`` (V)."""
    m1 = (state >> 2) & 1
    m2 = (state >> 1) & 1
    m3 = state & 1
    # space vector r_hex * (m1 + m2 a + m3 a^2), a = exp(j 2 pi / 3): an active
    # state has length r_hex (2/3 vdc amplitude-invariant, sqrt(2/3) vdc power-invariant)
    va = r_hex * (m1 - 0.5 * m2 - 0.5 * m3)
    vb = r_hex * _SQ3_2 * (m2 - m3)
    return va, vb


@njit(cache=True)
def sector(va, vb):
    """Hexagon sector ``0..5`` of the stationary-frame vector (va, vb) and its
    angle ``phi`` (rad, ``0 <= phi < pi/3``) from the sector's first edge."""
    ang = math.atan2(vb, va)
    if ang < 0.0:
        ang += 2.0 * math.pi
    sect = int(ang / (math.pi / 3.0))
    if sect > 5:
        sect = 5
    return sect, ang - sect * (math.pi / 3.0)


@njit(cache=True)
def hexagon_scale(va, vb, r_hex):
    """Factor s <= 1 that brings (va, vb) onto or inside the hexagon of vertex radius r_hex."""
    mag = math.hypot(va, vb)
    if mag == 0.0:
        return 1.0
    sect, phi = sector(va, vb)
    # distance from the centre to the hexagon edge along this direction
    edge = r_hex * _SQ3_2 / math.cos(phi - math.pi / 6.0)
    if mag > edge:
        return edge / mag
    return 1.0


@njit(cache=True)
def svm_times(va, vb, r_hex, ts):
    """Sector and dwell times of paper 002 eq (21)-(22).

    Returns ``(first, second, T_first, T_second, T0)`` where ``first`` is the
    active state adjacent (one cell away) to state 0, so the pattern
    0-first-second-7-second-first-0 commutes one cell at a time. Vectors
    outside the hexagon are scaled onto it (T0 = 0).
    """
    sect, phi = sector(va, vb)
    mag = math.hypot(va, vb)
    k_state = ACTIVE_ORDER[sect]
    l_state = ACTIVE_ORDER[(sect + 1) % 6]
    tk = ts * mag / r_hex * math.sin(math.pi / 3.0 - phi) / _SQ3_2
    tl = ts * mag / r_hex * math.sin(phi) / _SQ3_2
    if tk < 0.0:
        tk = 0.0
    if tl < 0.0:
        tl = 0.0
    if tk + tl > ts:
        s = ts / (tk + tl)
        tk *= s
        tl *= s
    t0 = ts - tk - tl
    if t0 < 0.0:
        t0 = 0.0
    # the state with a single bit set is adjacent to 000
    if k_state == 4 or k_state == 2 or k_state == 1:
        return k_state, l_state, tk, tl, t0
    return l_state, k_state, tl, tk, t0


@njit(cache=True)
def bit_changes(a, b):
    """Number of commutation cells that change between inverter states a and b."""
    x = a ^ b
    return (x & 1) + ((x >> 1) & 1) + ((x >> 2) & 1)
