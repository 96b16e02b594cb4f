"""FCS-MPC (paper 002): criterion (23) weights and the eq (19)-(20) baseline PI."""

import numpy as np
import pytest

from toolbox.artifact import ControllerArtifact
from toolbox.design import design
from toolbox.design.fcs_mpc import baseline_pi
from toolbox.errors import SpecError
from toolbox.spec import spec_from_dict


def spec(**cfg):
    return spec_from_dict({"motor": {"catalog": "cormerais2002"},
                           "drive": {"vdc": 300, "sample_time": 1e-4},
                           "controller": {"method": "fcs_mpc", "fcs_mpc": cfg}})


def test_weights_and_defaults():
    assert spec().controller.cfg.gamma == 0.0
    cfg = spec(alpha=2.0, beta=0.5, gamma=1e-3).controller.cfg
    assert (cfg.alpha, cfg.beta, cfg.gamma) == (2.0, 0.5, 1e-3)


def test_bad_weights():
    with pytest.raises(SpecError) as err:
        spec(alpha=0.0, beta=0.0)
    assert str(err.value) == ("controller.fcs_mpc.alpha: expected alpha + beta > 0 (criterion "
                              "(23) must weight the torque or the i_d error), got [0.0, 0.0]")
    with pytest.raises(SpecError, match=r"controller\.fcs_mpc\.gamma: expected a number >= 0 and <= 1e\+12, got -1"):
        spec(gamma=-1)
    with pytest.raises(SpecError, match="controller.fcs_mpc.delta"):
        spec(delta=1.0)


def test_artifact_holds_eq19_20_pi():
    """Kp = 10 R = 0.2 V/A, Ki = 10 R^2/L = 35.5 V/(A s) for R = 0.02, L = 112.6 uH;
    the axis controller is exactly Kp + Ki/s (1e-12)."""
    art = design(spec(alpha=1.0, beta=1.0, gamma=0.01))
    Kp, Ki = baseline_pi(0.02, 112.6e-6)
    assert Kp == pytest.approx(0.2) and Ki == pytest.approx(0.2 * 0.02 / 112.6e-6)
    K = art.axes["q"].to_statespace(domain="continuous")
    assert float(np.real(K(1e12j))) == pytest.approx(Kp, rel=1e-9)
    assert float(np.real(K(1.0) - K(2.0))) == pytest.approx(Ki / 2, rel=1e-9)
    assert art.design_parameters["baseline"] == "002 eq (19)-(20)"
    assert art.fcs.gamma == 0.01 and "gamma" not in art.design_parameters
    text = art.dumps()
    assert ControllerArtifact.loads(text).dumps() == text
