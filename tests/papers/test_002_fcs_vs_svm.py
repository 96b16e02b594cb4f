"""Paper 002 (Cormerais 2002), sect. 6 (conclusion): SVM with PI (sect. 3,
eq (19)-(22)) against Boolean predictive control (sect. 4, criterion (23)) at
about the same number of commutations per second.

The claim: "For Nb_c ~ 10000 (number of switches commutations by second), the
predictive control leads to better performances particularly if gamma is not
equal to 0." The paper's numbers behind it: SVM at F_ech = 1 kHz, E_Gamma =
2.43, E_Id = 3.82, Nb_c = 12000 (sect. 3.3 simulation 1); predictive control
at 10 kHz, gamma = 0: 1.93, 3.79, Nb_c = 10740; gamma = 35: 1.386, 2.38,
Nb_c = 10500 (sect. 4.3 simulations 1 and 3).

Setup: designs/002_cormerais2002_svm_pi.toml and 002_cormerais2002_fcs_mpc.toml
(motor catalog "cormerais2002", E = 12 V assumed: tests/sim/test_paper002.py
explains the choice; no delay; hexagon limit), built by
``toolbox.design.design`` with only ``drive.sample_time`` and
``controller.fcs_mpc.gamma`` changed per case, and simulated through
``toolbox.sim.control_law``. Scenario as in tests/sim/test_paper002.py: 36 N m
(i_q = 100 A, i_d = 0) from standstill with free acceleration (J = 1 kg m^2),
0.5 s; E_Gamma = ``mse_torque`` (N^2 m^2), E_Id = ``mse_id`` (A^2).
Every printed row on its own, at 0.4 s (the gallery's run length), is
tests/papers/test_002_rows.py; the assumptions searched are in
tests/papers/README.md "Paper 002".

Counting commutations. The simulator reports both ``commutations_per_s``
(switch commutations, two per cell change) and ``cell_transitions_per_s``.
The paper's SVM Nb_c = 12 F_ech is the switch count (6000 cell changes/s at
1 kHz) while its predictive-control Nb_c (10740 at 10 kHz) agrees with our
cell-change count (9524/s; our switch count is 19048/s). So:

* On the paper's own counts (SVM 12000 vs FCS ~10000), the simulation
  supports the claim for gamma = 0: E_Gamma 1.64 vs 2.15 (-24 %), E_Id 3.61
  vs 6.94 (-48 %).
* Counted consistently, that FCS commutes 1.6x as often as the SVM. At an
  equal switch count (~12000/s) the advantage disappears: FCS gamma = 35 at
  10 kHz (12040/s) gives E_Gamma 2.38 (+11 %), E_Id 6.74 (-3 %); FCS
  gamma = 0 at 6.5 kHz (12440/s) gives 2.20 (+2 %) and 8.53 (+23 %). We
  assert that: no torque advantage for predictive control at equal switching.
* The paper's gamma = 35 run has lower errors than its gamma = 0 run; ours
  has higher ones (E_Gamma x1.45, E_Id x1.86) for 37 % fewer commutations,
  so "particularly if gamma is not equal to 0" is not reproduced. Why we
  believe the simulation: with a one-period horizon, criterion (23) compares
  gamma with squared current errors (A^2); gamma = 35 equals a (5.9 A)^2
  error, of the order of the current change one active vector makes in one
  period at 10 kHz (sqrt(2/3) E Ts / L = 8.7 A, power-invariant dq), so the controller keeps a vector one more
  period whenever the predicted gain is below that, which must raise the
  ripple: fewer commutations cannot lower the error of a controller that
  already minimises it greedily each period. The paper does not give E, the
  run length nor its Nb_c counting, so its gamma = 35 numbers cannot be
  re-derived (note also that its simulation 4 repeats simulation 3's numbers
  exactly, a sign of editing damage).

Most of E_Gamma is the saturated start (0 -> 100 A takes ~1.6 ms at 12 V,
worth 1.26-1.41 N^2 m^2 of the 0.5 s mean for both SVM and FCS); the
steady-state split is printed by the first test (from two deterministic runs
of 50 ms and 0.5 s).
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest

from toolbox.design import design
from toolbox.sim import control_law, drive_params, simulate
from toolbox.spec import Scenario
from toolbox.spec import spec_from_dict

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
DURATION = 0.5            # s
T_START = 0.05            # s, end of the "start" window of the split


def _metrics(name: str, inverter: str, sample_time: float | None = None,
             gamma: float | None = None, duration: float = DURATION) -> dict:
    """Metrics of one design file with an optional period / gamma change."""
    with open(DESIGNS / f"002_cormerais2002_{name}.toml", "rb") as fh:
        data = copy.deepcopy(tomllib.load(fh))
    if sample_time is not None:
        data["drive"]["sample_time"] = sample_time
    if gamma is not None:
        data["controller"]["fcs_mpc"]["gamma"] = gamma
    spec = spec_from_dict(data)
    art = design(spec)
    sc = Scenario(kind="unloaded_start", duration=duration, torque_ref=36.0,
                  inverter=inverter)
    return simulate(control_law(art), spec.motor, sc,
                    drive_params(spec.drive, inverter)).metrics


def svm(**kw) -> dict:
    """SVM + PI at the design file's 1 kHz."""
    return _metrics("svm_pi", "svm", **kw)


def fcs(F: float, gamma: float, **kw) -> dict:
    """Predictive control at F_ech = F (Hz) with switching weight gamma."""
    return _metrics("fcs_mpc", "fcs_mpc", sample_time=1.0 / F, gamma=gamma, **kw)


@pytest.fixture(scope="module")
def runs():
    return {"svm": svm(), "fcs10k_g0": fcs(1e4, 0.0), "fcs10k_g35": fcs(1e4, 35.0),
            "fcs6k5_g0": fcs(6500.0, 0.0)}


def _line(name: str, m: dict) -> str:
    return (f"{name:11s} E_Gamma {m['mse_torque']:.3f}  E_Id {m['mse_id']:.3f}  "
            f"switch comm. {m['commutations_per_s']:.0f}/s  "
            f"cell changes {m['cell_transitions_per_s']:.0f}/s")


def test_fcs_beats_svm_at_the_papers_nbc(runs):
    """Sect. 6 on the paper's counts: SVM 1 kHz (Nb_c = 12 F = 12000) vs FCS
    10 kHz gamma = 0 (Nb_c ~ 10000 cell changes/s, paper 10740). Measured
    ratios FCS/SVM: E_Gamma 0.76, E_Id 0.52; asserted < 0.85 and < 0.7 (a
    margin for small simulator changes, still failing if FCS were not better
    on both)."""
    s, f = runs["svm"], runs["fcs10k_g0"]
    print()
    for name, m in runs.items():
        print(_line(name, m))
    # the steady-state part (after T_START) from two identical deterministic runs
    for name, short in (("svm", svm(duration=T_START)), ("fcs10k_g0", fcs(1e4, 0.0,
                                                                         duration=T_START))):
        ss = {k: (DURATION * runs[name][k] - T_START * short[k]) / (DURATION - T_START)
              for k in ("mse_torque", "mse_id")}
        print(f"{name:11s} start share of E_Gamma {short['mse_torque'] * T_START / DURATION:.3f}; "
              f"steady state (t > {T_START} s): E_Gamma {ss['mse_torque']:.3f}, "
              f"E_Id {ss['mse_id']:.3f}")
    assert s["commutations_per_s"] == pytest.approx(12000.0, rel=1e-9)
    assert 8500.0 < f["cell_transitions_per_s"] < 11500.0      # "Nb_c ~ 10000"
    assert f["mse_torque"] < 0.85 * s["mse_torque"]
    assert f["mse_id"] < 0.7 * s["mse_id"]
    for m in (s, f):                      # both hold the 36 N m (i_q = 100 A) demand
        assert abs(m["final_value"] - 100.0) < 2.0


def test_no_torque_advantage_at_equal_switch_count(runs):
    """Counted consistently (switch commutations, SVM 12000/s), predictive
    control at the same rate does not beat SVM on torque: gamma = 35 at
    10 kHz (12040/s) E_Gamma +11 %, gamma = 0 at 6.5 kHz (12440/s) +2 %. The
    rates are asserted within 6 % of SVM's; the torque errors asserted not
    below 0.95x SVM's, and E_Id not below 0.9x (measured 0.97x and 1.23x):
    the paper's "better performances" needs its unequal counting."""
    s = runs["svm"]
    for key in ("fcs10k_g35", "fcs6k5_g0"):
        f = runs[key]
        assert f["commutations_per_s"] == pytest.approx(s["commutations_per_s"], rel=0.06)
        assert f["mse_torque"] > 0.95 * s["mse_torque"]
        assert f["mse_id"] > 0.9 * s["mse_id"]


def test_gamma_35_commutes_less_but_errs_more_through_the_design_files(runs):
    """Sect. 4.3 simulation 3 vs 1 through design() and the artifact (the raw
    ControlLaw route is tests/sim/test_paper002.py): gamma = 35 cuts the
    commutations by 37 % (9524 -> 6020 cell changes/s; paper 10740 -> 10500,
    -2 %) and raises E_Gamma x1.45 and E_Id x1.86 (paper: x0.72 and x0.63).
    Asserted: a cut between 25 % and 50 %, and both errors up by > 20 % (the
    direction opposite to the paper's, explained in the module docstring)."""
    g0, g35 = runs["fcs10k_g0"], runs["fcs10k_g35"]
    cut = 1.0 - g35["cell_transitions_per_s"] / g0["cell_transitions_per_s"]
    print(f"\ngamma 0 -> 35 at 10 kHz: commutations -{cut * 100:.1f} %, "
          f"E_Gamma x{g35['mse_torque'] / g0['mse_torque']:.2f}, "
          f"E_Id x{g35['mse_id'] / g0['mse_id']:.2f}")
    assert 0.25 < cut < 0.5
    assert g35["mse_torque"] > 1.2 * g0["mse_torque"]
    assert g35["mse_id"] > 1.2 * g0["mse_id"]
    assert abs(g35["final_value"] - 100.0) < 3.0
