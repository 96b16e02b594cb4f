"""Unit tests for toolbox.design.pi (PI, IP, PI with lag).

The IP-with-cancellation-gains warning is tested once and silenced elsewhere.

Sections: (1) gain rules against their formulas and the papers' numbers
(000 appendix, 002 eq (19)-(20)), (2) law structures, (3) closed-loop poles by
an independent route (plant from ``toolbox.plant.numeric_plant`` + the
artifact's controllers, continuous and ZOH-discrete), (4) bad input,
(5) JSON round trip.
"""

import math

import control as ct
import numpy as np
import pytest
from scipy.linalg import block_diag, expm

from toolbox.artifact import ControllerArtifact
from toolbox.design import design
from toolbox.design import pi as P
from toolbox.errors import SpecError
from toolbox.plant import axis_plants, numeric_plant
from toolbox.spec import spec_from_dict

TS = 1e-4
pytestmark = pytest.mark.filterwarnings("ignore:ip with rule")


def make_spec(method, cfg, drive=None, motor=None):
    return spec_from_dict({"motor": motor or {"catalog": "lepioufle1992"},
                           "drive": drive or {"vdc": 150, "sample_time": TS},
                           "controller": {"method": method, method: cfg}})


def continuous_poles(art, motor, omega_e):
    """Eigenvalues of plant A(omega) closed by decoupling + error controllers (r = 0)."""
    plant = numeric_plant(motor)
    A, B = plant.A(omega_e), plant.B()
    dec = art.decoupling
    Dec = omega_e * dec.cross * np.array([[0.0, -dec.Lq_c], [dec.Ld_c, 0.0]])
    Ks = [art.axes[ax].to_statespace(domain="continuous") for ax in "dq"]
    n = sum(K.nstates for K in Ks)
    Ac = block_diag(*[np.asarray(K.A) for K in Ks]) if n else np.zeros((0, 0))
    Bc = block_diag(*[np.asarray(K.B) for K in Ks]) if Ac.size else np.zeros((0, 2))
    Cc = block_diag(*[np.asarray(K.C) for K in Ks]) if Ac.size else np.zeros((2, 0))
    Dc = np.diag([float(np.asarray(K.D)[0, 0]) for K in Ks])
    top = np.hstack([A + B @ (Dec - Dc), B @ Cc])
    bottom = np.hstack([-Bc, Ac])
    return np.linalg.eigvals(np.vstack([top, bottom]))


def discrete_poles(art, motor, delay):
    """ZOH plant at omega = 0, ``delay`` periods of computation delay, artifact laws."""
    plant = numeric_plant(motor)
    A, B = plant.A(0.0), plant.B()
    Ts = art.sample_time
    M = expm(np.block([[A, B], [np.zeros((2, 4))]]) * Ts)
    Ad, Bd = M[:2, :2], M[:2, 2:]
    laws = [art.axes[ax].law.to_statespace() for ax in "dq"]
    nc = sum(L.nstates for L in laws)
    Ac = block_diag(*[np.asarray(L.A) for L in laws]) if nc else np.zeros((0, 0))
    Bm = block_diag(*[np.asarray(L.B)[:, 1:2] for L in laws]) if nc else np.zeros((0, 2))
    Cc = block_diag(*[np.asarray(L.C) for L in laws]) if nc else np.zeros((2, 0))
    Dm = np.diag([float(np.asarray(L.D)[0, 1]) for L in laws])
    n = 2 + nc + 2 * delay
    F = np.zeros((n, n))
    F[2:2 + nc, :2] = Bm
    F[2:2 + nc, 2:2 + nc] = Ac
    u_rows = np.hstack([Dm, Cc])  # u[k] = Dm i + Cc xc
    if delay == 0:
        F[:2, :2] = Ad + Bd @ Dm
        F[:2, 2:2 + nc] = Bd @ Cc
    else:
        F[:2, :2] = Ad
        F[:2, n - 2:] = Bd
        F[2 + nc:4 + nc, :2 + nc] = u_rows
        for j in range(1, delay):
            F[2 + nc + 2 * j:4 + nc + 2 * j, 2 + nc + 2 * (j - 1):4 + nc + 2 * (j - 1)] = np.eye(2)
    return np.linalg.eigvals(F)


def pc_discrete_poles(art, motor, axis, delay):
    """python-control route: feedback(G_zoh z^-delay, K_law) of one axis."""
    G = ct.c2d(axis_plants(motor)[axis], art.sample_time, "zoh")
    G = G * ct.tf([1], [1] + [0] * delay, art.sample_time)
    K = -art.axes[axis].law.to_statespace()[0, 1]
    return ct.poles(ct.feedback(ct.ss(G) * K, 1))


def same_roots(a, b, tol):
    a, b = np.sort_complex(np.asarray(a)), np.sort_complex(np.asarray(b))
    return a.shape == b.shape and np.max(np.abs(a - b)) <= tol


# ---------------------------------------------------------------- (1) rules
def test_cancellation_from_bandwidth():
    spec = make_spec("pi", {"rule": "cancellation", "bandwidth": 2000})
    cfg = spec.controller.cfg
    assert cfg.Kp == pytest.approx((1.4e-3 * 2000, 2.8e-3 * 2000), rel=1e-15)
    assert cfg.Ki == pytest.approx((0.6 * 2000, 0.6 * 2000), rel=1e-15)


def test_cancellation_from_response_time_is_ln20_over_t():
    spec = make_spec("pi", {"response_time": 3e-3})  # default rule: cancellation
    wc = math.log(20) / 3e-3
    assert spec.controller.cfg.rule == "cancellation"
    assert spec.controller.cfg.Kp[1] == pytest.approx(2.8e-3 * wc, rel=1e-14)
    # a first-order loop wc/(s + wc) is 5 % from its final value at ln(20)/wc
    assert math.exp(-wc * 3e-3) == pytest.approx(0.05, rel=1e-12)


def test_bandwidth_rule_equals_cancellation_numbers():
    a = make_spec("pi", {"rule": "bandwidth", "bandwidth": 1500}).controller.cfg
    b = make_spec("pi", {"rule": "cancellation", "bandwidth": 1500}).controller.cfg
    assert (a.Kp, a.Ki) == (b.Kp, b.Ki)


def test_bandwidth_rule_is_open_loop_crossover():
    """|L(j wc)| = 1 for L = (Kp + Ki/s)/(R + L s) with cancellation gains."""
    spec = make_spec("pi", {"rule": "bandwidth", "bandwidth": 1500})
    art = design(spec)
    loop = art.axes["q"].to_statespace(domain="continuous").to_control() * axis_plants(spec.motor)["q"]
    mag = abs(ct.frequency_response(loop, [1500.0]).complex.ravel()[0])
    assert mag == pytest.approx(1.0, rel=1e-9)


def test_paper_002_eq_19_20_is_cancellation_with_10R():
    """002 eq (19)-(20): K = 10 R, Ti = L/R <=> cancellation at wc = 10 R / L per axis."""
    R, Ld, Lq = 0.6, 1.4e-3, 2.8e-3
    art = design(make_spec("pi", {"bandwidth": {"d": 10 * R / Ld, "q": 10 * R / Lq}}))
    for ax, L in (("d", Ld), ("q", Lq)):
        assert art.design_parameters["Kp"][ax] == pytest.approx(10 * R, rel=1e-14)
        assert art.design_parameters["Ti"][ax] == pytest.approx(L / R, rel=1e-14)


def test_symmetric_optimum_gym_electric_motor_formula():
    spec = make_spec("pi", {"rule": "symmetric_optimum"},
                     drive={"vdc": 150, "sample_time": TS, "delay_samples": 1})
    cfg = spec.controller.cfg
    T_sigma = 1.5 * TS  # one period of delay + half a period of ZOH
    assert cfg.details["T_sigma"] == pytest.approx(T_sigma, rel=1e-15)
    assert cfg.Kp[1] == pytest.approx(2.8e-3 / (2 * T_sigma), rel=1e-14)
    assert cfg.Kp[1] / cfg.Ki[1] == pytest.approx(4 * T_sigma, rel=1e-14)  # Ti = a^2 T_sigma
    cfg3 = make_spec("pi", {"rule": "symmetric_optimum", "a": 3}).controller.cfg
    assert cfg3.Kp[0] / cfg3.Ki[0] == pytest.approx(9 * T_sigma, rel=1e-14)


def test_complex_vector_records_delay_compensation():
    """The complex-vector PI's 1.5 Ts angle compensation is the drive's voltage
    placement, which every method shares (toolbox/ARCHITECTURE.md "The digital
    loop"): (delay + 1/2) Ts by default, 0 with angle_compensation = "none",
    a given time otherwise."""
    art = design(make_spec("pi", {"rule": "complex_vector", "bandwidth": 2000}))
    assert art.design_parameters["Kp"]["q"] == pytest.approx(2.8e-3 * 2000, rel=1e-15)
    assert art.design_parameters["Ki"]["d"] == pytest.approx(0.6 * 2000, rel=1e-15)
    # executed (exported) compensation: typed, in the decoupling terms
    assert art.decoupling.delay_compensation_time == pytest.approx(1.5 * TS, rel=1e-15)
    assert "delay_compensation_time" not in art.design_parameters
    plain = design(make_spec("pi", {"rule": "cancellation", "bandwidth": 2000}))
    assert plain.decoupling.delay_compensation_time == pytest.approx(1.5 * TS, rel=1e-15)
    for placement, t_c in (("none", 0.0), (2e-4, 2e-4)):
        drive = {"vdc": 150, "sample_time": TS, "angle_compensation": placement}
        art = design(make_spec("pi", {"rule": "complex_vector", "bandwidth": 2000}, drive))
        assert art.decoupling.delay_compensation_time == t_c
    two = design(make_spec("lq", {}, {"vdc": 150, "sample_time": TS, "delay_samples": 2}))
    assert two.decoupling.delay_compensation_time == pytest.approx(2.5 * TS, rel=1e-15)


def test_symmetric_optimum_reproduces_gem_control():
    """gem-control (PIController._tune_current_controller, PController): p_gain =
    L/(tau a), i_gain = p_gain/(tau a^2), tau = sample time, default a = 4."""
    cfg = make_spec("pi", {"rule": "symmetric_optimum", "a": 4,
                           "small_time_constant": TS}).controller.cfg
    p_gain = 2.8e-3 / (TS * 4)
    assert cfg.Kp[1] == pytest.approx(p_gain, rel=1e-14)
    assert cfg.Ki[1] == pytest.approx(p_gain / (TS * 16), rel=1e-14)


def test_complex_vector_2dof_motulator_gains_and_tracking():
    """motulator complex-vector 2DOF: Kt = a_c L, Kp = (a_c + a_i) L - R,
    Ki = a_c a_i L; reference tracking a_c/(s + a_c) on the decoupled axis
    (checked on the continuous law and the derived axis plant to 1e-9)."""
    a_c, a_i = 2000.0, 300.0
    spec = make_spec("pi", {"rule": "complex_vector", "bandwidth": a_c,
                            "integral_bandwidth": a_i})
    cfg = spec.controller.cfg
    assert cfg.Kt == pytest.approx((a_c * 1.4e-3, a_c * 2.8e-3), rel=1e-14)
    assert cfg.Kp[1] == pytest.approx((a_c + a_i) * 2.8e-3 - 0.6, rel=1e-14)
    assert cfg.Ki[0] == pytest.approx(a_c * a_i * 1.4e-3, rel=1e-14)
    w = np.array([30.0, 700.0, 9000.0])
    for k, ax in enumerate("dq"):
        law = P.pi_law(cfg.Kp[k], cfg.Ki[k], "pi", Kt=cfg.Kt[k]).to_control()
        G = ct.frequency_response(axis_plants(spec.motor)[ax], w).complex.ravel()
        Cr = ct.frequency_response(law[0, 0], w).complex.ravel()
        Cy = ct.frequency_response(law[0, 1], w).complex.ravel()
        T = G * Cr / (1 - G * Cy)
        assert np.allclose(T, a_c / (1j * w + a_c), rtol=1e-9)
    art = design(spec)
    assert same_roots(continuous_poles(art, spec.motor, 800.0), [-a_c, -a_i] * 2, 1e-6 * a_c)
    assert art.design_parameters["Kt"]["q"] == pytest.approx(a_c * 2.8e-3, rel=1e-14)


def test_paper_000_normalised_gains():
    """000 sect. 2 and appendix: Kp = 3.5/256, KI = 660/256, E = 150 V, k_i = 256/50."""
    art = design(make_spec("pi", {"Kp_normalised": 3.5 / 256, "Ki_normalised": 660 / 256,
                                  "sensor_gain": 256 / 50}))
    assert art.design_parameters["rule"] == "explicit"
    assert art.design_parameters["voltage_gain"] == 150.0  # defaults to drive.vdc = E
    assert art.design_parameters["Kp"] == pytest.approx({"d": 10.5, "q": 10.5}, rel=1e-14)
    assert art.design_parameters["Ki"] == pytest.approx({"d": 1980.0, "q": 1980.0}, rel=1e-14)


def test_paper_000_ip_uses_Kp_times_KI():
    """000 sect. 2, note on the IP: in (6)-(7) K_I becomes K_p K_I."""
    cfg = make_spec("ip", {"Kp_normalised": 3.5 / 256, "Ki_normalised": 660 / 256,
                           "sensor_gain": 256 / 50}).controller.cfg
    assert cfg.Kp == pytest.approx((10.5, 10.5), rel=1e-14)
    assert cfg.Ki == pytest.approx((10.5 * 660 / 256,) * 2, rel=1e-14)


def test_explicit_per_axis():
    cfg = make_spec("pi", {"Kp": {"d": 2, "q": 4}, "Ki": 500}).controller.cfg
    assert cfg.Kp == (2.0, 4.0) and cfg.Ki == (500.0, 500.0)


def test_plant_RL_reads_axis_plant():
    motor = make_spec("pi", {"bandwidth": 1000}).motor
    R, L = P.plant_RL(axis_plants(motor)["q"])
    assert (R, L) == pytest.approx((0.6, 2.8e-3), rel=1e-12)


# ---------------------------------------------------------------- (2) laws
def test_ip_law_has_no_proportional_action_on_reference():
    law = P.pi_law(2.0, 600.0, "ip").to_control()
    assert np.asarray(law.D).tolist() == [[0.0, -2.0]]
    # error controller (minus the measurement channel) is the PI Kp + Ki/s
    w = np.array([10.0, 1e3])
    K = -law[0, 1]
    ref = 2.0 + 600.0 / (1j * w)
    assert np.allclose(ct.frequency_response(K, w).complex.ravel(), ref, rtol=1e-12)


def test_ip_with_cancellation_gains_warns_about_slow_reference_response():
    """IP reference response Ki/((L s + R)(s + wc)): the plant pole stays."""
    with pytest.warns(UserWarning, match=r"L/R = 4\.67 ms"):
        make_spec("ip", {"bandwidth": 1000})


def test_pi_lag_filters_measurement_not_reference():
    """001 Fig. 2b: the lag acts on the measured currents (feedback path)."""
    Kp, Ki, Td = 2.8, 600.0, 2e-4
    law = P.pi_law(Kp, Ki, "pi_lag", Td).to_control()
    w = np.array([10.0, 300.0, 5e3])
    pi = Kp + Ki / (1j * w)
    r_ch = ct.frequency_response(law[0, 0], w).complex.ravel()
    y_ch = ct.frequency_response(law[0, 1], w).complex.ravel()
    assert np.allclose(r_ch, pi, rtol=1e-12)
    assert np.allclose(y_ch, -pi / (1 + 1j * w * Td), rtol=1e-12)


def test_artifact_equations_and_decoupling():
    art = design(make_spec("pi_lag", {"bandwidth": 1000, "lag_time_constant": 1e-4,
                                      "decoupling": False}))
    assert any("001 Fig. 2b" in e for e in art.provenance["equations"])
    assert art.decoupling.cross is False and art.decoupling.emf is False
    assert art.design_parameters["lag_time_constant"] == 1e-4
    art2 = design(make_spec("pi", {"bandwidth": 1000}))
    assert art2.decoupling.cross and art2.decoupling.emf
    assert art2.axes["q"].antiwindup is not None


# ---------------------------------------------------------------- (3) poles
@pytest.mark.parametrize("method", ["pi", "ip"])
def test_continuous_closed_loop_poles_cancellation(method):
    """Independent route: eig of [plant A(omega) + decoupling, PI]; the cancelled
    plant pole -R/L stays, the other is -wc. Decoupling makes it omega-free
    (checked at 0 and 800 rad/s electrical). Tolerance 1e-6 relative: eig of
    a 4x4 with entries up to ~1e6."""
    wc = 2500.0
    spec = make_spec(method, {"bandwidth": wc})
    art = design(spec)
    expected = [-0.6 / 1.4e-3, -wc, -0.6 / 2.8e-3, -wc]
    for omega in (0.0, 800.0):
        got = continuous_poles(art, spec.motor, omega)
        assert same_roots(got, expected, 1e-6 * wc)


def test_continuous_closed_loop_poles_without_decoupling_depend_on_speed():
    spec = make_spec("pi", {"bandwidth": 2500, "decoupling": False})
    art = design(spec)
    still = continuous_poles(art, spec.motor, 0.0)
    moving = continuous_poles(art, spec.motor, 800.0)
    assert not same_roots(still, moving, 1.0)


def test_pi_lag_closed_loop_poles():
    """Characteristic polynomial by hand: Td L s^3 + (L + R Td) s^2 + (R + Kp) s + Ki."""
    Td = 2e-4
    spec = make_spec("pi_lag", {"bandwidth": 1000, "lag_time_constant": Td})
    art = design(spec)
    expected = []
    for ax, L in (("d", 1.4e-3), ("q", 2.8e-3)):
        Kp, Ki = art.design_parameters["Kp"][ax], art.design_parameters["Ki"][ax]
        expected += list(np.roots([Td * L, L + 0.6 * Td, 0.6 + Kp, Ki]))
    assert same_roots(continuous_poles(art, spec.motor, 600.0), expected, 1e-6 * 5000)


ALL_RULES = [
    ("pi", {"bandwidth": 1000}), ("ip", {"bandwidth": 1000}),
    ("pi_lag", {"bandwidth": 1000, "lag_time_constant": 1e-4}),
    ("pi", {"rule": "symmetric_optimum"}),
    ("pi", {"rule": "complex_vector", "bandwidth": 1000, "integral_bandwidth": 200}),
    ("ip", {"Kp_normalised": 3.5 / 256, "Ki_normalised": 660 / 256, "sensor_gain": 5.12}),
]


@pytest.mark.parametrize("method,cfg", ALL_RULES)
def test_recorded_poles_equal_assembled_closed_loop(method, cfg):
    """gains["poles"] (roots of the hand-derived characteristic polynomial)
    = eig of the assembled loop (plant + decoupling + artifact controller) at
    600 rad/s electrical; tolerance 1e-6 of the largest pole."""
    spec = make_spec(method, cfg)
    art = design(spec)
    expected = np.concatenate([np.array(art.design_parameters["poles"][ax]) @ [1, 1j] for ax in "dq"])
    scale = np.max(np.abs(expected))
    assert same_roots(continuous_poles(art, spec.motor, 600.0), expected, 1e-6 * scale)


@pytest.mark.parametrize("method,cfg", ALL_RULES)
@pytest.mark.parametrize("delay", [0, 1])
def test_discrete_closed_loop_poles_two_routes(method, cfg, delay):
    """ZOH plant + the artifact's discrete law: state-matrix assembly vs
    python-control feedback per axis (1e-9: both exact up to rounding);
    all poles inside the unit circle."""
    spec = make_spec(method, cfg, drive={"vdc": 150, "sample_time": TS, "delay_samples": delay})
    art = design(spec)
    mine = discrete_poles(art, spec.motor, delay)
    theirs = np.concatenate([pc_discrete_poles(art, spec.motor, ax, delay) for ax in "dq"])
    assert same_roots(mine, theirs, 1e-9)
    assert np.max(np.abs(mine)) < 1.0


def test_discrete_poles_near_mapped_design_without_delay():
    """Without delay the sampled loop approximates exp(s Ts) of the design; the
    Tustin/ZOH mismatch is O((wc Ts)^2), here wc Ts = 0.1 -> tolerance 0.01."""
    wc = 1000.0
    spec = make_spec("pi", {"bandwidth": wc}, drive={"vdc": 150, "sample_time": TS,
                                                     "delay_samples": 0})
    art = design(spec)
    got = discrete_poles(art, spec.motor, 0)
    expected = np.exp(np.array([-0.6 / 1.4e-3, -wc, -0.6 / 2.8e-3, -wc]) * TS)
    assert same_roots(got, expected, (wc * TS) ** 2)


# ---------------------------------------------------------------- (4) errors
@pytest.mark.parametrize("method,cfg,message", [
    ("pi", {"bandwith": 1000},
     'controller.pi.bandwith: expected a known key of [controller.pi] (did you mean "bandwidth"?)'),
    ("pi", {"bandwidth": -100},
     "controller.pi.bandwidth: expected a number > 0 (rad/s), got -100"),
    ("ip", {"bandwidth": {"d": 100, "q": 0}},
     "controller.ip.bandwidth.q: expected a number > 0 (rad/s), got 0"),
    ("pi", {"bandwidth": 100, "response_time": 1e-3},
     "controller.pi.response_time: expected either bandwidth or response_time, not both, "
     "got 0.001"),
    ("pi", {"rule": "symmetric_optimum", "bandwidth": 100},
     'controller.pi.bandwidth: expected only keys that rule = "symmetric_optimum" reads '
     "(its keys: a, small_time_constant)"),
    ("ip", {"rule": "complex_vector", "bandwidth": 1000, "integral_bandwidth": 100},
     'controller.ip.integral_bandwidth: expected method = "pi" for a 2DOF PI (the '
     "two-degree-of-freedom complex-vector PI has its own reference feedforward)"),
    ("pi", {"rule": "symmetric_optimum", "a": 1},
     "controller.pi.a: expected a number > 1 and <= 100, got 1.0"),
    ("pi", {"rule": "cancelation", "bandwidth": 1},
     'controller.pi.rule: expected one of "cancellation", "bandwidth", "symmetric_optimum", '
     '"complex_vector", "explicit", got "cancelation" (did you mean "cancellation"?)'),
    ("pi", {"bandwidth": 1000, "lag_time_constant": 1e-4},
     'controller.pi.lag_time_constant: expected method = "pi_lag" for a lag '
     "(the PI with first-order lag of paper 001 Fig. 2b)"),
    ("pi", {"Kp": 1, "Ki": 2, "sensor_gain": 5.12},
     "controller.pi.sensor_gain: expected Kp_normalised and Ki_normalised alongside it "
     "(voltage_gain and sensor_gain scale the normalised gains)"),
    ("pi", {"Kp_normalised": 0.01, "Ki_normalised": 2},
     "controller.pi.sensor_gain: expected a number > 0 (1/A) (missing)"),
    ("pi", {"Kp": 1, "Kp_normalised": 0.01},
     "controller.pi.Kp_normalised: expected either Kp/Ki or Kp_normalised/Ki_normalised, got 0.01"),
    ("pi", {"Kp": 1},
     "controller.pi.Ki: expected a number or a table {d = .., q = ..} (missing)"),
])
def test_bad_parameters_exact_messages(method, cfg, message):
    with pytest.raises(SpecError) as err:
        make_spec(method, cfg)
    assert str(err.value) == message


# ---------------------------------------------------------------- (5) JSON
@pytest.mark.parametrize("method,cfg", [
    ("pi", {"bandwidth": 1000}), ("ip", {"response_time": 2e-3}),
    ("pi_lag", {"bandwidth": 1000, "lag_time_constant": 1e-4}),
    ("pi", {"rule": "symmetric_optimum"}), ("pi", {"rule": "complex_vector", "bandwidth": 800}),
    ("pi", {"Kp_normalised": 3.5 / 256, "Ki_normalised": 660 / 256, "sensor_gain": 5.12}),
])
def test_json_round_trip(method, cfg):
    art = design(make_spec(method, cfg))
    back = ControllerArtifact.loads(art.dumps())
    assert back.dumps() == art.dumps()
    assert back.design_parameters == art.design_parameters
    for ax in "dq":
        assert np.array_equal(back.axes[ax].law.A, art.axes[ax].law.A)
        assert np.array_equal(back.axes[ax].law.D, art.axes[ax].law.D)
