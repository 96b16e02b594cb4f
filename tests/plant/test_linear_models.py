"""The closed-form linear dq models of toolbox.plant equal the sympy-derived
ElectricalPlant and the textbook ZOH (toolbox/ARCHITECTURE.md "Parameters and
models": the model is written once, everything else calls it)."""

import math

import control as ct
import numpy as np
import pytest

from toolbox.plant import (ElectricalPlant, axis_coefficients, axis_plants, dq_matrices,
                           zoh_first_order)
from toolbox.spec import CATALOG, Motor, spec_from_dict

RNG = np.random.default_rng(7)


@pytest.mark.parametrize("convention", ["amplitude", "power"])
def test_dq_matrices_equal_symbolic_plant(convention):
    """dq_matrices == ElectricalPlant.A/B (lambdified sympy derivation) on 20
    random plausible motors and speeds. Tolerance 1e-12 relative: same
    arithmetic in another order, so only rounding differs."""
    for _ in range(20):
        R, Ld, Lq = RNG.uniform(0.01, 5), RNG.uniform(1e-4, 0.05), RNG.uniform(1e-4, 0.05)
        w = RNG.uniform(-3000, 3000)
        plant = ElectricalPlant(Motor(R=R, Ld=Ld, Lq=Lq, flux=0.1, pole_pairs=3, J=1e-3,
                                      convention=convention))
        A, B = dq_matrices(R, Ld, Lq, w)
        np.testing.assert_allclose(A[0], plant.A(w), rtol=1e-12, atol=0)
        np.testing.assert_allclose(B[0], plant.B(), rtol=1e-12, atol=0)


def test_dq_matrices_broadcast():
    """N parameter sets in, (N, 2, 2) out, row k equal to the scalar call."""
    R = np.array([0.5, 1.0, 2.0])
    A, B = dq_matrices(R, 1e-3, 2e-3, np.array([0.0, 100.0, -100.0]))
    assert A.shape == B.shape == (3, 2, 2)
    np.testing.assert_array_equal(A[1], dq_matrices(1.0, 1e-3, 2e-3, 100.0)[0][0])


def test_axis_coefficients_are_the_axis_plants():
    """1/(s - a) b == axis_plants(motor)[axis] (1/(R + s L)) for a catalog motor."""
    name = sorted(CATALOG)[0]
    spec_motor = spec_from_dict({
        "motor": {"catalog": name},
        "drive": {"vdc": 300.0, "sample_time": 1e-4},
        "controller": {"method": "pi", "pi": {"bandwidth": 1000.0}}}).motor
    G = axis_plants(spec_motor)
    for ax, L in (("d", spec_motor.Ld), ("q", spec_motor.Lq)):
        a, b = axis_coefficients(spec_motor.R, L)
        H = ct.tf([b], [1.0, -a])
        w = np.logspace(0, 5, 7)
        np.testing.assert_allclose(H(1j * w), G[ax](1j * w), rtol=1e-12)


@pytest.mark.parametrize("R, L, Ts", [(0.8, 2e-3, 1e-4), (1e-6, 1e-2, 1e-4), (10.0, 1e-4, 1e-3)])
def test_zoh_first_order_equals_c2d(R, L, Ts):
    """(a, b) equal python-control's ZOH of 1/(R + s L), including a tiny R
    (R Ts/L = 1e-8, where the expm1 form keeps precision). Tolerance 1e-9
    relative: c2d goes through a matrix exponential."""
    a, b = zoh_first_order(R, L, Ts)
    Gd = ct.c2d(ct.ss([[-R / L]], [[1 / L]], [[1.0]], [[0.0]]), Ts, "zoh")
    assert float(a) == pytest.approx(float(Gd.A[0, 0]), rel=1e-9)
    assert float(b) == pytest.approx(float(Gd.B[0, 0]), rel=1e-9)
    assert float(a) == pytest.approx(math.exp(-R * Ts / L), rel=1e-15)
