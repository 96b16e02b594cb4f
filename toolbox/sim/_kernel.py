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
``SC_DURATION``, ...) are generated from that declaration and
:func:`pack_indices` gives the same map to the Python side that fills the
arrays (``_simulate._pack``). :func:`run` allocates the work
arrays and :func:`_periods` runs the periods, a short loop over small
``@njit`` helpers (sensors, references, speed loop, law step with
anti-windup and voltage limit, predictive choice, inverter and plant RK4);
the plant state lives in local scalars, not in an array, so that LLVM keeps
it in registers across the RK4 stages.

Loop structure (gcc -O3 -march=native's plain C loop of the same
arithmetic, ``tests/benchmarks/bench_sim.py``, is the yardstick: both are
bound by the latency of the RK4 chain, ~100 cycles per plant step, so what
ours adds must stay off that chain and out of its way):

* the period loop and the plant steps are compiled without numba's
  reference counting (:data:`_jit_no_rc`): its increfs and decrefs are
  atomic read-modify-writes, full memory barriers that kept a period's
  plant steps from overlapping the previous period's;
* the online metrics are kept in local values over a run of steps
  (:func:`_load_acc`), with no division per step (:func:`_overshoot`), and
  are accumulated after the step's RK4 stages in program order;
* the periods without load torque have a loop of their own, without the
  load's ``- 0.0`` on the speed's chain (:func:`_steps`); the step
  split of a period (:func:`_split`) is computed once per run.

All of it leaves every result bit for bit as it was. What is left is the
chain itself: its longest path through one step, with this machine's
latencies (multiply 3 cycles, add 2, ~1 more per add/multiply hand-over,
measured), is ~93 cycles; the loop runs at ~99 (~25.3 ns), gcc's at ~102
(~26.2 ns).
Tried without gain (measured alternately, same bits): ``mech`` as a
compile-time constant (no branch per stage, but ~3 % slower: LLVM then
interleaves the stages differently), the derivatives in another order, not
advancing the angle where nothing reads it (rotor-frame hold without the
hexagon limit), and, as an experiment, no metrics at all (same time: they
are off the chain).

Arithmetic. The 1 us loop is bound by the latency of one
dependency chain (the four RK4 stages in sequence, each ending in a
division), so the plant multiplies by ``1/Ld``, ``1/Lq``, ``1/J`` computed once
per run (:func:`_plant`) instead of dividing: a division costs ~13 cycles, a
multiplication 3, and the loop runs ~30 % faster. Each derivative then
carries one more rounding (<= 1 ulp instead of 0.5), 1e-16 relative, far below
the RK4 truncation error; results moved by that much once, when this was
introduced, and are plain IEEE operations in a fixed order, the same on every
x86-64 CPU. No ``fastmath``: ``{"contract"}`` on the substep loop (FMA) saved
another 9 % when it was tried (29.1 -> 26.5 ns per step), and is deterministic run to run,
but whether LLVM may fuse depends on the host CPU (the numba cache is
compiled for it), so verify.json's digits of the dq-frame scenarios would
differ between machines with and without FMA, which today they do not
("same spec, same bytes", toolbox/ARCHITECTURE.md).
(The angle-dependent scenarios already differ there in the last bits: glibc
picks FMA variants of sin, cos, log by CPU, which numba calls: with FMA
disabled through GLIBC_TUNABLES, 1 in 1,300 sines differed by 1 ulp.)
``reassoc``/``arcp`` would let LLVM choose the evaluation order; the flags
that assume finite values ("nnan", "ninf") would break the divergence
detection of the metrics.

Cold compile. A process without a numba cache (a fresh clone,
each pytest-xdist worker) compiles :func:`run` on its first call; what it
compiles is kept to what the speed needs:

* a batch reuses :func:`run`'s compiled code from one thread per core
  (:func:`run_rows`, ~0.5 s), where a ``prange`` entry point compiled ~5 s
  more per process;
* one version of each helper, except the plant loop :func:`_steps` (four:
  ``frame`` and ``loaded``). Numba types a call from compiled code with the
  arguments' literal types, so a literal argument (``False``, ``0``, or a
  variable whose first value is ``0``) compiled a version of the callee of
  its own, and the helpers below it again;
* :func:`_steps` is a compiled function, not inlined in numba's IR: numba
  copies an inlined callee's IR block by block, each block with all the
  callee's variables, ~1 s per copy of the loop.

Measured (CPU s, fresh cache, median of 3 alternated with the code before):
:func:`run` 13.0 -> 10.5, a batch's own 5.2 -> 0.5 (``simulate_batch``'s
first call, :func:`run` already compiled); the plant loop as fast as before
(``bench_sim``).

Metrics are accumulated online (see :mod:`toolbox.sim._metrics` for their
definitions); traces are optional and decimated, so memory is flat in the
simulated duration when only metrics are requested.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numba import njit

from .._cache import cache_key
from .._io import write_atomic
from ._inverter import bit_changes, hexagon_scale, state_vector, svm_times
from ._metrics import METRIC_NAMES

__all__ = ["run", "run_rows", "N_METRICS", "N_TRACE", "N_SC", "LAYOUTS", "pack_indices",
           "KERNEL_SOURCES", "sources_digest"]

# ---- packed-array layouts: the one declaration of every slot ----------------
#: Slot names of each packed parameter array, in order, keyed by the array's
#: prefix: plant ``P`` (true motor), law ``LP`` (controller model, decoupling
#: flags, paper 002 criterion (23) weights), speed loop ``SP``, drive ``DP``
#: (``vlim``: 0 none, 1 circle, 2 hexagon; ``inverter``: 0 average, 1 svm,
#: 2 fcs_mpc; ``half_periods``: carrier half periods per sample of the svm
#: inverter, 0 = one centred pattern per sample; ``hold``: frame in which the
#: average inverter holds the voltage, 0 rotor dq, 1 stationary; ``t_comp``: the
#: voltage placement's compensation time, s; ``vprio``: voltage-limit priority,
#: 0 radial, 1 d axis) and scenario ``SC``. ``_simulate._pack*`` fill them by name
#: through :func:`pack_indices`.
LAYOUTS: dict[str, tuple[str, ...]] = {
    "P": ("R", "Ld", "Lq", "flux", "pole_pairs", "J", "friction", "torque_factor"),
    "LP": ("R_c", "Ld_c", "Lq_c", "flux_c", "cross", "emf", "alpha", "beta", "gamma"),
    "SP": ("enabled", "kp", "ki", "kd", "decim", "iq_limit"),
    "DP": ("Ts", "delay", "vlim", "v_max", "r_hex", "inverter", "half_periods", "hold",
           "t_comp", "vprio"),
    "SC": ("duration", "mech", "omega0", "acc", "id0", "iq0", "id1", "iq1",
           "t_step", "speed0", "speed1", "load", "load_time", "iq_amp", "f_sin",
           "ref_mode", "signal", "gain", "offset", "speed_noise", "noise_kind",
           "current_noise", "current_quantum", "seed", "h", "trace_decim",
           "current_gain_d", "current_gain_q", "current_delay_d", "current_delay_q"),
}

# Generated module constants ``<PREFIX>_<NAME>`` (e.g. ``P_LD``, ``SC_T_STEP``):
# numba reads module-level ints as compile-time constants, so named slots cost
# nothing over literal positions.
for _prefix, _names in LAYOUTS.items():
    globals().update({f"{_prefix}_{_n.upper()}": _i for _i, _n in enumerate(_names)})
del _prefix, _names

_SQ3_2 = math.sqrt(3.0) / 2.0

#: Length of the scenario array.
N_SC = len(LAYOUTS["SC"])
#: Metrics (raw kernel output order: ``_metrics.METRIC_NAMES``, the one
#: declaration; written through the generated slots ``M_<NAME>``, e.g.
#: ``M_OVERSHOOT_PCT``).
N_METRICS = len(METRIC_NAMES)
globals().update({f"M_{_n.upper()}": _i for _i, _n in enumerate(METRIC_NAMES)})
#: Trace columns: t, id, iq, vd, vq, speed (mech rad/s), torque, id_ref,
#: iq_ref, speed_measured.
N_TRACE = 10

# accumulator slots of the online metrics
_A_OUT5, _A_OUT2, _A_T10, _A_T90, _A_YEXT, _A_SQT, _A_SQID, _A_STAT, _A_STATT, \
    _A_FINAL, _A_SQIQ, _A_CELLS, _A_SAT = range(13)


def pack_indices(array: str = "SC") -> dict[str, int]:
    """Slot names of a packed kernel array, as a dict name -> index.

    Parameters
    ----------
    array : {"SC", "P", "LP", "SP", "DP"}
        Which array (see :data:`LAYOUTS`); the scenario by default.
    """
    return {n: i for i, n in enumerate(LAYOUTS[array])}


#: Decorator of the kernel's functions. ``error_model="numpy"``: a division by
#: zero gives inf/nan (IEEE) instead of a Python ZeroDivisionError, which drops
#: a compare-and-branch before every division of the 1 us loop; every divisor
#: there is a validated positive parameter or guarded. Cached on
#: disk although :func:`run`'s cache holds every helper's code: the tests
#: call helpers and ``run.py_func`` from Python, which compiled each helper
#: again in every process without it (~10 s of the kernel's test files).
_jit = njit(cache=True, error_model="numpy")
#: The helpers of the 1 us substep loop, inlined into it in numba's IR: called
#: as separate functions, each RK4 step passed ~20 arguments through the stack
#: and returned its state through memory (43.3 -> 41.5 ns per step).
#: The law step too, once per period (its fixed cost per period ~170 -> ~110 ns),
#: and every helper of the period loop that reads an array: called from the
#: loop compiled without reference counting (:data:`_jit_no_rc`), a function
#: would incref and decref its array arguments itself.
_jit_inline = njit(cache=True, error_model="numpy", inline="always")
#: The period loop (:func:`_periods`) and the plant steps (:func:`_steps`):
#: compiled without numba's reference counting (they allocate nothing; every
#: array is :func:`run`'s). With it, each array passed to a helper or used by
#: an inlined one was increfed and decrefed around the use, ~20 atomic
#: read-modify-writes per period, each a full memory barrier that kept the
#: next period's plant steps from starting before the previous ones had
#: retired: ~60-80 ns per period, 0.6-0.8 ns per plant step at 100 steps per
#: period.
_jit_no_rc = njit(cache=True, error_model="numpy", _nrt=False)


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
    multiplies instead of dividing (module docstring, "Arithmetic")."""
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
    """Right-hand side of the plant (module docstring); frame 1: (vx, vy) stationary."""
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
    out5, out2, t10, t90, yext, sqt, sqid, stat, statt, final, sqiq = m
    idr, iqr, sr, tref = refs
    sig, y0, yf, t_stat, t_step = mset
    e_t = _torque(pl, i_d, i_q) - tref
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


@_jit_inline
def _advance(x, t, vx, vy, frame, dur, h, pl, t_load, mech, acc, omega0, acc_m, refs,
             mset):
    """Integrate the state x = (id, iq, Omega, theta) over ``dur`` with ceil(dur/h)
    equal RK4 steps; returns (new time, new state)."""
    if dur <= 0.0:
        return t, x
    n, dt = _split(dur, h)
    return _advance_n(x, t, vx, vy, frame, n, dt, pl, t_load, mech, acc, omega0, acc_m,
                      refs, mset)


@_jit_inline
def _split(dur, h):
    """(n, dt): the ``n = ceil(dur / h)`` equal plant steps of length dt over ``dur``."""
    n = int(math.ceil(dur / h - 1e-9))
    if n < 1:
        n = 1
    return n, dur / n


@_jit_inline
def _advance_n(x, t, vx, vy, frame, n, dt, pl, t_load, mech, acc, omega0, acc_m, refs,
               mset):
    """:func:`_advance` over ``n`` steps of length ``dt`` (:func:`_split`).

    Two compiled loops (:func:`_steps`): with and without a load torque, the
    latter with the constant 0 (LLVM does not unswitch a loop this large
    itself). Inlined into its callers, so that the loop is one call away from
    the period loop, as it was when both loops were inlined here: numba
    copied the loop's inlined IR into each of them, ~1 s of cold compile
    each."""
    if t_load == 0.0 or mech == 1:
        return _steps(x, t, n, dt, vx, vy, frame, pl, t_load, False, mech, acc, omega0,
                      acc_m, refs, mset)
    return _steps(x, t, n, dt, vx, vy, frame, pl, t_load, True, mech, acc, omega0, acc_m,
                  refs, mset)


@_jit_no_rc
def _steps(x, t, n, dt, vx, vy, frame, pl, t_load, loaded, mech, acc, omega0, acc_m, refs,
           mset):
    """``n`` RK4 steps of length dt with the metrics accumulated at the start of
    each; returns (time, state).

    ``loaded`` is a literal (one compiled version each, as ``frame``): False
    integrates without the load torque, with the constant 0 in its place:
    ``x - 0.0`` is x exactly, so LLVM drops the subtraction, the last one
    before the multiplication by 1/J on the speed's dependency chain (~4 % of
    the plant step's latency)."""
    t_load = t_load if loaded else 0.0
    m = _load_acc(acc_m)
    for _ in range(n):
        x1 = _rk4(x[0], x[1], x[2], x[3], vx, vy, frame, dt, pl, t_load, mech, acc)
        # the metrics of the step's start state after its RK4 stages in program
        # order: the out-of-order core runs the oldest ready instruction first,
        # so the step's own stages (the dependency chain) win the execution
        # ports over the metrics that become ready with them
        m = _accumulate(m, x[0], x[1], x[2], t, dt, pl, refs, mset)
        x = x1
        t += dt
    if mech == 1:  # imposed speed: remove the round-off drift of the integral
        x = (x[0], x[1], omega0 + acc * t, x[3])
    _store_acc(acc_m, m)
    return t, x


# ------------------------------------------------------------------- controller
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
def _d_priority_hexagon(vd_u, vq_u, c0, s0, r_hex):
    """d-axis priority inside the SVM hexagon of vertex radius ``r_hex`` seen
    in a dq frame at the angle whose cos, sin are ``c0``, ``s0``: ``v_d`` clamped
    to the hexagon's d extent, then ``v_q`` clipped into the chord at that ``v_d``.

    The hexagon is ``|n_k . v_ab| <= a`` (apothem ``a = r_hex sqrt(3)/2``, edge
    normals at 30, 90, 150 deg); in dq the normal at ``alpha`` is
    ``(cos(alpha - theta), sin(alpha - theta))``. The d extent is the support
    function ``r_hex max_j |cos(theta - 60 j deg)|`` (vertices at 0, 60, 120 deg).
    """
    a = r_hex * _SQ3_2
    # d extent: vertices at 0, 60, 120 deg (and their opposites)
    d_max = r_hex * max(abs(c0), abs(0.5 * c0 + _SQ3_2 * s0), abs(-0.5 * c0 + _SQ3_2 * s0))
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
def _voltage_limit(vd_u, vq_u, th_m, w_m, DP):
    """Saturated dq voltage: circle of radius v_max, or the SVM hexagon at the
    angle where the voltage is placed (theta + t_comp w).

    ``vprio`` 0 (radial): ``v_dq`` scaled radially onto the limit. ``vprio`` 1
    (d-axis priority, the limiter of field-weakening drives, Briz et al.,
    IEEE Trans. Ind. Appl. 37(1) 2001): ``v_d`` kept (clamped to the limit's
    d extent), ``v_q`` gets the rest, ``sign(v_q) sqrt(v_max^2 - v_d^2)`` on
    the circle, the chord of the hexagon at that ``v_d`` otherwise.
    """
    vlim = int(DP[DP_VLIM])
    prio = int(DP[DP_VPRIO])
    if vlim == 1:
        v_max = DP[DP_V_MAX]
        if prio == 1:
            vd = min(max(vd_u, -v_max), v_max)
            q_max = math.sqrt(max(v_max * v_max - vd * vd, 0.0))
            return vd, min(max(vq_u, -q_max), q_max)
        mag = math.hypot(vd_u, vq_u)
        if mag > v_max:
            return vd_u * v_max / mag, vq_u * v_max / mag
    elif vlim == 2:
        thc = th_m + w_m * DP[DP_T_COMP]
        if prio == 1:
            return _d_priority_hexagon(vd_u, vq_u, math.cos(thc), math.sin(thc),
                                       DP[DP_R_HEX])
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
    vd_s, vq_s = _voltage_limit(vd_u, vq_u, th_m, w_m, DP)
    _update(A, B, Baw, 0, xd, xn, idr, i_d_m, vd_s - vd_u)
    _update(A, B, Baw, 1, xq, xn, iqr, i_q_m, vq_s - vq_u)
    return vd_s, vq_s, (vd_s != vd_u or vq_s != vq_u)


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


@_jit
def _svm_period(x, t, vd, vq, phi, conf, h, pl, t_load, mech, acc, omega0, acc_m,
                refs, mset, DP):
    """One period of space-vector modulation, paper 002 eq (21)-(22): the symmetric
    centred pattern 0-k-l-7-l-k-0 (six cell commutations) of ``v_dq`` placed at
    the angle ``phi``, the plant integrated segment by segment. Returns (time,
    state, inverter state at the end)."""
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
                        acc_m, refs, mset)
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


@_jit
def _carrier_half(x, t, dts, rising, conf, th_dur, h, pl, t_load, mech, acc, omega0,
                  acc_m, refs, mset, r_hex):
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
                        acc_m, refs, mset)
        t_prev = tj
        conf ^= 4 >> leg
        acc_m[_A_CELLS] += 1
    vx, vy = state_vector(conf, r_hex)
    t, x = _advance(x, t, vx, vy, 1, th_dur - t_prev, h, pl, t_load, mech, acc, omega0,
                    acc_m, refs, mset)
    return t, x, conf


@_jit
def _carrier_period(x, t, k, vd, vq, phi, conf, h, pl, t_load, mech, acc, omega0,
                    acc_m, refs, mset, DP):
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
                                   acc, omega0, acc_m, refs, mset, r_hex)
    return t, x, conf


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


# ------------------------------------------------------------------ simulation
@njit(cache=True, nogil=True, error_model="numpy")
def run(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces):
    """One closed-loop simulation (releases the GIL, as :func:`run_rows`).

    Parameters (all float64 arrays, filled by ``_simulate._pack*``; slots in
    :data:`LAYOUTS`)
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
    DP : (8,)
        Ts (s), delay (periods), limit kind, circle radius (V), hexagon
        vertex radius (V), inverter kind, carrier half periods per sample
        (0: one centred SVM pattern per sample), hold frame of the average
        inverter (0 rotor, 1 stationary).
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
                        np.zeros(int(SC[SC_CURRENT_DELAY_Q]) + 1), tr)
    return _finalise(acc_m, n_per, Ts, om_final, SC[SC_T_STEP], mset), tr


@_jit_no_rc
def _periods(P, A, B, C, D, Baw, LP, SP, DP, SC, keep_traces, n_per, mset, trdec, xd, xq,
             xn, acc_m, rng, vd_buf, vq_buf, ph_buf, cs_d, cs_q, tr):
    """The ``n_per`` controller periods of :func:`run` (metric set-up ``mset``,
    a trace row every ``trdec`` periods) over its work arrays (law states
    ``xd``, ``xq``, scratch ``xn``; metric accumulators; RNG state; delay ring
    buffers of the voltage and its placement angle; current-sensor delay
    lines; traces); returns the final mechanical speed."""
    pl = _plant(P)
    p = pl[4]
    Ts = DP[DP_TS]
    delay = int(DP[DP_DELAY])
    r_hex = DP[DP_R_HEX]
    inverter = int(DP[DP_INVERTER])
    carrier = DP[DP_HALF_PERIODS] > 0.5
    hold = int(DP[DP_HOLD])
    h = SC[SC_H]
    mech = int(SC[SC_MECH])
    acc = SC[SC_ACC]
    omega0 = SC[SC_OMEGA0]
    tf_p = pl[7] * p  # reference torque: true tf p with the model's flux and inductances
    Ld_c = LP[LP_LD_C]
    Lq_c = LP[LP_LQ_C]
    flux_c = LP[LP_FLUX_C]
    x = (0.0, 0.0, omega0, 0.0)  # plant state id, iq, Omega, theta
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
        i_d_m, i_q_m, om_m = _sense(x, rng, SC)
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
        if inverter == 2:
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
        else:
            vd_s, vq_s, saturated = _law_step(A, B, C, D, Baw, xd, xq, xn, idr, iqr,
                                              i_d_m, i_q_m, w_m, th_m, LP, DP)
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
            tr[row, 1] = x[0]
            tr[row, 2] = x[1]
            tr[row, 3] = vd_app
            tr[row, 4] = vq_app
            tr[row, 5] = x[2]
            tr[row, 6] = _torque(pl, x[0], x[1])
            tr[row, 7] = idr
            tr[row, 8] = iqr
            tr[row, 9] = om_m
        # ---- plant over one period
        if inverter == 0 and hold == 0:
            # rotor-frame hold: the placement's error from the true mid-period angle
            err = ph_app - (x[3] + p * x[2] * Ts * 0.5)
            vx, vy = _to_ab(vd_app, vq_app, math.cos(err), math.sin(err))
            t, x = _advance_n(x, t, vx, vy, 0, n_ts, dt_ts, pl, t_load, mech, acc,
                              omega0, acc_m, refs, mset)
        elif inverter == 0:  # held in the stationary frame at the placement angle
            vx, vy = _to_ab(vd_app, vq_app, math.cos(ph_app), math.sin(ph_app))
            t, x = _advance_n(x, t, vx, vy, 1, n_ts, dt_ts, pl, t_load, mech, acc, omega0,
                              acc_m, refs, mset)
        elif inverter == 1 and carrier:
            t, x, conf_applied = _carrier_period(x, t, k, vd_app, vq_app, ph_app,
                                                 conf_applied, h, pl, t_load, mech, acc,
                                                 omega0, acc_m, refs, mset, DP)
        elif inverter == 1:
            t, x, conf_applied = _svm_period(x, t, vd_app, vq_app, ph_app, conf_applied,
                                             h, pl, t_load, mech, acc, omega0, acc_m,
                                             refs, mset, DP)
        else:
            acc_m[_A_CELLS] += bit_changes(conf_applied, conf_now)
            conf_applied = conf_now
            vx, vy = state_vector(conf_now, r_hex)
            t, x = _advance_n(x, t, vx, vy, 1, n_ts, dt_ts, pl, t_load, mech, acc, omega0,
                              acc_m, refs, mset)
    return x[2]


@njit(cache=True, nogil=True, error_model="numpy")
def run_rows(P, start, stop, step, A, B, C, D, Baw, LP, SP, DP, SC, out):
    """Metrics of the simulations of the plants ``P[start:stop:step]`` into the
    same rows of ``out`` (N, N_METRICS): one thread's share of a batch
    (``_simulate.simulate_batch`` runs one per core).

    One call per share, not one per simulation: each return to Python hands
    the GIL between the threads, ~5 % of a batch of 20 ms simulations.
    Parameters as for :func:`run`, ``P`` (N, 8) one plant per row.
    """
    for i in range(start, stop, step):
        # np.bool_, not the literal False: a literal compiled run and its
        # helpers a second time (~3 s of cold compile)
        M, _ = run(P[i], A, B, C, D, Baw, LP, SP, DP, SC, np.bool_(False))
        # element by element: ``out[i] = M`` compiled numba's shape check and
        # its error message formatting (~1.2 s of cold compile)
        for j in range(N_METRICS):
            out[i, j] = M[j]


# ------------------------------------------------------------- disk cache
#: The sources compiled into this module's cached machine code. numba keys a
#: function's disk cache on the stamp of its own file and its own bytecode
#: only (a documented limitation, numba issue #1833): an edit of
#: ``_inverter.py`` (whose helpers are compiled into :func:`_periods` and
#: :func:`run`) or of ``_metrics.py`` (``METRIC_NAMES`` fixes the ``N_METRICS``
#: and ``M_*`` slots compiled in) left a checkout running the old kernel, and
#: its tests passing on it.
KERNEL_SOURCES = ("_kernel.py", "_inverter.py", "_metrics.py")


def sources_digest() -> str:
    """Key of :data:`KERNEL_SOURCES` (``toolbox._cache.cache_key``: their
    contents and numba's version)."""
    here = Path(__file__).parent
    return cache_key([here / name for name in KERNEL_SOURCES], packages=("numba",))


def _drop_stale_cache(cache_dir: Path) -> None:
    """Remove this module's numba cache indexes from ``cache_dir`` when the
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
        for index in cache_dir.glob("_kernel.*.nbi"):
            index.unlink(missing_ok=True)
        write_atomic(stamp, digest)
    except OSError:
        pass


if hasattr(run, "stats"):        # a numba dispatcher (not a plain function: NUMBA_DISABLE_JIT=1)
    _drop_stale_cache(Path(run.stats.cache_path))
