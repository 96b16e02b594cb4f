"""Quadratic-stability certificate (toolbox.analysis.certificate).

Checks against sampling (the same continuous model evaluated point by point, and
an independent python-control interconnection): anything certified is stable at
every sampled point; a box that contains an unstable point is not certified.
"""

import control as ct
import numpy as np
import pytest

from analysis_helpers import AZAIZ, DRIVE
from toolbox.analysis import margins as M
from toolbox.analysis.certificate import (ParameterBox, certify, largest_certified_scale,
                                          point_matrices)


def _pc_closed_loop_poles(art, R, Ld, Lq, om, g=1.0):
    """Independent route: python-control interconnection of the dq plant at speed,
    the continuous error controllers and the decoupling v = u + W i."""
    A, B = M.coupled_plant(R, Ld, Lq, om)
    P = ct.ss(A[0], B[0], np.eye(2), np.zeros((2, 2)))
    dec = art.decoupling
    W = g * om * np.array([[0, -dec.Lq_c], [dec.Ld_c, 0]])
    Pw = ct.feedback(P, ct.ss([], [], [], W), sign=+1)       # plant with v = u + W i
    K = ct.append(*[art.axes[k].continuous.to_statespace().to_control() for k in "dq"])
    return ct.feedback(Pw * K, np.eye(2)).poles()


def test_affine_model_matches_interconnection(pi):
    """The theta-affine closed-loop matrix has the poles of the python-control
    interconnection at random box points (1e-8 relative)."""
    box = ParameterBox.around(AZAIZ, 1.0, omega_max=3000.0, speed_gain=(0.9, 1.1))
    for p in box.sample(5, seed=3)[-5:]:
        ours = np.sort_complex(np.linalg.eigvals(point_matrices(pi, p)[0]))
        ref = np.sort_complex(_pc_closed_loop_poles(pi, *p))
        np.testing.assert_allclose(ours, ref, rtol=1e-8, atol=1e-6)


def test_certified_box_is_stable_everywhere_sampled(pi):
    """R, Ld, Lq x0.8..x1.25 and |w| <= 920 rad/s: certified; 2000 random points
    plus the 32 corners all have Hurwitz closed loops (and so does the
    interconnection route at a few of them)."""
    box = ParameterBox.around(AZAIZ, 1.0, R=(0.8, 1.25), L=(0.8, 1.25), omega_max=920.0)
    res = certify(pi, box)
    assert res.certified and res.n_vertices == 64
    pts = box.sample(2000)
    ev = np.linalg.eigvals(point_matrices(pi, pts))
    assert np.max(ev.real) < 0
    for p in pts[:3]:
        assert np.max(_pc_closed_loop_poles(pi, *p).real) < 0


def test_box_with_unstable_point_is_not_certified(pi):
    """L x0.5..x2 with |w| <= 3000 rad/s: opposite-sign inductance errors leave a
    residual coupling w^2 (Lq - Lq_c)(Ld_c - Ld) that beats the loop gain (det of
    the current dynamics changes sign), so some sampled points are unstable; the
    certificate must fail there."""
    box = ParameterBox.around(AZAIZ, 1.0, R=(1.0, 1.0), L=(0.5, 2.0), omega_max=3000.0)
    ev = np.linalg.eigvals(point_matrices(pi, box.sample(2000)))
    assert np.max(ev.real) > 0
    assert not certify(pi, box).certified


def test_largest_box_and_decay_rate(pi):
    """Bisection on the box scale (R, L x0.5..x2 and |w| <= 920 rad/s at scale 1):
    the returned box is certified and all its sampled points are stable; a decay
    rate alpha = 200 1/s is certified on a smaller box, where every sampled
    closed-loop pole has real part <= -200 (quadratic decay bounds the spectrum)."""
    r0 = largest_certified_scale(pi, AZAIZ, DRIVE, tol=0.1)
    assert r0.certified and 0.1 < r0.scale < 1.0
    box0 = ParameterBox.around(AZAIZ, r0.scale, omega_max=920.0)
    assert np.max(np.linalg.eigvals(point_matrices(pi, box0.sample(500))).real) < 0
    r1 = largest_certified_scale(pi, AZAIZ, DRIVE, tol=0.1, alpha=200.0)
    assert r1.certified and r1.scale <= r0.scale
    box1 = ParameterBox.around(AZAIZ, r1.scale, omega_max=920.0)
    assert np.max(np.linalg.eigvals(point_matrices(pi, box1.sample(500))).real) <= -200.0
    assert r1.to_json()["box"]["omega"][1] == pytest.approx(r1.scale * 920.0)


def test_delay_model_and_certificate(pi):
    """Pade-delay model (tau = 1.5 Ts, decoupling delayed too): poles equal those
    of a python-control interconnection (1e-8); at box scale 0.3 (R, L x0.85..x1.3,
    |w| <= 276 rad/s) the PI is certified with the delay and every sampled point
    of that model is stable; at scale 1 the delayed model is not certified."""
    p = np.array([0.5, 1.2e-3, 3e-3, 700.0, 1.05])
    ours = np.sort_complex(np.linalg.eigvals(point_matrices(pi, p, delay=True)[0]))
    R, Ld, Lq, om, g = p
    A, B = M.coupled_plant(R, Ld, Lq, om)
    num, den = ct.pade(1.5e-4, 1)
    Dl = ct.ss(ct.tf(num, den))
    Pd = ct.ss(A[0], B[0], np.eye(2), np.zeros((2, 2))) * ct.append(Dl, Dl)
    W = g * om * np.array([[0, -pi.decoupling.Lq_c], [pi.decoupling.Ld_c, 0]])
    Pw = ct.feedback(Pd, ct.ss([], [], [], W), sign=+1)
    K = ct.append(*[pi.axes[k].continuous.to_statespace().to_control() for k in "dq"])
    ref = np.sort_complex(ct.feedback(Pw * K, np.eye(2)).poles())
    np.testing.assert_allclose(ours, ref, rtol=1e-8)
    box = ParameterBox.around(AZAIZ, 0.3, omega_max=920.0)
    res = certify(pi, box, delay=True)
    assert res.certified and res.n_vertices == 512
    ev = np.linalg.eigvals(point_matrices(pi, box.sample(1000), delay=True))
    assert np.max(ev.real) < 0
    assert not certify(pi, ParameterBox.around(AZAIZ, 1.0, omega_max=920.0), delay=True).certified
