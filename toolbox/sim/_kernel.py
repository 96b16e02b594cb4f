"""Numba kernel of the closed-loop simulation: PMSM plant + sampled current control.

Plant (rotor dq frame, electrical speed ``w = p * Omega``), integrated with
classical 4th-order Runge-Kutta at the fine step ``h`` (1 us by default, as in
Takami's simulations, paper 001)::

    Ld did/dt = vd - R id + w Lq iq
    Lq diq/dt = vq - R iq - w Ld id - w flux
    J dOmega/dt = T - friction Omega - T_load,  T = tf p (flux iq + (Ld - Lq) id iq)
    dtheta/dt = w

RK4 is used because the electrical time constants (L/R ~ 2-6 ms) are three
orders of magnitude above the step and the switching-level inverter models
make the right-hand side piecewise constant in the stationary frame: the step
is split at every switching instant, so RK4 never integrates across a
discontinuity (local error O(h^5) on smooth pieces; the global error on a 1 s
run is far below the 1e-6 relative level of the tests).

Controller at ``Ts`` (an integer number of plant steps; the plant step is
reduced to ``Ts / ceil(Ts / h)``), zero-order hold, computation delay of
``delay`` periods (Le Pioufle 1992, paper 000). The two current controllers are
discrete state-space systems with inputs ``[i_ref, i_measured]``.

Everything is plain float arrays so that the same core runs one simulation
(:func:`run`) or a parallel batch (:func:`run_batch`, ``numba.prange``).
Metrics are accumulated online (see :mod:`toolbox.sim._metrics` for their
definitions); traces are optional and decimated, so memory is flat in the
simulated duration when only metrics are requested.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._inverter import bit_changes, hexagon_scale, state_vector, svm_times

__all__ = ["run", "run_batch", "N_METRICS", "N_TRACE", "pack_indices"]

# ---- packed-array layouts (documented in _simulate.py, which fills them) ----
# plant P: R, Ld, Lq, flux, p, J, friction, torque_factor
# law LP: R_c, Ld_c, Lq_c, flux_c, cross, emf, alpha, beta, gamma
# speed loop SP: enabled, kp, ki, kd, decim (current periods), iq_limit
# drive DP: Ts, delay, vlim_kind (0 none, 1 circle, 2 hexagon), v_max, r_hex,
#           inverter (0 average, 1 svm, 2 fcs_mpc)
# scenario SC: see SC_* below
SC_DURATION, SC_MECH, SC_OMEGA0, SC_ACC, SC_ID0, SC_IQ0, SC_ID1, SC_IQ1, \
    SC_TSTEP, SC_SPD0, SC_SPD1, SC_TLOAD, SC_TLOAD_T, SC_IQAMP, SC_FSIN, \
    SC_REFMODE, SC_SIG, SC_GAIN, SC_OFFSET, SC_SNOISE, SC_NOISEKIND, \
    SC_CNOISE, SC_CQUANT, SC_SEED, SC_H, SC_TRDEC = range(26)
N_SC = 26

# metrics (raw kernel output order; names in _metrics.METRIC_NAMES)
N_METRICS = 13
# trace columns: t, id, iq, vd, vq, speed (mech rad/s), torque, id_ref, iq_ref, speed_measured
N_TRACE = 10

# accumulator slots
_A_OUT5, _A_OUT2, _A_T10, _A_T90, _A_OVER, _A_SQT, _A_SQID, _A_STAT, _A_STATT, \
    _A_FINAL, _A_SQIQ, _A_CELLS, _A_SAT = range(13)


def pack_indices():
    """Scenario-array slot names (for the Python side), as a dict name -> index."""
    names = ["duration", "mech", "omega0", "acc", "id0", "iq0", "id1", "iq1",
             "t_step", "speed0", "speed1", "load", "load_time", "iq_amp", "f_sin",
             "ref_mode", "signal", "gain", "offset", "speed_noise", "noise_kind",
             "current_noise", "current_quantum", "seed", "h", "trace_decim"]
    return {n: i for i, n in enumerate(names)}


# --------------------------------------------------------------------------- RNG
@njit(cache=True)
def _splitmix(st):
    """splitmix64 step on the 1-element uint64 state array; returns a float in [0, 1)."""
    z = st[0] + np.uint64(0x9E3779B97F4A7C15)
    st[0] = z
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(cache=True)
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


# ------------------------------------------------------------------------- plant
@njit(cache=True)
def _deriv(i_d, i_q, om, th, vx, vy, frame, P, t_load, mech, acc):
    R = P[0]
    Ld = P[1]
    Lq = P[2]
    flux = P[3]
    p = P[4]
    w = p * om
    if frame == 0:
        vd = vx
        vq = vy
    else:  # stationary-frame voltage held constant: rotate into dq
        c = math.cos(th)
        s = math.sin(th)
        vd = vx * c + vy * s
        vq = -vx * s + vy * c
    did = (vd - R * i_d + w * Lq * i_q) / Ld
    diq = (vq - R * i_q - w * Ld * i_d - w * flux) / Lq
    if mech == 1:
        dom = acc
    else:
        torque = P[7] * p * (flux * i_q + (Ld - Lq) * i_d * i_q)
        dom = (torque - P[6] * om - t_load) / P[5]
    return did, diq, dom, w


@njit(cache=True)
def _rk4(s, vx, vy, frame, dt, P, t_load, mech, acc):
    """One RK4 step of the plant state s = [id, iq, Omega, theta], in place."""
    a1, b1, c1, d1 = _deriv(s[0], s[1], s[2], s[3], vx, vy, frame, P, t_load, mech, acc)
    h2 = 0.5 * dt
    a2, b2, c2, d2 = _deriv(s[0] + h2 * a1, s[1] + h2 * b1, s[2] + h2 * c1,
                            s[3] + h2 * d1, vx, vy, frame, P, t_load, mech, acc)
    a3, b3, c3, d3 = _deriv(s[0] + h2 * a2, s[1] + h2 * b2, s[2] + h2 * c2,
                            s[3] + h2 * d2, vx, vy, frame, P, t_load, mech, acc)
    a4, b4, c4, d4 = _deriv(s[0] + dt * a3, s[1] + dt * b3, s[2] + dt * c3,
                            s[3] + dt * d3, vx, vy, frame, P, t_load, mech, acc)
    k = dt / 6.0
    s[0] += k * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    s[1] += k * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
    s[2] += k * (c1 + 2.0 * c2 + 2.0 * c3 + c4)
    s[3] += k * (d1 + 2.0 * d2 + 2.0 * d3 + d4)


@njit(cache=True)
def _accumulate(acc_m, s, t, dt, P, idr, iqr, sr, tref, SC):
    """Online metrics at the start of a plant step of length dt (time-weighted)."""
    torque = P[7] * P[4] * (P[3] * s[1] + (P[1] - P[2]) * s[0] * s[1])
    e_t = torque - tref
    acc_m[_A_SQT] += e_t * e_t * dt
    e_id = s[0] - idr
    acc_m[_A_SQID] += e_id * e_id * dt
    e_iq = s[1] - iqr
    acc_m[_A_SQIQ] += e_iq * e_iq * dt
    sig = int(SC[SC_SIG])
    if sig == 0:
        y = s[1]
        r = iqr
        y0 = SC[SC_IQ0]
        yf = SC[SC_IQ1]
    elif sig == 1:
        y = s[0]
        r = idr
        y0 = SC[SC_ID0]
        yf = SC[SC_ID1]
    else:
        y = s[2]
        r = sr
        y0 = SC[SC_SPD0]
        yf = SC[SC_SPD1]
    dur = SC[SC_DURATION]
    if t >= 0.9 * dur - 1e-12:
        acc_m[_A_STAT] += (r - y) * dt
        acc_m[_A_FINAL] += y * dt
        acc_m[_A_STATT] += dt
    delta = yf - y0
    if t >= SC[SC_TSTEP] - 1e-12 and delta != 0.0:
        dev = abs(y - yf)
        if dev > 0.05 * abs(delta):
            acc_m[_A_OUT5] = t + dt
        if dev > 0.02 * abs(delta):
            acc_m[_A_OUT2] = t + dt
        frac = (y - y0) / delta
        if frac >= 0.1 and acc_m[_A_T10] < 0.0:
            acc_m[_A_T10] = t
        if frac >= 0.9 and acc_m[_A_T90] < 0.0:
            acc_m[_A_T90] = t
        over = (y - yf) / delta
        if over > acc_m[_A_OVER]:
            acc_m[_A_OVER] = over


@njit(cache=True)
def _advance(s, t, vx, vy, frame, dur, h, P, t_load, SC, acc_m, idr, iqr, sr, tref):
    """Integrate over ``dur`` with ceil(dur/h) equal RK4 steps; returns the new time."""
    if dur <= 0.0:
        return t
    n = int(math.ceil(dur / h - 1e-9))
    if n < 1:
        n = 1
    dt = dur / n
    mech = int(SC[SC_MECH])
    acc = SC[SC_ACC]
    for _ in range(n):
        _accumulate(acc_m, s, t, dt, P, idr, iqr, sr, tref, SC)
        _rk4(s, vx, vy, frame, dt, P, t_load, mech, acc)
        t += dt
    if mech == 1:  # imposed speed: remove the round-off drift of the integral
        s[2] = SC[SC_OMEGA0] + acc * t
    return t


@njit(cache=True)
def _linear(A, B, C, D, x, r, y):
    """Output and next state (without anti-windup) of one discrete axis controller."""
    n = x.shape[0]
    u = D[0] * r + D[1] * y
    for i in range(n):
        u += C[i] * x[i]
    return u


@njit(cache=True)
def _update(A, B, Baw, x, xn, r, y, dv):
    n = x.shape[0]
    for i in range(n):
        v = B[i, 0] * r + B[i, 1] * y + Baw[i] * dv
        for j in range(n):
            v += A[i, j] * x[j]
        xn[i] = v
    for i in range(n):
        x[i] = xn[i]


@njit(cache=True)
def run(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces):
    """One closed-loop simulation.

    Parameters (all float64 arrays, filled by ``_simulate._pack*``)
    ----------
    P : (8,)
        Plant: R (ohm), Ld, Lq (H), flux (Wb), p, J (kg m^2), friction
        (N m s/rad), torque_factor.
    A, B, C, D, Baw : (2, n, n), (2, n, 2), (2, n), (2, 2), (2, n)
        Discrete d and q controllers (inputs [i_ref, i_meas], output V),
        back-calculation anti-windup gains.
    LP : (9,)
        Controller model R, Ld, Lq, flux; cross, emf flags; alpha, beta, gamma.
    SP : (6,)
        Speed loop: enabled, kp, ki, kd, period in current periods, iq limit.
    DP : (6,)
        Ts (s), delay (periods), limit kind, circle radius (V), hexagon
        vertex radius (V), inverter kind.
    SC : (N_SC,)
        Scenario (slots SC_*; see ``pack_indices``).
    keep_traces : bool
        Record a row every ``trace_decim`` periods (else an empty array).

    Returns
    -------
    metrics : (N_METRICS,)
        In the order of ``_metrics.METRIC_NAMES``.
    traces : (n_rows, N_TRACE)
        t, id, iq, vd, vq, speed, torque, id_ref, iq_ref, speed_measured.
    """
    Ts = DP[0]
    delay = int(DP[1])
    vlim = int(DP[2])
    v_max = DP[3]
    r_hex = DP[4]
    inverter = int(DP[5])
    h = SC[SC_H]
    dur = SC[SC_DURATION]
    n_per = int(round(dur / Ts))
    p = P[4]
    R_c = LP[0]
    Ld_c = LP[1]
    Lq_c = LP[2]
    flux_c = LP[3]
    cross = LP[4]
    emf = LP[5]
    tf = P[7]
    n = A.shape[1]
    xd = np.zeros(n)
    xq = np.zeros(n)
    xn = np.zeros(n)
    s = np.zeros(4)
    s[2] = SC[SC_OMEGA0]
    acc_m = np.zeros(13)
    acc_m[_A_OUT5] = -1.0
    acc_m[_A_OUT2] = -1.0
    acc_m[_A_T10] = -1.0
    acc_m[_A_T90] = -1.0
    rng = np.zeros(1, dtype=np.uint64)
    rng[0] = np.uint64(int(SC[SC_SEED]))
    nbuf = delay + 1
    vd_buf = np.zeros(nbuf)
    vq_buf = np.zeros(nbuf)
    trdec = int(SC[SC_TRDEC])
    if trdec < 1:
        trdec = 1
    if keep_traces:
        tr = np.empty(((n_per + trdec - 1) // trdec, 10))
    else:
        tr = np.empty((0, 10))
    # speed loop
    sp_on = SP[0] > 0.5
    sp_dec = int(SP[4])
    if sp_dec < 1:
        sp_dec = 1
    Tsp = Ts * sp_dec
    integ = 0.0
    e_prev = 0.0
    first_sp = True
    iqr_sp = 0.0
    # inverter bookkeeping
    conf_applied = 0  # inverter state in force at the end of the last segment
    conf_next = 0  # fcs with delay: state chosen last period, applied now
    conf_now = 0
    vd_app = 0.0
    vq_app = 0.0
    t = 0.0
    for k in range(n_per):
        t = k * Ts
        # ---- sampling: sensors (paper 000: offset/gain/noise on the speed)
        i_d_m = s[0] + _noise(rng, SC[SC_CNOISE], int(SC[SC_NOISEKIND]))
        i_q_m = s[1] + _noise(rng, SC[SC_CNOISE], int(SC[SC_NOISEKIND]))
        q = SC[SC_CQUANT]
        if q > 0.0:
            i_d_m = q * math.floor(i_d_m / q + 0.5)
            i_q_m = q * math.floor(i_q_m / q + 0.5)
        om_m = (1.0 + SC[SC_GAIN]) * s[2] + SC[SC_OFFSET] \
            + _noise(rng, SC[SC_SNOISE], int(SC[SC_NOISEKIND]))
        w_m = p * om_m
        th_m = s[3]
        # ---- references
        sr = SC[SC_SPD0] if t < SC[SC_TSTEP] else SC[SC_SPD1]
        ref_mode = int(SC[SC_REFMODE])
        if t < SC[SC_TSTEP]:
            idr = SC[SC_ID0]
            iqr = SC[SC_IQ0]
        else:
            idr = SC[SC_ID1]
            iqr = SC[SC_IQ1]
        if ref_mode == 1:
            idr = SC[SC_ID1]
            iqr = SC[SC_IQAMP] * math.sin(2.0 * math.pi * SC[SC_FSIN] * t)
        if sp_on:
            if k % sp_dec == 0:
                e = sr - om_m
                if first_sp:
                    e_prev = e
                    first_sp = False
                integ_new = integ + SP[2] * e * Tsp
                u = SP[1] * e + integ_new + SP[3] * (e - e_prev) / Tsp
                e_prev = e
                lim = SP[5]
                if u > lim:
                    u = lim
                elif u < -lim:
                    u = -lim
                else:
                    integ = integ_new  # conditional integration (anti-windup)
                iqr_sp = u
            iqr = iqr_sp
            idr = SC[SC_ID1]
        tref = tf * p * (flux_c * iqr + (Ld_c - Lq_c) * idr * iqr)
        t_load = SC[SC_TLOAD] if t >= SC[SC_TLOAD_T] else 0.0
        if inverter == 2:
            # ---- Boolean predictive control, paper 002 criterion (23)
            if delay >= 1:
                # predict the sampling instant at which the choice takes effect
                va0, vb0 = state_vector(conf_next, r_hex)
                c = math.cos(th_m)
                sn = math.sin(th_m)
                vd0 = va0 * c + vb0 * sn
                vq0 = -va0 * sn + vb0 * c
                idp = i_d_m + Ts / Ld_c * (vd0 - R_c * i_d_m + w_m * Lq_c * i_q_m)
                iqp = i_q_m + Ts / Lq_c * (vq0 - R_c * i_q_m - w_m * Ld_c * i_d_m
                                           - w_m * flux_c)
                thp = th_m + w_m * Ts
                prev = conf_next
            else:
                idp = i_d_m
                iqp = i_q_m
                thp = th_m
                prev = conf_applied
            c = math.cos(thp)
            sn = math.sin(thp)
            best = 0
            best_j = 1e300
            best_c = 99
            for cand in range(8):
                va, vb = state_vector(cand, r_hex)
                vdc_ = va * c + vb * sn
                vqc = -va * sn + vb * c
                idn = idp + Ts / Ld_c * (vdc_ - R_c * idp + w_m * Lq_c * iqp)
                iqn = iqp + Ts / Lq_c * (vqc - R_c * iqp - w_m * Ld_c * idp
                                         - w_m * flux_c)
                nch = bit_changes(cand, prev)
                jc = LP[6] * (iqn - iqr) ** 2 + LP[7] * (idn - idr) ** 2 + LP[8] * nch
                # ties (the two zero vectors 000 and 111) go to the fewest commutations
                if jc < best_j or (jc == best_j and nch < best_c):
                    best_j = jc
                    best = cand
                    best_c = nch
            if delay >= 1:
                conf_now = conf_next
                conf_next = best
            else:
                conf_now = best
            va, vb = state_vector(conf_now, r_hex)
            c = math.cos(th_m)
            sn = math.sin(th_m)
            vd_app = va * c + vb * sn
            vq_app = -va * sn + vb * c
        else:
            # ---- linear current controllers + decoupling (paper 000 eq 11/20)
            ud = _linear(A[0], B[0], C[0], D[0], xd, idr, i_d_m)
            uq = _linear(A[1], B[1], C[1], D[1], xq, iqr, i_q_m)
            vd_u = ud - cross * w_m * Lq_c * i_q_m
            vq_u = uq + cross * w_m * Ld_c * i_d_m + emf * w_m * flux_c
            vd_s = vd_u
            vq_s = vq_u
            if vlim == 1:
                mag = math.hypot(vd_u, vq_u)
                if mag > v_max:
                    vd_s = vd_u * v_max / mag
                    vq_s = vq_u * v_max / mag
            elif vlim == 2:
                thc = th_m + w_m * Ts * (delay + 0.5)
                c = math.cos(thc)
                sn = math.sin(thc)
                va = vd_u * c - vq_u * sn
                vb = vd_u * sn + vq_u * c
                sc = hexagon_scale(va, vb, r_hex)
                vd_s = vd_u * sc
                vq_s = vq_u * sc
            if vd_s != vd_u or vq_s != vq_u:
                acc_m[_A_SAT] += Ts
            _update(A[0], B[0], Baw[0], xd, xn, idr, i_d_m, vd_s - vd_u)
            _update(A[1], B[1], Baw[1], xq, xn, iqr, i_q_m, vq_s - vq_u)
            slot = k % nbuf
            vd_buf[slot] = vd_s
            vq_buf[slot] = vq_s
            if k >= delay:
                old = (k - delay) % nbuf
                vd_app = vd_buf[old]
                vq_app = vq_buf[old]
            else:
                vd_app = 0.0
                vq_app = 0.0
        if keep_traces and k % trdec == 0:
            row = k // trdec
            tr[row, 0] = t
            tr[row, 1] = s[0]
            tr[row, 2] = s[1]
            tr[row, 3] = vd_app
            tr[row, 4] = vq_app
            tr[row, 5] = s[2]
            tr[row, 6] = tf * p * (P[3] * s[1] + (P[1] - P[2]) * s[0] * s[1])
            tr[row, 7] = idr
            tr[row, 8] = iqr
            tr[row, 9] = om_m
        # ---- plant over one period
        if inverter == 0:
            t = _advance(s, t, vd_app, vq_app, 0, Ts, h, P, t_load, SC, acc_m,
                         idr, iqr, sr, tref)
        elif inverter == 1:
            tha = th_m + w_m * Ts * 0.5
            c = math.cos(tha)
            sn = math.sin(tha)
            va = vd_app * c - vq_app * sn
            vb = vd_app * sn + vq_app * c
            st1, st2, t1, t2, t0 = svm_times(va, vb, r_hex, Ts)
            # symmetric centred pattern 0-k-l-7-l-k-0: six cell commutations
            seq_s = (0, st1, st2, 7, st2, st1, 0)
            seq_t = (0.25 * t0, 0.5 * t1, 0.5 * t2, 0.5 * t0, 0.5 * t2, 0.5 * t1,
                     0.25 * t0)
            for j in range(7):
                stj = seq_s[j]
                acc_m[_A_CELLS] += bit_changes(conf_applied, stj)
                conf_applied = stj
                vx, vy = state_vector(stj, r_hex)
                t = _advance(s, t, vx, vy, 1, seq_t[j], h, P, t_load, SC, acc_m,
                             idr, iqr, sr, tref)
        else:
            acc_m[_A_CELLS] += bit_changes(conf_applied, conf_now)
            conf_applied = conf_now
            vx, vy = state_vector(conf_now, r_hex)
            t = _advance(s, t, vx, vy, 1, Ts, h, P, t_load, SC, acc_m,
                         idr, iqr, sr, tref)
    # ---- metrics
    M = np.full(N_METRICS, np.nan)
    total = n_per * Ts
    t_step = SC[SC_TSTEP]
    if acc_m[_A_OUT5] < 0.0:
        M[0] = 0.0
    elif acc_m[_A_OUT5] < total - 1e-12:
        M[0] = acc_m[_A_OUT5] - t_step
    if acc_m[_A_T10] >= 0.0 and acc_m[_A_T90] >= 0.0:
        M[1] = acc_m[_A_T90] - acc_m[_A_T10]
    if acc_m[_A_OUT2] < 0.0:
        M[2] = 0.0
    elif acc_m[_A_OUT2] < total - 1e-12:
        M[2] = acc_m[_A_OUT2] - t_step
    M[3] = 100.0 * acc_m[_A_OVER]
    if acc_m[_A_STATT] > 0.0:
        M[4] = acc_m[_A_STAT] / acc_m[_A_STATT]
        M[10] = acc_m[_A_FINAL] / acc_m[_A_STATT]
    if total > 0.0:
        M[5] = acc_m[_A_SQT] / total
        M[6] = acc_m[_A_SQID] / total
        M[11] = acc_m[_A_SQIQ] / total
        M[7] = 2.0 * acc_m[_A_CELLS] / total
        M[8] = acc_m[_A_CELLS] / total
    M[9] = acc_m[_A_SAT]
    M[12] = s[2]
    sig = int(SC[SC_SIG])
    if sig == 0:
        delta = SC[SC_IQ1] - SC[SC_IQ0]
    elif sig == 1:
        delta = SC[SC_ID1] - SC[SC_ID0]
    else:
        delta = SC[SC_SPD1] - SC[SC_SPD0]
    if delta == 0.0:
        M[0] = np.nan
        M[1] = np.nan
        M[2] = np.nan
        M[3] = np.nan
    return M, tr


@njit(cache=True, parallel=True)
def run_batch(P, A, B, C, D, Baw, LP, SP, DP, SC):
    """Metrics of N simulations, one per row of the plant-parameter array P (N, 8)."""
    N = P.shape[0]
    out = np.empty((N, N_METRICS))
    for i in prange(N):
        M, _ = run(P[i], A, B, C, D, Baw, LP, SP, DP, SC, False)
        out[i, :] = M
    return out
