"""The derived dq model equals the papers' equations (symbolic proofs).

Each test subtracts the printed equation from the derivation of
:func:`toolbox.plant.derive_dq_model` and requires the difference to simplify
to exactly zero: these tests cannot pass by tolerance.
"""

import sympy as sp
import pytest

from toolbox.plant import SYMBOLS as S
from toolbox.plant import derive_dq_model, park_matrix
from toolbox.plant._symbolic import _simplify
from toolbox.plant._symbolic import _trig_inverse

R, Ld, Lq, psi_f, p, J, F = (S[k] for k in ("R", "L_d", "L_q", "psi_f", "p", "J", "F"))
i_d, i_q, v_d, v_q, omega, Omega, T_L = (S[k] for k in
                                         ("i_d", "i_q", "v_d", "v_q", "omega", "Omega", "T_L"))


def zero(expr) -> bool:
    return sp.simplify(sp.expand(expr)) == 0


@pytest.fixture(scope="module")
def amplitude():
    return derive_dq_model("amplitude")


@pytest.fixture(scope="module")
def power():
    return derive_dq_model("power")


def test_paper000_eq1_state_equation(power):
    """Paper 000 eq (1): d/dt [i_d, i_q] = A [i_d, i_q] + B [v_d, v_q - p Phi_f Omega]."""
    A = sp.Matrix([[-R / Ld, p * Omega * Lq / Ld], [-p * Omega * Ld / Lq, -R / Lq]])
    B = sp.diag(1 / Ld, 1 / Lq)
    printed = A * sp.Matrix([i_d, i_q]) + B * sp.Matrix([v_d, v_q - p * psi_f * Omega])
    derived = power.di_dt.subs(omega, p * Omega)
    assert all(zero(d - e) for d, e in zip(derived, printed))


def test_paper000_eq2_torque_is_power_invariant(power, amplitude):
    """Paper 000 eq (2): C = p (Ld - Lq) i_d i_q + p Phi_f i_q.

    It has no 3/2 factor: it is the power-invariant torque. The amplitude-
    invariant derivation differs from it by exactly 3/2 (paper 003 eq (5)).
    """
    printed = p * (Ld - Lq) * i_d * i_q + p * psi_f * i_q
    assert zero(power.torque - printed)
    assert zero(amplitude.torque - sp.Rational(3, 2) * printed)


def test_paper003_eq3_eq4_voltages(amplitude):
    """Paper 003 eq (3)-(4): v_d = r_s i_d + L_d di_d/dt - omega L_q i_q, ..."""
    di_d, di_q = sp.symbols("di_d di_q", real=True)
    assert zero(amplitude.voltage[0] - (R * i_d + Ld * di_d - omega * Lq * i_q))
    assert zero(amplitude.voltage[1] - (R * i_q + Lq * di_q + omega * Ld * i_d + omega * psi_f))


def test_paper003_eq5_to_eq7_torque_and_mechanics(amplitude):
    """Paper 003 eq (5) torque with 3/2; eq (6) J dw_r/dt = T_e - F w_r - T_m; eq (7)."""
    T_e = sp.Rational(3, 2) * p * (psi_f * i_q + (Ld - Lq) * i_d * i_q)
    assert zero(amplitude.torque - T_e)
    assert zero(amplitude.dOmega_dt - (T_e - F * Omega - T_L) / J)
    # eq (7) omega = p omega_r: the state equations use omega = p * Omega
    full = amplitude.state_equations()
    assert zero(full[1] - amplitude.di_dt[1].subs(omega, p * Omega))


def test_paper002_eq4_to_eq8_after_change_of_variables(power):
    """Paper 002 eq (4)-(8): fluxes Phi_d = L_d i_d, Phi_q = L_q i_q, momentum P = J Omega.

    Notes on the printed paper (Cormerais 2002):
    - eq (1) defines Phi_d = L_d i_d + Phi_f, but eq (4)-(5) and (8) only hold
      with Phi_d = L_d i_d (eq (5) adds Phi_f explicitly): the state is the
      armature-reaction flux.
    - eq (6) prints Phi_d Phi_q (1/L_d - 1/L_q); eq (8) and the derivation give
      (1/L_q - 1/L_d): eq (6) has a sign misprint in the reluctance term.
    - eq (2)-(3) print the q row of the Park transform with +sin; with it the
      coupling terms of eq (4)-(5) change sign (see the next test). Eq (4)-(5)
      match the -sin row (q axis leading d), the convention used here.
    """
    Phi_d, Phi_q, P, nbp, Phi_f, Rf, C_brk = sp.symbols("Phi_d Phi_q P nb_p Phi_f R_f C_brk")
    to_paper = {i_d: Phi_d / Ld, i_q: Phi_q / Lq, Omega: P / J, p: nbp, psi_f: Phi_f,
                F: Rf, T_L: C_brk}
    eqs = power.state_equations().subs(omega, p * Omega)
    dPhi_d = (Ld * eqs[0]).subs(to_paper)
    dPhi_q = (Lq * eqs[1]).subs(to_paper)
    dP = (J * eqs[2]).subs(to_paper)
    assert zero(dPhi_d - (-R / Ld * Phi_d + nbp / J * Phi_q * P + v_d))             # eq (4)
    assert zero(dPhi_q - (-R / Lq * Phi_q - nbp / J * (Phi_d + Phi_f) * P + v_q))   # eq (5)
    printed_eq6 = (nbp * Phi_d * Phi_q * (1 / Ld - 1 / Lq) + nbp * Phi_q * Phi_f / Lq
                   - P * Rf / J - C_brk)
    corrected_eq6 = (nbp * Phi_d * Phi_q * (1 / Lq - 1 / Ld) + nbp * Phi_q * Phi_f / Lq
                     - P * Rf / J - C_brk)
    assert zero(dP - corrected_eq6)
    assert not zero(dP - printed_eq6)  # the misprint is real unless L_d = L_q
    torque_eq8 = -nbp * Phi_d * Phi_q / Ld + nbp * (Phi_d + Phi_f) * Phi_q / Lq
    assert zero(power.torque.subs(to_paper) - torque_eq8)                          # eq (8)


@pytest.mark.slow
def test_park_q_row_sign_flips_rotation():
    """With paper 002's printed +sin q row, T dT^-1/dtheta has the opposite sign.

    The inverses are the derivation's adjugate route, each proven exact here
    (``T T^-1`` reduces to the identity)."""
    th = S["theta"]
    for convention in ("amplitude", "power"):
        T = park_matrix(th, convention)
        T_plus = sp.Matrix(T)
        T_plus[1, :] = -T[1, :]
        for m, sign in ((T, 1), (T_plus, -1)):
            m_inv = _trig_inverse(m)
            assert (m * m_inv).applyfunc(_simplify) == sp.eye(3)
            rot = (m * m_inv.diff(th)).applyfunc(_simplify)
            assert rot[0, 1] == -sign and rot[1, 0] == sign


def test_dq_inductances_from_phase_quantities(amplitude, power):
    """L_d = L_s + 3/2 (L_0 + L_2), L_q = L_s + 3/2 (L_0 - L_2) in both conventions;
    the PM flux is psi_pm (amplitude) or sqrt(3/2) psi_pm (power)."""
    L_s, L_0, L_2, psi_pm = sp.symbols("L_sigma L_0 L_2 psi_pm", positive=True)
    for model in (amplitude, power):
        assert zero(model.inductance_map[Ld] - (L_s + sp.Rational(3, 2) * (L_0 + L_2)))
        assert zero(model.inductance_map[Lq] - (L_s + sp.Rational(3, 2) * (L_0 - L_2)))
    assert zero(amplitude.inductance_map[psi_f] - psi_pm)
    assert zero(power.inductance_map[psi_f] - sp.sqrt(sp.Rational(3, 2)) * psi_pm)
