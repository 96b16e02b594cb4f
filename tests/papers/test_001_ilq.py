"""Paper 001 (Takami 2004): the ILQ servo is less sensitive to inductance than
the PI servo with a first-order lag (Fig. 2, Fig. 4-5 (d)-(e), 0.5x and 2x L_1).

The paper prints neither the assigned poles s* nor sigma (checked: sect. 2-3 give
only the structure, eq (2)-(4), and Tables 1-2), nor the PI gains and T_d. Both
controllers come from the reference design files (one source of truth with
test_001_speed_step.py and reports/): designs/001_takami2004_ilq.toml and
designs/001_takami2004_pi_lag.toml, for the catalog motor "takami2004"
(L = 1.788 mH, R = 0.4 ohm assumed, a = -R/L = -223.7 1/s), controller period
0.1 ms (sect. 3.1), one period of computation delay, 200 V link (not given by
the paper; the linear analysis below does not depend on it, and the 5 A steps
of the simulator test stay far below the limit):

* ILQ: s* = -1000 rad/s on both axes (1 ms time constant), sigma = 2500 1/s:
  1.6 x the eq (3) bound 2(a - s*) = 1552.5 1/s, and sigma Ts = 0.25 so that at
  0.5 L (where the loop sees 2 sigma) the delayed loop stays well damped.
* PI with lag (Fig. 2b): pole-zero cancellation Ti = L/R, Kp = L wc, Ki = R wc
  with wc = 1000 rad/s, and a first-order lag T_d = 0.2 ms (two periods) on the
  measured current.

T_d: this test used T_d = 0.1 ms and a 300 V link while the design files use
0.2 ms and 200 V. It now reads the design files; T_d = 0.1 ms is kept as a
second case because it equalises the nominal 5 % response times (2.3 ms both),
whereas at 0.2 ms the PI is faster (1.8 ms vs 2.3 ms). The conclusion holds for
both, so it does not hinge on the unprinted T_d.

Figure of merit (per inductance factor k): the integrated absolute change of the
unit step response relative to nominal, normalised by the nominal integrated
absolute error, M_k = sum |y_k - y_1| / sum |1 - y_1| over 40 ms; small = robust.
Measured: ILQ M_0.5 = 0.172, M_2 = 0.404; PI (T_d 0.2 ms, design file)
M_0.5 = 0.931, M_2 = 1.554 (ILQ 3.8-5.4 x less); PI (T_d 0.1 ms) M_0.5 = 0.729,
M_2 = 1.321 (3.3-4.2 x less). Asserted: ILQ < PI / 3 in every case.
"""

import control as ct
import numpy as np
import pytest

from pathlib import Path

from toolbox.design import design
from toolbox.spec import load_spec

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
TS = 1e-4
N = 400                                     # 40 ms of samples


def ilq_spec():
    return load_spec(DESIGNS / "001_takami2004_ilq.toml")


def pi_lag_spec():
    return load_spec(DESIGNS / "001_takami2004_pi_lag.toml")


def pi_lag_law(L, R, wc=1000.0, Td=2e-4):
    """Fig. 2(b): v = (Kp + Ki/s)(i_ref - i/(1 + Td s)), Tustin at TS (an
    independent construction of the design file's law, checked equal below)."""
    s = ct.tf("s")
    C = L * wc + R * wc / s
    F = 1 / (1 + Td * s)
    law = ct.ss(ct.tf([[C.num[0][0], (-C * F).num[0][0]]], [[C.den[0][0], (-C * F).den[0][0]]]))
    return ct.sample_system(law, TS, "tustin")


def step(law, L, R, delay=1):
    """Unit step i_ref -> i of the sampled loop: ZOH plant 1/(R + sL), `delay` periods."""
    z = ct.tf([1, 0], [1], TS)
    G = ct.ss(ct.sample_system(ct.tf([1], [L, R]), TS, "zoh") / z ** delay)
    T = ct.feedback(G, law[0, 1], sign=1) * law[0, 0]
    return np.asarray(ct.step_response(T, np.arange(N) * TS).outputs).ravel()


def merit(law, L, R):
    y1 = step(law, L, R)
    out = {k: float(np.sum(np.abs(step(law, k * L, R) - y1)) / np.sum(np.abs(1 - y1)))
           for k in (0.5, 2.0)}
    return out, y1


def t5(y):
    outside = np.flatnonzero(np.abs(1 - y) > 0.05)
    return (outside[-1] + 1) * TS


def test_design_files_agree_with_the_test():
    """The drive and T_d of the design files are the ones this module describes,
    and the design's PI-with-lag law is the independent construction above."""
    ilq, pi = ilq_spec(), pi_lag_spec()
    for sp in (ilq, pi):
        assert (sp.drive.sample_time, sp.drive.delay_samples, sp.drive.vdc) == (TS, 1, 200)
    assert pi.controller.cfg.lag_time_constant == 2e-4
    m = pi.motor
    ours = pi_lag_law(m.Lq, m.R)
    art = design(pi).axes["q"].law.to_statespace().to_control()
    w = np.logspace(1, 4.4, 30)
    for j in (0, 1):
        assert np.allclose(ct.frequency_response(art[0, j], w).complex,
                           ct.frequency_response(ours[0, j], w).complex, rtol=1e-8)


@pytest.mark.parametrize("Td,ratio_t5,m_pi_ref", [
    (2e-4, 1.8 / 2.3, (0.931, 1.554)),   # design file: the PI is faster
    (1e-4, 1.0, (0.729, 1.321)),         # equal nominal response times
])
def test_ilq_less_sensitive_to_inductance_than_pi_with_lag(Td, ratio_t5, m_pi_ref):
    sp = ilq_spec()
    m = sp.motor
    art = design(sp)
    assert art.design_parameters["optimal"] and art.design_parameters["sigma_bound"]["q"] == pytest.approx(1552.53, rel=1e-5)
    ilq_law = art.axes["q"].law.to_statespace().to_control()
    m_ilq, y_ilq = merit(ilq_law, m.Lq, m.R)
    m_pi, y_pi = merit(pi_lag_law(m.Lq, m.R, Td=Td), m.Lq, m.R)
    print(f"\nT_d {Td * 1e3:.1f} ms: ILQ: M_0.5 = {m_ilq[0.5]:.3f}, M_2 = {m_ilq[2.0]:.3f}, "
          f"t5 = {t5(y_ilq)*1e3:.1f} ms; PI+lag: M_0.5 = {m_pi[0.5]:.3f}, "
          f"M_2 = {m_pi[2.0]:.3f}, t5 = {t5(y_pi)*1e3:.1f} ms")
    # the PI is never the slower one (the comparison is not won by a slow PI)
    assert t5(y_pi) == pytest.approx(ratio_t5 * t5(y_ilq), abs=TS + 1e-12)
    # both settle without overshoot above 1 % at nominal parameters
    assert y_ilq.max() < 1.01 and y_pi.max() < 1.01
    # the claim of sect. 3-4, quantified: at least 3 x less change at 0.5 L and 2 L
    for k in (0.5, 2.0):
        assert m_ilq[k] < m_pi[k] / 3, k
    # and the measured values (loose 5 %: they depend only on linear algebra)
    assert m_ilq[0.5] == pytest.approx(0.172, rel=0.05)
    assert m_ilq[2.0] == pytest.approx(0.404, rel=0.05)
    assert m_pi[0.5] == pytest.approx(m_pi_ref[0], rel=0.05)
    assert m_pi[2.0] == pytest.approx(m_pi_ref[1], rel=0.05)


def test_slow_pole_of_pi_vs_ilq_eq4():
    """Why (sect. 1 and Fig. 5: the PI "converges to zero slowly"): the PI cancels the
    plant pole -R/L with its zero, so the loop keeps a pole near -R/L (-224 rad/s)
    that only cancels at nominal L; at 0.5 L and 2 L it appears in the response.
    The ILQ loop (eq 4 with the plant's L scaled by k, controller unchanged:
    s^2 + (sigma/k - a_k) s - sigma s*/k, a_k = -R/(k L)) has no pole slower than
    600 rad/s for k in {0.5, 1, 2}. Continuous-time analysis (exact roots)."""
    R, L, s_star, sigma = 0.4, 1.78783e-3, -1000.0, 2500.0
    s = ct.tf("s")
    C = L * 1000.0 + R * 1000.0 / s
    for k in (0.5, 1.0, 2.0):
        a = -R / (k * L)
        ilq = np.roots([1.0, sigma / k - a, -sigma * s_star / k])
        assert np.min(np.abs(np.real(ilq))) > 600, k
        for Td in (2e-4, 1e-4):    # design file's lag and the equal-speed variant
            pi = ct.feedback(C / (k * L * s + R), 1 / (1 + Td * s)).poles()
            # slowest: -329 +/- 131j rad/s at 2 L with T_d = 0.2 ms, always < 600
            assert np.min(np.abs(np.real(pi))) < 350, (k, Td)


def test_simulator_agrees_with_linear_analysis():
    """Independent route: the nonlinear closed-loop simulator (toolbox.sim, plant
    integrated at 1 us as in sect. 3.1, ZOH, one period of delay, average inverter,
    decoupling at standstill) runs the artifact's ILQ law on a 5 A i_q step with the
    plant inductance at 0.5, 1 and 2 x nominal. Its 5 % response times agree with the
    sampled linear analysis above within one period, and the figure of merit computed
    from the simulated traces (20 ms window) within 5 % of the linear one."""
    from toolbox.sim import control_law, drive_params, simulate
    from toolbox.spec import Scenario

    sp = ilq_spec()
    art = design(sp)
    law = art.axes["q"].law.to_statespace().to_control()
    sc = Scenario.from_dict({"kind": "current_step", "duration": 0.02, "iq_ref": 5.0,
                             "keep_traces": True}, sample_time=TS)
    sim, lin = {}, {}
    for k in (0.5, 1.0, 2.0):
        res = simulate(control_law(art),
                       sp.motor.with_overrides({}, {"Ld": k, "Lq": k}),
                       sc, drive_params(sp.drive))
        y = step(law, k * sp.motor.Lq, sp.motor.R)[:200]
        assert abs(res.metrics["response_time_5pct"] - t5(y)) <= TS
        sim[k], lin[k] = np.asarray(res.iq)[:200] / 5.0, y
    for k in (0.5, 2.0):
        m_sim = np.sum(np.abs(sim[k] - sim[1.0])) / np.sum(np.abs(1 - sim[1.0]))
        m_lin = np.sum(np.abs(lin[k] - lin[1.0])) / np.sum(np.abs(1 - lin[1.0]))
        assert m_sim == pytest.approx(m_lin, rel=0.05), k
