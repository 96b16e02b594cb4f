"""Packed-array layouts of the simulation kernel (the one declaration of every
slot, the generated index constants, the accumulator slots) and the
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

# Generated module constants ``<PREFIX>_<NAME>`` (e.g. ``P_LD``, ``SC_T_STEP``):
# numba reads module-level ints as compile-time constants, so named slots cost
# nothing over literal positions.
for _prefix, _names in LAYOUTS.items():
    globals().update({f"{_prefix}_{_n.upper()}": _i for _i, _n in enumerate(_names)})
del _prefix, _names

_SQ3_2 = math.sqrt(3.0) / 2.0

#: Length of the named part of the plant array; a saturated motor's table
#: starts here.
N_P = len(LAYOUTS["P"])

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
