"""Plant integration of the simulation kernel: a run of equal RK4 steps over a
duration, the online metrics accumulated at the start of each.
"""

from __future__ import annotations

import math

from ._kernel_layout import _jit_inline, _jit_no_rc_variant
from ._kernel_plant import _current_of_flux, _rk4, _rk4_flux
from ._kernel_metrics import _accumulate, _accumulate_torque, _load_acc, _store_acc


@_jit_inline
def _advance(x, t, vx, vy, frame, dur, h, pl, t_load, mech, acc, omega0, acc_m, refs,
             mset, flux):
    """Integrate the state x = (id, iq, Omega, theta) over ``dur`` with ceil(dur/h)
    equal RK4 steps; returns (new time, new state)."""
    if dur <= 0.0:
        return t, x
    n, dt = _split(dur, h)
    return _advance_n(x, t, vx, vy, frame, n, dt, pl, t_load, mech, acc, omega0, acc_m,
                      refs, mset, flux)


@_jit_inline
def _split(dur, h):
    """(n, dt): the ``n = ceil(dur / h)`` equal plant steps of length dt over ``dur``."""
    n = int(math.ceil(dur / h - 1e-9))
    if n < 1:
        n = 1
    return n, dur / n


@_jit_inline
def _advance_n(x, t, vx, vy, frame, n, dt, pl, t_load, mech, acc, omega0, acc_m, refs,
               mset, flux):
    """:func:`_advance` over ``n`` steps of length ``dt`` (:func:`_split`).

    Two compiled loops (:func:`_steps`): with and without a load torque, the
    latter with the constant 0 (LLVM does not unswitch a loop this large
    itself). Inlined into its callers, so that the loop is one call away from
    the period loop, as it was when both loops were inlined here: numba
    copied the loop's inlined IR into each of them, ~1 s of cold compile
    each. A saturated motor (``flux`` the constant True, the kernel's variant
    flag: ``_kernel``, "Variants") integrates its flux linkages in a loop of
    its own (:func:`_steps_flux`), so the constant-parameter loops are
    unchanged; with ``flux`` None numba prunes that branch and never
    compiles it."""
    if flux is None:
        if t_load == 0.0 or mech == 1:
            return _steps(x, t, n, dt, vx, vy, frame, pl, t_load, False, mech, acc, omega0,
                          acc_m, refs, mset)
        return _steps(x, t, n, dt, vx, vy, frame, pl, t_load, True, mech, acc, omega0,
                      acc_m, refs, mset)
    return _steps_flux(x, t, n, dt, vx, vy, frame, pl, t_load, mech, acc, omega0, acc_m,
                       refs, mset)


@_jit_no_rc_variant
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


@_jit_no_rc_variant
def _steps_flux(x, t, n, dt, vx, vy, frame, pl, t_load, mech, acc, omega0, acc_m, refs,
                mset):
    """:func:`_steps` of a saturated motor: state (psi_d, psi_q, Omega, theta),
    current from the inverse table (``_kernel_plant._current_of_flux``), torque
    ``tf p (psi_d i_q - psi_q i_d)``."""
    m = _load_acc(acc_m)
    tfp = pl[7] * pl[4]
    for _ in range(n):
        x1 = _rk4_flux(x[0], x[1], x[2], x[3], vx, vy, frame, dt, pl, t_load, mech, acc)
        i_d, i_q = _current_of_flux(pl[12], x[0], x[1])
        m = _accumulate_torque(m, i_d, i_q, x[2], tfp * (x[0] * i_q - x[1] * i_d), t, dt,
                               refs, mset)
        x = x1
        t += dt
    if mech == 1:
        x = (x[0], x[1], omega0 + acc * t, x[3])
    _store_acc(acc_m, m)
    return t, x
