"""Packed-array layouts of the simulation kernel (the one declaration of every
slot, the index constants written out, the accumulator slots) and the
decorators its functions are compiled with.
"""

from __future__ import annotations

import math

from numba import njit

from ._metrics import METRIC_NAMES

# ---- packed-array layouts: the one declaration of every slot ----------------
#: Slot names of each packed parameter array, in order, keyed by the array's
#: prefix: plant ``P`` (true motor), law ``LP`` (controller model, decoupling
#: flags, paper 002 criterion (23) weights; ``cv`` 1 for the complex-vector law
#: of method ``cv`` with its poles ``cv_pc``, ``cv_pi``, ``cv_pd`` and its
#: design delay ``cv_d``, ``_kernel_cv``), speed loop ``SP``, drive ``DP``
#: (``vlim``: 0 none, 1 circle, 2 hexagon; ``inverter``: 0 average, 1 svm,
#: 2 fcs_mpc; ``half_periods``: carrier half periods per sample of the svm
#: inverter, 0 = one centred pattern per sample; ``hold``: frame in which the
#: average inverter holds the voltage, 0 rotor dq, 1 stationary; ``t_comp``: the
#: voltage placement's compensation time, s; ``vprio``: voltage-limit priority,
#: 0 radial, 1 d axis) and scenario ``SC``. The plant's ``magnetic`` slot is 0
#: for constant parameters (state: currents) and 1 for a saturated motor
#: (state: flux linkages), whose current-from-flux table
#: (``toolbox.spec.MagneticModel.inverse_table``) follows the named slots
#: in the same array (:data:`N_P` on). ``_simulate._pack*`` fill them by name
#: through :func:`pack_indices`.
LAYOUTS: dict[str, tuple[str, ...]] = {
    "P": ("R", "Ld", "Lq", "flux", "pole_pairs", "J", "friction", "torque_factor",
          "magnetic"),
    "LP": ("R_c", "Ld_c", "Lq_c", "flux_c", "cross", "emf", "alpha", "beta", "gamma",
           "cv", "cv_pc", "cv_pi", "cv_pd", "cv_d"),
    "SP": ("enabled", "kp", "ki", "kd", "decim", "iq_limit"),
    "DP": ("Ts", "delay", "vlim", "v_max", "r_hex", "inverter", "half_periods", "hold",
           "t_comp", "vprio"),
    "SC": ("duration", "mech", "omega0", "acc", "id0", "iq0", "id1", "iq1",
           "t_step", "speed0", "speed1", "load", "load_time", "iq_amp", "f_sin",
           "ref_mode", "signal", "gain", "offset", "speed_noise", "noise_kind",
           "current_noise", "current_quantum", "seed", "h", "trace_decim",
           "current_gain_d", "current_gain_q", "current_delay_d", "current_delay_q"),
}

# The slot constants ``<PREFIX>_<NAME>`` (e.g. ``P_LD``, ``SC_T_STEP``) and the
# metric slots ``M_<NAME>`` (``_metrics.METRIC_NAMES``), written out: numba
# reads module-level ints as compile-time constants, so named slots cost
# nothing over literal positions. tests/sim/test_kernel_layout.py checks that
# they are the positions in LAYOUTS and METRIC_NAMES, one constant per slot.
P_R = 0
P_LD = 1
P_LQ = 2
P_FLUX = 3
P_POLE_PAIRS = 4
P_J = 5
P_FRICTION = 6
P_TORQUE_FACTOR = 7
P_MAGNETIC = 8

LP_R_C = 0
LP_LD_C = 1
LP_LQ_C = 2
LP_FLUX_C = 3
LP_CROSS = 4
LP_EMF = 5
LP_ALPHA = 6
LP_BETA = 7
LP_GAMMA = 8
LP_CV = 9
LP_CV_PC = 10
LP_CV_PI = 11
LP_CV_PD = 12
LP_CV_D = 13

SP_ENABLED = 0
SP_KP = 1
SP_KI = 2
SP_KD = 3
SP_DECIM = 4
SP_IQ_LIMIT = 5

DP_TS = 0
DP_DELAY = 1
DP_VLIM = 2
DP_V_MAX = 3
DP_R_HEX = 4
DP_INVERTER = 5
DP_HALF_PERIODS = 6
DP_HOLD = 7
DP_T_COMP = 8
DP_VPRIO = 9

SC_DURATION = 0
SC_MECH = 1
SC_OMEGA0 = 2
SC_ACC = 3
SC_ID0 = 4
SC_IQ0 = 5
SC_ID1 = 6
SC_IQ1 = 7
SC_T_STEP = 8
SC_SPEED0 = 9
SC_SPEED1 = 10
SC_LOAD = 11
SC_LOAD_TIME = 12
SC_IQ_AMP = 13
SC_F_SIN = 14
SC_REF_MODE = 15
SC_SIGNAL = 16
SC_GAIN = 17
SC_OFFSET = 18
SC_SPEED_NOISE = 19
SC_NOISE_KIND = 20
SC_CURRENT_NOISE = 21
SC_CURRENT_QUANTUM = 22
SC_SEED = 23
SC_H = 24
SC_TRACE_DECIM = 25
SC_CURRENT_GAIN_D = 26
SC_CURRENT_GAIN_Q = 27
SC_CURRENT_DELAY_D = 28
SC_CURRENT_DELAY_Q = 29

M_RESPONSE_TIME_5PCT = 0
M_RISE_TIME_10_90 = 1
M_SETTLING_TIME_2PCT = 2
M_OVERSHOOT_PCT = 3
M_STATIC_ERROR = 4
M_MSE_TORQUE = 5
M_MSE_ID = 6
M_COMMUTATIONS_PER_S = 7
M_CELL_TRANSITIONS_PER_S = 8
M_SATURATION_TIME = 9
M_FINAL_VALUE = 10
M_MSE_IQ = 11
M_FINAL_SPEED = 12

_SQ3_2 = math.sqrt(3.0) / 2.0

#: Length of the named part of the plant array; a saturated motor's table
#: starts here.
N_P = len(LAYOUTS["P"])

#: Length of the scenario array.
N_SC = len(LAYOUTS["SC"])
#: Metrics (raw kernel output order: ``_metrics.METRIC_NAMES``, the one
#: declaration; written through the slot constants ``M_<NAME>``, e.g.
#: ``M_OVERSHOOT_PCT``).
N_METRICS = len(METRIC_NAMES)
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
#: :data:`_jit` and :data:`_jit_no_rc` without the disk cache, for the functions
#: whose signatures depend on the kernel's variant (flags, hold frame). numba
#: numbers a cache entry's data file by the count of entries in the index it
#: read: processes compiling different signatures of one function at once
#: (xdist or Dask workers; two ``cct design`` runs of different methods)
#: wrote the same file, and an index then named another signature's machine
#: code (numba's "descr is NULL" on return, or a wrong kernel). Each variant's
#: entry point (``_kernel.ENTRIES``) is cached whole, under a name of its own.
_jit_variant = njit(cache=False, error_model="numpy")
_jit_no_rc_variant = njit(cache=False, error_model="numpy", _nrt=False)
