"""simulate / simulate_batch behaviour: batch = single runs, progress, flat
memory, speed loop scenarios, inverter limits, seeded noise, bad drives."""

import dataclasses
import math
import resource

import numpy as np
import pytest

from toolbox.errors import SpecError
from toolbox.spec import Scenario
from toolbox.artifact import Decoupling
from toolbox.sim._simulate import (ControlLaw, DriveParams, SpeedLoop, discrete_pi, simulate,
                                   simulate_batch)

from sim_helpers import PAPER000 as M, tc_law

Ts = 1e-4
DRIVE = DriveParams(vdc=150, sample_time=Ts, delay_samples=1)


def _pi(wc=2000.0, speed_loop=None):
    return ControlLaw(d=discrete_pi(M.Ld * wc, M.R * wc, Ts),
                      q=discrete_pi(M.Lq * wc, M.R * wc, Ts), sample_time=Ts,
                      decoupling=Decoupling.from_motor(M, delay_compensation_time=1.5 * Ts),
                      speed_loop=speed_loop)


@pytest.mark.parametrize("threads", [1, 3])
def test_batch_equals_single_runs_and_reports_progress(threads):
    """Every row of a batch is :func:`simulate`'s run of its plant, bit for bit
    (the same compiled kernel; the rows are independent), whatever the thread
    count: 3 threads on chunks of 3 give shares of one row each and, in the
    last chunk, empty shares; progress comes after each chunk."""
    sc = Scenario(kind="unloaded_start", duration=0.01, iq_ref=5.0)
    scales = np.linspace(0.5, 2.0, 7)
    plants = {"R": M.R, "Ld": M.Ld * scales, "Lq": M.Lq * scales, "flux": M.flux,
              "pole_pairs": M.pole_pairs, "J": M.J, "friction": M.friction,
              "torque_factor": 1.0}
    calls = []
    out = simulate_batch(_pi(), plants, sc, DRIVE, progress=lambda d, n: calls.append((d, n)),
                         chunk=3, threads=threads)
    assert calls == [(3, 7), (6, 7), (7, 7)]
    for i, s in enumerate(scales):
        single = simulate(_pi(), M.with_overrides(scale={"Ld": s, "Lq": s}), sc, DRIVE)
        for k, v in single.metrics.items():
            b = out.metrics[k][i]
            assert (math.isnan(v) and math.isnan(b)) or b == v, k


def test_batch_refuses_empty_chunks_and_no_threads():
    """A chunk or thread count below one would never finish: refused."""
    sc = Scenario(kind="unloaded_start", duration=0.001, iq_ref=5.0)
    for kw in ({"chunk": 0}, {"threads": 0}):
        with pytest.raises(ValueError, match="chunk and threads must be >= 1"):
            simulate_batch(_pi(), [M], sc, DRIVE, **kw)


@pytest.mark.slow
def test_metrics_only_memory_is_flat():
    """A 20 s metrics-only run allocates no trace: peak RSS grows < 20 MB
    (a trace at every 1 us step would need 20e6 * 10 * 8 B = 1.6 GB)."""
    sc = Scenario(kind="unloaded_start", duration=0.001, iq_ref=5.0)
    simulate(_pi(), M, sc, DRIVE)                      # compile / warm up
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    res = simulate(_pi(), M, Scenario(kind="unloaded_start", duration=20.0, iq_ref=5.0),
                   DRIVE)
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert res.t is None and math.isfinite(res.metrics["mse_torque"])
    assert (after - before) * 1024 < 20e6


def test_speed_step_with_pid_speed_loop():
    """Speed PID (paper 003's Kp = 0.5045 and KD = 0.0045, KI raised to 10 for
    this motor's small inertia) tracks a 100 rad/s step with zero static error."""
    sl = SpeedLoop(kp=0.5045, ki=10.0, kd=0.0045, sample_time=1e-3, iq_limit=15.0)
    sc = Scenario(kind="speed_step", duration=1.0, speed_ref=100.0, step_time=0.01)
    m = simulate(_pi(speed_loop=sl), M, sc, DRIVE).metrics
    assert abs(m["static_error"]) < 0.5
    assert 0 < m["response_time_5pct"] < 0.9
    assert abs(m["final_speed"] - 100) < 1.0


def test_load_step_recovers_speed():
    sl = SpeedLoop(kp=0.5, ki=10.0, sample_time=1e-3, iq_limit=15.0)
    sc = Scenario(kind="load_step", duration=2.0, speed_ref=50.0, initial_speed=50.0,
                  load_torque=0.5, load_time=0.5, keep_traces=True, trace_step=1e-3)
    res = simulate(_pi(speed_loop=sl), M, sc, DRIVE)
    assert abs(res.metrics["static_error"]) < 0.2
    assert len(res.t) == 2000
    # the load must be carried by i_q: T = p flux iq (torque factor 1)
    assert res.iq[-1] == pytest.approx((0.5 + M.friction * 50) / (M.pole_pairs * M.flux),
                                       rel=0.02)


def test_sinusoidal_torque_and_hexagon_limit():
    sc = Scenario(kind="sinusoidal_torque", duration=0.2, torque_amplitude=3.0,
                  torque_frequency=5.0, keep_traces=True)
    drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=1, v_limit="hexagon")
    res = simulate(_pi(), M, sc, drive)
    assert np.max(np.abs(res.iq_ref)) == pytest.approx(3.0 / (4 * 0.12), rel=1e-3)
    assert res.metrics["mse_torque"] < 0.05
    assert math.isnan(res.metrics["response_time_5pct"])
    # hexagon vertex radius sqrt(2/3) vdc for torque factor 1: never exceeded
    r = np.hypot(res.vd, res.vq)
    assert np.all(r <= math.sqrt(2 / 3) * 150 * (1 + 1e-12))


def test_noise_is_seeded():
    base = dict(kind="current_step", duration=0.01, iq_ref=10.0, initial_speed=100.0,
                speed_noise=5.0, current_noise=0.05, current_quantum=50 / 256)
    law = tc_law(M, 800, 800, Ts)
    a = simulate(law, M, Scenario(**base, seed=1), DRIVE).metrics
    b = simulate(law, M, Scenario(**base, seed=1), DRIVE).metrics
    c = simulate(law, M, Scenario(**base, seed=2, noise="gaussian"), DRIVE).metrics
    assert a.keys() == b.keys()
    assert all(a[k] == b[k] or (np.isnan(a[k]) and np.isnan(b[k])) for k in a)  # bit for bit
    assert a["mse_iq"] != c["mse_iq"]


def test_bad_drive_inputs():
    sc = Scenario(kind="current_step", duration=0.01, iq_ref=1.0)
    with pytest.raises(SpecError, match="drive.sample_time"):
        simulate(_pi(), M, sc, DriveParams(vdc=150, sample_time=2e-4))
    with pytest.raises(SpecError, match="drive.v_limit"):
        simulate(_pi(), M, sc, DriveParams(vdc=150, sample_time=Ts, v_limit="square"))
    with pytest.raises(SpecError, match="a law with a speed loop"):
        simulate(_pi(), M, Scenario(kind="speed_step", duration=0.01, speed_ref=1.0),
                 DRIVE)
    with pytest.raises(SpecError, match="scenario.plant_scale.Ld"):
        simulate(_pi(), M, Scenario(kind="current_step", duration=0.01,
                                    plant_values={"Ld": 1e-3}, plant_scale={"Ld": 0.0}),
                 DRIVE)


def test_axis_law_from_error_controller_equals_two_input_form():
    """The artifact's error -> voltage controller, widened to [i_ref, i_meas],
    gives the same simulation as the hand-written two-input PI."""
    from toolbox.sim._simulate import AxisLaw
    wc = 2000.0
    pi_d, pi_q = discrete_pi(M.Ld * wc, M.R * wc, Ts), discrete_pi(M.Lq * wc, M.R * wc, Ts)
    wide = [AxisLaw.from_error_controller(ax.A, ax.B[:, :1], ax.C, ax.D[0, 0], ax.antiwindup)
            for ax in (pi_d, pi_q)]
    law2 = ControlLaw(d=wide[0], q=wide[1], sample_time=Ts,
                      decoupling=Decoupling.from_motor(M, delay_compensation_time=1.5 * Ts))
    sc = Scenario(kind="unloaded_start", duration=0.01, iq_ref=5.0)
    assert simulate(law2, M, sc, DRIVE).metrics == simulate(_pi(), M, sc, DRIVE).metrics


def test_plant_step_follows_the_fastest_time_constant():
    """A stiff motor (R 39 ohm, L 10 uH: L/R = 0.26 us, below the 1 us default
    step) is integrated at 5 % of L/R (``plant_step``), so a stable loop (a PI
    with GM 9.2 dB, PM 57 deg at Ts = 20 us) is not failed by RK4 diverging:
    its run (0.3 A: 12 V of the 27.7 V limit) equals one at an explicit 1e-9 s step within 1e-6 A
    (RK4 at 5 % of tau: local error ~ 1e-8 per step)."""
    from toolbox.sim._simulate import plant_step
    from toolbox.spec import Motor
    stiff = Motor(R=39.0, Ld=1e-5, Lq=1e-5, flux=0.01, pole_pairs=4, J=1e-5, friction=1e-5)
    ts = 2e-5
    wc = 0.3 / ts
    law = ControlLaw(d=discrete_pi(stiff.Ld * wc, stiff.R * wc, ts),
                     q=discrete_pi(stiff.Lq * wc, stiff.R * wc, ts), sample_time=ts,
                     decoupling=Decoupling.from_motor(stiff, delay_compensation_time=1.5 * ts))
    drive = DriveParams(vdc=48, sample_time=ts, delay_samples=1)
    sc = Scenario(kind="current_step", duration=2e-3, iq_ref=0.3, keep_traces=True)
    assert plant_step(sc, [stiff]) == pytest.approx(0.05 * 1e-5 / 39.0)
    auto = simulate(law, stiff, sc, drive)
    fine = simulate(law, stiff, dataclasses.replace(sc, plant_step=1e-9), drive)
    assert np.all(np.isfinite(auto.iq)) and auto.metrics["final_value"] == pytest.approx(0.3, abs=1e-4)
    assert np.max(np.abs(auto.iq - fine.iq)) < 1e-6
