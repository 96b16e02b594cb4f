"""The numba kernel's pieces against their single sources (toolbox/ARCHITECTURE.md
"Parameters and models").

* its packed-array slots are the ones declared in ``_kernel.LAYOUTS``;
* its plant right-hand side and its predictive-control model are the dq model
  derived symbolically by :mod:`toolbox.plant` (the kernel cannot call sympy
  or numpy per step, so it carries a compiled copy; these tests keep the copy
  equal to the source);
* the simulated plant is built from the spec's ``Motor`` only.

Tolerances: the kernel and the lambdified sympy expressions evaluate the
same formulas in a different operation order (``(R i)/L`` against
``(R/L) i``), so they agree to a few ulps of the largest term; 1e-12 relative
to the largest term leaves three orders of magnitude for that and still
catches any wrong coefficient or sign (those are O(1) relative errors).
"""

import math

import numpy as np
import pytest
import sympy as sp

from toolbox.plant import SYMBOLS as S
from toolbox.plant import derive_dq_model, dq_matrices, numeric_plant
from toolbox.sim import _kernel, _kernel_layout
from toolbox.sim._kernel_layout import LAYOUTS
from toolbox.sim._metrics import METRIC_NAMES
from toolbox.sim._simulate import _packed, _plant_array
from toolbox.spec import Motor

REL = 1e-12
MOTORS = {
    "amplitude": Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4, J=1.11e-3,
                       friction=1.4e-3, convention="amplitude"),
    "power": Motor(R=0.02, Ld=112.6e-6, Lq=150e-6, flux=60.39e-3, pole_pairs=6, J=0.5,
                   friction=0.01, convention="power"),
}


def _points(n=25, seed=1):
    """Random operating points: id, iq (A), Omega (rad/s), theta, vd, vq (V), T_L (N m)."""
    rng = np.random.default_rng(seed)
    return rng.uniform([-20, -20, -300, -math.pi, -200, -200, -2],
                       [20, 20, 300, math.pi, 200, 200, 2], size=(n, 7))


def _close(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.max(np.abs(a - b)) <= REL * max(np.max(np.abs(b)), 1e-300)


# ----------------------------------------------------------------- layouts
def test_slot_constants_follow_the_layout_declaration():
    """The slot constants written out in ``_kernel_layout`` (for numba) are the
    positions of LAYOUTS and METRIC_NAMES: one per slot, none stray."""
    declared = {}
    for prefix, names in LAYOUTS.items():
        assert len(set(names)) == len(names), f"duplicate slot in {prefix}"
        declared.update({f"{prefix}_{name.upper()}": i for i, name in enumerate(names)})
        assert _kernel.pack_indices(prefix) == {n: i for i, n in enumerate(names)}
    declared.update({f"M_{name.upper()}": i for i, name in enumerate(METRIC_NAMES)})
    for name, index in declared.items():
        assert getattr(_kernel_layout, name, None) == index, name
    prefixes = tuple(f"{p}_" for p in LAYOUTS) + ("M_",)
    written = {n for n, v in vars(_kernel_layout).items()
               if n.isupper() and n.startswith(prefixes) and type(v) is int}
    assert written == set(declared)
    assert _kernel.N_SC == len(LAYOUTS["SC"])


def test_packed_fills_by_name_and_refuses_missing_or_unknown_slots():
    names = _kernel.LAYOUTS["DP"]
    arr = _packed("DP", **{n: float(i + 1) for i, n in enumerate(names)})
    assert arr.tolist() == [float(i + 1) for i in range(len(names))]
    partial = {n: 0.0 for n in names[1:]}
    with pytest.raises(ValueError, match=r"missing slots \['Ts'\]"):
        _packed("DP", **partial)
    with pytest.raises(ValueError, match=r"unknown slots \['bogus'\]"):
        _packed("DP", bogus=1.0, **{n: 0.0 for n in names})


# ---------------------------------------------------- one parameter source
@pytest.mark.parametrize("convention,tf", [("amplitude", 1.5), ("power", 1.0)])
def test_kernel_plant_array_is_packed_from_the_motor(convention, tf):
    """The simulator's true plant is a ``Motor`` (one parameter type): its
    kernel array holds exactly the motor's values (equality, no arithmetic),
    the dq convention entering only as ``torque_factor``."""
    motor = MOTORS[convention]
    arr = _plant_array(motor)
    ix = _kernel.pack_indices("P")
    for name in ("R", "Ld", "Lq", "flux", "pole_pairs", "J", "friction"):
        assert arr[ix[name]] == getattr(motor, name), name
    assert arr[ix["torque_factor"]] == tf == motor.torque_factor


# ------------------------------------------------- kernel model == plant model
@pytest.mark.parametrize("convention", sorted(MOTORS))
def test_kernel_rhs_is_the_derived_model(convention):
    """``_deriv`` (dq frame, free mechanics) == lambdified ``state_equations``."""
    motor = MOTORS[convention]
    f = derive_dq_model(convention).state_equations()
    args = (S["R"], S["L_d"], S["L_q"], S["psi_f"], S["p"], S["J"], S["F"], S["i_d"],
            S["i_q"], S["Omega"], S["v_d"], S["v_q"], S["T_L"])
    rhs = sp.lambdify(args, f, "numpy")
    pl = _kernel._plant(_plant_array(motor))  # the tuple run() passes, reciprocals included
    for i_d, i_q, om, th, vd, vq, tl in _points():
        did, diq, dom, w = _kernel._deriv(i_d, i_q, om, th, vd, vq, 0, pl, tl, 0, 0.0)
        ref = np.array(rhs(motor.R, motor.Ld, motor.Lq, motor.flux, motor.pole_pairs,
                           motor.J, motor.friction, i_d, i_q, om, vd, vq, tl),
                       float).reshape(3)
        assert _close([did, diq, dom], ref), (convention, [did, diq, dom], ref)
        assert w == motor.pole_pairs * om


def test_kernel_rhs_stationary_frame_and_imposed_speed():
    """Frame 1 rotates the held stationary-frame voltage into dq by theta
    (inverse of ``_to_ab``); mech = 1 imposes dOmega/dt = acc."""
    motor = MOTORS["amplitude"]
    plant = numeric_plant(motor)
    pl = _kernel._plant(_plant_array(motor))  # the tuple run() passes, reciprocals included
    for i_d, i_q, om, th, vd, vq, tl in _points(seed=2):
        va, vb = _kernel._to_ab(vd, vq, math.cos(th), math.sin(th))
        did, diq, dom, _ = _kernel._deriv(i_d, i_q, om, th, va, vb, 1, pl, tl, 1, 123.0)
        w = motor.pole_pairs * om
        ref = plant.A(w) @ [i_d, i_q] + plant.B() @ [vd, vq] + plant.emf(w)
        # the rotation there and back adds a few ulps of |v|: relative to the
        # voltage term's scale |v|/L, not to di/dt, which may be small
        scale = math.hypot(vd, vq) / min(motor.Ld, motor.Lq)
        assert np.max(np.abs(np.array([did, diq]) - ref)) <= 1e-12 * scale
        assert dom == 123.0


@pytest.mark.parametrize("convention", sorted(MOTORS))
def test_predictive_model_is_the_plant_euler_step(convention):
    """The paper 002 eq (23) predictor == ``i + Ts (A(w) i + B v + e(w))`` of
    :func:`toolbox.plant.dq_matrices` with the controller's model parameters."""
    motor = MOTORS[convention]
    Ts = 1e-4
    LP = _packed("LP", R_c=motor.R, Ld_c=motor.Ld, Lq_c=motor.Lq, flux_c=motor.flux,
                 cross=1.0, emf=1.0, alpha=1.0, beta=1.0, gamma=0.0,
                 cv=0.0, cv_pc=0.0, cv_pi=0.0, cv_pd=0.0, cv_d=0.0)
    for i_d, i_q, om, _, vd, vq, _ in _points(seed=3):
        w = motor.pole_pairs * om
        A, B = dq_matrices(motor.R, motor.Ld, motor.Lq, w)
        e = numeric_plant(motor).emf(w)
        ref = np.array([i_d, i_q]) + Ts * (A[0] @ [i_d, i_q] + B[0] @ [vd, vq] + e)
        got = _kernel._euler_predict(i_d, i_q, vd, vq, w, Ts, LP)
        assert _close(got, ref), (got, ref)


# ------------------------------------------------------------- small helpers
def test_circle_limit_keeps_direction_and_hexagon_scales_inside():
    names = _kernel.LAYOUTS["DP"]
    base = {n: 0.0 for n in names}
    circle = _packed("DP", **{**base, "Ts": 1e-4, "vlim": 1, "v_max": 100.0})
    vd, vq = _kernel._voltage_limit(300.0, -400.0, 0.0, 0.0, circle, 0.0)
    assert math.isclose(math.hypot(vd, vq), 100.0, rel_tol=1e-15)
    assert math.isclose(vd / vq, 300.0 / -400.0, rel_tol=1e-15)
    assert _kernel._voltage_limit(30.0, -40.0, 0.0, 0.0, circle, 0.0) == (30.0, -40.0)
    hexagon = _packed("DP", **{**base, "Ts": 1e-4, "vlim": 2, "r_hex": 100.0})
    vd, vq = _kernel._voltage_limit(300.0, 0.0, 0.0, 0.0, hexagon, 0.0)
    assert math.isclose(vd, 100.0, rel_tol=1e-12) and vq == 0.0  # along a vertex
    none = _packed("DP", **{**base, "Ts": 1e-4, "vlim": 0})
    assert _kernel._voltage_limit(1e6, 1e6, 0.0, 0.0, none, 0.0) == (1e6, 1e6)


def test_speed_pid_integrates_only_inside_the_limit():
    SP = _packed("SP", enabled=1.0, kp=1.0, ki=10.0, kd=0.0, decim=1, iq_limit=5.0)
    u, integ = _kernel._speed_pid(2.0, 2.0, 0.0, 1e-3, SP)
    assert u == pytest.approx(2.0 + 10.0 * 2.0 * 1e-3, rel=1e-15)
    assert integ == pytest.approx(0.02, rel=1e-15)
    u, integ = _kernel._speed_pid(100.0, 100.0, 0.02, 1e-3, SP)
    assert u == 5.0 and integ == 0.02  # saturated: the integral is frozen
    u, integ = _kernel._speed_pid(-100.0, -100.0, 0.02, 1e-3, SP)
    assert u == -5.0 and integ == 0.02
