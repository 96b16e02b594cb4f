"""Paper 002 (Cormerais 2002), every printed row in the paper's own scenario.

The scenario, as the paper states it (sect. 3.2 and 4.3): the motor of
sect. 3.2 (power-invariant dq, L = 112.6 uH, R = 0.02 ohm, flux 60.39 mWb,
6 pole pairs) drives an inertia J = 1 kg m^2 with no friction and no load
torque; the torque reference 36 N m (i_q = 100 A, i_d = 0) is applied from
standstill and the rotor accelerates freely. Simulation 3 of sect. 3.2 and
simulation 4 of sect. 4.3 follow Gamma_c = 36 sin(10 pi t) instead.

What the paper does not give, and what we assume (the search behind each
choice is tests/papers/README.md "Paper 002"):

* E (DC link): 12 V (tests/sim/test_paper002.py gives the two hints).
* Run length: 0.4 s, the longest that stays within the voltage reach at
  12 V (the gallery designs run the same).
* E_Gamma, E_Id: the time-weighted mean of e^2 over the whole run
  (``mse_torque``, ``mse_id``). Nb_c: switch commutations per second
  (``commutations_per_s``, two per cell change), the count that makes the
  paper's SVM Nb_c = 12 F_ech; ``cell_transitions_per_s`` is reported too.
* No computation delay (the Simulink model applies the voltage in the
  period it is computed), hexagon limit, SVM as one centred pattern
  0-k-l-7-l-k-0 per sample (eq (21)-(22), 12 F_ech commutations).

Run ``python tests/papers/test_002_rows.py`` for the table of printed and
simulated numbers. Each test asserts our number (tolerance stated) and its
docstring gives the paper's; rows that do not reproduce are asserted as
they are, with the assumptions searched.
"""

from __future__ import annotations

import copy
import tomllib
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from toolbox.design import design
from toolbox.sim import control_law, drive_params, simulate
from toolbox.spec import Scenario
from toolbox.spec import spec_from_dict

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
T_RUN = 0.4          # s, assumed run length (module docstring)


@lru_cache(maxsize=None)
def _spec_law(name: str, sample_time: float | None, gamma: float | None,
              alpha: float | None):
    with open(DESIGNS / f"002_cormerais2002_{name}.toml", "rb") as fh:
        data = copy.deepcopy(tomllib.load(fh))
    if sample_time is not None:
        data["drive"]["sample_time"] = sample_time
    for key, v in (("gamma", gamma), ("alpha", alpha)):
        if v is not None:
            data["controller"]["fcs_mpc"][key] = v
    spec = spec_from_dict(data)
    return spec, control_law(design(spec))


def run(name: str, inverter: str, *, sample_time: float | None = None,
        gamma: float | None = None, alpha: float | None = None, sinus: bool = False,
        duration: float = T_RUN, traces: bool = False, **sensor):
    """One simulation of a paper-002 design file in the paper's scenario."""
    spec, law = _spec_law(name, sample_time, gamma, alpha)
    if sinus:
        sc = Scenario(kind="sinusoidal_torque", duration=duration, torque_amplitude=36.0,
                      torque_frequency=5.0, inverter=inverter, keep_traces=traces, **sensor)
    else:
        sc = Scenario(kind="unloaded_start", duration=duration, torque_ref=36.0,
                      inverter=inverter, keep_traces=traces, **sensor)
    return simulate(law, spec.motor, sc, drive_params(spec.drive, inverter))


def svm(F: float, **kw):
    return run("svm_pi", "svm", sample_time=1.0 / F, **kw)


def fcs(F: float, gamma: float = 0.0, **kw):
    return run("fcs_mpc", "fcs_mpc", sample_time=1.0 / F, gamma=gamma, **kw)


def oscillation(res, t_from: float) -> tuple[float, float]:
    """Peak-to-peak torque (N m) and i_d (A) after ``t_from`` at the controller
    instants: the predictive law switches only there, so within a period the
    currents move monotonically and their extremes are sampled."""
    sel = res.t >= t_from
    return (float(np.ptp(res.torque[sel])), float(np.ptp(res.id[sel])))


#: (row, printed E_Gamma, E_Id, Nb_c, how we run it)
ROWS = [
    ("3.2 sim 1: SVM 1 kHz", 2.4293, 3.8223, 12000, lambda: svm(1000.0)),
    ("3.2 sim 2: SVM 2.5 kHz", 0.8067, 0.4157, 30000, lambda: svm(2500.0)),
    ("3.2 sim 3: SVM 1 kHz, 36 sin(10 pi t)", 1.1087, 2.4896, 12000,
     lambda: svm(1000.0, sinus=True)),
    ("4.3 sim 1: FCS gamma 0 (F lost; 10 kHz)", 1.9294, 3.7877, 10740,
     lambda: fcs(10000.0)),
    ("4.3 sim 1 at 4 kHz (F from Nb_c/F of sim 2)", 1.9294, 3.7877, 10740,
     lambda: fcs(4000.0)),
    ("4.3 sim 2: FCS 12 kHz gamma 0", 0.9342, 1.3713, 32120, lambda: fcs(12000.0)),
    ("4.3 sim 3: FCS 10 kHz gamma 35", 1.386, 2.3787, 10500, lambda: fcs(10000.0, 35.0)),
    ("4.3 sim 4: FCS 4 kHz alpha 10, sin (printed = sim 3)", 1.386, 2.3787, 10500,
     lambda: fcs(4000.0, alpha=10.0, sinus=True)),
]


def table() -> str:
    lines = [f"{'row':52s} {'printed E_G / E_Id / Nb_c':>28s}   "
             f"{'ours E_G / E_Id / switch / cell':>36s}"]
    for name, eg, eid, nb, fn in ROWS:
        m = fn().metrics
        lines.append(f"{name:52s} {eg:8.3f} {eid:8.3f} {nb:8.0f}   "
                     f"{m['mse_torque']:8.3f} {m['mse_id']:8.3f} "
                     f"{m['commutations_per_s']:8.0f} {m['cell_transitions_per_s']:8.0f}")
    return "\n".join(lines)


# ------------------------------------------------------------------ sect. 3.2
def test_svm_1khz_sim1():
    """Sect. 3.2 simulation 1, printed E_Gamma = 2.4293, E_Id = 3.8223,
    Nb_c = 12000. Ours (12 V, 0.4 s): 2.59, 4.57, 12000. E_Gamma is within
    7 % of the paper's; E_Id is 20 % above it. Both depend on the run length
    the paper does not give (E_Gamma falls and E_Id rises with it: 3.09 /
    2.90 at 0.3 s, 2.28 / 5.64 at 0.45 s, 2.08 / 6.91 at 0.5 s, the figure
    first measured, against 3.82 printed): no single length gives both, see README "Paper 002".
    Asserted: our numbers within 3 % (simulator changes), E_Gamma within
    10 % of the printed one, Nb_c = 12 F_ech exactly."""
    m = svm(1000.0).metrics
    assert m["mse_torque"] == pytest.approx(2.59, rel=0.03)
    assert m["mse_id"] == pytest.approx(4.57, rel=0.03)
    assert m["mse_torque"] == pytest.approx(2.4293, rel=0.10)
    assert m["commutations_per_s"] == pytest.approx(12000.0, rel=1e-12)


def test_svm_2k5hz_sim2():
    """Sect. 3.2 simulation 2, printed E_Gamma = 0.8067, E_Id = 0.4157,
    Nb_c = 30000. Ours (12 V, 0.4 s): 1.67, 0.71, 30000. Going from 1 to
    2.5 kHz the paper divides E_Gamma by 3.0 and E_Id by 9.2, we by 1.55 and
    6.4: the direction is reproduced, not the size. Our E_Gamma is mostly the
    saturated start (0 -> 100 A at 12 V, ~0.6 N^2 m^2 s of the 0.67 integral),
    which no E or run length in the searched grid (E 6-96 V, 0.1-1 s) brings
    to the printed 0.81 while keeping the 1 kHz row; README "Paper 002".
    Asserted: our numbers within 3 %, both errors lower than at 1 kHz,
    Nb_c = 12 F_ech exactly."""
    m = svm(2500.0).metrics
    m1 = svm(1000.0).metrics
    assert m["mse_torque"] == pytest.approx(1.67, rel=0.03)
    assert m["mse_id"] == pytest.approx(0.71, rel=0.03)
    assert m["mse_torque"] < 0.7 * m1["mse_torque"] and m["mse_id"] < 0.2 * m1["mse_id"]
    assert m["commutations_per_s"] == pytest.approx(30000.0, rel=1e-12)


def test_svm_sinusoidal_sim3():
    """Sect. 3.2 simulation 3 (36 sin(10 pi t), 1 kHz), printed E_Gamma =
    1.1087, E_Id = 2.4896, Nb_c = 12000. Ours: 0.351, 0.109 (0.4 s, two
    periods of the reference; 0.346 / 0.179 over 0.2 s, 0.349 / 0.128 over
    1 s): 3x and 20x below the paper. The torque error is the PI loop's
    tracking error of a 5 Hz sine (bandwidth K/L = 1776 rad/s: 1.8 A of
    i_q lag, 0.2 N^2 m^2) plus the SVM ripple; it hardly moves with E (0.43
    at 24 V, 0.49 at 96 V). Not reconciled: the paper's sine errors exceed
    its own step errors at 2.5 kHz, which no ripple or tracking model of the
    stated loop gives. Asserted: our numbers within 5 % and Nb_c exact."""
    m = svm(1000.0, sinus=True).metrics
    assert m["mse_torque"] == pytest.approx(0.351, rel=0.05)
    assert m["mse_id"] == pytest.approx(0.109, rel=0.05)
    assert m["commutations_per_s"] == pytest.approx(12000.0, rel=1e-12)



# ------------------------------------------------------------------ sect. 4.3
def test_fcs_sim1_reproduces_at_10khz_counting_cell_changes():
    """Sect. 4.3 simulation 1 (alpha = beta = 1, gamma = 0; its F_ech was lost
    in the text, 10 kHz assumed as in sect. 4.3 sim 3), printed E_Gamma =
    1.9294, E_Id = 3.7877, Nb_c = 10740. Ours (12 V, 0.4 s): 1.916, 3.630 and
    10152 cell changes/s (20305 switch commutations/s): all three within 6 %
    of the paper when Nb_c counts cell (leg) changes, not switch
    commutations as its SVM count 12 F_ech does. The other reading of the
    lost F_ech (4 kHz, from sim 2's Nb_c / F = 2.68) gives 3.96, 22.5, 4012
    cell changes/s: far off. Asserted: within 5 % of the printed errors and
    6 % of the printed Nb_c as cell changes."""
    m = fcs(10000.0).metrics
    assert m["mse_torque"] == pytest.approx(1.9294, rel=0.05)
    assert m["mse_id"] == pytest.approx(3.7877, rel=0.05)
    assert m["cell_transitions_per_s"] == pytest.approx(10740.0, rel=0.06)
    assert m["commutations_per_s"] == pytest.approx(2 * m["cell_transitions_per_s"])


def test_fcs_sim2_12khz():
    """Sect. 4.3 simulation 2 (12 kHz, gamma = 0), printed E_Gamma = 0.9342,
    E_Id = 1.3713, Nb_c = 32120. Ours: 1.793, 2.520, 12123 cell changes/s
    (24245 switch commutations/s). The count matches neither reading: 32120
    would be 2.68 switch commutations per sample, 1.4x our rate at 10 or
    12 kHz, while the paper's own sim 1 has 1.07 per sample; our cell count
    12123 is what a misprint of 12120 would read (a hypothesis, not a
    reconciliation). The errors halve from 10 to 12 kHz in the paper, ours
    fall by 6 % (E_Gamma, mostly the saturated start, which the period does
    not shorten) and 31 % (E_Id). Asserted: our numbers within 3 %."""
    m = fcs(12000.0).metrics
    assert m["mse_torque"] == pytest.approx(1.793, rel=0.03)
    assert m["mse_id"] == pytest.approx(2.520, rel=0.03)
    assert m["cell_transitions_per_s"] == pytest.approx(12123.0, rel=0.03)


def test_fcs_sim3_gamma35_raises_errors():
    """Sect. 4.3 simulation 3 (10 kHz, gamma = 35), printed E_Gamma = 1.386,
    E_Id = 2.3787, Nb_c = 10500: lower errors than sim 1 for 2 % fewer
    commutations. Ours: 2.771, 6.740, 6112 cell changes/s: 40 % fewer
    commutations for 1.45x and 1.86x the errors of gamma = 0. Not
    reconciled: criterion (23) compares gamma with squared current errors
    (A^2), so gamma = 35 is a (5.9 A)^2 dead band against the 8.7 A one
    vector moves the current in a period; a greedy one-step law that keeps
    a vector longer must let the error grow (README "Paper 002"; E 6-96 V
    all give higher errors with gamma = 35). Asserted: our numbers within
    3 % and the direction (both errors above gamma = 0's by > 30 %)."""
    m = fcs(10000.0, 35.0).metrics
    m0 = fcs(10000.0).metrics
    assert m["mse_torque"] == pytest.approx(2.771, rel=0.03)
    assert m["mse_id"] == pytest.approx(6.740, rel=0.03)
    assert m["cell_transitions_per_s"] == pytest.approx(6112.0, rel=0.03)
    assert m["mse_torque"] > 1.3 * m0["mse_torque"] and m["mse_id"] > 1.3 * m0["mse_id"]


def test_fcs_sim4_sinusoidal_4khz():
    """Sect. 4.3 simulation 4 (4 kHz, alpha = 10, beta = 1, gamma = 0,
    36 sin(10 pi t)); the printed numbers (1.386, 2.3787, 10500) repeat sim
    3's digit for digit, so they are not this run's. Ours: E_Gamma 1.72,
    E_Id 65.8, 2030 cell changes/s: with alpha = 10 the law trades i_d for
    i_q, and at 4 kHz one vector moves the current 22 A a period.
    Asserted: our numbers within 5 %."""
    m = fcs(4000.0, alpha=10.0, sinus=True).metrics
    assert m["mse_torque"] == pytest.approx(1.723, rel=0.05)
    assert m["mse_id"] == pytest.approx(65.8, rel=0.05)


# -------------------------------------------------------------------- sect. 5
def _amplitudes(**sensor) -> tuple[float, float]:
    """Half peak-to-peak torque (N m) and i_d (A) of sect. 4.3 sim 2 (12 kHz,
    gamma = 0) over 0.1-0.2 s with current-sensor gains / delays (periods of
    1/12 ms)."""
    pt, pi = oscillation(fcs(12000.0, duration=0.2, traces=True, **sensor), 0.1)
    return pt / 2, pi / 2


def test_sect5_oscillation_magnitudes():
    """Sect. 5: "In the simulation 2 ... the oscillation magnitudes are equal
    to 1 for the torque and 3 for the current i_d" (the 12 kHz predictive
    run, 0.2 ms = 2.4 T_ech). Ours, as half peak-to-peak: 1.43 N m and
    3.96 A (at E = 8 V: 0.94 and 2.61; the peak-to-peak reading doubles
    them). Asserted: ours within 5 %, and within 50 % of the paper's."""
    at, ai = _amplitudes()
    assert at == pytest.approx(1.43, rel=0.05) and ai == pytest.approx(3.96, rel=0.05)
    assert at == pytest.approx(1.0, rel=0.5) and ai == pytest.approx(3.0, rel=0.5)


def test_sect5_gain_acts_on_its_own_axis():
    """Sect. 5: a gain on Phi_d does not change the torque oscillation, a gain
    on Phi_q not the i_d one. We apply the gain to the measured current
    (Phi_d - flux = Ld i_d, Phi_q = Lq i_q; a gain on Phi_d itself would add
    (g - 1) flux / Ld = 536 A to i_d). Gain 2 on d: torque 1.43 -> 1.66
    (+16 %), gain 2 on q: i_d 3.96 -> 4.18 (+6 %): nearly no influence,
    reproduced. The stability limit (oscillation 10) "at a gain equal to 2"
    is not: with gain 2 on both the largest amplitude is 5.3 A. Asserted:
    cross influence below 25 % and 10 %, and gain 2 below the limit."""
    at0, ai0 = _amplitudes()
    at_d, _ = _amplitudes(current_gain_d=2.0)
    _, ai_q = _amplitudes(current_gain_q=2.0)
    assert at_d < 1.25 * at0
    assert ai_q < 1.10 * ai0
    at2, ai2 = _amplitudes(current_gain_d=2.0, current_gain_q=2.0)
    assert max(at2, ai2) < 10.0


def test_sect5_delay_limit():
    """Sect. 5: the stability limit (oscillation 10) is reached with a time
    delay of 0.2 ms = 2.4 T_ech. Our delays are whole periods (1/12 ms). A
    delay on both currents: i_d reaches 10 A of amplitude at one period
    (0.083 ms, 10.4 A), the torque 10 N m at four (0.33 ms; 8.4 at three):
    the paper's 0.2 ms lies between our two limits. A delay on i_d alone
    raises the torque oscillation 1.43 -> 2.27 N m at two periods, where
    the paper sees no influence. Asserted: those crossings (each at a period
    count that fails if the loop were one period more or less robust)."""
    _, ai1 = _amplitudes(current_delay_d=1, current_delay_q=1)
    assert ai1 >= 10.0
    at3, _ = _amplitudes(current_delay_d=3, current_delay_q=3)
    at4, _ = _amplitudes(current_delay_d=4, current_delay_q=4)
    assert at3 < 10.0 <= at4
    at_dd, _ = _amplitudes(current_delay_d=2)
    assert at_dd == pytest.approx(2.27, rel=0.05)


if __name__ == "__main__":
    print(table())
