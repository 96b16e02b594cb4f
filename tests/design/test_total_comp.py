"""Unit tests for toolbox.design.total_comp (paper 000 eq (8)-(11), (18)-(24)).

Sections: (1) gains from K, response time, poles, natural frequency and the PI
match of eq (22)-(24); (2) the law (R_c feedback in the measurement channel,
decoupling); (3) closed-loop poles by an independent route (plant from
``toolbox.plant.numeric_plant`` + artifact), continuous and ZOH-discrete,
nominal and with parameter mismatch; (4) bad input; (5) JSON round trip.
"""

import math

import control as ct
import numpy as np
import pytest
from scipy.linalg import block_diag, expm

from toolbox.artifact import ControllerArtifact
from toolbox.design import design
from toolbox.design import total_comp as TC
from toolbox.errors import SpecError
from toolbox.plant import axis_plants, numeric_plant
from toolbox.spec import spec_from_dict

TS = 1e-4
R, LD, LQ = 0.6, 1.4e-3, 2.8e-3  # paper 000 appendix
PI_000 = {"Kp_normalised": 3.5 / 256, "Ki_normalised": 660 / 256, "sensor_gain": 256 / 50}


def make_spec(method, cfg, delay=1):
    return spec_from_dict({"motor": {"catalog": "lepioufle1992"},
                           "drive": {"vdc": 150, "sample_time": TS, "delay_samples": delay},
                           "controller": {"method": method, method: cfg}})


def _blocks(systems, with_B_col=None):
    n = sum(s.nstates for s in systems)
    if not n:
        return np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((2, 0))
    A = block_diag(*[np.asarray(s.A) for s in systems])
    if with_B_col is None:
        B = block_diag(*[np.asarray(s.B) for s in systems])
    else:
        B = block_diag(*[np.asarray(s.B)[:, with_B_col:with_B_col + 1] for s in systems])
    C = block_diag(*[np.asarray(s.C) for s in systems])
    return A, B, C


def continuous_poles(art, motor, omega_e):
    """eig of the plant A(omega) closed by Decoupling + the artifact's error controllers."""
    plant = numeric_plant(motor)
    A, B = plant.A(omega_e), plant.B()
    dec = art.decoupling
    Dec = omega_e * dec.cross * np.array([[0.0, -dec.Lq_c], [dec.Ld_c, 0.0]])
    Ks = [art.axes[ax].to_statespace(domain="continuous") for ax in "dq"]
    Ac, Bc, Cc = _blocks(Ks)
    Dc = np.diag([float(np.asarray(K.D)[0, 0]) for K in Ks])
    M = np.block([[A + B @ (Dec - Dc), B @ Cc], [-Bc, Ac]])
    return np.linalg.eigvals(M)


def discrete_poles(art, motor, delay):
    """ZOH plant at omega = 0 with ``delay`` periods, the artifact's discrete laws."""
    plant = numeric_plant(motor)
    Md = expm(np.block([[plant.A(0.0), plant.B()], [np.zeros((2, 4))]]) * art.sample_time)
    Ad, Bd = Md[:2, :2], Md[:2, 2:]
    laws = [art.axes[ax].law.to_statespace() for ax in "dq"]
    Ac, Bm, Cc = _blocks(laws, with_B_col=1)
    Dm = np.diag([float(np.asarray(L.D)[0, 1]) for L in laws])
    nc = Ac.shape[0]
    n = 2 + nc + 2 * delay
    F = np.zeros((n, n))
    F[2:2 + nc, :2], F[2:2 + nc, 2:2 + nc] = Bm, Ac
    if delay == 0:
        F[:2, :2], F[:2, 2:2 + nc] = Ad + Bd @ Dm, Bd @ Cc
    else:
        F[:2, :2], F[:2, n - 2:] = Ad, Bd
        F[2 + nc:4 + nc, :2 + nc] = np.hstack([Dm, Cc])
        for j in range(1, delay):
            F[2 + nc + 2 * j:4 + nc + 2 * j, nc + 2 * j:2 + nc + 2 * j] = np.eye(2)
    return np.linalg.eigvals(F)


def same_roots(a, b, tol):
    a, b = np.sort_complex(np.asarray(a)), np.sort_complex(np.asarray(b))
    return a.shape == b.shape and np.max(np.abs(a - b)) <= tol


# ---------------------------------------------------------------- (1) gains
def test_tc_explicit_gains_and_poles():
    art = design(make_spec("tc", {"K1": 800, "K2": 900}))
    assert (art.design_parameters["K1"], art.design_parameters["K2"]) == (800.0, 900.0)
    assert art.design_parameters["poles"] == {"d": [[-800.0, 0.0]], "q": [[-900.0, 0.0]]}


def test_tc_from_response_time_is_ln20_over_t():
    """Eq (8): e(t) = e0 exp(-K t) is 5 % of e0 at t = ln(20)/K."""
    cfg = make_spec("tc", {"response_time": 2.5e-3}).controller.cfg
    assert cfg.K_prop == pytest.approx((math.log(20) / 2.5e-3,) * 2, rel=1e-14)


@pytest.mark.parametrize("poles,expected", [(-800, (800.0, 800.0)), ([-700], (700.0, 700.0)),
                                             ({"d": -600, "q": -900}, (600.0, 900.0))])
def test_tc_from_poles(poles, expected):
    assert make_spec("tc", {"poles": poles}).controller.cfg.K_prop == expected


def test_tci_match_pi_paper_000_eq_22_24():
    """000 eq (23): K21 = E k_i Kp/Lq ~ 3750, K22 = E k_i KI/Lq ~ 707 100
    (printed to 4 significant figures: rel 1e-4); eq (24): K11 = K21, K12 = K22."""
    art = design(make_spec("tci", {"match_pi": True, **PI_000}))
    g = art.design_parameters
    assert g["K21"] == pytest.approx(3750.0, rel=1e-12)   # 10.5 / 2.8e-3 exactly
    assert g["K22"] == pytest.approx(707_100.0, rel=1e-4)  # 1980 / 2.8e-3 = 707 142.9
    assert (g["K11"], g["K12"]) == (g["K21"], g["K22"])
    assert g["matched_Kp"] == pytest.approx(10.5, rel=1e-14)
    assert g["matched_Ki"] == pytest.approx(1980.0, rel=1e-14)


def test_tci_from_natural_frequency_and_damping():
    cfg = make_spec("tci", {"natural_frequency": 1000, "damping": 0.7}).controller.cfg
    assert cfg.K_prop == pytest.approx((1400.0, 1400.0), rel=1e-14)
    assert cfg.K_int == pytest.approx((1e6, 1e6), rel=1e-14)


@pytest.mark.parametrize("poles,expected", [
    ([-200, -3000], [-200, -3000]),
    ([[-1000, 500]], [-1000 + 500j, -1000 - 500j]),
    ([[-1000, 500], [-1000, -500]], [-1000 + 500j, -1000 - 500j]),
])
def test_tci_from_poles(poles, expected):
    cfg = make_spec("tci", {"poles": poles}).controller.cfg
    got = TC.designed_poles(cfg.K_prop[1], cfg.K_int[1])
    assert same_roots(got, expected, 1e-9 * 3000)


def test_tci_per_axis_poles():
    cfg = make_spec("tci", {"poles": {"d": [-100, -2000], "q": [[-500, 100]]}}).controller.cfg
    assert cfg.K_prop == pytest.approx((2100.0, 1000.0), rel=1e-14)
    assert cfg.K_int == pytest.approx((2e5, 260_000.0), rel=1e-14)


# ---------------------------------------------------------------- (2) law
def test_tc_law_has_resistance_feedback_in_measurement_channel():
    """Eq (11): V = R_c i + K L_c (i_ref - i); the Omega terms are the Decoupling."""
    art = design(make_spec("tc", {"K1": 800, "K2": 800, "model": {"R": 0.5}}))
    law = art.axes["q"].law
    assert law.order == 0
    assert law.D[0].tolist() == pytest.approx([800 * LQ, 0.5 - 800 * LQ], rel=1e-14)
    dec = art.decoupling
    assert dec.cross and dec.emf
    assert (dec.R_c, dec.Ld_c, dec.Lq_c, dec.flux_c, dec.pole_pairs) == (0.5, LD, LQ, 0.12, 4)
    # error controller = minus the measurement channel = K L_c - R_c
    assert float(art.axes["q"].to_statespace(domain="continuous").D[0, 0]) == pytest.approx(800 * LQ - 0.5)


def test_tci_error_controller_is_pi_minus_resistance():
    art = design(make_spec("tci", {"K11": 3000, "K12": 4e5, "K21": 3000, "K22": 4e5}))
    K = art.axes["d"].to_statespace(domain="continuous").to_control()
    w = np.array([50.0, 2000.0])
    ref = 3000 * LD + 4e5 * LD / (1j * w) - R
    assert np.allclose(ct.frequency_response(K, w).complex.ravel(), ref, rtol=1e-12)


def test_model_override_for_mismatch_studies():
    art = design(make_spec("tci", {"match_pi": True, **PI_000,
                                   "model": {"Lq": 3.0e-3, "flux": 0.13}}))
    assert art.design_parameters["model"] == {"R": R, "Ld": LD, "Lq": 3.0e-3, "flux": 0.13}
    assert art.design_parameters["K21"] == pytest.approx(10.5 / 3.0e-3, rel=1e-14)  # eq (23) with L_qc
    assert art.decoupling.flux_c == 0.13


# ---------------------------------------------------------------- (3) poles
@pytest.mark.parametrize("method,cfg", [
    ("tc", {"K1": 800, "K2": 1200}),
    ("tci", {"match_pi": True, **PI_000}),
    ("tci", {"poles": [[-1500, 800]]}),
])
def test_continuous_closed_loop_poles_equal_designed(method, cfg):
    """Independent route: plant A(omega) + Decoupling + error controllers; with
    nominal parameters the poles are the designed ones at any speed (0 and
    920 rad/s electrical = 230 rad/s mechanical). Tolerance 1e-7 relative to
    the largest pole (eig of a <= 4x4 matrix)."""
    spec = make_spec(method, cfg)
    art = design(spec)
    expected = np.concatenate([np.array(art.design_parameters["poles"][ax]) @ [1, 1j] for ax in "dq"])
    scale = np.max(np.abs(expected))
    for omega in (0.0, 920.0):
        assert same_roots(continuous_poles(art, spec.motor, omega), expected, 1e-7 * scale)


def test_continuous_poles_with_resistance_mismatch():
    """With R_c != R the tc pole moves to -(K L_c + R - R_c)/L (from eq (12))."""
    spec = make_spec("tc", {"K1": 800, "K2": 800, "model": {"R": 0.9}})
    art = design(spec)
    expected = [-(800 * LD + R - 0.9) / LD, -(800 * LQ + R - 0.9) / LQ]
    assert same_roots(continuous_poles(art, spec.motor, 0.0), expected, 1e-9)


@pytest.mark.parametrize("delay", [0, 1])
def test_tc_discrete_poles_match_hand_derivation(delay):
    """ZOH plant i+ = a i + b v, a = exp(-R Ts/L), b = (1 - a)/R, law
    v = (R - K L) i: delay 0 -> z = a + b (R - K L); delay 1 ->
    z^2 - a z - b (R - K L) = 0. Exact up to rounding (1e-12)."""
    spec = make_spec("tc", {"K1": 800, "K2": 800}, delay=delay)
    art = design(spec)
    expected = []
    for L in (LD, LQ):
        a = math.exp(-R * TS / L)
        b = (1 - a) / R
        g = R - 800 * L
        expected += [a + b * g] if delay == 0 else list(np.roots([1, -a, -b * g]))
    assert same_roots(discrete_poles(art, spec.motor, delay), expected, 1e-12)


@pytest.mark.parametrize("delay", [0, 1])
def test_tci_discrete_poles_two_routes(delay):
    """State-matrix assembly vs python-control feedback(G_zoh z^-d, K_law) per axis."""
    spec = make_spec("tci", {"match_pi": True, **PI_000}, delay=delay)
    art = design(spec)
    theirs = []
    for ax in "dq":
        G = ct.c2d(axis_plants(spec.motor)[ax], TS, "zoh") * ct.tf([1], [1] + [0] * delay, TS)
        K = -art.axes[ax].law.to_statespace()[0, 1]
        theirs += list(ct.poles(ct.feedback(ct.ss(G) * K, 1)))
    mine = discrete_poles(art, spec.motor, delay)
    assert same_roots(mine, theirs, 1e-9)
    assert np.max(np.abs(mine)) < 1.0


# ---------------------------------------------------------------- (4) errors
@pytest.mark.parametrize("method,cfg,message", [
    ("tc", {"poles": 800},
     "controller.tc.poles: expected stable poles (negative real part, rad/s), got 800 "
     "(a pole at 800+0j makes the current loop unstable)"),
    ("tc", {"poles": {"d": -800, "q": 0}},
     "controller.tc.poles: expected stable poles (negative real part, rad/s), got "
     "{'d': -800, 'q': 0} (a pole at 0+0j makes the current loop unstable)"),
    ("tci", {"poles": [[100, 50]]},
     "controller.tci.poles: expected stable poles (negative real part, rad/s), got "
     "[[100, 50]] (a pole at 100+50j makes the current loop unstable)"),
    ("tci", {"poles": {"d": [-100, -200], "q": [-300, 20]}},
     "controller.tci.poles.q: expected stable poles (negative real part, rad/s), got "
     "[-300, 20] (a pole at 20+0j makes the current loop unstable)"),
    ("tci", {"poles": {"d": [-100, -200]}},
     "controller.tci.poles.q: expected the poles of this axis (missing)"),
    ("tci", {"poles": [-100]},
     "controller.tci.poles: expected two real poles [s1, s2] or one complex pair "
     "[[re, im]] (rad/s), got [-100]"),
    ("tc", {"K1": -800, "K2": 800},
     "controller.tc.K1: expected a number > 0 (1/s), got -800.0 (paper 000 eq (18) prints "
     "de/dt = K e + K' int e; the stable law (20) needs K, K' > 0 (de/dt = -K e - K' int e))"),
    ("tc", {"K1": 800},
     "controller.tc.K2: expected a number > 0 (1/s) (missing)"),
    ("tc", {"K1": 800, "K2": 800, "response_time": 1e-3},
     "controller.tc.response_time: expected either K1 or response_time, not both, got 0.001"),
    ("tc", {"K1": 800, "K2": 800, "K3": 1},
     "controller.tc.K3: expected a known key of [controller.tc] (allowed keys: K1, K2, "
     "discretisation, model, poles, response_time)"),
    ("tc", {"K1": 800, "K2": 800, "model": {"L": 1e-3}},
     "controller.tc.model.L: expected a known key of [controller.tc.model] "
     '(did you mean "Lq"?)'),
    ("tc", {"K1": 800, "K2": 800, "model": {"R": -1}},
     "controller.tc.model.R: expected a number > 0 (ohm), got -1"),
    ("tci", {"match_pi": False},
     "controller.tci.match_pi: expected true (or leave it out), got False"),
    ("tci", {"natural_frequency": 1000},
     "controller.tci.damping: expected a number > 0 (missing)"),
    ("tci", {"K11": 3750, "K12": 7e5, "K21": 3750},
     "controller.tci.K22: expected a number > 0 (1/s^2) (missing)"),
    ("tci", {"K11": 3750, "K12": 7e5, "K21": 3750, "K22": 7e5, "poles": [-1, -2]},
     "controller.tci.poles: expected either K11 or poles, not both, got [-1, -2]"),
])
def test_bad_parameters_exact_messages(method, cfg, message):
    with pytest.raises(SpecError) as err:
        make_spec(method, cfg)
    assert str(err.value) == message


# ---------------------------------------------------------------- (5) JSON
@pytest.mark.parametrize("method,cfg", [
    ("tc", {"K1": 800, "K2": 800}), ("tc", {"response_time": 3e-3, "model": {"R": 0.5}}),
    ("tci", {"match_pi": True, **PI_000}), ("tci", {"poles": [[-1000, 300]]}),
])
def test_json_round_trip(method, cfg):
    art = design(make_spec(method, cfg))
    back = ControllerArtifact.loads(art.dumps())
    assert back.dumps() == art.dumps()
    assert back.design_parameters == art.design_parameters
    for ax in "dq":
        assert np.array_equal(back.axes[ax].law.D, art.axes[ax].law.D)


def test_end_to_end_spec_from_dict():
    """The brief's example: catalog motor, drive, tci matched to 000's PI."""
    spec = spec_from_dict({"motor": {"catalog": "lepioufle1992"},
                           "drive": {"vdc": 150, "sample_time": 1e-4},
                           "controller": {"method": "tci",
                                          "tci": {"match_pi": True,
                                                  "Kp_normalised": 0.013671875,
                                                  "Ki_normalised": 660 / 256,
                                                  "sensor_gain": 256 / 50}}})
    art = design(spec)
    assert art.method == "tci"
    assert "000 eq (22)-(24)" in " ".join(art.provenance["equations"])
    assert art.design_parameters["K21"] == pytest.approx(3750.0, rel=1e-12)


def test_tc_sampled_response_time_vs_paper():
    """000 sect. 3.2 / Fig. 6: "5 % response time ... about 2.5 ms" with K = 800,
    ZOH and one period of delay. The design (8) gives ln(20)/800 = 3.74 ms in
    continuous time; the sampled loop (ZOH plant, Ts = 100 us, one period of
    delay, the artifact's law) reaches 5 % at 3.6 ms (step response on the
    100 us grid, so +/- 0.1 ms). DISCREPANCY: the paper's 2.5 ms is about
    2/K (86 %), not a 5 % time of a first-order loop with K = 800."""
    spec = make_spec("tc", {"K1": 800, "K2": 800}, delay=1)
    law = design(spec).axes["q"].law.to_statespace().to_control()
    G = ct.c2d(axis_plants(spec.motor)["q"], TS, "zoh") * ct.tf([1], [1, 0], TS)
    Cr, Cy = ct.ss2tf(law[0, 0]), ct.ss2tf(law[0, 1])
    T = ct.minreal(G * Cr / (1 - G * Cy), verbose=False)
    t = np.arange(0, 0.02, TS)
    y = np.squeeze(ct.step_response(T, t).outputs)
    t5 = (np.nonzero(np.abs(y - 1) > 0.05)[0][-1] + 1) * TS
    assert math.log(20) / 800 == pytest.approx(3.745e-3, abs=1e-6)
    assert t5 == pytest.approx(3.6e-3, abs=1.5e-4)
    assert y.max() <= 1 + 1e-9  # first order with a short delay: no overshoot
