"""Numeric plants made from the derivation agree with independent routes."""

import control
import numpy as np
import pytest

from toolbox.plant import axis_plants, linearise, numeric_plant
from toolbox.spec import CATALOG, Motor


@pytest.fixture
def motor():
    return Motor(**CATALOG["azaiz2007"])


def test_state_matrices_match_paper000_eq1(motor):
    """A(omega) and B read off the sympy model equal paper 000 eq (1) numbers.

    Exact up to float rounding (1e-12 relative): same formula, other route.
    """
    w = motor.pole_pairs * 200.0
    plant = numeric_plant(motor)
    A = np.array([[-motor.R / motor.Ld, w * motor.Lq / motor.Ld],
                  [-w * motor.Ld / motor.Lq, -motor.R / motor.Lq]])
    np.testing.assert_allclose(plant.A(w), A, rtol=1e-12)
    np.testing.assert_allclose(plant.B(), np.diag([1 / motor.Ld, 1 / motor.Lq]), rtol=1e-12)
    np.testing.assert_allclose(plant.emf(w), [0.0, -w * motor.flux / motor.Lq], rtol=1e-12)


def test_axis_plants_are_first_order_paper003_eq33_34(motor):
    """G_d = 1/(r_s + s L_d) and G_q = 1/(r_s + s L_q) (paper 003 eq (33)-(34)),
    and their state form equals eq (50) (pole -214.2857, gain 357.1429)."""
    G = axis_plants(motor)
    assert np.allclose(control.poles(G["q"]), [-214.2857142857], rtol=1e-10)
    assert np.isclose(control.dcgain(G["q"]), 1 / motor.R, rtol=1e-12)
    assert np.isclose(control.dcgain(G["d"]), 1 / motor.R, rtol=1e-12)
    assert np.allclose(control.poles(G["d"]), [-motor.R / motor.Ld], rtol=1e-10)


def test_linearisation_matches_finite_differences(motor):
    """Jacobians from sympy equal central finite differences of the nonlinear
    model (relative 1e-6: step 1e-6 relative, truncation O(h^2))."""
    id0, iq0, W0 = -2.0, 8.0, 150.0
    sys, u0 = linearise(motor, id0, iq0, W0)
    p, tf = motor.pole_pairs, motor.torque_factor

    def f(x, u):
        i_d, i_q, W = x
        v_d, v_q, T_L = u
        w = p * W
        T = tf * p * (motor.flux * i_q + (motor.Ld - motor.Lq) * i_d * i_q)
        return np.array([(v_d - motor.R * i_d + w * motor.Lq * i_q) / motor.Ld,
                         (v_q - motor.R * i_q - w * motor.Ld * i_d - w * motor.flux) / motor.Lq,
                         (T - motor.friction * W - T_L) / motor.J])

    x0 = np.array([id0, iq0, W0])
    np.testing.assert_allclose(f(x0, u0), 0.0, atol=1e-9)  # u0 is an equilibrium
    A_fd = np.column_stack([(f(x0 + h, u0) - f(x0 - h, u0)) / (2 * 1e-4)
                            for h in np.eye(3) * 1e-4])
    np.testing.assert_allclose(sys.A, A_fd, rtol=1e-6, atol=1e-9)
