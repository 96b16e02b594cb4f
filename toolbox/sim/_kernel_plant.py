"""Plant of the simulation kernel: Park rotations, the plant array, the dq-frame
right-hand side and its RK4 step (the model of :mod:`toolbox.sim._kernel`).
"""

from __future__ import annotations

import math

from ._kernel_layout import (P_FLUX, P_FRICTION, P_J, P_LD, P_LQ, P_POLE_PAIRS, P_R,
                             P_TORQUE_FACTOR, _jit, _jit_inline)


# ------------------------------------------------------------ frames and plant
@_jit
def _to_dq(va, vb, c, s):
    """Park rotation of a stationary-frame vector by the angle whose cos, sin are c, s."""
    return va * c + vb * s, -va * s + vb * c


@_jit
def _to_ab(vd, vq, c, s):
    """Inverse Park rotation (dq -> stationary frame)."""
    return vd * c - vq * s, vd * s + vq * c


@_jit
def _plant(P):
    """The plant array as a tuple (R, Ld, Lq, flux, p, J, friction, tf, 1/Ld,
    1/Lq, 1/J): passed by value, so the parameters stay in registers inside the
    RK4 loop. The reciprocals are computed once per run: each RK4 stage then
    multiplies instead of dividing (``docs/performance.md``, "Arithmetic")."""
    Ld = P[P_LD]
    Lq = P[P_LQ]
    J = P[P_J]
    return (P[P_R], Ld, Lq, P[P_FLUX], P[P_POLE_PAIRS], J, P[P_FRICTION],
            P[P_TORQUE_FACTOR], 1.0 / Ld, 1.0 / Lq, 1.0 / J)


@_jit_inline
def _torque(pl, i_d, i_q):
    """Electromagnetic torque ``tf p (flux iq + (Ld - Lq) id iq)`` (N m)."""
    return pl[7] * pl[4] * (pl[3] * i_q + (pl[1] - pl[2]) * i_d * i_q)


@_jit_inline
def _deriv(i_d, i_q, om, th, vx, vy, frame, pl, t_load, mech, acc):
    """Right-hand side of the plant (``_kernel``'s module docstring); frame 1: (vx, vy)
    stationary."""
    R, Ld, Lq, flux, p, _, friction, tf, inv_Ld, inv_Lq, inv_J = pl
    w = p * om
    if frame == 0:
        vd = vx
        vq = vy
    else:  # stationary-frame voltage held constant: rotate into dq
        vd, vq = _to_dq(vx, vy, math.cos(th), math.sin(th))
    did = (vd - R * i_d + w * Lq * i_q) * inv_Ld
    diq = (vq - R * i_q - w * Ld * i_d - w * flux) * inv_Lq
    if mech == 1:
        dom = acc
    else:
        torque = tf * p * (flux * i_q + (Ld - Lq) * i_d * i_q)
        dom = (torque - friction * om - t_load) * inv_J
    return did, diq, dom, w


@_jit_inline
def _rk4(i_d, i_q, om, th, vx, vy, frame, dt, pl, t_load, mech, acc):
    """One classical RK4 step of the plant state (id, iq, Omega, theta); returns the new state."""
    a1, b1, c1, d1 = _deriv(i_d, i_q, om, th, vx, vy, frame, pl, t_load, mech, acc)
    h2 = 0.5 * dt
    a2, b2, c2, d2 = _deriv(i_d + h2 * a1, i_q + h2 * b1, om + h2 * c1, th + h2 * d1,
                            vx, vy, frame, pl, t_load, mech, acc)
    a3, b3, c3, d3 = _deriv(i_d + h2 * a2, i_q + h2 * b2, om + h2 * c2, th + h2 * d2,
                            vx, vy, frame, pl, t_load, mech, acc)
    a4, b4, c4, d4 = _deriv(i_d + dt * a3, i_q + dt * b3, om + dt * c3, th + dt * d3,
                            vx, vy, frame, pl, t_load, mech, acc)
    k = dt / 6.0
    return (i_d + k * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            i_q + k * (b1 + 2.0 * b2 + 2.0 * b3 + b4),
            om + k * (c1 + 2.0 * c2 + 2.0 * c3 + c4),
            th + k * (d1 + 2.0 * d2 + 2.0 * d3 + d4))

