"""controller.json schema 2: typed fields instead of an untyped ``gains`` dict.

What a later stage executes or draws (the fcs_mpc weights, the H-infinity
weights, the delay compensation, the executed law of each axis) is a typed,
validated field; a bad value is refused with an ArtifactError naming the key
path, what was expected and what was found. The error -> voltage ``discrete``
view is derived from the executed ``law`` (same order), never stored.

Artifacts are built directly (no design module) so that every check here
fails on its own: each refusal test mutates one key of a valid document.
"""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from toolbox.artifact import (AxisController, AxisWeights, ControllerArtifact, Decoupling,
                              FcsWeights, TransferFunctionData)
from toolbox.errors import ArtifactError

TS = 1e-4
FILE = "out/controller.json"
W1 = TransferFunctionData(np.array([0.66225, 117.4499]), np.array([1.0, 0.0117]))  # 003 eq (44)


def _pi_axis(kp: float = 2.8, ki: float = 1200.0) -> AxisController:
    return AxisController.from_error_controller(control.tf([kp, ki], [1, 0]), TS)


def _artifact(method: str = "pi", **typed) -> ControllerArtifact:
    return ControllerArtifact(
        method=method, spec={"title": "t"}, sample_time=TS, delay_samples=1,
        axes={"d": _pi_axis(), "q": _pi_axis(5.6)},
        decoupling=Decoupling(True, True, 0.6, 1.4e-3, 2.8e-3, 0.12, 4, 1.5 * TS),
        design_parameters={"note": "informational"},
        provenance={"version": "x", "spec_sha256": "0" * 64, "created": "now"}, **typed)


def _fcs_json() -> dict:
    return json.loads(_artifact("fcs_mpc", fcs=FcsWeights(1.0, 0.5, 0.01)).dumps())


def _hinf_json() -> dict:
    w = AxisWeights(gamma=1.0, w1=W1)
    return json.loads(_artifact("hinf", weights={"d": w, "q": w}).dumps())


def _refused(data: dict, message: str) -> None:
    with pytest.raises(ArtifactError) as info:
        ControllerArtifact.from_json(data, file=FILE)
    assert str(info.value) == f"{FILE}: {message}"


def test_typed_fields_round_trip_exactly():
    """fcs, weights and the delay compensation survive JSON byte for byte."""
    for data in (_fcs_json(), _hinf_json()):
        text = json.dumps(data, indent=1) + "\n"
        back = ControllerArtifact.loads(text)
        assert back.dumps() == text
    back = ControllerArtifact.from_json(_fcs_json())
    assert back.fcs == FcsWeights(1.0, 0.5, 0.01)
    assert back.decoupling.delay_compensation_time == 1.5 * TS
    hinf = ControllerArtifact.from_json(_hinf_json())
    np.testing.assert_array_equal(hinf.weights["q"].w1.den, W1.den)
    assert hinf.weights["q"].w2 is None and hinf.weights["q"].gamma == 1.0


def test_schema_1_is_refused_with_a_remedy():
    data = _fcs_json()
    data["schema"] = "cct.controller/1"
    _refused(data, 'schema: expected "cct.controller/2", got "cct.controller/1" (written by '
                   "an older toolbox whose gains dict later stages had to guess keys from; "
                   "re-run cct design on the spec)")


def test_gains_key_is_unknown_in_schema_2():
    data = _fcs_json()
    data["gains"] = {"alpha": 1.0}
    with pytest.raises(ArtifactError, match=r"gains: expected one of \[.*'design_parameters'"):
        ControllerArtifact.from_json(data)


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.update(fcs=None),
     'fcs: expected an object {alpha, beta, gamma} (the fcs_mpc law executes criterion (23) '
     'with it), got "nothing (missing or null)"'),
    (lambda d: d["fcs"].pop("beta"),
     'fcs.beta: expected a finite number >= 0 (the fcs_mpc law reads it), '
     'got "nothing (missing)"'),
    (lambda d: d["fcs"].update(gamma=-0.1),
     "fcs.gamma: expected a finite number >= 0 (the fcs_mpc law reads it), got -0.1"),
    (lambda d: d["fcs"].update(alpha=True),
     "fcs.alpha: expected a finite number >= 0 (the fcs_mpc law reads it), got True"),
    (lambda d: d["fcs"].update(alpha=0.0, beta=0.0),
     "fcs.alpha: expected alpha + beta > 0, got [0.0, 0.0]"),
    (lambda d: d["fcs"].update(delta=1.0),
     "fcs.delta: expected one of ['alpha', 'beta', 'gamma'], got \"unknown key\""),
])
def test_bad_fcs_weights_are_refused(mutate, message):
    data = _fcs_json()
    mutate(data)
    _refused(data, message)


def test_fcs_weights_on_a_linear_method_are_refused():
    """A linear law would silently ignore criterion (23) weights."""
    data = json.loads(_artifact().dumps())
    data["fcs"] = {"alpha": 1.0, "beta": 1.0, "gamma": 0.0}
    _refused(data, "fcs: expected null (only method fcs_mpc executes criterion (23) weights), "
                   'got "weights for method pi"')


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.update(weights=None),
     'weights: expected an object with the axes "d" and "q" (the H-infinity weights the '
     'bounds of 003 eq (41)-(43) are drawn from), got "nothing (missing or null)"'),
    (lambda d: d["weights"].pop("d"),
     'weights: expected null or an object with the axes "d" and "q", got [\'q\']'),
    (lambda d: d["weights"]["q"].update(gamma=0),
     "weights.q.gamma: expected a number > 0, got 0"),
    (lambda d: d["weights"]["q"].update(w1=None),
     'weights.q.w1: expected a weight {num, den} (W1 is required), '
     'got "nothing (missing or null)"'),
    (lambda d: d["weights"]["q"]["w1"].update(den=[0.0, 1.0]),
     "weights.q.w1.den[0]: expected a non-zero leading coefficient, got 0.0"),
    (lambda d: d["weights"]["d"]["w1"].update(num=[1.0, "nan"]),
     'weights.d.w1.num[1]: expected a finite number, got "nan"'),
    (lambda d: d["weights"]["d"].update(w3={"num": []}),
     "weights.d.w3.num: expected a non-empty list of numbers (highest power of s first), "
     "got []"),
])
def test_bad_hinf_weights_are_refused(mutate, message):
    data = _hinf_json()
    mutate(data)
    _refused(data, message)


def test_bad_delay_compensation_is_refused():
    data = _fcs_json()
    data["decoupling"]["delay_compensation_time"] = -1e-4
    _refused(data, "decoupling.delay_compensation_time: expected a finite number >= 0 (s), "
                   "got -0.0001")


def test_discrete_is_derived_from_the_executed_law():
    """discrete = minus the law's measurement channel: same states, same order,
    identical matrices (no tolerance: it is a view, not a second design)."""
    art = _artifact()
    for ax in art.axes.values():
        law, disc = ax.law, ax.discrete
        assert disc.order == law.order == ax.order
        np.testing.assert_array_equal(disc.A, law.A)
        np.testing.assert_array_equal(disc.B, -law.B[:, 1:2])
        np.testing.assert_array_equal(disc.D, -law.D[:, 1:2])
        assert (disc.dt, disc.method) == (law.dt, law.method)
    assert "discrete" not in json.loads(art.dumps())["axes"]["d"]


def test_stored_discrete_is_refused():
    """A separately stored discrete controller (schema 1) could disagree with the law."""
    data = _fcs_json()
    data["axes"]["d"]["discrete"] = data["axes"]["d"]["law"]
    _refused(data, 'axes.d.discrete: expected no stored discrete controller (it is derived '
                   'from law), got "a stored one (cct.controller/1)" (re-run cct design on '
                   "the spec)")


def test_continuous_of_another_order_is_refused():
    """The continuous twin must be of the executed law (003 schema 1 had a 4th-order
    continuous next to a 3rd-order law); other controllers go under full_order."""
    data = _fcs_json()
    big = control.ss(control.tf([1.0, 2.0, 3.0], [1.0, 4.0, 0.0]))
    data["axes"]["q"]["continuous"] = {"A": big.A.tolist(), "B": big.B.tolist(),
                                       "C": big.C.tolist(), "D": big.D.tolist()}
    _refused(data, "axes.q.continuous: expected the continuous twin of the executed law "
                   '(order 1), got "order 2" (a controller that is not executed belongs '
                   "under full_order or reduced)")


def test_full_order_and_reduced_are_exclusive_and_not_nested():
    full, red = _pi_axis(), _pi_axis(1.0, 10.0)
    with pytest.raises(ArtifactError, match="^reduced: expected either reduced"):
        AxisController(red.law, red.continuous, red.antiwindup, reduced=red, full_order=full)
    data = _fcs_json()
    data["axes"]["q"]["full_order"] = dict(data["axes"]["d"], reduced=data["axes"]["d"])
    with pytest.raises(ArtifactError, match=r"^axes\.q\.full_order\.reduced: expected one of"):
        ControllerArtifact.from_json(data)


def test_simulator_reads_the_typed_fcs_weights():
    """control_law passes artifact.fcs through (the kernel's LP vector reads it);
    informational design parameters with the same names are ignored."""
    from dataclasses import replace

    from toolbox.sim import control_law

    art = ControllerArtifact.from_json(_fcs_json())
    decoy = replace(art, design_parameters={"alpha": 99.0, "beta": 99.0, "gamma": 99.0})
    assert control_law(decoy).fcs == FcsWeights(1.0, 0.5, 0.01)
    assert control_law(_artifact()).fcs is None
