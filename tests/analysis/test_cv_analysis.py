"""The sampled analyses execute method ``cv``'s complex-vector law at speed.

toolbox/ARCHITECTURE.md "Direct discrete-time complex-vector control": the
coupled closed loop (sweep, drift verdict, MIMO stability) and the MIMO loop
responses close the loop with the law's gains at each model's measured speed
(``analysis._laws.CvExecuted``), not with the standstill axes. Independent
routes: :func:`toolbox.design.cv_discrete.closed_loop_matrix` (the law and
the exact ZOH plant written out by hand) for the closed loop, and the law's
state-space realisation evaluated at ``z`` for its frequency response.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import toolbox
from toolbox.analysis import largest_certified_scale
from toolbox.analysis.margins import coupled_closed_loop
from toolbox.analysis._laws import executed_laws
from toolbox.design import cv_discrete as cvd
from toolbox.errors import ArtifactError

SPEC = Path(__file__).resolve().parents[2] / "designs" / "003_azaiz2007_cv.toml"
TS = 1e-4


@pytest.fixture(scope="module")
def designed():
    spec = toolbox.load_spec(SPEC)
    return spec, toolbox.design_spec(spec)


@pytest.mark.parametrize("w,w_meas,scale", [(0.0, 0.0, (1, 1, 1)), (920.0, 920.0, (1, 1, 1)),
                                            (920.0, 1022.0, (0.5, 2.0, 0.5)),
                                            (-460.0, -400.0, (2.0, 0.5, 2.0))])
def test_coupled_loop_is_the_hand_written_loop(designed, w, w_meas, scale):
    """Same closed-loop poles as :func:`closed_loop_matrix` with the gains at the
    measured speed, the true plant at the true speed and the placement error
    ``t_c w_meas - (d + 1/2) Ts w``."""
    spec, art = designed
    m = spec.motor
    R, Ld, Lq = m.R * scale[0], m.Ld * scale[1], m.Lq * scale[2]
    loop = coupled_closed_loop(executed_laws(art), art.decoupling, TS, 1, R=R, Ld=Ld, Lq=Lq,
                               omega=w, omega_meas=w_meas, flux=m.flux)
    g = cvd.executed_gains(art.cv, m.R, m.Ld, m.Lq, w_meas, TS, 1,
                           art.decoupling.delay_compensation_time)
    eps = art.decoupling.delay_compensation_time * w_meas - 1.5 * TS * w
    want = cvd.closed_loop_poles(g, R, Ld, Lq, w, TS, eps=eps)
    got = np.linalg.eigvals(loop.A[0])
    # the analysis' loop carries the law's delayed voltages twice (law state and
    # delay line): two more poles at 0
    assert np.allclose(np.sort(np.abs(got))[2:], np.sort(np.abs(want)), rtol=0, atol=1e-6)
    assert np.allclose(np.sort(np.abs(got))[:2], 0.0, atol=1e-6)
    if scale == (1, 1, 1) and w == w_meas:
        assert loop.spectral_radius()[0] == pytest.approx(max(art.cv.poles(TS, 1)), abs=1e-6)
        # the EMF feed-forward cancels the back-EMF: zero static error
        assert np.allclose(loop.steady_currents((-2.0, 10.0))[0], (-2.0, 10.0), atol=1e-9)


def test_error_response_is_the_law_realisation(designed):
    """``K(z)`` of :meth:`CvExecuted.error_response` equals minus the measurement
    channel of the law's state-space realisation (states ``[x, v_(k-1)]``) at
    920 rad/s, where every gain is coupled."""
    spec, art = designed
    law = executed_laws(art)
    z = np.exp(1j * np.array([1.0, 300.0, 3000.0, 20000.0]) * TS)
    K = law.error_response(z, [920.0])[0]
    g = cvd.executed_gains(art.cv, spec.motor.R, spec.motor.Ld, spec.motor.Lq, 920.0, TS, 1,
                           art.decoupling.delay_compensation_time)
    I2, O2 = np.eye(2), np.zeros((2, 2))
    A = np.block([[I2, O2], [I2, -g.K2[0]]])
    Bi = np.vstack([-g.Ki, -g.K1])
    C = np.hstack([I2, -g.K2[0]])
    for k, zk in enumerate(z):
        G = C @ np.linalg.solve(zk * np.eye(4) - A, Bi) - g.K1
        assert np.allclose(K[k], -G, rtol=1e-10, atol=1e-12)
    assert abs(K[1, 0, 1]) > 1e-2 * abs(K[1, 0, 0])           # coupled at speed


def test_certificates_refuse_the_cv_law(designed):
    """The certificates' polytopes need a law affine in the measured speed:
    refused by name (and left null in analysis.json and cct compare)."""
    spec, art = designed
    with pytest.raises(ArtifactError, match="not affine in the measured speed"):
        largest_certified_scale(art, spec.motor, spec.drive)
