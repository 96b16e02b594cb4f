"""Unit tests for toolbox.design.steady_state.

The derived steady states are checked against independent numerical routes:
a long integration of the closed loop (numeric plant from
``toolbox.plant.numeric_plant``, speed ramp Omega = gamma t) with scipy's
``solve_ivp``, and a numpy linear solve for the constant-speed case. The
comparisons with the printed formulas of paper 000 are in
``tests/papers/test_000_steady_state.py``.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from toolbox.design import steady_state as SS
from toolbox.plant import SYMBOLS, numeric_plant
from toolbox.spec import spec_from_dict

S = {**SYMBOLS, **SS.SS_SYMBOLS}


@pytest.fixture(scope="module")
def motor():
    return spec_from_dict({"motor": {"catalog": "lepioufle1992"},
                           "drive": {"vdc": 150, "sample_time": 1e-4},
                           "controller": {"method": "tc", "tc": {"K1": 800, "K2": 800}}}).motor


def test_constant_speed_gives_reference_eq5():
    """000 eq (5): with gamma = 0 the PI steady state is the reference."""
    sol = SS.pi_acceleration_steady_state("power")
    assert sp.simplify(sol[S["i_d"]].subs(S["gamma"], 0) - S["i_dref"]) == 0
    assert sp.simplify(sol[S["i_q"]].subs(S["gamma"], 0) - S["i_qref"]) == 0


def test_conventions_give_the_same_electrical_steady_state():
    """The dq electrical equations have the same form in both conventions."""
    a = SS.pi_acceleration_steady_state("amplitude")
    b = SS.pi_acceleration_steady_state("power")
    assert all(sp.simplify(a[k] - b[k]) == 0 for k in a)


def test_ip_equals_pi_with_KI_replaced_by_Kp_KI():
    """000 sect. 2, note on the IP controller."""
    pi = SS.pi_acceleration_steady_state("power", "pi")
    ip = SS.pi_acceleration_steady_state("power", "ip")
    for k in pi:
        assert sp.simplify(ip[k] - pi[k].subs(S["K_I"], S["K_p"] * S["K_I"])) == 0


def _simulate(rhs, x0, t_end):
    sol = solve_ivp(rhs, (0.0, t_end), x0, method="LSODA", rtol=1e-10, atol=1e-10)
    assert sol.success
    return sol.y[:, -1]


@pytest.mark.slow
def test_pi_acceleration_against_time_integration(motor):
    """Closed loop (3) integrated over 60 ms with Omega = gamma t (the slowest
    closed-loop pole is ~-190 rad/s, so transients decay as exp(-11)
    ~ 2e-5 of the initial error): currents agree with eq (6)-(7) to 1e-4 A."""
    plant = numeric_plant(motor)
    Kp, Ki, gamma, ref = 10.5, 1980.0, 5000.0, np.array([0.0, 10.0])

    def rhs(t, x):
        i, z = x[:2], x[2:]
        w = motor.pole_pairs * gamma * t
        v = Kp * (ref - i) + Ki * z
        return np.concatenate([plant.A(w) @ i + plant.B() @ v + plant.emf(w), ref - i])

    x = _simulate(rhs, np.zeros(4), 0.06)
    expected = SS.pi_acceleration_values(motor, Kp, Ki, gamma, *ref)
    assert x[:2] == pytest.approx(expected, abs=1e-4)


@pytest.mark.slow
def test_tc_speed_error_against_linear_solve(motor):
    """Constant speed: 0 = A(omega) i + B v(i) + e(omega) solved with numpy."""
    plant = numeric_plant(motor)
    K1 = K2 = 800.0
    Omega, Omega_m, ref = 200.0, 223.0, np.array([0.5, 10.0])
    p, Ld, Lq, psi, R = motor.pole_pairs, motor.Ld, motor.Lq, motor.flux, motor.R
    w, wm = p * Omega, p * Omega_m
    # v = M i + c (law (11) with the measured speed)
    M = np.array([[R - K1 * Ld, -wm * Lq], [wm * Ld, R - K2 * Lq]])
    c = np.array([K1 * Ld * ref[0], K2 * Lq * ref[1] + wm * psi])
    i = np.linalg.solve(plant.A(w) + plant.B() @ M, -(plant.B() @ c + plant.emf(w)))
    got = SS.tc_speed_error_values(motor, K1, K2, Omega, Omega_m, *ref)
    assert got == pytest.approx(tuple(i), rel=1e-12)


def test_tc_mismatch_reduces_to_nominal():
    nom = SS.tc_speed_error_steady_state("power")
    mis = SS.tc_speed_error_steady_state("power", mismatch=True)
    back = {S["R_c"]: S["R"], S["L_dc"]: S["L_d"], S["L_qc"]: S["L_q"], S["psi_fc"]: S["psi_f"]}
    assert all(sp.simplify(mis[k].subs(back) - nom[k]) == 0 for k in nom)


@pytest.mark.slow
def test_tci_acceleration_against_time_integration(motor):
    """Law (20) with Omega_m = 1.1 Omega + 5 (eq (28)), Omega = gamma t,
    integrated over 60 ms (slowest pole -199 rad/s): agrees with the derived
    steady state to 1e-4 A."""
    plant = numeric_plant(motor)
    K11, K12 = 3750.0, 707_142.857
    gamma, lam, Om0, ref = 5000.0, 0.1, 5.0, np.array([0.0, 10.0])
    p, Ld, Lq, psi, R = motor.pole_pairs, motor.Ld, motor.Lq, motor.flux, motor.R

    def rhs(t, x):
        i, z = x[:2], x[2:]
        Om = gamma * t
        wm = p * ((1 + lam) * Om + Om0)
        e = ref - i
        v = np.array([R * i[0] - wm * Lq * i[1] + Ld * (K11 * e[0] + K12 * z[0]),
                      R * i[1] + wm * Ld * i[0] + Lq * (K11 * e[1] + K12 * z[1]) + wm * psi])
        w = p * Om
        return np.concatenate([plant.A(w) @ i + plant.B() @ v + plant.emf(w), e])

    x = _simulate(rhs, np.zeros(4), 0.06)
    expected = SS.tci_acceleration_values(motor, K12, K12, gamma, lam, *ref)
    assert x[:2] == pytest.approx(expected, abs=1e-4)


def test_tci_offset_drops_out_and_perfect_sensor_has_no_error():
    """000 eq (29)-(30): only the gain error lambda matters; lambda = 0 gives i = i_ref."""
    sol = SS.tci_acceleration_steady_state("power")
    assert all(not e.has(S["Omega_0"]) for e in sol.values())
    assert sp.simplify(sol[S["i_d"]].subs(S["lam"], 0) - S["i_dref"]) == 0
    assert sp.simplify(sol[S["i_q"]].subs(S["lam"], 0) - S["i_qref"]) == 0


def test_values_are_floats(motor):
    out = SS.pi_acceleration_values(motor, 10.5, 1980.0, 1000.0, 0.0, 2.0)
    assert all(isinstance(v, float) for v in out)
