"""analysis.json["responses"]: the figure data of the executed loops.

Independent routes: python-control builds the sampled loop ``K(z) G_zoh(z)
z^-1`` of a one-degree-of-freedom PI (whose feedback channel is its error
controller) and evaluates the H-infinity weights as transfer functions; the
stored data must match them to the 6-significant-digit rounding.
"""

from __future__ import annotations

import json
import math

import control as ct
import numpy as np
import pytest

from analysis_helpers import AZAIZ
from toolbox.analysis import compute_margins
from toolbox.analysis._responses import N_POINTS, loop_responses, round_sig

# 6 significant digits: relative rounding error <= 5e-6; dB values of order
# 10-100 carry an absolute error <= 5e-4 dB. Tolerances below add the
# evaluation round-off (1e-9 relative) on top.
REL6 = 5e-6


@pytest.fixture(scope="module")
def pi_responses(pi):
    return loop_responses(pi, AZAIZ)


def test_layout_json_and_rounding(pi_responses):
    """Strict JSON, both axes, N_POINTS frequencies ending just below Nyquist, 6 digits."""
    r = pi_responses
    assert json.loads(json.dumps(r, allow_nan=False)) == r
    assert r["schema"] == "cct.responses/1" and r["domain"] == "discrete"
    for ax in ("d", "q"):
        a = r[ax]
        w = np.array(a["omega"])
        assert w.size == N_POINTS and np.all(np.diff(w) > 0)
        assert w[-1] == pytest.approx(0.999 * math.pi / 1e-4, rel=REL6)
        for key in ("mag_db", "phase_deg", "re", "im"):
            assert len(a["loop"][key]) == N_POINTS
        for v in a["loop"]["mag_db"] + a["S_db"] + a["step"]["y"]:
            assert v == float(f"{v:.6g}")  # already rounded: a second rounding is a no-op
        assert a["weight_bounds"] is None  # a PI has no weights
        assert len(a["step"]["t"]) <= 410  # STEP_POINTS plus the kept peak/last samples


def test_round_sig():
    assert round_sig(123456789.0) == 123457000.0
    assert round_sig([1.234567e-9, -0.0]) == [1.23457e-9, -0.0]
    assert math.isinf(round_sig(math.inf))


def test_loop_matches_python_control(pi, pi_responses):
    """|L|, angle L and |S| of the stored PI loop equal python-control's sampled loop
    built from the executed law's feedback channel ``-K_m`` (v = K_r i_ref + K_m i)."""
    ts = pi.sample_time
    for ax, L_h in (("d", AZAIZ.Ld), ("q", AZAIZ.Lq)):
        G = ct.sample_system(ct.tf([1.0], [L_h, AZAIZ.R]), ts, method="zoh")
        law = pi.axes[ax].law
        K = ct.ss(law.A, -law.B[:, 1:2], law.C, -law.D[:, 1:2], ts)
        L = K * G * ct.tf([1.0], [1.0, 0.0], ts)
        a = pi_responses[ax]
        w = np.array(a["omega"])
        Lw = np.asarray(L(np.exp(1j * w * ts)), complex).reshape(-1)
        np.testing.assert_allclose(a["loop"]["mag_db"], 20 * np.log10(np.abs(Lw)),
                                   rtol=REL6 + 1e-9, atol=1e-9)
        np.testing.assert_allclose(a["loop"]["re"], Lw.real, rtol=REL6 + 1e-9, atol=1e-12)
        np.testing.assert_allclose(a["S_db"], -20 * np.log10(np.abs(1 + Lw)),
                                   rtol=REL6 + 1e-9, atol=1e-9)
        # unwrapped phase: equal to angle(L) modulo 360 deg
        diff = (np.array(a["loop"]["phase_deg"]) - np.degrees(np.angle(Lw)) + 180) % 360 - 180
        assert np.max(np.abs(diff)) < 1e-3  # deg; 6 digits of |phase| < 360 deg: 5e-4 deg


def test_step_is_the_reference_response_of_the_executed_law(tc):
    """Total compensation is a 2-DOF law (v = L K i_ref - (L K - R) i, paper 000 eq (11)):
    the stored step is its reference response (unit DC gain, the analysis' figures), not
    the unit-feedback closure of its feedback channel, whose DC gain (L K - R)/(L K) is
    not 1 (0.93 on the d axis here)."""
    r = loop_responses(tc, AZAIZ)
    m = compute_margins(tc, AZAIZ)
    ts = tc.sample_time
    for ax, L_h in (("d", AZAIZ.Ld), ("q", AZAIZ.Lq)):
        t, y = np.array(r[ax]["step"]["t"]), np.array(r[ax]["step"]["y"])
        assert t[0] == 0.0 and y[0] == 0.0
        assert max((max(y) - 1) * 100, 0.0) == pytest.approx(m[ax].overshoot_pct,
                                                              abs=5e-4 + 1e-12)
        # the 5 % time read off the stored curve brackets the analysis' value:
        # decimation keeps at most ~400 samples, so the bracket is one stored interval
        outside = np.nonzero(np.abs(y - 1) > 0.05)[0]
        k = outside[-1]
        assert t[k] <= m[ax].response_time_5pct + 1e-12 <= t[k + 1] + 1e-12
        # the 1-DOF rebuild feedback(K_m G z^-1, 1) settles elsewhere: that was the old bug
        G = ct.sample_system(ct.tf([1.0], [L_h, AZAIZ.R]), ts, method="zoh")
        K = tc.axes[ax].to_statespace(discrete=True).to_control()
        wrong = ct.feedback(K * G * ct.tf([1.0], [1.0, 0.0], ts), 1)
        assert abs(ct.dcgain(wrong) - 1) > 0.01 > abs(y[-1] - 1)


def test_pole_zero_data(pi, pi_responses):
    """Closed-loop poles inside the unit circle (stable sampled loop), conjugate pairs."""
    for ax in ("d", "q"):
        pz = pi_responses[ax]["pz"]
        assert pz["domain"] == "z"
        p = np.array(pz["poles"], float)
        # law states + plant (1) + one period of delay (1)
        assert p.shape == (pi.axes[ax].law.A.shape[0] + 2, 2)
        assert np.all(np.hypot(p[:, 0], p[:, 1]) < 1)
        assert sorted(p[:, 1]) == pytest.approx(sorted(-p[:, 1]))


# paper 003's w1 as makeweight, its w2 (eq (47)) as zpk, a constant w3: with
# gamma = "optimal" these give a realisable controller at Ts = 1e-4 s (a
# constant w2 does not: no roll-off, controller poles beyond pi/Ts)
MAKEWEIGHT = {"dc_gain": 1e4, "crossover": 156.0, "crossover_gain": 1.0, "hf_gain": 1 / 1.51}
ZPK = {"zeros": [-1000.0], "poles": [-50000.0], "gain": 25.0}
CONSTANT = 0.5


@pytest.fixture(scope="module")
def hinf_mixed_forms():
    """An H-infinity design whose weights use the makeweight, constant and zpk forms."""
    from toolbox.spec import spec_from_dict

    weights = {"w1": MAKEWEIGHT, "w2": ZPK, "w3": CONSTANT}
    spec = spec_from_dict({
        "title": "weights in three forms", "motor": {"catalog": "azaiz2007"},
        "drive": {"vdc": 150, "sample_time": 1e-4},
        "controller": {"method": "hinf", "hinf": {"gamma": "optimal",
                                                  "weights": {"d": weights, "q": weights}}}})
    from toolbox.pipeline import design_spec

    return spec, design_spec(spec)


def test_design_records_weights_in_every_form(hinf_mixed_forms):
    """artifact.weights (typed) holds num/den (s) of each validated weight, whatever
    its spec form, and the level gamma of the synthesis on that axis."""
    from toolbox.design.hinf import read_weight

    _, art = hinf_mixed_forms
    for ax in ("d", "q"):
        rec = art.weights[ax]
        assert rec.gamma == art.design_parameters["gamma"][ax]
        for key, raw in (("w1", MAKEWEIGHT), ("w2", ZPK), ("w3", CONSTANT)):
            ref = read_weight(raw, key)
            for w in (1.0, 156.0, 1e5):
                got = getattr(rec, key)(1j * w)
                assert abs(got) == pytest.approx(abs(complex(ref(1j * w))), rel=1e-12)


def test_weight_bounds_for_makeweight_constant_zpk(hinf_mixed_forms):
    """The stored bounds are gamma/|W_i(j w)| for all three forms (none dropped);
    makeweight's crossover: |W_1| = crossover_gain there, so the S bound is gamma/1."""
    from toolbox.design.hinf import read_weight

    spec, art = hinf_mixed_forms
    r = loop_responses(art, spec.motor)
    for ax in ("d", "q"):
        wb = r[ax]["weight_bounds"]
        gamma = art.weights[ax].gamma
        assert wb["gamma"] == gamma and gamma > 0
        w = np.array(r[ax]["omega"])
        for fn, key, raw in (("S", "w1", MAKEWEIGHT), ("KS", "w2", ZPK), ("T", "w3", CONSTANT)):
            W = np.abs(np.asarray(read_weight(raw, key)(1j * w), complex).reshape(-1))
            np.testing.assert_allclose(wb[fn], 20 * np.log10(gamma / W),
                                       rtol=REL6 + 1e-9, atol=1e-9)
        at_wc = np.interp(math.log(156.0), np.log(w), wb["S"])
        # log-linear interpolation of a smooth dB curve between grid points (ratio 1.028):
        # error well below 0.05 dB
        assert at_wc == pytest.approx(20 * math.log10(gamma / 1.0), abs=0.05)
