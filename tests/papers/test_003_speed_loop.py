"""Paper 003 (Azaiz et al. 2007), sect. 4, Fig. 12-13, and the +/-50 %
time-constant claim of sect. 4-5.

Design: designs/003_azaiz2007_speed.toml, the gamma = 1 third-order H-infinity
current controllers of eq (71)-(72) (designs/003_azaiz2007_hinf.toml) inside
the speed loop of Fig. 4, run by ``toolbox.sim.simulate``.

What the paper gives (sect. 4): speed PID "Kp = 0.5045, KD = 0.0045, KI = 0.5";
omega_ref a 175 rad/s step; 3 N m load at t = 0.08 s; "the electromagnetic
torque climbs to nearly 14.3 N m when the motor starts and stabilizes rapidly
when the motor reaches the reference value"; with the time constants varied
by 50 % (Fig. 13) T_e, i_d, i_q "do not differ" from the nominal ones; sect. 5:
"although the time constants of the models vary by 50 %, the stability and
performance are maintained within acceptable limits".

What it does not give: the PID's form, units, sampling, derivative filter and
output limit. We read the parallel form i_qr = Kp e + KI int e + KD de/dt
(e in mechanical rad/s, i_qr in A: kp A s/rad, ki A/rad, kd A s^2/rad;
``toolbox.sim.SpeedLoop``), executed every 0.1 ms, unfiltered derivative on
the error, i_qr limited to I_qmax = 20 A (sect. 6). The inverter's saturation
is neglected (remark on Fig. 5), hence the 1000 V link of the design file.

Paper vs ours (Run with ``-s`` to print them):

* Peak torque, Fig. 12: paper "nearly 14.3 N m" = 0.72 N m/A x 19.9 A, i.e.
  the torque of the 20 A limit (3/2 p phi_f = 0.72 N m/A, eq (5)). Ours:
  11.2 N m with the 20 A limit, 15.9 N m without a limit. The gap is the
  derivative term: at full acceleration KD dOmega/dt = 0.0045 x 14.3/1.11e-3
  = 58 A pulls i_qr off its limit as soon as the rotor moves, and the current
  loop (145 rad/s, rise time 13 ms, Fig. 8) cannot follow the short kick. The
  peak depends on the unspecified limit and derivative implementation, so it
  is NOT reproduced as a number; the test asserts the paper's 14.3 N m lies
  between our two readings (limit on / off) and that the limited run stays
  under the 14.4 N m bound of the limit.
* Reaching 175 rad/s without visible overshoot (Fig. 12): ours overshoot
  0.3 %, 98 % of the step at 44 ms; tolerance 1 %.
* After the 3 N m load (Fig. 12): torque -> 3 + F Omega; ours 3.244 N m at the
  end of the 1 s run against 3 + F Omega(1 s) = 3.241 N m, tolerance 2 %. The
  speed dips by 7.4 rad/s and is recovered only by KI = 0.5 A/rad (time
  constant Kp/KI ~ 1 s): the 2 % band is re-entered at 0.88 s, 171.9 rad/s at
  1 s (the paper's figure has no readable axis; its text says the torque
  increases "to maintain the speed at its reference value").
* Fig. 13, time constants +/-50 %: the paper prints tau_d = 2.33e-3 s and
  tau_q = 4.66e-3 s as the "varied" values, but these are the NOMINAL
  L_d/r_s = 1.4e-3/0.6 and L_q/r_s = 2.8e-3/0.6: the paper disagrees with its
  own text. We vary tau through L (x1.5 and x0.5, R kept; the controllers and
  the decoupling keep the nominal model). Ours: speed trajectories differ by
  at most 11.4 rad/s (6.5 % of 175), torque by at most 2.1 N m, but i_d
  moves by up to 8.8 A (nominal peak 0.4 A), from the decoupling terms
  computed with the nominal inductances: "i_d does not differ" is NOT
  reproduced, speed and torque are (bounds below, each ~1.3x ours).
* Current loop alone, 10 A step on i_q at standstill (the Fig. 8 setup of
  designs/003_azaiz2007_hinf.toml, 150 V): nominal 5 % response 18.6 ms,
  no overshoot; L x1.5: 16.4 ms, 2.6 %; L x0.5: 23.8 ms, 0 %; the claim of
  sect. 5 holds when tau varies through L (asserted: response within 30 % of
  nominal, overshoot < 5 %, error < 1 % at 80 ms). Varied through R it does
  not hold as well: the controller's zero at 214.3 rad/s (eq 71) cancels the
  nominal pole R/L_q; with R x2 the uncancelled pole at 428 rad/s leaves a
  slow tail (5 % response 44 ms, 6.8 % error at 80 ms). Asserted: stable and
  slower; documented, not claimed by the paper (it varies "time constants").
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from toolbox.design import design
from toolbox.sim import SpeedLoop, control_law, drive_params, simulate
from toolbox.spec import Scenario
from toolbox.spec import load_spec

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
PAPER_PEAK_TORQUE = 14.3     # N m, sect. 4 (Fig. 12)
SPEED_REF = 175.0            # rad/s
LOAD = 3.0                   # N m at 0.08 s


@pytest.fixture(scope="module")
def speed_setup():
    spec = load_spec(DESIGNS / "003_azaiz2007_speed.toml")
    art = design(spec)
    fig12, fig13 = spec.scenarios
    sl = SpeedLoop(**dict(fig12.speed_loop))
    return spec, art, fig12, fig13, sl


@pytest.fixture(scope="module")
def runs(speed_setup):
    spec, art, fig12, fig13, sl = speed_setup
    drive = drive_params(spec.drive)
    law = control_law(art, sl)
    out = {k: simulate(law, spec.motor.with_overrides(scale={"Ld": k, "Lq": k}), fig12, drive)
           for k in (1.0, 1.5, 0.5)}
    unlimited = control_law(art, dataclasses.replace(sl, iq_limit=float("inf")))
    out["no_limit"] = simulate(unlimited, spec.motor, fig12, drive)
    return out


def test_design_file_matches_sect_4(speed_setup):
    spec, _, fig12, fig13, sl = speed_setup
    assert (sl.kp, sl.ki, sl.kd, sl.iq_limit) == (0.5045, 0.5, 0.0045, 20.0)
    assert fig12.kind == "speed_step" and fig12.speed_ref == SPEED_REF
    assert (fig12.load_torque, fig12.load_time) == (LOAD, 0.08)
    assert dict(fig13.plant_scale) == {"Ld": 1.5, "Lq": 1.5}
    assert spec.motor.torque_factor * spec.motor.pole_pairs * spec.motor.flux == pytest.approx(0.72)


def test_fig12_peak_torque(runs):
    """14.3 N m (paper) lies between our peaks with and without the 20 A limit."""
    lim, free = runs[1.0].torque.max(), runs["no_limit"].torque.max()
    print(f"\nFig. 12 peak torque: paper 14.3 N m; ours {lim:.2f} N m (i_qr <= 20 A), "
          f"{free:.2f} N m (no limit)")
    assert lim < PAPER_PEAK_TORQUE < free
    assert lim <= 0.72 * 20.0 + 0.05
    assert lim == pytest.approx(11.16, abs=0.3) and free == pytest.approx(15.89, abs=0.3)


def test_fig12_speed_and_load(runs, speed_setup):
    spec = speed_setup[0]
    r = runs[1.0]
    before = r.t < 0.08
    over = (r.speed.max() / SPEED_REF - 1) * 100
    t98 = r.t[np.argmax(r.speed >= 0.98 * SPEED_REF)]
    t_end = spec.motor.friction * r.speed[-1] + LOAD
    vmax = float(np.max(np.hypot(r.vd, r.vq)))
    print(f"\nFig. 12: overshoot {over:.2f} %, 98 % at {t98 * 1e3:.1f} ms, speed at 0.08 s "
          f"{r.speed[before][-1]:.2f} rad/s, dip after load {SPEED_REF - r.speed[~before].min():.2f} "
          f"rad/s, torque at {r.t[-1]:.2f} s {r.torque[-1]:.3f} N m (3 + F Omega = {t_end:.3f}), "
          f"max |v| {vmax:.0f} V")
    assert abs(r.speed[before][-1] - SPEED_REF) < 0.01 * SPEED_REF
    assert over < 1.0
    assert r.torque[-1] == pytest.approx(t_end, rel=0.02)
    assert r.torque[before][-1] < 0.5   # no load: only friction before 0.08 s
    assert vmax < 150.0                 # the 1000 V link never limits (577 V)


def test_fig13_time_constants_50pct(runs):
    """Speed and torque within bounds of nominal under L x1.5 / x0.5; i_d not."""
    ref = runs[1.0]
    for k in (1.5, 0.5):
        r = runs[k]
        dw = np.abs(r.speed - ref.speed).max()
        dt = np.abs(r.torque - ref.torque).max()
        did = np.abs(r.id - ref.id).max()
        print(f"\nFig. 13, L x{k}: max|dOmega| {dw:.2f} rad/s, max|dT_e| {dt:.2f} N m, "
              f"max|di_d| {did:.2f} A (paper: 'do not differ')")
        assert abs(r.speed[r.t < 0.08][-1] - SPEED_REF) < 0.01 * SPEED_REF
        assert dw < 15.0 and dt < 2.8
        assert did > 5.0 * np.abs(ref.id).max()   # the claim on i_d is not reproduced


@pytest.fixture(scope="module")
def current_steps():
    spec = load_spec(DESIGNS / "003_azaiz2007_hinf.toml")
    law = control_law(design(spec))
    sc = Scenario(kind="current_step", duration=0.08, iq_ref=10.0)
    drive = drive_params(spec.drive)
    cases = {"nominal": {}, "L x1.5": {"Ld": 1.5, "Lq": 1.5}, "L x0.5": {"Ld": 0.5, "Lq": 0.5},
             "R x2": {"R": 2.0}, "R /1.5": {"R": 1 / 1.5}}
    return {n: simulate(law, spec.motor.with_overrides(scale=s), sc, drive).metrics
            for n, s in cases.items()}


def test_current_loop_time_constant_via_L(current_steps):
    nom = current_steps["nominal"]["response_time_5pct"]
    for n in ("L x1.5", "L x0.5"):
        m = current_steps[n]
        print(f"\n{n}: 5 % response {m['response_time_5pct'] * 1e3:.1f} ms (nominal "
              f"{nom * 1e3:.1f}), overshoot {m['overshoot_pct']:.2f} %, error {m['static_error']:.2e}")
        assert abs(m["response_time_5pct"] / nom - 1) < 0.3
        assert m["overshoot_pct"] < 5.0 and abs(m["static_error"]) < 0.01


def test_current_loop_time_constant_via_R(current_steps):
    nom = current_steps["nominal"]["response_time_5pct"]
    for n in ("R x2", "R /1.5"):
        m = current_steps[n]
        print(f"\n{n}: 5 % response {m['response_time_5pct'] * 1e3:.1f} ms, overshoot "
              f"{m['overshoot_pct']:.2f} %, error at 80 ms {m['static_error']:.2e}")
        assert np.isfinite(m["response_time_5pct"]) and m["overshoot_pct"] < 10.0
    assert current_steps["R x2"]["response_time_5pct"] > 2 * nom
    assert current_steps["R x2"]["static_error"] > 0.03
