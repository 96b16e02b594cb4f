"""LQI servo via CARE/DARE, cross-checked against python-control lqr/dlqr."""

import math

import control as ct
import numpy as np
import pytest

from toolbox.artifact import ControllerArtifact
from toolbox.design import design
from toolbox.design.lq import (bryson_weights, discrete_model, lqi_continuous, lqi_discrete,
                               lqi_from_plant)
from toolbox.errors import SpecError
from toolbox.plant import axis_plants
from toolbox.spec import spec_from_dict

TS = 1e-4
R, LQ = 0.6, 2.8e-3               # catalog "azaiz2007" q axis
A, B = -R / LQ, 1 / LQ


def spec(delay=1, **lq):
    return spec_from_dict({"motor": {"catalog": "azaiz2007"},
                           "drive": {"vdc": 150, "sample_time": TS, "delay_samples": delay},
                           "controller": {"method": "lq", "lq": lq}})


def test_continuous_matches_python_control_lqr():
    """Same (A, B, Q, R) into control.lqr (slycot/scipy route): gains agree to 1e-8."""
    ax = lqi_continuous(A, B, (1e-2, 3e4), 1e-4)
    K, _, _ = ct.lqr(ax.A, ax.B, ax.Q, ax.R)
    assert ax.K == pytest.approx(np.asarray(K), rel=1e-8)
    assert np.all(np.real(ax.poles) < 0)


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_discrete_matches_python_control_dlqr(delay):
    ax = lqi_discrete(A, B, (1e-2, 3e4), 1e-4, TS, delay)
    K, _, _ = ct.dlqr(ax.A, ax.B, ax.Q, ax.R)
    assert ax.K == pytest.approx(np.asarray(K), rel=1e-8)
    assert ax.K.shape == (1, 2 + delay)


def test_discrete_model_is_zoh_with_delay():
    """The i-row of the model equals python-control's ZOH of 1/(R + sL) (1e-12)."""
    Ad, Bd = discrete_model(A, B, TS, 0)
    Gd = ct.sample_system(ct.ss(A, B, 1, 0), TS, "zoh")
    assert Ad[0, 0] == pytest.approx(float(Gd.A[0, 0]), rel=1e-12)
    assert Bd[0, 0] * float(Gd.C[0, 0]) == pytest.approx(float(Gd.B[0, 0]), rel=1e-12)
    Ad1, Bd1 = discrete_model(A, B, TS, 1)
    assert Ad1[0, 2] == pytest.approx(Bd[0, 0]) and Bd1[2, 0] == 1.0


def closed_loop(G, law):
    """r -> i of plant G (D = 0) with the two-input law [i_ref, i] -> v, one state vector."""
    Ap, Bp, Cp = (np.asarray(M) for M in (G.A, G.B, G.C))
    Al, Bl, Cl, Dl = (np.asarray(M) for M in (law.A, law.B, law.C, law.D))
    A = np.block([[Ap + Bp @ Dl[:, 1:] @ Cp, Bp @ Cl], [Bl[:, 1:] @ Cp, Al]])
    B = np.vstack([Bp @ Dl[:, :1], Bl[:, :1]])
    C = np.hstack([Cp, np.zeros((1, Al.shape[0]))])
    return ct.ss(A, B, C, 0, G.dt)


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_artifact_law_closes_the_designed_loop(delay):
    """Plant (toolbox.plant, ZOH, `delay` periods) + the artifact's two-input law:
    the closed-loop poles away from z = 0 equal eig(A - B K) of the DARE design
    (1e-6 in the z-plane). The plant's delay states and the law's input history
    are copies of each other, so the assembled loop has `delay` extra modes at
    z = 0 (multiple roots, found within 1e-3)."""
    sp = spec(delay=delay)
    art = design(sp)
    G = ct.sample_system(ct.ss(axis_plants(sp.motor)["q"]), TS, "zoh")
    if delay:
        G = ct.ss(G * ct.ss(ct.tf([1], [1] + [0] * delay, TS)))
    cl = closed_loop(G, art.axes["q"].law.to_statespace())
    got = cl.poles()
    ref = np.asarray(art.design_parameters["closed_loop_poles"]["q"], complex)
    big = np.sort_complex(got[np.abs(got) > 1e-2])
    assert big == pytest.approx(np.sort_complex(ref[np.abs(ref) > 1e-2]), abs=1e-6)
    assert np.all(np.abs(got[np.abs(got) <= 1e-2]) < 1e-3)
    assert len(got) == len(ref) + delay
    # unit step i_ref -> i has zero static error (integral action), 1e-9
    assert float(np.real(cl(1.0))) == pytest.approx(1.0, abs=1e-9)


def test_continuous_artifact_tustin_and_error_controller():
    sp = spec(domain="continuous")
    art = design(sp)
    k = np.asarray(art.design_parameters["K"]["q"]).ravel()
    C = art.axes["q"].to_statespace(domain="continuous")            # k_i + (-k_z)/s
    assert float(np.real(C(1e9j))) == pytest.approx(k[0], rel=1e-6)
    assert art.axes["q"].discrete.method == "tustin"
    G = axis_plants(sp.motor)["q"]
    cl = ct.feedback(ct.ss(G) * C, 1).poles()
    ref = lqi_continuous(A, B, sp.controller.cfg.Q["q"], sp.controller.cfg.R["q"]).poles
    assert np.sort_complex(cl) == pytest.approx(np.sort_complex(ref), rel=1e-8)


def test_bryson_defaults():
    """i_max = rated 20 A, w_b = wc/4 and per axis v_max = min(vdc/sqrt(3), wc L i_max),
    wc = (90 - 65 - atan(1/4)) deg / ((delay + 0.5) Ts) (exact formulas; README.md
    "Defaults (no method parameters)": the drive's whole voltage as v_max
    crossed over too fast for the delay)."""
    sp = spec()
    cfg = sp.controller.cfg
    wc = math.radians(90 - 65 - math.degrees(math.atan(0.25))) / (
        (sp.drive.delay_samples + 0.5) * TS)
    for ax, L in (("d", sp.motor.Ld), ("q", sp.motor.Lq)):
        v = min(150 / math.sqrt(3), wc * L * 20.0)
        (qi, qz), r = bryson_weights(20.0, v, wc / 4)
        assert cfg.Q[ax] == pytest.approx((qi, qz), rel=1e-12)
        assert cfg.R[ax] == pytest.approx(r, rel=1e-12)
    assert qi == pytest.approx(1 / 400)
    assert "min(V_max drive, wc L i_max)" in cfg.defaults["weights"]["v_max"]


def test_explicit_weights_and_errors():
    cfg = spec(Q={"d": [0.0, 1e4], "q": [1e-2, 2e4]}, R={"d": 1e-3, "q": 2e-3}).controller.cfg
    assert cfg.Q["d"] == (0.0, 1e4) and cfg.R["q"] == 2e-3
    with pytest.raises(SpecError) as err:
        spec(Q=[1e-2, 0.0])
    assert str(err.value) == ("controller.lq.Q: expected [q_i, q_z] for the d axis with q_i >= 0 "
                              "and q_z > 0 (the integrator must be weighted for the Riccati "
                              "solution to stabilise it), got [0.01, 0.0]")
    with pytest.raises(SpecError, match=r"controller\.lq\.R: expected a number > 0"):
        spec(R=0.0)
    with pytest.raises(SpecError, match=r"controller\.lq\.Q: expected \[q_i, q_z\]"):
        spec(Q=[-1.0, 1.0])
    with pytest.raises(SpecError, match=r"controller\.lq\.Q: expected a list of 2 numbers"):
        spec(Q=[1.0, 2.0, 3.0])
    with pytest.raises(SpecError, match="controller.lq.domain"):
        spec(domain="z")
    with pytest.raises(SpecError, match="controller.lq.bandwidth"):
        spec(bandwidth=-5.0)


def test_json_round_trip():
    for dom in ("continuous", "discrete"):
        art = design(spec(domain=dom))
        text = art.dumps()
        assert ControllerArtifact.loads(text).dumps() == text


def test_python_control_plant_route():
    """A python-control plant 1/(R + sL) gives the same gains as (a, b) (1e-12)."""
    G = ct.tf([1], [LQ, R])
    for dom in ("continuous", "discrete"):
        ax = lqi_from_plant(G, (1e-2, 3e4), 1e-4, domain=dom, sample_time=TS)
        ref = (lqi_continuous(A, B, (1e-2, 3e4), 1e-4) if dom == "continuous"
               else lqi_discrete(A, B, (1e-2, 3e4), 1e-4, TS, 1))
        assert ax.K == pytest.approx(ref.K, rel=1e-9)


def test_extreme_weights_are_a_spec_error_without_a_leaked_warning():
    """Q = [1e300, 1e300], R = 1e-300 made scipy's DARE print "RuntimeWarning:
    invalid value encountered in cast" on stderr before the spec error."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SpecError, match=r"controller\.lq"):
            design(spec(Q=[1e300, 1e300], R=1e-300))
