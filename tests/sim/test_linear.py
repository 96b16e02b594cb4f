"""Small-signal agreement of the simulator with linear analysis.

At zero (imposed) speed the dq model is linear and decoupled, so the q-axis
current loop is exactly ``1/(Lq s + R)`` in closed loop with the discrete
controller; any difference comes from the RK4 integration only.
"""

import control
import numpy as np

from toolbox.artifact import Decoupling
from toolbox.spec import Scenario
from toolbox.sim._simulate import (ControlLaw, DriveParams, discrete_pi, simulate)

from sim_helpers import PAPER000 as M


def _pi_law(wc, Ts):
    # pole-zero cancellation: Kp = L wc, Ki = R wc -> closed loop wc / (s + wc)
    return ControlLaw(d=discrete_pi(M.Ld * wc, M.R * wc, Ts),
                      q=discrete_pi(M.Lq * wc, M.R * wc, Ts),
                      sample_time=Ts,
                      decoupling=Decoupling.from_motor(M, cross=False, emf=False))


def test_pi_tiny_sample_time_matches_first_order():
    """Ts = h = 1 us, no delay: iq(t) = 10 (1 - exp(-wc t)).

    Tolerance 10 A * wc * Ts = 0.02 A: the sampled PI lags the continuous one
    by about one period (ZOH + forward-Euler integrator), an O(wc Ts) effect.
    """
    wc, Ts = 2000.0, 1e-6
    drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=0, v_limit="none")
    sc = Scenario(kind="current_step", duration=5e-3, iq_ref=10.0, keep_traces=True)
    res = simulate(_pi_law(wc, Ts), M, sc, drive)
    expected = 10.0 * (1.0 - np.exp(-wc * res.t))
    assert np.max(np.abs(res.iq - expected)) < 10.0 * wc * Ts
    assert np.max(np.abs(res.id)) == 0.0
    # 5 % response time of a first-order system: ln(20)/wc
    assert abs(res.metrics["response_time_5pct"] - np.log(20) / wc) < 2 * Ts


def test_pi_sampled_with_delay_matches_discrete_closed_loop():
    """Ts = 100 us, one-period delay, vs python-control: c2d(ZOH) plant * z^-1
    closed with the discrete PI (independent route). Tolerance 1e-8 A on a
    10 A step: RK4 at 1 us on a 2 ms time constant has a relative error ~1e-15
    per step; 1e-8 leaves room for round-off only."""
    wc, Ts = 2000.0, 1e-4
    law = _pi_law(wc, Ts)
    drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=1, v_limit="none")
    sc = Scenario(kind="current_step", duration=0.01, iq_ref=10.0, keep_traces=True)
    res = simulate(law, M, sc, drive)

    G = control.c2d(control.tf([1.0], [M.Lq, M.R]), Ts, method="zoh")
    P = G * control.tf([1.0], [1.0, 0.0], Ts)            # one-period delay
    ax = law.q
    K = control.ss(ax.A, ax.B, ax.C, ax.D, Ts)
    Kr, Ky = K[0, 0], K[0, 1]                              # i_ref -> v, i_meas -> v
    T = control.feedback(P, Ky, sign=+1) * Kr              # y = P (Kr r + Ky y)
    n = len(res.t)
    _, y = control.step_response(T, T=np.arange(n) * Ts)
    assert np.max(np.abs(res.iq - 10.0 * np.ravel(y))) < 1e-8


def test_metrics_match_offline_definitions():
    """Online (kernel) step metrics equal the trace-based definitions of
    toolbox.metrics.step_metrics when evaluated on every plant step (Ts = h)."""
    from toolbox.metrics import step_metrics
    wc, Ts = 3000.0, 1e-6
    drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=1, v_limit="none")
    sc = Scenario(kind="current_step", duration=4e-3, iq_ref=5.0, iq_ref0=1.0,
                  step_time=1e-3, keep_traces=True)
    res = simulate(_pi_law(wc, Ts), M, sc, drive)
    off = step_metrics(res.t, res.iq, 1.0, 5.0, 1e-3)
    for k, v in off.items():
        assert abs(res.metrics[k] - v) < 1e-9, k
