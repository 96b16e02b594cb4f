"""Cormerais 2002 (paper 002): SVM with PI (eq 19-22) and Boolean predictive
control (criterion 23). Motor of section 3.2, power-invariant dq.

The paper gives no DC-link voltage. We use E = 12 V (a standard battery
voltage), chosen from two hints: (1) the voltage needed at the end of a 0.5 s
run from standstill at 36 N m (J = 1 -> 18 rad/s) is R iq + w flux ~ 2 + 6.5 V,
just inside the inscribed circle 0.707 E = 8.5 V; (2) with E = 12 V the
predictive control at 10 kHz, alpha = beta = 1, gamma = 0 gives E_Gamma 1.64,
E_Id 3.61 and 9524 cell changes/s against the paper's 1.93, 3.79 and
Nb_c = 10740 (a 24 V link gives E_Id 15.8). The SVM errors fit a 24 V link
better (E_Gamma 3.85 vs 2.43 at 1 kHz); at 12 V they are 3.76 and 6.77
(paper 2.43 and 3.82), dominated by the saturated start, whose length the
paper does not give. The paper counts Nb_c = 12 F_ech for SVM (switch
commutations, two per cell change) but its predictive-control Nb_c matches
our cell changes; both counts are reported.
"""

import pytest

from toolbox.artifact import Decoupling
from toolbox.spec import Scenario
from toolbox.sim._simulate import (ControlLaw, DriveParams, FcsWeights, discrete_pi,
                                   simulate)

from sim_helpers import PAPER002 as M

VDC = 12.0


def _law(Ts, gamma=0.0):
    K = 10 * M.R                 # eq (19)-(20): K = 10 R, Ti = L/R
    Ki = K * M.R / M.Ld
    return ControlLaw(d=discrete_pi(K, Ki, Ts), q=discrete_pi(K, Ki, Ts), sample_time=Ts,
                      decoupling=Decoupling.from_motor(M),
                      fcs=FcsWeights(alpha=1.0, beta=1.0, gamma=gamma))


@pytest.mark.parametrize("F", [1000.0, 2500.0])
def test_svm_commutations_are_12_F(F):
    """Symmetric pattern 0-k-l-7-l-k-0: six cell changes = twelve switch
    commutations per period, so Nb_c = 12 F_ech exactly (paper: 12000 at 1 kHz,
    30000 at 2.5 kHz). Torque 36 N m -> i_q = 100 A."""
    Ts = 1.0 / F
    drive = DriveParams(vdc=VDC, sample_time=Ts, delay_samples=0, v_limit="hexagon",
                        inverter="svm")
    sc = Scenario(kind="unloaded_start", duration=0.2, torque_ref=36.0)
    m = simulate(_law(Ts), M, sc, drive).metrics
    assert m["commutations_per_s"] == pytest.approx(12 * F, rel=1e-12)
    assert m["cell_transitions_per_s"] == pytest.approx(6 * F, rel=1e-12)
    assert abs(m["final_value"] - 100.0) < 2.0       # current ripple averages out


def test_fcs_mpc_switching_penalty_reduces_commutations():
    """F_ech = 10 kHz, alpha = beta = 1, 0.5 s run. The paper reports that
    gamma = 35 commutes less than gamma = 0 (10500 vs 10740 /s) with *lower*
    errors. We reproduce the fewer commutations; the errors trade off instead:
    gamma = 10 saves >= 5 % of the commutations for <= 15 % more error, gamma = 35
    saves >= 30 % for < 2x the error (measured: 9524 -> 8740 -> 6020 cell
    changes/s; E_Gamma 1.64 -> 1.72 -> 2.37; E_Id 3.61 -> 3.97 -> 6.73)."""
    Ts = 1e-4
    drive = DriveParams(vdc=VDC, sample_time=Ts, delay_samples=0, inverter="fcs_mpc")
    sc = Scenario(kind="unloaded_start", duration=0.5, torque_ref=36.0)
    m = {g: simulate(_law(Ts, g), M, sc, drive).metrics for g in (0.0, 10.0, 35.0)}
    n0 = m[0.0]["commutations_per_s"]
    assert m[10.0]["commutations_per_s"] < 0.95 * n0
    assert m[35.0]["commutations_per_s"] < 0.7 * n0
    for key in ("mse_torque", "mse_id"):
        assert m[10.0][key] < 1.15 * m[0.0][key]
        assert m[35.0][key] < 2.0 * m[0.0][key]
    # paper: E_Gamma 1.93, E_Id 3.79, Nb_c 10740 (gamma = 0)
    assert 1.0 < m[0.0]["mse_torque"] < 3.0 and 2.0 < m[0.0]["mse_id"] < 6.0
    assert 7000 < m[0.0]["cell_transitions_per_s"] < 14000
    assert abs(m[35.0]["final_value"] - 100.0) < 3.0


def test_fcs_mpc_with_one_period_delay_compensation():
    """With delay_samples = 1 the prediction first advances the state over the
    period in progress (standard delay compensation); the loop still holds
    i_q = 100 A."""
    Ts = 1e-4
    drive = DriveParams(vdc=VDC, sample_time=Ts, delay_samples=1, inverter="fcs_mpc")
    sc = Scenario(kind="unloaded_start", duration=0.1, torque_ref=36.0)
    m = simulate(_law(Ts, 0.0), M, sc, drive).metrics
    assert abs(m["final_value"] - 100.0) < 2.0 and m["mse_id"] < 10.0
