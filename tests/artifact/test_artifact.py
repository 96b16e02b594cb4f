"""controller.json: exact round trip and refusal of bad content."""

import json

import control
import numpy as np
import pytest

from toolbox.artifact import AxisController, ControllerArtifact, Decoupling
from toolbox.errors import ArtifactError

TS = 1e-4


def make_artifact() -> ControllerArtifact:
    pi_d = AxisController.from_error_controller(control.tf([2.8, 1200.0], [1, 0]), TS)
    # IP law: v = Ki/s (r - y) - Kp y (two inputs), continuous then Tustin
    Kp, Ki = 5.6, 1200.0
    ip = control.ss([[0.0]], [[1.0, -1.0]], [[Ki]], [[0.0, -Kp]])
    ip_q = AxisController.from_law(ip, sample_time=TS, method="tustin")
    return ControllerArtifact(
        method="pi", spec={"title": "t", "motor": {"R": 0.6}}, sample_time=TS,
        delay_samples=1, axes={"d": pi_d, "q": ip_q},
        decoupling=Decoupling(True, True, 0.6, 1.4e-3, 2.8e-3, 0.12, 4),
        design_parameters={"Kp": {"d": 2.8, "q": 5.6}, "Ki": np.float64(1200.0)},
        provenance={"version": "x", "spec_sha256": "0" * 64, "created": "now"})


def test_round_trip_is_exact():
    art = make_artifact()
    text = art.dumps()
    again = ControllerArtifact.loads(text)
    assert again.dumps() == text  # byte-identical: floats written with repr precision
    np.testing.assert_array_equal(again.axes["q"].law.B, art.axes["q"].law.B)


def test_measurement_channel_is_minus_error_controller():
    """For a 1-DOF PI the law is [K, -K]: its loop controller equals K exactly."""
    art = make_artifact()
    law = art.axes["d"].law.to_statespace()
    K = art.axes["d"].discrete.to_statespace()
    w = np.logspace(1, 4, 20)
    np.testing.assert_allclose(-law[0, 1](np.exp(1j * w * TS)), K(np.exp(1j * w * TS)),
                               rtol=1e-12)


def test_ip_error_controller_is_pi_of_same_loop():
    """IP: the loop sees Kp + Ki/s (minus the measurement channel), the
    reference only Ki/s; zpk gives the PI zero at -Ki/Kp (rad/s)."""
    art = make_artifact()
    zpk = art.axes["q"].zpk
    np.testing.assert_allclose(zpk.zeros, [-1200.0 / 5.6], rtol=1e-9)
    np.testing.assert_allclose(zpk.gain, 5.6, rtol=1e-12)


def test_python_control_conversion():
    art = make_artifact()
    sys = art.axes["d"].to_statespace(domain="continuous")
    assert np.isclose(sys(1j * 1000.0), 2.8 + 1200.0 / (1j * 1000.0))
    assert np.isclose(control.evalfr(sys.to_control(), 1j * 1000.0), 2.8 + 1200.0 / (1j * 1000.0))
    assert art.axes["d"].to_statespace(discrete=True).dt == TS


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.update(schema="cct.controller/0"),
     'schema: expected "cct.controller/2", got "cct.controller/0" '
     "(written by another version of the toolbox?)"),
    (lambda d: d["axes"].pop("q"),
     'axes: expected an object with the axes "d" and "q", got [\'d\']'),
    (lambda d: d["axes"]["d"]["law"].update(dt=2e-4),
     "axes.d.law.dt: expected dt equal to sample_time 0.0001, got 0.0002"),
    (lambda d: d["axes"]["d"]["law"].update(method="magic"),
     "axes.d.law.method: expected one of ['tustin', 'zoh', 'foh', 'backward_diff', "
     "'euler', 'native'], got \"magic\""),
    (lambda d: d["axes"]["d"]["law"].update(A=[[1.0, 2.0]]),
     "axes.d.law.A: expected a square matrix, got [1, 2]"),
    (lambda d: d["decoupling"].update(Lq_c=-1),
     "decoupling.Lq_c: expected a finite number >= 0, got -1"),
    (lambda d: d.update(extra=1),
     "extra: expected one of ['axes', 'cv', 'decoupling', 'delay_samples', 'design_parameters', "
     "'fcs', 'margins', 'method', 'provenance', 'sample_time', 'schema', 'spec', 'weights'], "
     "got \"unknown key\""),
])
def test_bad_content_is_refused(mutate, message):
    data = json.loads(make_artifact().dumps())
    mutate(data)
    with pytest.raises(ArtifactError) as info:
        ControllerArtifact.from_json(data, file="out/controller.json")
    assert str(info.value) == f"out/controller.json: {message}"


def test_invalid_json_text():
    with pytest.raises(ArtifactError, match="controller.json: expected valid JSON"):
        ControllerArtifact.loads("{", file="controller.json")
