"""Saturated machine models (toolbox/spec/_magnetics.py, toolbox/plant/_saturation.py,
toolbox/plant/_symbolic_flux.py; toolbox/ARCHITECTURE.md "Saturated motors").

Reference values: the 5.5 kW PM-SyRM of motulator's example
``plot_flux_vector_pmsyrm_5kw.py`` (Lelli, Hinkkanen, Giulii Capponi, ICEM
2024), whose initial flux at zero current the example prints as
``psi_s0 = 0.477`` V s; the constant-parameter model of
:func:`toolbox.plant.derive_dq_model` for the linear special case.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from toolbox.plant import (at_operating_point, derive_dq_model, derive_flux_linkage_model,
                           dq_matrices, incremental_dq_matrices)
from toolbox.plant._symbolic_flux import psi_d, psi_q
from toolbox.spec import AlgebraicSaturation, FluxMapData, MagneticModel, Motor

PMSYRM = AlgebraicSaturation(a_d0=3.96, a_dd=28.46, S=4, a_q0=5.89, a_qq=2.672, T=6,
                             a_dq=41.52, U=1, V=1, a_b=81.75, a_bp=1, k_q=0.1, psi_n=0.804,
                             W=2, current_range=30.0)
SYRM = AlgebraicSaturation(a_d0=17.4, a_dd=373, S=5, a_q0=52.1, a_qq=658, T=1, a_dq=1120,
                           U=1, V=0, current_range=40.0)


@pytest.mark.slow   # two sympy derivations (about 4 CPU-s each)
@pytest.mark.parametrize("convention", ["amplitude", "power"])
def test_flux_linkage_form_reduces_to_the_dq_model(convention):
    """d psi/dt = v - R i - w J psi and T = k p (psi_d i_q - psi_q i_d), derived
    from the phase equations with arbitrary flux, equal the constant-parameter
    derivation (state equations and torque) for psi_d = Ld id + psi_f, psi_q = Lq iq."""
    m = derive_flux_linkage_model(convention)
    ref = derive_dq_model(convention)
    from toolbox.plant import SYMBOLS as S
    lin = {psi_d: S["L_d"] * S["i_d"] + S["psi_f"], psi_q: S["L_q"] * S["i_q"]}
    di = [m.dpsi_dt[0].subs(lin) / S["L_d"], m.dpsi_dt[1].subs(lin) / S["L_q"]]
    assert sp.simplify(di[0] - ref.di_dt[0]) == 0
    assert sp.simplify(di[1] - ref.di_dt[1]) == 0
    assert sp.simplify(m.torque.subs(lin) - ref.torque) == 0
    assert m.power_factor == (sp.Rational(3, 2) if convention == "amplitude" else 1)


def _linear_map(Ld, Lq, flux, n=9, r=40.0):
    ids = np.linspace(-r, r, n)
    D, Q = np.meshgrid(ids, ids, indexing="ij")
    return MagneticModel("map", FluxMapData(i_d=ids, i_q=ids.copy(), psi_d=Ld * D + flux,
                                            psi_q=Lq * Q))


def test_linear_map_is_the_constant_parameter_motor():
    """A linear map gives back Ld, Lq, flux, zero cross inductance, the
    constant-parameter torque and exact inverse (bilinear is exact on linear data)."""
    m = _linear_map(2e-3, 5e-3, 0.1)
    np.testing.assert_allclose(m.nominal(), (2e-3, 5e-3, 0.1), rtol=1e-12)
    np.testing.assert_allclose(m.incremental_inductance(7.0, -13.0), np.diag([2e-3, 5e-3]),
                               rtol=1e-12, atol=1e-18)
    i_d, i_q = np.array([-30.0, 3.0, 55.0]), np.array([12.0, -4.0, 60.0])  # 55, 60: extrapolated
    np.testing.assert_allclose(m.torque(i_d, i_q, 4, 1.5),
                               1.5 * 4 * (0.1 * i_q + (2e-3 - 5e-3) * i_d * i_q), rtol=1e-12)
    back = m.current(*m.flux(i_d, i_q))
    np.testing.assert_allclose(back, (i_d, i_q), atol=1e-9)


@pytest.mark.parametrize("model", [PMSYRM, SYRM], ids=["pmsyrm", "syrm"])
def test_algebraic_model_inverse_and_reciprocity(model):
    """psi(i) by Newton inverts the closed form i(psi) to 1e-9 A; L_inc is
    symmetric (the current is the gradient of a co-energy: the model's cross
    terms a_dq/(V+2) and a_dq/(U+2) are built so), to the 1e-6 relative
    accuracy of its central differences; saturation lowers L_q with i_q."""
    m = MagneticModel("algebraic", model)
    i_d = np.array([0.0, 5.0, -8.0, 12.0])
    i_q = np.array([0.0, 10.0, 20.0, -25.0])
    back = m.current(*m.flux(i_d, i_q))
    np.testing.assert_allclose(back, (i_d, i_q), atol=1e-9)
    L = m.incremental_inductance(6.0, 14.0)
    assert abs(L[0, 1] - L[1, 0]) < 1e-6 * abs(L).max()
    assert L[0, 1] != 0.0                                   # cross saturation present
    assert m.incremental_inductance(0.0, 25.0)[1, 1] < 0.7 * m.nominal()[1]


def test_pmsyrm_flux_at_zero_current_is_the_published_value():
    """motulator's example solves the zero-current flux as psi_s0 = 0.477 V s."""
    Ld, Lq, flux = MagneticModel("algebraic", PMSYRM).nominal()
    assert flux == pytest.approx(0.477, abs=5e-4)
    # unsaturated inductances at i = 0: 1/(a_d0 + bridge term) and 1/a_q0 (+ k_q G_b)
    assert Lq == pytest.approx(1 / (5.89 + 0.1 * 81.75 * (0.804 - flux) ** 2
                                    / (1 + (0.804 - flux) ** 2)), rel=1e-6)


def test_inverse_table_interpolation_error():
    """The simulator's 129 x 129 bilinear table reads the PM-SyRM's current
    within 0.05 A (0.17 % of the 30 A range; measured 0.028 A, worst in the
    saturated corners) over its current box: the budget of
    tests/sim/test_flux_state.py."""
    m = MagneticModel("algebraic", PMSYRM)
    T = m.inverse_table()
    rng = np.random.default_rng(1)
    i_d = rng.uniform(-30, 30, 400)
    i_q = rng.uniform(-30, 30, 400)
    psd, psq = m.flux(i_d, i_q)
    nd = int(T[2])
    u = (psd - T[0]) * T[1]
    v = (psq - T[3]) * T[4]
    j = np.clip(np.floor(u).astype(int), 0, nd - 2)
    k = np.clip(np.floor(v).astype(int), 0, nd - 2)
    fu, fv = u - j, v - k
    tab = T[8:].reshape(2, nd, nd)
    est = [(1 - fu) * ((1 - fv) * t[j, k] + fv * t[j, k + 1])
           + fu * ((1 - fv) * t[j + 1, k] + fv * t[j + 1, k + 1]) for t in tab]
    err = max(np.abs(est[0] - i_d).max(), np.abs(est[1] - i_q).max())
    assert 1e-6 < err < 0.05, err


def test_incremental_model_at_an_operating_point():
    """A constant-parameter motor gives dq_matrices exactly; a saturated one
    uses L_inc with its cross term, and at_operating_point's axis inductances
    are L_inc's diagonal."""
    M = Motor(R=0.63, Ld=0.03, Lq=0.15, flux=0.47, pole_pairs=2, J=0.015)
    A, B = incremental_dq_matrices(M, 3.0, 7.0, 300.0)
    A0, B0 = dq_matrices(M.R, M.Ld, M.Lq, 300.0)
    np.testing.assert_allclose(A, A0[0], rtol=1e-14)
    np.testing.assert_allclose(B, B0[0], rtol=1e-14)
    mag = MagneticModel("algebraic", PMSYRM)
    Ld, Lq, flux = mag.nominal()
    S = Motor(R=0.63, Ld=Ld, Lq=Lq, flux=flux, pole_pairs=2, J=0.015, magnetics=mag)
    L = mag.incremental_inductance(-5.0, 15.0)
    A, B = incremental_dq_matrices(S, -5.0, 15.0, 300.0)
    np.testing.assert_allclose(B, np.linalg.inv(L), rtol=1e-12)
    # the flux equation it linearises, by finite differences of the model itself
    i0 = np.array([-5.0, 15.0])
    def f(i):
        psd, psq = mag.flux(i[0], i[1])
        v = np.zeros(2)
        return -0.63 * i - 300.0 * np.array([-psq, psd]) + v
    h = 1e-4
    Jf = np.column_stack([(f(i0 + h * e) - f(i0 - h * e)) / (2 * h) for e in np.eye(2)])
    np.testing.assert_allclose(A, np.linalg.inv(L) @ Jf, rtol=1e-5)
    op = at_operating_point(S, -5.0, 15.0)
    assert (op.Ld, op.Lq, op.magnetics) == (L[0, 0], L[1, 1], None)
    assert op.Lq < 0.8 * S.Lq
