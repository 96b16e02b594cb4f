"""``steady_state_voltage`` is the derived voltage equation with di/dt = 0
(toolbox/ARCHITECTURE.md "Parameters and models": the simulator's reach check does not
type the model again).

Tolerance 1e-12 relative to the largest term: the closed form and the
lambdified sympy expression differ only in operation order (a few ulps); a
wrong sign or coefficient is an O(1) error.
"""

import numpy as np
import pytest
import sympy as sp

from toolbox.plant import SYMBOLS as S
from toolbox.plant import derive_dq_model, steady_state_voltage


@pytest.mark.parametrize("convention", ["amplitude", "power"])
def test_steady_state_voltage_is_the_derived_voltage_equation(convention):
    model = derive_dq_model(convention)
    v = model.voltage.subs({S["di_d"]: 0, S["di_q"]: 0})
    args = (S["R"], S["L_d"], S["L_q"], S["psi_f"], S["omega"], S["i_d"], S["i_q"])
    ref_fn = sp.lambdify(args, v, "numpy")
    rng = np.random.default_rng(7)
    pts = rng.uniform([0.01, 1e-5, 1e-5, 0.01, -3000, -50, -50],
                      [2.0, 5e-3, 5e-3, 0.5, 3000, 50, 50], size=(30, 7))
    for R, Ld, Lq, flux, w, i_d, i_q in pts:
        got = np.array(steady_state_voltage(R, Ld, Lq, flux, w, i_d, i_q))
        ref = np.array(ref_fn(R, Ld, Lq, flux, w, i_d, i_q), float).reshape(2)
        scale = max(abs(R * i_d), abs(R * i_q), abs(w * Lq * i_q), abs(w * Ld * i_d),
                    abs(w * flux))
        assert np.max(np.abs(got - ref)) <= 1e-12 * scale, (got, ref)


def test_steady_state_voltage_broadcasts():
    vd, vq = steady_state_voltage(0.5, 1e-3, 2e-3, 0.1, np.array([0.0, 100.0]), 1.0, 2.0)
    assert np.allclose(vd, [0.5, 0.5 - 100.0 * 2e-3 * 2.0], rtol=1e-15, atol=0)
    assert np.allclose(vq, [1.0, 1.0 + 100.0 * (1e-3 + 0.1)], rtol=1e-15, atol=0)
