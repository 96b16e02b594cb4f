"""Slow pure-Python reference of the closed loop (average inverter only).

Written independently of toolbox.sim._kernel, from the equations of the
interface: dq plant + mechanics integrated by RK4 at h, discrete controllers
at Ts with ZOH and `delay` periods of delay, decoupling with the measured
speed, circle voltage limit with back-calculation anti-windup, speed sensor
gain/offset, the voltage placed at ``theta_k + t_c w_meas`` and held in the
rotor frame, rotated by its error from the true mid-period angle
(toolbox/ARCHITECTURE.md "The digital loop"). Returns the samples at the controller instants and the
time-weighted mean-square torque and i_d errors.
"""

import math

import numpy as np


def reference(plant, law, Ts, delay, v_max, duration, h, iq_ref, id_ref=0.0,
              omega0=0.0, imposed_acc=None, gain=0.0, offset=0.0, load=0.0):
    dec = law.decoupling  # the controller's model (what the law believes)
    R, Ld, Lq, flux, p, J, fr, tf = (plant.R, plant.Ld, plant.Lq, plant.flux,
                                     plant.pole_pairs, plant.J, plant.friction,
                                     plant.torque_factor)

    def f(x, vd, vq):
        i_d, i_q, om, th = x
        w = p * om
        did = (vd - R * i_d + w * Lq * i_q) / Ld
        diq = (vq - R * i_q - w * Ld * i_d - w * flux) / Lq
        if imposed_acc is not None:
            dom = imposed_acc
        else:
            dom = (tf * p * (flux * i_q + (Ld - Lq) * i_d * i_q) - fr * om - load) / J
        return np.array([did, diq, dom, w])

    axes = []
    for ax in (law.d, law.q):
        A = np.atleast_2d(np.asarray(ax.A, float))
        n = A.shape[0] if np.size(ax.A) else 0
        axes.append(dict(A=A.reshape(n, n), B=np.asarray(ax.B, float).reshape(n, 2),
                         C=np.asarray(ax.C, float).reshape(n),
                         D=np.asarray(ax.D, float).reshape(2),
                         W=(np.zeros(n) if ax.antiwindup is None
                            else np.asarray(ax.antiwindup, float).reshape(n)),
                         x=np.zeros(n)))
    x = np.array([0.0, 0.0, omega0, 0.0])
    n_per = int(round(duration / Ts))
    n_sub = int(math.ceil(Ts / h - 1e-9))
    dt = Ts / n_sub
    queue = [(0.0, 0.0, 0.0)] * delay           # (v_d, v_q, placement angle)
    rows = []
    sq_t = sq_id = 0.0
    tref = tf * p * (dec.flux_c * iq_ref + (dec.Ld_c - dec.Lq_c) * id_ref * iq_ref)
    for k in range(n_per):
        om_m = (1 + gain) * x[2] + offset
        w_m = p * om_m
        meas = (x[0], x[1])
        refs = (id_ref, iq_ref)
        u = []
        for a in range(2):
            ax = axes[a]
            u.append(ax["C"] @ ax["x"] + ax["D"] @ np.array([refs[a], meas[a]]))
        vd = u[0] - dec.cross * w_m * dec.Lq_c * meas[1]
        vq = u[1] + dec.cross * w_m * dec.Ld_c * meas[0] + dec.emf * w_m * dec.flux_c
        mag = math.hypot(vd, vq)
        s = v_max / mag if mag > v_max else 1.0
        sat = (vd * s, vq * s)
        for a, v_un in enumerate((vd, vq)):
            ax = axes[a]
            ax["x"] = ax["A"] @ ax["x"] + ax["B"] @ np.array([refs[a], meas[a]]) \
                + ax["W"] * (sat[a] - v_un)
        queue.append((*sat, x[3] + dec.delay_compensation_time * w_m))
        vd_c, vq_c, phi = queue.pop(0)
        rows.append([k * Ts, x[0], x[1], vd_c, vq_c, x[2]])
        err = phi - (x[3] + p * x[2] * Ts / 2) if (vd_c, vq_c) != (0.0, 0.0) else 0.0
        v_app = (vd_c * math.cos(err) - vq_c * math.sin(err),
                 vd_c * math.sin(err) + vq_c * math.cos(err))
        for _ in range(n_sub):
            torque = tf * p * (flux * x[1] + (Ld - Lq) * x[0] * x[1])
            sq_t += (torque - tref) ** 2 * dt
            sq_id += (x[0] - id_ref) ** 2 * dt
            k1 = f(x, *v_app)
            k2 = f(x + 0.5 * dt * k1, *v_app)
            k3 = f(x + 0.5 * dt * k2, *v_app)
            k4 = f(x + dt * k3, *v_app)
            x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    total = n_per * Ts
    return np.array(rows), sq_t / total, sq_id / total
