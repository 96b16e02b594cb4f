"""Paper 001 (Takami 2004), sect. 3.1, Figs. 4-5 (a), (d), (e): speed-step
responses of the ILQ and the PI-with-lag current servo systems inside a speed
loop (Fig. 3: speed PI on top, i_d* = 0) at nominal, 0.5x and 2x armature
inductance L_1 (Ld = Lq both scaled; the controllers keep the nominal model).

The paper's claim (text after Figs. 4-5): "In Fig. 4 [ILQ] the variations of
current i_1d are very small and responses of the motor speed are very robust.
While in Fig. 5 [PI] the variations of current i_1d are large ... the PI
servo-system is more sensitive to variations of armature inductance L_1."

Designs: designs/001_takami2004_ilq.toml (eq (1)-(4), s* = -1000 rad/s,
sigma = 2500 1/s) and designs/001_takami2004_pi_lag.toml (Fig. 2b, pole-zero
cancellation at 1000 rad/s, lag T_d = 0.2 ms), built by ``toolbox.design.design``
and run by ``toolbox.sim.simulate`` through ``toolbox.sim.control_law``. Both
use the drive of the design files: 0.1 ms controller period (sect. 3.1), one
period of computation delay, 200 V link, and the plant integrated at 1 us
(sect. 3.1 solves the motor equations at 1 us as well).

Choices the paper does not print (its figures carry no readable axis values):

* Speed step 0 -> 50 rad/s (477 rpm, a third of the 1500 rpm rating: the
  paper's subject is low speed) at t = 5 ms, 80 ms simulated.
* Speed PI (same for both systems, executed every 0.1 ms, i_q* limited to the
  catalog's 30 A): K_t = 1.5 p lambda_f = 0.714 N m/A; kp = J w_s / K_t with
  w_s = 500 rad/s -> 0.861 A s/rad; ki = kp D / J (zero cancels the
  mechanical pole D/J = 29.8 1/s) -> 25.6 A/rad. The step demands about 30 A
  of i_q, so the current loops see a large, fast reference, as in Figs. 4-5.

Figures of merit, per inductance factor k in {0.5, 2} and system, against the
same system's nominal (k = 1) run, on traces sampled every 0.1 ms:

* ``dspeed`` = integral of |Omega_k(t) - Omega_1(t)| dt (rad);
* ``did`` = max |i_d,k(t) - i_d,1(t)| (A).

Measured (this simulator): ILQ dspeed 0.0073 / 0.031 rad, did 0.32 / 1.13 A;
PI dspeed 0.032 / 0.071 rad, did 1.25 / 2.36 A (k = 0.5 / 2), i.e. the ILQ
responses move 2.1-4.3x less; nominal 5 % speed
response times 4.47 ms (ILQ) and 4.97 ms (PI). Assertion: every ILQ figure <= 0.6x the PI one
(a 1.67x margin, well inside the smallest measured ratio 2.1, and failing if
the two systems were equally sensitive). The nominal responses must be
comparable (5 % speed response times within 20 %), so the comparison is not
won by a slower design.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from toolbox.design import design
from toolbox.sim import SpeedLoop, control_law, drive_params, simulate
from toolbox.spec import Scenario
from toolbox.spec import load_spec

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
SPEED_REF = 50.0          # rad/s
W_S = 500.0               # speed-loop bandwidth (rad/s)
FACTORS = (1.0, 0.5, 2.0)
RATIO = 0.6               # ILQ figure <= RATIO x PI figure


def speed_loop(motor) -> SpeedLoop:
    """Speed PI of Fig. 3 (choice documented in the module docstring)."""
    k_t = motor.torque_factor * motor.pole_pairs * motor.flux      # N m/A
    kp = motor.J * W_S / k_t
    return SpeedLoop(kp=kp, ki=kp * motor.friction / motor.J, sample_time=1e-4,
                     iq_limit=motor.max_current)


def run_system(name: str) -> dict:
    """Speed-step traces of one servo system at the three inductance factors."""
    spec = load_spec(DESIGNS / f"001_takami2004_{name}.toml")
    art = design(spec)
    law = control_law(art, speed_loop(spec.motor))
    plant, drive = spec.motor, drive_params(spec.drive)
    sc = Scenario(kind="speed_step", duration=0.08, step_time=0.005, speed_ref=SPEED_REF,
                  keep_traces=True)
    return {k: simulate(law, plant.with_overrides(scale={"Ld": k, "Lq": k}), sc, drive)
            for k in FACTORS}


def merits(runs: dict, ts: float = 1e-4) -> dict:
    """{k: (dspeed (rad), did (A))} against the nominal run."""
    ref = runs[1.0]
    return {k: (float(np.sum(np.abs(runs[k].speed - ref.speed)) * ts),
                float(np.max(np.abs(runs[k].id - ref.id))))
            for k in FACTORS if k != 1.0}


@pytest.fixture(scope="module")
def results():
    return {name: run_system(name) for name in ("ilq", "pi_lag")}


def test_nominal_speed_responses_comparable(results):
    """Both systems reach the speed command and have similar nominal speed
    response times (within 20 %), so the sensitivity comparison below is fair.
    Final speed within 1 % (the speed integrator, ki/kp = 30 1/s, is still
    closing the last fraction of a per cent at 80 ms)."""
    t5 = {n: r[1.0].metrics["response_time_5pct"] for n, r in results.items()}
    print(f"\nnominal 5 % speed response: ILQ {t5['ilq'] * 1e3:.2f} ms, "
          f"PI {t5['pi_lag'] * 1e3:.2f} ms")
    assert math.isfinite(t5["ilq"]) and math.isfinite(t5["pi_lag"])
    assert abs(t5["ilq"] / t5["pi_lag"] - 1.0) < 0.2
    for r in results.values():
        for k in FACTORS:
            assert abs(r[k].speed[-1] - SPEED_REF) < 0.01 * SPEED_REF


def test_ilq_less_sensitive_to_inductance_than_pi(results):
    """Fig. 4 vs Fig. 5 (d)-(e): the ILQ servo's speed and i_d responses move
    less with L_1 than the PI servo's (figures and margin in the module
    docstring)."""
    m = {n: merits(r) for n, r in results.items()}
    for k in (0.5, 2.0):
        (s_i, d_i), (s_p, d_p) = m["ilq"][k], m["pi_lag"][k]
        print(f"k = {k}: int|dOmega| ILQ {s_i:.4g} rad, PI {s_p:.4g} rad "
              f"(ratio {s_p / s_i:.2f}); max|di_d| ILQ {d_i:.3g} A, PI {d_p:.3g} A "
              f"(ratio {d_p / d_i:.2f})")
    for k in (0.5, 2.0):
        (s_i, d_i), (s_p, d_p) = m["ilq"][k], m["pi_lag"][k]
        assert s_i <= RATIO * s_p
        assert d_i <= RATIO * d_p
    # the absolute i_d excursion of the ILQ servo stays small (Fig. 4: "very
    # small"): below 5 % of the ~30 A i_q transient at every factor (measured
    # max 1.11 A, at 2x L) and below RATIO x the PI servo's (2.18 A)
    peak_id = {n: max(float(np.max(np.abs(r[k].id))) for k in FACTORS)
               for n, r in results.items()}
    print(f"max |i_d| over the factors: ILQ {peak_id['ilq']:.3g} A, "
          f"PI {peak_id['pi_lag']:.3g} A")
    assert peak_id["ilq"] < 1.5
    assert peak_id["ilq"] <= RATIO * peak_id["pi_lag"]


# ------------------------------------------------ Figs. 4-5 (b)-(c) and (f)-(g)
# Sect. 3.1: "(b) and (c) are the results at one-half the rated value and at two
# times the rated value of r_1 ... (f) and (g) ... 0.8 times ... and 1.2 times the
# rated value of lambda_f"; claim: "the variations of state variables due to the
# error of armature resistance r_1 are very small in both the ILQ and the PI servo
# systems". The paper states nothing about (f)-(g). Same setup and figures of
# merit as above (true plant varied, controllers and decoupling nominal).
# Measured (dspeed rad, did A): R x0.5: ILQ 0.0029 / 0.013, PI 0.0127 / 0.070;
# R x2: ILQ 0.0079 / 0.022, PI 0.0234 / 0.085; flux x0.8: ILQ 0.0365 / 0.039,
# PI 0.0356 / 0.082; flux x1.2: ILQ 0.0251 / 0.040, PI 0.0293 / 0.080.
R_FLUX = {"R x0.5": {"R": 0.5}, "R x2": {"R": 2.0},
          "flux x0.8": {"flux": 0.8}, "flux x1.2": {"flux": 1.2}}


@pytest.fixture(scope="module")
def r_flux_merits(results):
    out = {}
    for name in ("ilq", "pi_lag"):
        spec = load_spec(DESIGNS / f"001_takami2004_{name}.toml")
        law = control_law(design(spec), speed_loop(spec.motor))
        sc = Scenario(kind="speed_step", duration=0.08, step_time=0.005, speed_ref=SPEED_REF,
                      keep_traces=True)
        ref = results[name][1.0]
        for case, scale in R_FLUX.items():
            r = simulate(law, spec.motor.with_overrides(scale=scale), sc,
                         drive_params(spec.drive))
            out[name, case] = (float(np.sum(np.abs(r.speed - ref.speed)) * 1e-4),
                               float(np.max(np.abs(r.id - ref.id))))
    return out


def test_resistance_variation_small_in_both(r_flux_merits, results):
    """Figs. 4-5 (b)-(c): with r_1 x0.5 / x2 the i_d excursion of both systems
    stays below 0.1 A, under a tenth of the PI's i_d excursion at 2x L_1
    (2.36 A), and the speed moves at most 0.025 rad, a third of the PI's
    0.071 rad at 2x L_1: 'very small in both' reproduced. The ILQ still moves
    less than the PI (speed 2.9-4.4x, i_d 3.9-5.4x less), which the paper does
    not say."""
    pi_L = merits(results["pi_lag"])[2.0]
    for case in ("R x0.5", "R x2"):
        (s_i, d_i), (s_p, d_p) = r_flux_merits["ilq", case], r_flux_merits["pi_lag", case]
        print(f"\n{case}: int|dOmega| ILQ {s_i:.4f} rad, PI {s_p:.4f} rad; max|di_d| ILQ "
              f"{d_i:.3f} A, PI {d_p:.3f} A (PI at 2x L: {pi_L[0]:.4f} rad, {pi_L[1]:.2f} A)")
        for s_, d_ in ((s_i, d_i), (s_p, d_p)):
            assert d_ < 0.1 and d_ < 0.1 * pi_L[1]
            assert s_ < 0.035 and s_ < 0.5 * pi_L[0]
        assert s_i <= RATIO * s_p and d_i <= RATIO * d_p


def test_flux_variation_same_for_both(r_flux_merits):
    """Figs. 4-5 (f)-(g) (no claim in the text): lambda_f x0.8 / x1.2 changes the
    torque constant, which the speed loop, not the current servo, absorbs; the
    speed changes of the two systems agree within 25 % (0.025-0.037 rad) and
    i_d stays below 0.1 A in both."""
    for case in ("flux x0.8", "flux x1.2"):
        (s_i, d_i), (s_p, d_p) = r_flux_merits["ilq", case], r_flux_merits["pi_lag", case]
        print(f"\n{case}: int|dOmega| ILQ {s_i:.4f} rad, PI {s_p:.4f} rad; max|di_d| ILQ "
              f"{d_i:.3f} A, PI {d_p:.3f} A")
        assert abs(s_i / s_p - 1) < 0.25
        assert d_i < 0.1 and d_p < 0.1


# ------------------------------------------------ dq convention of Tables 1-2
# Paper 001 (Takami 2004): which dq convention Tables 1-2 use, and why the
# catalog's amplitude-invariant reading does not change what we reproduce.
#
# The paper prints no torque equation and no Park normalisation (sect. 2 gives
# only the decoupled electrical model eq (1)); Table 1: 1.3 kW, 1500 rpm,
# 8.34 N m, 8 poles, phase current 10.7 A; Table 2: lambda_f = 0.11896 Wb, EMF
# 49.83 V at 1000 rpm. The EMF is exactly p lambda_f omega_m (4 x 0.11896 x
# 104.72 = 49.83 V), the dq back-EMF magnitude in the paper's frame, so the
# convention is to be read from the rated point:
#
# * amplitude-invariant (catalog "takami2004"): lambda_f is the phase-peak flux,
#   the EMF is the phase-peak EMF, i_q = sqrt(2) x 10.7 = 15.13 A and
#   T = 3/2 p lambda_f i_q = 10.80 N m: 29.5 % above the printed 8.34 N m;
# * power-invariant: the EMF is the line-to-line rms EMF (the usual datasheet
#   figure), i_q = sqrt(3) x 10.7 = 18.53 A and T = p lambda_f i_q = 8.82 N m:
#   5.7 % above 8.34 N m (a hot-magnet / rating margin of that size is usual),
#   and the electromagnetic power 8.82 x 157.1 = 1.39 kW against 1.3 kW rated
#   (amplitude: 1.70 kW).
#
# So Tables 1-2 support the power-invariant convention; the paper never says so.
# The catalog keeps the amplitude-invariant reading (changing it changes the
# physical motor: the phase flux is then 0.11896 sqrt(2/3) = 0.0971 Wb, and the
# reference reports of designs/001_*). What we reproduce of paper 001 does not
# depend on it: the dq electrical equations, hence every current-loop figure
# (test_001_ilq.py), hold the same numbers in both conventions; the speed-step
# comparison (above, in this file) designs its speed PI from the torque
# constant, and the test below re-runs it with the power-invariant motor (same
# physical current limit, 30 A x sqrt(3/2)): ILQ still <= 0.6 x PI on every figure
# (measured: speed 0.0060 / 0.022 rad vs 0.029 / 0.066 rad, i_d 0.35 / 1.28 A vs
# 1.50 / 3.20 A, at 0.5x / 2x L).
PAPER_TORQUE, PAPER_CURRENT_RMS, PAPER_POWER = 8.34, 10.7, 1300.0   # Table 1
RATED_SPEED = 1500 * 2 * math.pi / 60


def test_table_1_favours_power_invariant():
    m = load_spec(DESIGNS / "001_takami2004_ilq.toml").motor
    assert m.convention == "amplitude" and m.flux == 0.11896
    assert m.pole_pairs * m.flux * 1000 * 2 * math.pi / 60 == pytest.approx(49.83, abs=0.005)
    t_amp = 1.5 * m.pole_pairs * m.flux * math.sqrt(2) * PAPER_CURRENT_RMS
    t_pow = m.pole_pairs * m.flux * math.sqrt(3) * PAPER_CURRENT_RMS
    print(f"\nTable 1: 8.34 N m at 10.7 A; amplitude-invariant {t_amp:.2f} N m "
          f"({t_amp / PAPER_TORQUE - 1:+.1%}), power-invariant {t_pow:.2f} N m "
          f"({t_pow / PAPER_TORQUE - 1:+.1%}); power {t_pow * RATED_SPEED:.0f} W vs "
          f"{t_amp * RATED_SPEED:.0f} W (rated 1300 W)")
    assert t_amp == pytest.approx(10.80, abs=0.01) and t_pow == pytest.approx(8.82, abs=0.01)
    assert abs(t_pow / PAPER_TORQUE - 1) < 0.06 < 0.25 < abs(t_amp / PAPER_TORQUE - 1)
    assert t_pow * RATED_SPEED == pytest.approx(PAPER_POWER, rel=0.07)


@pytest.fixture(scope="module")
def power_invariant_merits():
    out = {}
    for name in ("ilq", "pi_lag"):
        spec = load_spec(DESIGNS / f"001_takami2004_{name}.toml")
        motor = dataclasses.replace(spec.motor, convention="power",
                                    max_current=spec.motor.max_current * math.sqrt(1.5))
        law = control_law(design(dataclasses.replace(spec, motor=motor)), speed_loop(motor))
        sc = Scenario(kind="speed_step", duration=0.08, step_time=0.005, speed_ref=SPEED_REF,
                      keep_traces=True)
        runs = {k: simulate(law, motor.with_overrides(scale={"Ld": k, "Lq": k}), sc,
                            drive_params(spec.drive)) for k in FACTORS}
        out[name] = merits(runs)
    return out


def test_inductance_conclusion_holds_power_invariant(power_invariant_merits):
    m = power_invariant_merits
    for k in (0.5, 2.0):
        (s_i, d_i), (s_p, d_p) = m["ilq"][k], m["pi_lag"][k]
        print(f"\npower-invariant, L x{k}: int|dOmega| ILQ {s_i:.4f} rad, PI {s_p:.4f} rad; "
              f"max|di_d| ILQ {d_i:.2f} A, PI {d_p:.2f} A")
        assert s_i <= RATIO * s_p and d_i <= RATIO * d_p
