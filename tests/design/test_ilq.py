"""ILQ servo design (paper 001, Takami 2004): eq (2)-(4) and the inverse LQ weights."""


import control as ct
import numpy as np
import pytest

from toolbox.artifact import ControllerArtifact
from toolbox.design import design
from toolbox.design.ilq import (design_ilq, ilq_axis, ilq_axis_from_plant, inverse_lq, inverse_lq_sdp,
                                servo_matrices, sigma_bound)
from toolbox.errors import SpecError
from toolbox.plant import axis_plants
from toolbox.spec import spec_from_dict

TS = 1e-4
L, R = 1.78783e-3, 0.4            # catalog "takami2004" (R assumed, see catalog)
A = -R / L                         # eq (1): a = -R/L = -223.7 1/s


def spec(ts=TS, **ilq):
    return spec_from_dict({"motor": {"catalog": "takami2004"},
                           "drive": {"vdc": 300, "sample_time": ts},
                           "controller": {"method": "ilq", "ilq": ilq}})


def test_basic_gains_eq2_and_sigma():
    """K_F0 = L, K_I0 = -L s*; K = sigma K0 (eq 2). Exact up to rounding (1e-12)."""
    ax = ilq_axis(R, L, -1000.0, 2500.0)
    assert ax.K_F0 == pytest.approx(L, rel=1e-12)
    assert ax.K_I0 == pytest.approx(1000.0 * L, rel=1e-12)
    assert ax.K_F == pytest.approx(2500 * L, rel=1e-12)
    assert ax.K_I == pytest.approx(2500 * 1000 * L, rel=1e-12)


def test_sigma_bound_eq3_both_branches():
    assert sigma_bound(A, -1000.0) == pytest.approx(2 * (A + 1000.0))      # s* < a
    assert sigma_bound(A, -100.0) == 0.0                                   # a <= s* < 0


@pytest.mark.parametrize("axis", ["d", "q"])
def test_characteristic_equation_eq4_matches_assembled_loop(axis):
    """Closed loop of the derived plant (toolbox.plant) and the artifact's error
    controller: poles equal the roots of s^2 + (sigma - a) s - sigma s* (eq 4).
    Tolerance 1e-8 relative: only polynomial root-finding separates them."""
    art = design(spec(poles={"d": -800.0, "q": -1000.0}, sigma={"d": 3000.0, "q": 2500.0}))
    s_star, sigma = {"d": (-800.0, 3000.0), "q": (-1000.0, 2500.0)}[axis]
    G = axis_plants(art_motor())[axis]
    K = art.axes[axis].to_statespace(domain="continuous")
    cl = np.sort_complex(ct.feedback(ct.ss(G) * K, 1).poles())
    ref = np.sort_complex(np.roots([1.0, sigma - A, -sigma * s_star]).astype(complex))
    assert cl == pytest.approx(ref, rel=1e-8)
    # the executed (two-input) law, discretised with Tustin, with a ZOH plant and no
    # delay, at Ts = 1e-5 s: the equivalent continuous poles log(z)/Ts stay within 3 %
    # of eq (4) (the sampled proportional feedback shifts them by O(sigma Ts) = 3 %)
    ts = 1e-5
    art = design(spec(poles={"d": -800.0, "q": -1000.0}, sigma={"d": 3000.0, "q": 2500.0}, ts=ts))
    law = art.axes[axis].law.to_statespace().to_control()
    Gd = ct.sample_system(ct.ss(G), ts, "zoh")
    cld = ct.feedback(Gd, law[0, 1], sign=1)
    zp = cld.poles()
    zp = np.sort_complex(zp[np.abs(zp) > 1e-9])
    assert zp.size == 2 and np.all(np.abs(zp) < 1)
    assert np.sort_complex(np.log(zp.astype(complex)) / ts) == pytest.approx(ref, rel=0.03)


def art_motor():
    return spec(poles=-1000.0, sigma=2500.0).motor


def test_inverse_lq_closed_form_and_care():
    """Q = R diag(K_F^2 (1 - bound/sigma), K_I^2) is PSD and the CARE with (Q, R)
    returns the ILQ gains (relative error < 1e-9: one Riccati solve)."""
    ax = ilq_axis(R, L, -1000.0, 2500.0)
    assert ax.optimal
    assert np.all(np.linalg.eigvalsh(ax.Q) >= 0)
    assert ax.Q[0, 0] == pytest.approx(ax.K_F ** 2 * (1 - ax.bound / ax.sigma), rel=1e-9)
    assert ax.care_error < 1e-9
    # the law u = -K x of the LQ problem is the ILQ law: A - B K has the eq (4) poles
    Aa, Ba = servo_matrices(ax.a, ax.b)
    K = np.array([[ax.K_F, -ax.K_I]])
    assert np.sort_complex(np.linalg.eigvals(Aa - Ba @ K)) == pytest.approx(
        np.sort_complex(ax.poles.astype(complex)), rel=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("sigma", [1200.0, 1600.0, 2500.0, 10000.0])
def test_inverse_lq_sdp_cross_check(sigma):
    """Independent route (cvxpy + CLARABEL): the best margin t of Q >= t S equals
    min(1, 1 - bound/sigma) (tolerance 1e-5, interior-point accuracy), so the SDP is
    feasible (t > 0) exactly above the bound of eq (3) (1552.5 1/s here)."""
    a, b = A, 1 / L
    K_F, K_I = sigma * L, sigma * 1000.0 * L
    t, P, Q = inverse_lq_sdp(a, b, K_F, K_I)
    bound = sigma_bound(a, -1000.0)
    assert t == pytest.approx(min(1.0, 1 - bound / sigma), abs=1e-5)
    assert (t > 0) == (sigma > bound)
    if t > 0:
        Qc, Rc, Pc, err = inverse_lq(a, b, K_F, K_I)
        assert err < 1e-9
        assert P[:, 0] == pytest.approx(Pc[:, 0], rel=1e-6)       # fixed by R^-1 B'P = K


def test_sigma_below_bound_is_refused_with_bound_in_message():
    with pytest.raises(SpecError) as err:
        spec(poles=-1000.0, sigma=1000.0)
    assert err.value.key == "controller.ilq.sigma"
    assert str(err.value) == ("controller.ilq.sigma: expected sigma_d > the optimality bound "
                              "of Takami eq (3), 2(a - s*) = 1552.53 1/s, got 1000.0 "
                              "(raise sigma, or set allow_non_optimal = true)")


def test_allow_non_optimal_warns_and_omits_weights():
    with pytest.warns(RuntimeWarning, match="not LQ-optimal"):
        sp = spec(poles=-1000.0, sigma=1000.0, allow_non_optimal=True)
    art = design(sp)
    assert art.design_parameters["optimal"] is False and "Q" not in art.design_parameters


def test_bad_parameters():
    with pytest.raises(SpecError, match=r"controller\.ilq\.poles: expected a number < 0 \(rad/s\), got 500"):
        spec(poles=500.0, sigma=2500.0)
    with pytest.raises(SpecError, match='controller.ilq.sigmaa: .*did you mean "sigma"'):
        spec(poles=-1000.0, sigmaa=2500.0)
    with pytest.raises(SpecError, match="controller.ilq.sigma: expected a number > 0"):
        spec(poles=-1000.0, sigma=-1.0)
    with pytest.raises(SpecError, match="controller.ilq.sigma_factor"):
        spec(poles=-100.0, sigma_factor=2.0)                      # bound is 0 there
    with pytest.raises(SpecError, match="controller.ilq.sigma"):
        spec(poles=-1000.0, sigma_factor=1.0)                     # sigma == bound


def test_sigma_factor_and_s1_s2():
    sp = spec(s1=-1000.0, s2=-900.0, sigma_factor=2.0)
    assert sp.controller.cfg.sigma[0] == pytest.approx(2 * sigma_bound(A, -1000.0))
    assert sp.controller.cfg.poles == (-1000.0, -900.0)


def test_artifact_gains_and_json_round_trip():
    art = design(spec(poles=-1000.0, sigma=2500.0))
    g = art.design_parameters
    assert g["K_F"][1][1] == pytest.approx(2500 * L) and g["optimal"] is True
    assert np.asarray(g["Q"]["q"]).shape == (2, 2)
    assert art.decoupling.cross and art.decoupling.emf
    text = art.dumps()
    assert ControllerArtifact.loads(text).dumps() == text
    # error controller K_F + K_I/s: zero at s*, integrator
    z = art.axes["q"].zpk
    assert z.zeros[0].real == pytest.approx(-1000.0, rel=1e-9)
    assert abs(z.poles[0]) < 1e-12


def test_plain_api_both_axes():
    des = design_ilq(L, L, R, (-1000.0, -1000.0), (2500.0, 2500.0), TS)
    assert set(des.axes) == {"d", "q"} and des.gains()["sigma"] == {"d": 2500.0, "q": 2500.0}


def test_python_control_plant_route():
    """The plant API (python-control 1/(R + sL) from toolbox.plant) gives the same gains."""
    G = axis_plants(art_motor())["q"]
    ax = ilq_axis_from_plant(G, -1000.0, 2500.0)
    ref = ilq_axis(R, L, -1000.0, 2500.0)
    assert (ax.K_F, ax.K_I, ax.bound) == pytest.approx((ref.K_F, ref.K_I, ref.bound), rel=1e-9)
    with pytest.raises(ValueError, match="first-order"):
        ilq_axis_from_plant(G * G, -1000.0, 2500.0)
