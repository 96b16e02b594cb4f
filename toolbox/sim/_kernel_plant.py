"""Plant of the simulation kernel: Park rotations, the plant array, the dq-frame
right-hand side and its RK4 step (the model of :mod:`toolbox.sim._kernel`).
"""

from __future__ import annotations

import math

from ._kernel_layout import (N_P, P_FLUX, P_FRICTION, P_J, P_LD, P_LQ, P_MAGNETIC,
                             P_POLE_PAIRS, P_R, P_TORQUE_FACTOR, _jit, _jit_inline)


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
    1/Lq, 1/J, magnetic, P): passed by value, so the parameters stay in
    registers inside the RK4 loop. The reciprocals are computed once per run:
    each RK4 stage then multiplies instead of dividing (``docs/performance.md``,
    "Arithmetic"). ``magnetic`` (bool): a saturated motor, whose state is the
    flux linkage and whose current is read from the table in ``P`` (from
    :data:`N_P` on, :func:`_current_of_flux`)."""
    Ld = P[P_LD]
    Lq = P[P_LQ]
    J = P[P_J]
    return (P[P_R], Ld, Lq, P[P_FLUX], P[P_POLE_PAIRS], J, P[P_FRICTION],
            P[P_TORQUE_FACTOR], 1.0 / Ld, 1.0 / Lq, 1.0 / J, P[P_MAGNETIC] > 0.5, P)


@_jit_inline
def _torque(pl, i_d, i_q):
    """Electromagnetic torque ``tf p (flux iq + (Ld - Lq) id iq)`` (N m)."""
    return pl[7] * pl[4] * (pl[3] * i_q + (pl[1] - pl[2]) * i_d * i_q)


@_jit_inline
def _deriv(i_d, i_q, om, th, vx, vy, frame, pl, t_load, mech, acc):
    """Right-hand side of the plant (``_kernel``'s module docstring); frame 1: (vx, vy)
    stationary."""
    R, Ld, Lq, flux, p, _, friction, tf, inv_Ld, inv_Lq, inv_J, _, _ = pl
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



# ------------------------------------------------------- saturated motors
# State (psi_d, psi_q, Omega, theta); the current is read from the inverse
# table of ``toolbox.spec.MagneticModel.inverse_table`` packed after the
# named slots of ``P``: header psi_d0, 1/dpsi_d, n_d, psi_q0, 1/dpsi_q, n_q,
# psi_d(i=0), psi_q(i=0), then i_d and i_q (n_d x n_q, row-major).
_T_ID = N_P + 8


@_jit_inline
def _cell(u, n):
    """Cell index j in [0, n-2] and fraction of the regular-grid coordinate u
    (outside the grid: the edge cell, extrapolated linearly; NaN: cell 0)."""
    jf = 0.0
    if u >= 0.0:
        jf = math.floor(u)
    if jf > n - 2.0:
        jf = n - 2.0
    return int(jf), u - jf


@_jit_inline
def _current_of_flux(P, psd, psq):
    """``(i_d, i_q)`` at the flux ``(psd, psq)`` by bilinear interpolation of
    the table in ``P``."""
    nd = P[N_P + 2]
    nq = P[N_P + 5]
    j, fu = _cell((psd - P[N_P]) * P[N_P + 1], nd)
    k, fv = _cell((psq - P[N_P + 3]) * P[N_P + 4], nq)
    n = int(nq)
    o = _T_ID + j * n + k
    o2 = o + int(nd) * n
    gu = 1.0 - fu
    gv = 1.0 - fv
    i_d = gu * (gv * P[o] + fv * P[o + 1]) + fu * (gv * P[o + n] + fv * P[o + n + 1])
    i_q = gu * (gv * P[o2] + fv * P[o2 + 1]) + fu * (gv * P[o2 + n] + fv * P[o2 + n + 1])
    return i_d, i_q


@_jit_inline
def _currents(pl, x, flux):
    """The state with its first two entries as currents: ``x`` itself for a
    constant-parameter motor (``flux`` None), ``i(psi)`` for a saturated one.

    ``flux`` is the kernel's variant flag (``_kernel``, "Variants"): None or
    the constant True, so that numba prunes the other branch unseen."""
    if flux is None:
        return x
    i_d, i_q = _current_of_flux(pl[12], x[0], x[1])
    return i_d, i_q, x[2], x[3]


@_jit_inline
def _initial_state(pl, omega0, flux):
    """Zero current at speed ``omega0``: ``(0, 0, omega0, 0)``, or the flux at
    zero current of a saturated motor (``flux`` as for :func:`_currents`)."""
    if flux is None:
        return 0.0, 0.0, omega0, 0.0
    P = pl[12]
    return P[N_P + 6], P[N_P + 7], omega0, 0.0


@_jit_inline
def _torque_of_state(pl, x, flux):
    """Electromagnetic torque of the plant state (N m): :func:`_torque` of the
    currents, or ``tf p (psi_d i_q - psi_q i_d)`` of a saturated motor
    (``flux`` as for :func:`_currents`)."""
    if flux is None:
        return _torque(pl, x[0], x[1])
    i_d, i_q = _current_of_flux(pl[12], x[0], x[1])
    return pl[7] * pl[4] * (x[0] * i_q - x[1] * i_d)


@_jit_inline
def _deriv_flux(psd, psq, om, th, vx, vy, frame, pl, t_load, mech, acc):
    """Right-hand side of a saturated motor: ``d psi/dt = v - R i(psi) - w J
    psi`` and the mechanics with ``T = tf p (psi_d i_q - psi_q i_d)``."""
    R = pl[0]
    p = pl[4]
    w = p * om
    if frame == 0:
        vd = vx
        vq = vy
    else:
        vd, vq = _to_dq(vx, vy, math.cos(th), math.sin(th))
    i_d, i_q = _current_of_flux(pl[12], psd, psq)
    dpd = vd - R * i_d + w * psq
    dpq = vq - R * i_q - w * psd
    if mech == 1:
        dom = acc
    else:
        torque = pl[7] * p * (psd * i_q - psq * i_d)
        dom = (torque - pl[6] * om - t_load) * pl[10]
    return dpd, dpq, dom, w


@_jit_inline
def _rk4_flux(a, b, om, th, vx, vy, frame, dt, pl, t_load, mech, acc):
    """One classical RK4 step of a saturated motor's state (psi_d, psi_q, Omega, theta)."""
    a1, b1, c1, d1 = _deriv_flux(a, b, om, th, vx, vy, frame, pl, t_load, mech, acc)
    h2 = 0.5 * dt
    a2, b2, c2, d2 = _deriv_flux(a + h2 * a1, b + h2 * b1, om + h2 * c1, th + h2 * d1,
                                 vx, vy, frame, pl, t_load, mech, acc)
    a3, b3, c3, d3 = _deriv_flux(a + h2 * a2, b + h2 * b2, om + h2 * c2, th + h2 * d2,
                                 vx, vy, frame, pl, t_load, mech, acc)
    a4, b4, c4, d4 = _deriv_flux(a + dt * a3, b + dt * b3, om + dt * c3, th + dt * d3,
                                 vx, vy, frame, pl, t_load, mech, acc)
    k = dt / 6.0
    return (a + k * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            b + k * (b1 + 2.0 * b2 + 2.0 * b3 + b4),
            om + k * (c1 + 2.0 * c2 + 2.0 * c3 + c4),
            th + k * (d1 + 2.0 * d2 + 2.0 * d3 + d4))
