"""Method parameters with absurd sizes are refused by key, before any design.

gamma = 1e300 and backoff = 1e300 overflowed in the gamma iteration
(OverflowError), symmetric optimum a = 1e300 gave a zero integral gain, a
makeweight order of 1e6 and a 5,000-coefficient weight hung the H-infinity
design. The bounds and their reasons are in the design modules (hinf.py,
pi.py, ilq.py, _weights.py).
"""

from __future__ import annotations

import math

import pytest

from toolbox.design._weights import makeweight
from toolbox.errors import SpecError
from toolbox.spec import spec_from_dict

from hostile_helpers import run_cli, spec_dict

W1 = {"num": [0.66225, 117.4499], "den": [1.0, 0.0117]}  # paper 003 eq (44)


def hinf(**params) -> dict:
    weights = params.pop("weights", {"d": {"w1": W1}, "q": {"w1": W1}})
    return {"method": "hinf", "hinf": {**params, "weights": weights}}


MW = {"dc_gain": 1e4, "crossover": 156.0, "crossover_gain": 1.0, "hf_gain": 0.5}

CASES = [
    ("gamma_1e300", hinf(gamma=1e300),
     "controller.hinf.gamma: expected a number > 0 and <= 10000, got 1e+300"),
    ("backoff_1e300", hinf(gamma="optimal", backoff=1e300),
     "controller.hinf.backoff: expected a number >= 0 and <= 10, got 1e+300"),
    ("so_a_1e300", {"method": "pi", "pi": {"rule": "symmetric_optimum", "a": 1e300}},
     "controller.pi.a: expected a number > 1 and <= 100, got 1e+300"),
    ("so_a_1", {"method": "pi", "pi": {"rule": "symmetric_optimum", "a": 1.0}},
     "controller.pi.a: expected a number > 1 and <= 100, got 1.0"),
    ("makeweight_order_1e6", hinf(weights={"d": {"w1": {**MW, "order": 1_000_000}},
                                           "q": {"w1": W1}}),
     "controller.hinf.weights.d.w1.order: expected an integer >= 1 and <= 10, got 1000000"),
    ("makeweight_order_float", hinf(weights={"d": {"w1": {**MW, "order": 1e6}},
                                             "q": {"w1": W1}}),
     "controller.hinf.weights.d.w1.order: expected an integer >= 1 and <= 10, got 1000000.0"),
    ("weight_5000_coefficients", hinf(weights={"d": {"w1": W1}, "q": {"w1": {
        "num": [1.0] * 5000, "den": [1.0, 1.0]}}}),
     'controller.hinf.weights.q.w1.num: expected a list of at most 21 numbers, '
     'got "5000 numbers"'),
    ("weight_order_21", hinf(weights={"d": {"w1": W1}, "q": {"w1": {
        "num": [1.0], "den": [1.0] * 22}}}),
     'controller.hinf.weights.q.w1.den: expected a list of at most 21 numbers, '
     'got "22 numbers"'),
    ("weight_5000_poles", hinf(weights={"d": {"w1": W1}, "q": {"w1": {
        "zeros": [], "poles": [-1.0] * 5000, "gain": 1.0}}}),
     'controller.hinf.weights.q.w1.poles: expected at most 20 roots, got "5000 roots"'),
    # QA: w1 = 1e300 reached the synthesis and came back as "A3 fails"
    ("weight_gain_1e300", hinf(weights={"d": {"w1": W1}, "q": {"w1": 1e300}}),
     'controller.hinf.weights.q.w1: expected a weight whose gain stays below 1e+12, '
     'got "a peak gain of 1e+300" (only the ratio of the weights to gamma matters: '
     'scale them down)'),
    ("weight_peak_1e13", hinf(weights={"d": {"w1": W1}, "q": {"w1": {
        "num": [1e7], "den": [1.0, 1e-6]}}}),
     'controller.hinf.weights.q.w1: expected a weight whose gain stays below 1e+12, '
     'got "a peak gain of 1e+13" (only the ratio of the weights to gamma matters: '
     'scale them down)'),
    # QA: cct check accepted alpha = 1e300, which the header export then refused
    ("fcs_alpha_1e300", {"method": "fcs_mpc", "fcs_mpc": {"alpha": 1e300}},
     "controller.fcs_mpc.alpha: expected a number >= 0 and <= 1e+12, got 1e+300"),
    ("ilq_sigma_factor", {"method": "ilq", "ilq": {"poles": -1000.0, "sigma_factor": 1e300}},
     "controller.ilq.sigma_factor: expected a number > 0 and <= 1000, got 1e+300"),
    # sigma Ts = 1e300 x 1e-4: the bound is 100 / Ts = 1e6 1/s
    ("ilq_sigma", {"method": "ilq", "ilq": {"poles": -1000.0, "sigma": 1e300}},
     "controller.ilq.sigma: expected a number > 0 and <= 1e+06 (1/s), got 1e+300"),
]


@pytest.mark.parametrize("name, controller, message", CASES, ids=[c[0] for c in CASES])
def test_method_parameter_out_of_bounds(name, controller, message):
    # refused by key while reading (an unbounded order or coefficient count
    # made the weight construction or the design hang)
    with pytest.raises(SpecError) as info:
        spec_from_dict(spec_dict(controller=controller), file="s.toml")
    assert str(info.value) == f"s.toml: {message}"


@pytest.mark.parametrize("controller", [
    hinf(gamma=1e4), hinf(gamma="optimal", backoff=10.0),
    {"method": "pi", "pi": {"rule": "symmetric_optimum", "a": 100.0}},
    hinf(weights={"d": {"w1": {**MW, "order": 10}}, "q": {"w1": W1}}),
    # (s + 1)^20 / (s + 2)^20: stable, biproper, order 20
    hinf(weights={"d": {"w1": W1}, "q": {"w1": {
        "num": [float(math.comb(20, k)) for k in range(21)],
        "den": [float(math.comb(20, k) * 2 ** k) for k in range(21)]}}}),
], ids=["gamma_1e4", "backoff_10", "a_100", "makeweight_10", "order_20"])
def test_parameters_at_the_bound_are_read(controller):
    """The bounds are inclusive, so the refusals above are the bounds, not a typo."""
    spec = spec_from_dict(spec_dict(controller=controller))
    assert spec.controller.method == controller["method"]


def test_makeweight_api_has_the_same_order_bound():
    with pytest.raises(SpecError, match=r"w\.order: expected an integer >= 1 and <= 10, "
                                        r"got 1000000"):
        makeweight(1e4, 156.0, 1.0, 0.5, order=1_000_000, key="w")


@pytest.mark.parametrize("name", ["gamma_1e300", "backoff_1e300", "so_a_1e300",
                                  "makeweight_order_1e6"])
def test_cli_exit_2(write_spec, tmp_path, name):
    controller, message = next((c, m) for n, c, m in CASES if n == name)
    res = run_cli("design", write_spec(spec_dict(controller=controller)), "--out",
                  tmp_path / "out")
    assert res.exit_code == 2, res.output
    assert f"cct: error: {tmp_path / 'spec.toml'}: {message}" in res.output
    assert not (tmp_path / "out").exists()
