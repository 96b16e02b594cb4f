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

Voltage placement (toolbox/ARCHITECTURE.md "The digital loop"): the
voltage computed at sample k is placed, as the firmware header does, at the
angle ``phi_k = theta_k + t_c w_m`` (sampled angle, measured electrical
speed, the drive's compensation time ``t_c``, ``DP_T_COMP``) and applied over
period ``k + delay``. Inverters: the average model holds it over the period
in the stationary frame (``hold = 1``: constant ``v_alpha_beta`` at
``phi_k``, the fundamental of a PWM inverter) or in the rotor frame
(``hold = 0``: constant ``v_dq`` rotated by ``phi_k`` minus the true
mid-period angle, the idealisation the linear analysis discretises); the ``svm`` model switches the legs, either
one centred 0-k-l-7-l-k-0 pattern per sample (paper 002 eq (21)-(22)) or a
regular-sampled triangle carrier with min-max injection at the drive's
switching frequency (``half_periods`` carrier half periods per sample,
:func:`_carrier_period`); ``fcs_mpc`` holds one of the eight states.

Controller at ``Ts`` (an integer number of plant steps; the plant step is
reduced to ``Ts / ceil(Ts / h)``), zero-order hold, computation delay of
``delay`` periods (Le Pioufle 1992, paper 000). The two current controllers are
discrete state-space systems with inputs ``[i_ref, i_measured]``.

Everything is plain float arrays; :func:`run` simulates one closed loop, and
:func:`run_rows` a thread's share of a batch (``_simulate.simulate_batch``
runs one per core). The arrays' slots are declared once, by
name, in :data:`LAYOUTS`; the index constants (``P_R``, ``DP_TS``,
``SC_DURATION``, ...) are written out in ``_kernel_layout`` (checked against
that declaration by tests/sim/test_kernel_model.py) and
:func:`pack_indices` gives the same map to the Python side that fills the
arrays (``_simulate._pack``). :func:`_run` allocates the work
arrays and :func:`_periods` runs the periods, a short loop over small
``@njit`` helpers (sensors, references, speed loop, law step with
anti-windup and voltage limit, predictive choice, inverter and plant RK4);
the plant state lives in local scalars, not in an array, so that LLVM keeps
it in registers across the RK4 stages.

Variants. Four paths are compiled only into the runs that take them: the
complex-vector law of method ``cv``, the flux-state plant of a saturated
motor, the switching inverters (svm, carrier, fcs_mpc) and the average
inverter's stationary-frame hold (a spec holds in one frame).
:func:`variant` names the one a run needs, ``(cv, flux, switching,
stationary)``, each flag None or True; :data:`ENTRIES` holds a compiled ``(run, run_rows)``
pair per variant (:func:`_entries`), which passes the flags to :func:`_run`
as compile-time constants, and :func:`run`, :func:`run_rows` (plain Python)
call the pair of their inputs. The one period loop :func:`_periods` and the
plant helpers branch on ``flag is None``, a test numba resolves, and
prunes, before typing: a branch not taken is never typed, so its callees
(``_kernel_cv``, ``_kernel_steps._steps_flux``, ``_kernel_pwm``,
:func:`_fcs_choice`) are not compiled either. A constant-parameter,
linear-law, average-inverter run (every ``cct design`` of a linear method)
thus compiles none of them; each other variant compiles on its first use
and is cached on disk apart (``docs/performance.md``, "Cold compile"), an
entry's first call holding a lock between processes (:func:`_first_call_locked`).

Loop structure in brief (gcc -O3's plain C loop of the same arithmetic,
``tests/benchmarks/bench_sim.py``, is the yardstick): the period loop and the
plant steps are compiled without numba's reference counting
(:data:`_jit_no_rc`); the online metrics are kept in local values over a run
of steps (:func:`_load_acc`) and accumulated after each step's RK4 stages;
the periods without load torque have a loop of their own (:func:`_steps`);
the plant multiplies by ``1/Ld``, ``1/Lq``, ``1/J`` computed once per run
(:func:`_plant`); no ``fastmath`` (same bits on every x86-64 CPU). Why, with
the measured timings, the cold compile and the experiments tried:
``docs/performance.md``.

The plant (``_kernel_plant``), the online metrics (``_kernel_metrics``), the
plant steps (``_kernel_steps``), the switching inverters (``_kernel_pwm``),
the complex-vector law of method ``cv`` (``_kernel_cv``) and the sensors,
references and speed loop (``_kernel_sense``)
live in sibling modules compiled with the same decorators; the layouts, slot
constants and decorators are declared in ``_kernel_layout``. All of them are
in :data:`KERNEL_SOURCES`.

Metrics are accumulated online (see :mod:`toolbox.sim._metrics` for their
definitions); traces are optional and decimated, so memory is flat in the
simulated duration when only metrics are requested.
"""

from __future__ import annotations

import fcntl
import math
import os
import threading
from pathlib import Path

import numpy as np
from numba import njit

from .._cache import cache_key
from .._io import write_atomic
from ._inverter import bit_changes, hexagon_scale, state_vector
from ._kernel_layout import (LAYOUTS, N_METRICS, N_SC, N_TRACE, _A_CELLS, _A_OUT2, _A_OUT5, _A_SAT,
                             _A_T10, _A_T90, _A_YEXT, _SQ3_2, _jit, _jit_inline, _jit_no_rc_variant,
                             pack_indices)
from ._kernel_layout import (  # the slot constants (compile-time ints)
    LP_R_C, LP_LD_C, LP_LQ_C, LP_FLUX_C, LP_CROSS, LP_EMF, LP_ALPHA, LP_BETA, LP_GAMMA,
    LP_CV, LP_CV_PC, LP_CV_PI, LP_CV_PD, LP_CV_D, P_MAGNETIC, SP_ENABLED, SP_DECIM, DP_TS,
    DP_DELAY, DP_VLIM, DP_V_MAX, DP_R_HEX, DP_INVERTER, DP_HALF_PERIODS, DP_HOLD, DP_T_COMP,
    DP_VPRIO, SC_DURATION, SC_MECH, SC_OMEGA0, SC_ACC, SC_ID1, SC_T_STEP, SC_LOAD, SC_LOAD_TIME,
    SC_SEED, SC_H, SC_TRACE_DECIM, SC_CURRENT_DELAY_D, SC_CURRENT_DELAY_Q)
from ._kernel_plant import (_currents, _deriv, _initial_state, _plant, _to_ab,  # noqa: F401
                            _to_dq, _torque, _torque_of_state)
from ._kernel_metrics import _finalise, _metric_setup, _overshoot  # noqa: F401 (tests)
from ._kernel_steps import _advance_n, _split
from ._kernel_pwm import _carrier_period, _svm_period
from ._kernel_cv import _cv_linear, _cv_update
from ._kernel_sense import _current_sensor, _references, _sense, _speed_pid

__all__ = ["run", "run_rows", "variant", "ENTRIES", "N_METRICS", "N_TRACE", "N_SC",
           "LAYOUTS", "pack_indices", "KERNEL_SOURCES", "sources_digest"]



# ------------------------------------------------------------------- controller
@_jit_inline
def _linear(C, D, ax, x, r, y):
    """Output (without anti-windup) of the axis ``ax`` controller (0 d, 1 q)."""
    u = D[ax, 0] * r + D[ax, 1] * y
    for i in range(x.shape[0]):
        u += C[ax, i] * x[i]
    return u


@_jit_inline
def _update(A, B, Baw, ax, x, xn, r, y, dv):
    """Next state ``A x + B [r, y] + Baw dv`` of the axis ``ax`` controller, in place."""
    n = x.shape[0]
    for i in range(n):
        v = B[ax, i, 0] * r + B[ax, i, 1] * y + Baw[ax, i] * dv
        for j in range(n):
            v += A[ax, i, j] * x[j]
        xn[i] = v
    for i in range(n):
        x[i] = xn[i]


@_jit_inline
def d_priority_cap(v_in, e_q):
    """The d-axis priority guard, as a fraction of the limit's d extent:
    ``sqrt(1 - min(|e_q| / v_in, 1)^2)``, on the circle (``v_in`` its radius)
    the largest ``|v_d|`` that leaves ``v_q`` the speed voltage ``e_q = w
    (Ld_c i_d + psi_c)`` (the controller's model, at the measured current and
    speed); the hexagon (``v_in`` its apothem) scales its d extent alike. Without it a flying start above base
    speed runs away: the decoupling's ``-w Lq i_q`` takes the voltage as ``i_q``
    brakes, ``v_q`` falls below the back-EMF, ``i_q`` brakes harder
    (toolbox/ARCHITECTURE.md "Operating envelope")."""
    e = min(abs(e_q) / v_in, 1.0)
    return math.sqrt(max(1.0 - e * e, 0.0))


@_jit_inline
def _d_priority_hexagon(vd_u, vq_u, c0, s0, r_hex, d_cap):
    """d-axis priority inside the SVM hexagon of vertex radius ``r_hex`` seen
    in a dq frame at the angle whose cos, sin are ``c0``, ``s0``: ``v_d`` clamped
    to ``d_cap`` (:func:`d_priority_cap`) times the hexagon's d extent, then
    ``v_q`` clipped into the chord at that ``v_d``.

    The hexagon is ``|n_k . v_ab| <= a`` (apothem ``a = r_hex sqrt(3)/2``, edge
    normals at 30, 90, 150 deg); in dq the normal at ``alpha`` is
    ``(cos(alpha - theta), sin(alpha - theta))``. The d extent is the support
    function ``r_hex max_j |cos(theta - 60 j deg)|`` (vertices at 0, 60, 120 deg).
    """
    a = r_hex * _SQ3_2
    # d extent: vertices at 0, 60, 120 deg (and their opposites)
    d_max = d_cap * r_hex * max(abs(c0), abs(0.5 * c0 + _SQ3_2 * s0),
                                abs(-0.5 * c0 + _SQ3_2 * s0))
    vd = min(max(vd_u, -d_max), d_max)
    lo = -1e300
    hi = 1e300
    for k in range(3):
        if k == 0:
            ca, sa = _SQ3_2, 0.5
        elif k == 1:
            ca, sa = 0.0, 1.0
        else:
            ca, sa = -_SQ3_2, 0.5
        ck = ca * c0 + sa * s0    # cos(alpha - theta)
        sk = sa * c0 - ca * s0    # sin(alpha - theta)
        if abs(sk) > 1e-12:
            b1 = (a - ck * vd) / sk
            b2 = (-a - ck * vd) / sk
            if b1 > b2:
                b1, b2 = b2, b1
            lo = max(lo, b1)
            hi = min(hi, b2)
    if lo > hi:  # v_d on a vertex, rounding: the chord is one point
        lo = hi = 0.5 * (lo + hi)
    return vd, min(max(vq_u, lo), hi)


@_jit_inline
def _voltage_limit(vd_u, vq_u, th_m, w_m, DP, e_q):
    """Saturated dq voltage: circle of radius v_max, or the SVM hexagon at the
    angle where the voltage is placed (theta + t_comp w).

    ``vprio`` 0 (radial): ``v_dq`` scaled radially onto the limit. ``vprio`` 1
    (d-axis priority, the limiter of field-weakening drives, Briz et al.,
    IEEE Trans. Ind. Appl. 37(1) 2001): ``v_d`` kept (clamped to the limit's
    d extent and to :func:`d_priority_cap` of the speed voltage ``e_q``, so
    that ``v_q`` keeps the back-EMF), ``v_q`` gets the rest, ``sign(v_q) sqrt(v_max^2 - v_d^2)`` on
    the circle, the chord of the hexagon at that ``v_d`` otherwise.
    """
    vlim = int(DP[DP_VLIM])
    prio = int(DP[DP_VPRIO])
    if vlim == 1:
        v_max = DP[DP_V_MAX]
        if prio == 1:
            d_max = d_priority_cap(v_max, e_q) * v_max
            vd = min(max(vd_u, -d_max), d_max)
            q_max = math.sqrt(max(v_max * v_max - vd * vd, 0.0))
            return vd, min(max(vq_u, -q_max), q_max)
        mag = math.hypot(vd_u, vq_u)
        if mag > v_max:
            return vd_u * v_max / mag, vq_u * v_max / mag
    elif vlim == 2:
        thc = th_m + w_m * DP[DP_T_COMP]
        if prio == 1:
            return _d_priority_hexagon(vd_u, vq_u, math.cos(thc), math.sin(thc),
                                       DP[DP_R_HEX], d_priority_cap(DP[DP_R_HEX] * _SQ3_2, e_q))
        va, vb = _to_ab(vd_u, vq_u, math.cos(thc), math.sin(thc))
        sc = hexagon_scale(va, vb, DP[DP_R_HEX])
        return vd_u * sc, vq_u * sc
    return vd_u, vq_u


@_jit_inline
def _law_step(A, B, C, D, Baw, xd, xq, xn, idr, iqr, i_d_m, i_q_m, w_m, th_m, LP, DP):
    """Linear current laws + decoupling (paper 000 eq (11)/(20)), voltage limit and
    back-calculation anti-windup; updates the law states, returns
    (vd, vq saturated, saturated?)."""
    cross = LP[LP_CROSS]
    ud = _linear(C, D, 0, xd, idr, i_d_m)
    uq = _linear(C, D, 1, xq, iqr, i_q_m)
    vd_u = ud - cross * w_m * LP[LP_LQ_C] * i_q_m
    vq_u = uq + cross * w_m * LP[LP_LD_C] * i_d_m + LP[LP_EMF] * w_m * LP[LP_FLUX_C]
    e_q = w_m * (LP[LP_LD_C] * i_d_m + LP[LP_FLUX_C])  # the d-priority guard's reserve
    vd_s, vq_s = _voltage_limit(vd_u, vq_u, th_m, w_m, DP, e_q)
    _update(A, B, Baw, 0, xd, xn, idr, i_d_m, vd_s - vd_u)
    _update(A, B, Baw, 1, xq, xn, iqr, i_q_m, vq_s - vq_u)
    return vd_s, vq_s, (vd_s != vd_u or vq_s != vq_u)


@_jit_inline
def _cv_law_step(xd, xq, idr, iqr, i_d_m, i_q_m, w_m, th_m, LP, DP):
    """The complex-vector law of method ``cv`` (``_kernel_cv``: gains at the
    measured speed ``w_m``), the EMF feedforward, the voltage limit and the
    realised-voltage integrator; updates the states ``xd``, ``xq`` (integrator,
    then the delayed voltages); returns (vd, vq saturated, saturated?)."""
    d = int(LP[LP_CV_D])  # the design's delay (the drive's may differ: a robustness case)
    pi = LP[LP_CV_PI]
    vd, vq, delta1, gi00, gi01, gi10, gi11 = _cv_linear(
        xd, xq, idr, iqr, i_d_m, i_q_m, w_m, DP[DP_TS], d, DP[DP_T_COMP], LP[LP_R_C],
        LP[LP_LD_C], LP[LP_LQ_C], LP[LP_CV_PC], pi, LP[LP_CV_PD])
    ff = LP[LP_EMF] * w_m * LP[LP_FLUX_C]
    vq_u = vq + ff
    e_q = w_m * (LP[LP_LD_C] * i_d_m + LP[LP_FLUX_C])  # the d-priority guard's reserve
    vd_s, vq_s = _voltage_limit(vd, vq_u, th_m, w_m, DP, e_q)
    _cv_update(xd, xq, idr, iqr, i_d_m, i_q_m, d, pi, delta1, gi00, gi01, gi10, gi11,
               vd_s - vd, vq_s - vq_u, vd_s, vq_s - ff)
    return vd_s, vq_s, (vd_s != vd or vq_s != vq_u)


@_jit
def _euler_predict(i_d, i_q, vd, vq, w, Ts, LP):
    """One forward-Euler step of the controller's dq model (paper 002 eq (23) predictor)."""
    R_c = LP[LP_R_C]
    Ld_c = LP[LP_LD_C]
    Lq_c = LP[LP_LQ_C]
    return (i_d + Ts / Ld_c * (vd - R_c * i_d + w * Lq_c * i_q),
            i_q + Ts / Lq_c * (vq - R_c * i_q - w * Ld_c * i_d - w * LP[LP_FLUX_C]))


@_jit
def _fcs_choice(i_d_m, i_q_m, w_m, th_m, idr, iqr, conf_prev, predict, Ts, r_hex, LP):
    """Boolean predictive control, paper 002 criterion (23): the switch state of
    least ``alpha (iq - iq_ref)^2 + beta (id - id_ref)^2 + gamma commutations``.

    With ``predict`` (one period of delay) the currents are first advanced over
    the period during which ``conf_prev`` (chosen last period) is applied.
    """
    if predict:
        va0, vb0 = state_vector(conf_prev, r_hex)
        vd0, vq0 = _to_dq(va0, vb0, math.cos(th_m), math.sin(th_m))
        idp, iqp = _euler_predict(i_d_m, i_q_m, vd0, vq0, w_m, Ts, LP)
        thp = th_m + w_m * Ts
    else:
        idp = i_d_m
        iqp = i_q_m
        thp = th_m
    c = math.cos(thp)
    sn = math.sin(thp)
    best = 0
    best_j = 1e300
    best_c = 99
    for cand in range(8):
        va, vb = state_vector(cand, r_hex)
        vdc, vqc = _to_dq(va, vb, c, sn)
        idn, iqn = _euler_predict(idp, iqp, vdc, vqc, w_m, Ts, LP)
        nch = bit_changes(cand, conf_prev)
        jc = LP[LP_ALPHA] * (iqn - iqr) ** 2 + LP[LP_BETA] * (idn - idr) ** 2 \
            + LP[LP_GAMMA] * nch
        # ties (the two zero vectors 000 and 111) go to the fewest commutations
        if jc < best_j or (jc == best_j and nch < best_c):
            best_j = jc
            best = cand
            best_c = nch
    return best



# ------------------------------------------------------------------ simulation
def run(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces):
    """One closed-loop simulation (compiled code that releases the GIL, as
    :func:`run_rows`), by the compiled variant of its inputs (:func:`variant`).

    Parameters (all float64 arrays, filled by ``_simulate._pack*``; slots in
    :data:`LAYOUTS`)
    ----------
    P : (9,) or longer
        Plant: R (ohm), Ld, Lq (H), flux (Wb), p, J (kg m^2), friction
        (N m s/rad), torque_factor, magnetic (0 constant parameters; 1
        saturated, its current-from-flux table following, see
        ``_kernel_plant._current_of_flux``).
    A, B, C, D, Baw : (2, n, n), (2, n, 2), (2, n), (2, 2), (2, n)
        Discrete d and q controllers (inputs [i_ref, i_meas], output V),
        back-calculation anti-windup gains.
    LP : (14,)
        Controller model R, Ld, Lq, flux; cross, emf flags; alpha, beta, gamma;
        cv flag, poles and design delay (``_kernel_cv``; the states ``xd``, ``xq``
        then hold the integrator and the delayed voltages, ``A`` sized for them).
    SP : (6,)
        Speed loop: enabled, kp, ki, kd, period in current periods, iq limit.
    DP : (10,)
        Ts (s), delay (periods), limit kind, circle radius (V), hexagon
        vertex radius (V), inverter kind, carrier half periods per sample
        (0: one centred SVM pattern per sample), hold frame of the average
        inverter (0 rotor, 1 stationary), compensation time (s), limit priority.
    SC : (N_SC,)
        Scenario (slots ``SC_*``; see :func:`pack_indices`).
    keep_traces : bool
        Record a row every ``trace_decim`` periods (else an empty array).

    Returns
    -------
    metrics : (N_METRICS,)
        In the order of ``_metrics.METRIC_NAMES``.
    traces : (n_rows, N_TRACE)
        t, id, iq, vd, vq, speed, torque, id_ref, iq_ref, speed_measured.
    """
    return _first_call_locked(ENTRIES[variant(P[P_MAGNETIC], LP, DP)][0],
                              P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces)


def run_rows(P, start, stop, step, A, B, C, D, Baw, LP, SP, DP, SC, out):
    """Metrics of the simulations of the plants ``P[start:stop:step]`` into the
    same rows of ``out`` (N, N_METRICS): one thread's share of a batch
    (``_simulate.simulate_batch`` runs one per core), compiled code that
    releases the GIL.

    One call per share, not one per simulation: each return to Python hands
    the GIL between the threads, ~5 % of a batch of 20 ms simulations.
    Parameters as for :func:`run`, ``P`` (N, 9 or longer) one plant per row,
    all of one kind (constant parameters or saturated: one variant).
    """
    magnetic = P[:, P_MAGNETIC] > 0.5
    if magnetic.any() != magnetic.all():
        raise ValueError("run_rows: constant-parameter and saturated plants in one batch")
    _first_call_locked(ENTRIES[variant(P[0, P_MAGNETIC] if len(P) else 0.0, LP, DP)][1],
                       P, start, stop, step, A, B, C, D, Baw, LP, SP, DP, SC, out)


#: Serialises an entry's first call between a process's threads (a batch's).
_FIRST_CALL = threading.Lock()


def _first_call_locked(entry, *args):
    """``entry(*args)``; its first call in a process (numba loads or compiles
    it) holds a lock (``flock``) on the numba cache directory, shared by every
    process and released if its holder dies: numba's read-modify-write of a
    cache index is not safe between processes (``_kernel_layout._jit_variant``)."""
    if entry.signatures:
        return entry(*args)
    with _FIRST_CALL:
        try:
            fd = os.open(entry.stats.cache_path, os.O_RDONLY | os.O_DIRECTORY)
        except (OSError, AttributeError):  # no cache directory; NUMBA_DISABLE_JIT=1
            return entry(*args)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            return entry(*args)
        finally:
            os.close(fd)


def variant(magnetic, LP, DP):
    """The kernel variant ``(cv, flux, switching, stationary)`` that runs
    these inputs: each flag None (the path is not compiled in) or True:
    ``cv`` the complex-vector law (``LP`` slot ``cv``), ``flux`` a saturated
    plant (plant slot ``magnetic``), ``switching`` an inverter other than the
    average model (``DP`` slot ``inverter``: svm, carrier, fcs_mpc),
    ``stationary`` the average inverter's hold in the stationary frame
    (``DP`` slot ``hold`` 1; None with a switching inverter)."""
    switching = int(DP[DP_INVERTER]) != 0
    return (True if LP[LP_CV] > 0.5 else None, True if magnetic > 0.5 else None,
            True if switching else None,
            True if not switching and int(DP[DP_HOLD]) == 1 else None)


def _entries(cv, flux, switching, stationary):
    """The compiled entry points ``(run, run_rows)`` of one variant: thin
    wrappers that call :func:`_run` with the flags as compile-time constants
    (closure variables), so that numba types, and prunes, every branch on
    them before compiling anything below (module docstring, "Variants").
    Each is cached on disk under a name of its own (``run_cv0_flux0_sw0_st1``,
    ...): closures of one code object share numba's symbol and cache names."""
    tag = "_".join(f"{k}{int(bool(v))}" for k, v in
                   (("cv", cv), ("flux", flux), ("sw", switching), ("st", stationary)))

    def run_variant(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces):
        return _run(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces, cv, flux, switching,
                    stationary)

    def rows_variant(P, start, stop, step, A, B, C, D, Baw, LP, SP, DP, SC, out):
        for i in range(start, stop, step):
            # np.bool_, not the literal False: the same _run as run_variant's
            # (a literal compiled run and its helpers a second time, ~3 s)
            M, _ = _run(P[i], A, B, C, D, Baw, LP, SP, DP, SC, np.bool_(False), cv, flux,
                        switching, stationary)
            # element by element: ``out[i] = M`` compiled numba's shape check and
            # its error message formatting (~1.2 s of cold compile)
            for j in range(N_METRICS):
                out[i, j] = M[j]

    entry = njit(cache=True, nogil=True, error_model="numpy")
    run_variant.__name__ = run_variant.__qualname__ = f"run_{tag}"
    rows_variant.__name__ = rows_variant.__qualname__ = f"rows_{tag}"
    return entry(run_variant), entry(rows_variant)


#: The compiled entry points ``(run, run_rows)`` of each variant
#: ``(cv, flux, switching, stationary)`` (:func:`variant`); each compiles on
#: its first call.
ENTRIES = {(cv, flux, sw, st): _entries(cv, flux, sw, st)
           for cv in (None, True) for flux in (None, True)
           for sw, st in ((None, None), (None, True), (True, None))}


@njit(cache=False, nogil=True, error_model="numpy")  # variant-dependent: _jit_variant
def _run(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces, cv, flux, switching, stationary):
    """:func:`run` of the variant ``(cv, flux, switching, stationary)`` (:func:`variant`;
    the flags None or True, constants of the caller): allocates the work
    arrays, runs :func:`_periods`, returns (metrics, traces)."""
    Ts = DP[DP_TS]
    n_per = int(round(SC[SC_DURATION] / Ts))
    mset = _metric_setup(SC)
    n = A.shape[1]
    acc_m = np.zeros(13)
    acc_m[_A_OUT5] = -1.0
    acc_m[_A_OUT2] = -1.0
    acc_m[_A_T10] = -1.0
    acc_m[_A_T90] = -1.0
    acc_m[_A_YEXT] = mset[2]  # overshoot 0 until y passes yf
    rng = np.zeros(1, dtype=np.uint64)
    rng[0] = np.uint64(int(SC[SC_SEED]))
    nbuf = int(DP[DP_DELAY]) + 1  # ring buffer of the computation delay
    trdec = max(int(SC[SC_TRACE_DECIM]), 1)
    tr = np.empty(((n_per + trdec - 1) // trdec if keep_traces else 0, N_TRACE))
    om_final = _periods(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces, n_per, mset, trdec,
                        np.zeros(n), np.zeros(n), np.zeros(n), acc_m, rng, np.zeros(nbuf),
                        np.zeros(nbuf), np.zeros(nbuf),
                        np.zeros(int(SC[SC_CURRENT_DELAY_D]) + 1),
                        np.zeros(int(SC[SC_CURRENT_DELAY_Q]) + 1), tr, cv, flux, switching,
                        stationary)
    return _finalise(acc_m, n_per, Ts, om_final, SC[SC_T_STEP], mset), tr


@_jit_no_rc_variant
def _periods(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces, n_per, mset, trdec, xd, xq,
             xn, acc_m, rng, vd_buf, vq_buf, ph_buf, cs_d, cs_q, tr, cv, flux, switching,
             stationary):
    """The ``n_per`` controller periods of :func:`run` (metric set-up ``mset``,
    a trace row every ``trdec`` periods) over its work arrays (law states
    ``xd``, ``xq``, scratch ``xn``; metric accumulators; RNG state; delay ring
    buffers of the voltage and its placement angle; current-sensor delay
    lines; traces); returns the final mechanical speed.

    One loop for every variant: ``cv``, ``flux``, ``switching``,
    ``stationary`` (None or the constant True, :func:`variant`) select the
    law, the plant state, the inverter and the average inverter's hold frame
    in branches ``is None`` that numba prunes before typing."""
    pl = _plant(P)
    p = pl[4]
    Ts = DP[DP_TS]
    delay = int(DP[DP_DELAY])
    r_hex = DP[DP_R_HEX]
    inverter = int(DP[DP_INVERTER])
    carrier = DP[DP_HALF_PERIODS] > 0.5
    h = SC[SC_H]
    mech = int(SC[SC_MECH])
    acc = SC[SC_ACC]
    omega0 = SC[SC_OMEGA0]
    tf_p = pl[7] * p  # reference torque: true tf p with the model's flux and inductances
    Ld_c = LP[LP_LD_C]
    Lq_c = LP[LP_LQ_C]
    flux_c = LP[LP_FLUX_C]
    # plant state id, iq, Omega, theta (a saturated motor: psi_d, psi_q, Omega,
    # theta; its currents are _currents(pl, x, flux))
    x = _initial_state(pl, omega0, flux)
    n_ts, dt_ts = _split(Ts, h)  # the plant steps of a period held constant
    nbuf = vd_buf.shape[0]
    # speed loop state
    sp_on = SP[SP_ENABLED] > 0.5
    sp_dec = max(int(SP[SP_DECIM]), 1)
    Tsp = Ts * sp_dec
    integ = 0.0
    e_prev = 0.0
    first_sp = True
    iqr_sp = 0.0
    # inverter bookkeeping, typed int64 from the start: with the literal 0, numba
    # compiled every callee once more for the literal's type (cold compile)
    conf_applied = np.int64(0)  # inverter state in force at the end of the last segment
    conf_next = np.int64(0)  # fcs with delay: state chosen last period, applied now
    conf_now = np.int64(0)
    t_comp = DP[DP_T_COMP]
    vd_app = 0.0
    vq_app = 0.0
    ph_app = 0.0
    for k in range(n_per):
        t = k * Ts
        xi = _currents(pl, x, flux)
        i_d_m, i_q_m, om_m = _sense(xi, rng, SC)
        i_d_m, i_q_m = _current_sensor(i_d_m, i_q_m, k, cs_d, cs_q, SC)
        w_m = p * om_m
        th_m = x[3]
        idr, iqr, sr = _references(t, SC)
        if sp_on:
            if k % sp_dec == 0:
                e = sr - om_m
                if first_sp:
                    e_prev = e
                    first_sp = False
                iqr_sp, integ = _speed_pid(e, e_prev, integ, Tsp, SP)
                e_prev = e
            iqr = iqr_sp
            idr = SC[SC_ID1]
        refs = (idr, iqr, sr, tf_p * (flux_c * iqr + (Ld_c - Lq_c) * idr * iqr))
        t_load = SC[SC_LOAD] if t >= SC[SC_LOAD_TIME] else 0.0
        fcs = False
        if switching is not None and inverter == 2:
            fcs = True
            # one call with a run-time flag, not two with the literals True and
            # False: each literal compiled a version of its own (cold compile)
            predict = delay >= 1
            choice = _fcs_choice(i_d_m, i_q_m, w_m, th_m, idr, iqr,
                                 conf_next if predict else conf_applied, predict, Ts,
                                 r_hex, LP)
            if predict:
                conf_now = conf_next
                conf_next = choice
            else:
                conf_now = choice
            va, vb = state_vector(conf_now, r_hex)
            vd_app, vq_app = _to_dq(va, vb, math.cos(th_m), math.sin(th_m))
        if not fcs:
            if cv is None:
                vd_s, vq_s, saturated = _law_step(A, B, C, D, Baw, xd, xq, xn, idr, iqr,
                                                  i_d_m, i_q_m, w_m, th_m, LP, DP)
            else:
                vd_s, vq_s, saturated = _cv_law_step(xd, xq, idr, iqr, i_d_m, i_q_m, w_m,
                                                     th_m, LP, DP)
            if saturated:
                acc_m[_A_SAT] += Ts
            slot = k % nbuf
            vd_buf[slot] = vd_s
            vq_buf[slot] = vq_s
            ph_buf[slot] = th_m + t_comp * w_m  # the firmware's placement angle
            if k >= delay:
                old = (k - delay) % nbuf
                vd_app = vd_buf[old]
                vq_app = vq_buf[old]
                ph_app = ph_buf[old]
            else:
                vd_app = 0.0
                vq_app = 0.0
                ph_app = 0.0
        if keep_traces and k % trdec == 0:
            row = k // trdec
            tr[row, 0] = t
            tr[row, 1] = xi[0]
            tr[row, 2] = xi[1]
            tr[row, 3] = vd_app
            tr[row, 4] = vq_app
            tr[row, 5] = x[2]
            tr[row, 6] = _torque_of_state(pl, x, flux)
            tr[row, 7] = idr
            tr[row, 8] = iqr
            tr[row, 9] = om_m
        # ---- plant over one period
        if switching is None:
            if stationary is None:
                # rotor-frame hold: the placement's error from the true mid-period angle
                err = ph_app - (x[3] + p * x[2] * Ts * 0.5)
                vx, vy = _to_ab(vd_app, vq_app, math.cos(err), math.sin(err))
                t, x = _advance_n(x, t, vx, vy, 0, n_ts, dt_ts, pl, t_load, mech, acc,
                                  omega0, acc_m, refs, mset, flux)
            else:  # held in the stationary frame at the placement angle
                vx, vy = _to_ab(vd_app, vq_app, math.cos(ph_app), math.sin(ph_app))
                t, x = _advance_n(x, t, vx, vy, 1, n_ts, dt_ts, pl, t_load, mech, acc,
                                  omega0, acc_m, refs, mset, flux)
        elif inverter == 1 and carrier:
            t, x, conf_applied = _carrier_period(x, t, k, vd_app, vq_app, ph_app,
                                                 conf_applied, h, pl, t_load, mech, acc,
                                                 omega0, acc_m, refs, mset, DP, flux)
        elif inverter == 1:
            t, x, conf_applied = _svm_period(x, t, vd_app, vq_app, ph_app, conf_applied, h,
                                             pl, t_load, mech, acc, omega0, acc_m, refs,
                                             mset, DP, flux)
        else:
            acc_m[_A_CELLS] += bit_changes(conf_applied, conf_now)
            conf_applied = conf_now
            vx, vy = state_vector(conf_now, r_hex)
            t, x = _advance_n(x, t, vx, vy, 1, n_ts, dt_ts, pl, t_load, mech, acc, omega0,
                              acc_m, refs, mset, flux)
    return x[2]



# ------------------------------------------------------------- disk cache
#: The sources compiled into this module's cached machine code. numba keys a
#: function's disk cache on the stamp of its own file and its own bytecode
#: only (a documented limitation, numba issue #1833): an edit of
#: ``_inverter.py`` (whose helpers are compiled into :func:`_periods` and
#: :func:`run`) or of ``_metrics.py`` (``METRIC_NAMES`` fixes the ``N_METRICS``
#: and ``M_*`` slots compiled in) left a checkout running the old kernel, and
#: its tests passing on it.
#: The kernel's own parts (``_kernel_*.py``, split from this module) are
#: compiled into it and read its slot constants: they are covered too, and
#: their cache indexes are dropped with this module's (:data:`_KERNEL_PARTS`).
KERNEL_SOURCES = ("_kernel.py", "_inverter.py", "_metrics.py", "_kernel_layout.py",
                  "_kernel_plant.py", "_kernel_metrics.py", "_kernel_steps.py",
                  "_kernel_pwm.py", "_kernel_cv.py", "_kernel_sense.py")
#: Modules whose numba cache indexes depend on :data:`KERNEL_SOURCES` beyond
#: their own file (``_inverter`` is self-contained).
_KERNEL_PARTS = ("_kernel", "_kernel_plant", "_kernel_metrics", "_kernel_steps",
                 "_kernel_pwm", "_kernel_cv", "_kernel_sense")


def sources_digest() -> str:
    """Key of :data:`KERNEL_SOURCES` (``toolbox._cache.cache_key``: their
    contents and numba's version)."""
    here = Path(__file__).parent
    return cache_key([here / name for name in KERNEL_SOURCES], packages=("numba",))


def _drop_stale_cache(cache_dir: Path) -> None:
    """Remove this module's numba cache indexes and its parts'
    (:data:`_KERNEL_PARTS`) from ``cache_dir`` when the
    :func:`sources_digest` recorded there is another (numba's own workaround,
    deleting the cache, limited to what depends on the sources); the next
    call compiles and caches afresh. ``_inverter``'s own indexes stay: they
    are keyed on their own file. A cache directory that cannot be read or
    written is left alone (numba then caches nowhere else either).

    Not covered: a process started before an edit of ``_inverter.py`` or
    ``_metrics.py`` alone that compiles a new signature afterwards saves its
    old code under numba's unchanged stamp of ``_kernel.py``."""
    digest = sources_digest()
    stamp = cache_dir / "_kernel.sources.key"
    try:
        if stamp.is_file() and stamp.read_text() == digest:
            return
        for part in _KERNEL_PARTS:
            for index in cache_dir.glob(f"{part}.*.nbi"):
                index.unlink(missing_ok=True)
        write_atomic(stamp, digest)
    except OSError:
        pass


_ENTRY = ENTRIES[(None, None, None, None)][0]
if hasattr(_ENTRY, "stats"):        # a numba dispatcher (not a plain function: NUMBA_DISABLE_JIT=1)
    _drop_stale_cache(Path(_ENTRY.stats.cache_path))

