"""Tests of the structured robust tuner (``method = "tune"``).

Paper 003's motor as designs/003_azaiz2007_tune.toml (vdc 150 V, Ts = 100 us,
one period of computation delay, up to 230 rad/s mechanical = 920 rad/s
electrical, voltage placed at mid-period): the hard goal - multiloop disk
margin >= 0.5 over R, Ld, Lq x0.5..x2, speed-sensor gain 0.9..1.1 and offset
+/-10 rad/s, with the design delay and one period more - must hold on the
tuner's dense check (2,000 Latin-hypercube points + 64 corners + nominal of
the 6-D box) and on an independent re-check (another Latin hypercube, a finer
frequency grid); the q-axis 5 % response must be no slower than the robust
PI's 2.46 ms (README.md, paper 003 table).

Tolerances: the tuner verifies on a 1200-point frequency grid; the re-check
uses 2000 points and may find a slightly higher peak of mu between grid
points, so margins are compared with the 1 % relative tolerance of
tests/design/test_robust_pi.py (well-damped loops; a 1200-point log grid over
6.5 decades misses a peak by well under that). The response times are the
analysis stage's own figures (intersample current at Ts/10, i.e. 10 us
resolution) and are compared without tolerance against 2.46 ms: the tuned
design is at about 1.4 ms.

Cost: one tuner run (about 25 s on one core), shared by the module.
"""

from dataclasses import replace

import numpy as np
import pytest

from toolbox.analysis.margins import compute_margins
from toolbox.design import design
from toolbox.design import tune as T
from toolbox.errors import SpecError
from toolbox.spec import load_spec, spec_from_dict

SPEC = "designs/003_azaiz2007_tune.toml"
ALPHA = 0.5
RTOL = 0.01
ROBUST_PI_T5_Q = 2.46e-3      # robust_pi's q-axis 5 % response on this motor (README)


@pytest.fixture(scope="module")
def tuned():
    spec = load_spec(SPEC)
    return spec, design(spec)


@pytest.mark.slow
def test_dense_check_holds_with_design_delay_and_one_more(tuned):
    spec, art = tuned
    tu = art.design_parameters["tune"]
    assert set(tu["per_delay"]) == {"1", "2"}
    for d, rec in tu["per_delay"].items():
        assert rec["dense_points"] >= 2000 + 64
        assert rec["worst_disk_margin"] >= ALPHA, d
        assert rec["dense_worst"] >= ALPHA, d
    assert tu["worst_disk_margin"] >= ALPHA


@pytest.mark.slow
def test_independent_recheck_other_samples_finer_grid(tuned):
    """Another Latin hypercube (seed 7, 600 points + corners) on a 2000-point grid."""
    spec, art = tuned
    cfg = spec.controller.cfg
    other = replace(cfg, check_samples=600, models=replace(cfg.models, seed=7))
    M = T.dense_check(spec, other, art, n_grid=2000)
    assert set(M) == {1, 2}
    for d, v in M.items():
        assert v.size == 600 + 64 + 1
        assert float(np.min(v)) >= ALPHA * (1 - RTOL), d


@pytest.mark.slow
def test_q_response_no_slower_than_robust_pi(tuned):
    spec, art = tuned
    m = compute_margins(art, spec.motor)        # the analysis stage's own figures
    t5 = {ax: m[ax].response_time_5pct for ax in ("d", "q")}
    assert t5["q"] <= ROBUST_PI_T5_Q
    assert t5["d"] <= ROBUST_PI_T5_Q            # the soft goal is the slower axis
    rec = art.design_parameters["response_time_5pct_s"]
    assert rec["q"] == pytest.approx(t5["q"], abs=1e-5)


@pytest.mark.slow
def test_artifact_is_the_pi_methods(tuned):
    """Tustin PI per axis + decoupling, the cross-coupling inductances scaled by k."""
    spec, art = tuned
    dp = art.design_parameters
    assert art.method == "tune" and dp["structure"] == "pi"
    assert art.axes["q"].law.method == "tustin"
    k = dp["decoupling_scale"]
    assert 0 < k <= 2.0
    assert art.decoupling.Ld_c == pytest.approx(k * spec.motor.Ld)
    assert art.decoupling.Lq_c == pytest.approx(k * spec.motor.Lq)
    assert art.decoupling.flux_c == pytest.approx(spec.motor.flux)
    from toolbox.design.pi import design_pi
    ref = design_pi((dp["Kp"]["d"], dp["Kp"]["q"]), (dp["Ki"]["d"], dp["Ki"]["q"]),
                    spec.drive.sample_time)
    for ax in ("d", "q"):
        for name in ("A", "B", "C", "D"):
            assert np.allclose(getattr(art.axes[ax].law, name), getattr(ref[ax].law, name))


@pytest.mark.slow
def test_binding_goal_reported(tuned):
    _, art = tuned
    b = art.design_parameters["tune"]["binding"]
    assert any("extra period of delay" in h for h in b["hard"])
    assert "5 % response" in b["soft"]


@pytest.mark.slow
def test_worst_case_search_finds_what_robust_pi_misses():
    """robust_pi's gains (1421 rad/s, w_z = wc/10, k = 1) keep 0.501 with the
    design delay but not with one period more: from an interior point
    (0.76 there) the search walks to the corner R, Ld, Lq x0.5, top speed,
    sensor 1.1 w + 10 rad/s, where the margin is about 0.18."""
    spec = load_spec(SPEC)
    cfg = spec.controller.cfg
    m = spec.motor
    wc = 1421.0
    Kp = (m.Ld * wc, m.Lq * wc)
    art = T._candidate(spec, cfg, Kp, (Kp[0] * wc / 10, Kp[1] * wc / 10), 1.0)
    start = {"R": 0.8, "Ld": 0.8, "Lq": 0.8, "speed": 500.0, "speed_gain": 1.0,
             "speed_offset": 0.0}
    (margin, point), = T.worst_case_search(spec, cfg, art, [start], 2, evaluations=80)
    assert margin < 0.25
    assert point["Ld"] < 0.6 and point["speed"] > 800.0 and point["speed_gain"] > 1.05


def test_bad_keys():
    base = {"motor": {"catalog": "azaiz2007"},
            "drive": {"vdc": 150, "sample_time": 1e-4, "delay_samples": 1}}
    with pytest.raises(SpecError, match="controller.tune"):
        spec_from_dict(dict(base, controller={"method": "tune", "tune": {"zero_ratios": [4]}}))
    with pytest.raises(SpecError, match="controller.tune.starts"):
        spec_from_dict(dict(base, controller={"method": "tune", "tune": {"starts": 0}}))
    with pytest.raises(SpecError, match="controller.tune.disk_margin"):
        spec_from_dict(dict(base, controller={"method": "tune", "tune": {"disk_margin": 3}}))
    spec = spec_from_dict(dict(base, controller={"method": "tune", "tune": {"starts": 2}}))
    again = spec_from_dict(dict(base, controller={"method": "tune",
                                                  "tune": spec.controller.cfg.to_spec()}))
    assert again.controller.cfg.to_spec() == spec.controller.cfg.to_spec()
