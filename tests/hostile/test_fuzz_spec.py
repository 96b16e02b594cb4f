"""Property: the spec loader answers any input with a spec or a CctError.

Random mutations of a valid spec (every key of motor, drive, controller
parameters of every method, scenarios, requirements) and random TOML-like
text: the loader must return a Spec or raise CctError with a message; any
other exception (ZeroDivisionError, OverflowError, LinAlgError,
RecursionError, KeyError, TypeError ...) is a bug. Derandomised and bounded
(max_examples) so CI time is fixed: about 10 s on one core.
"""

from __future__ import annotations

import copy
import math

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from toolbox.errors import CctError
from toolbox.spec import METHODS, load_spec, spec_from_dict
from toolbox.spec._load import DRIVE_KEYS, MOTOR_KEYS

from hostile_helpers import BASE, to_toml

FUZZ = settings(derandomize=True, max_examples=200, deadline=None,
                suppress_health_check=[HealthCheck.too_slow,
                                       HealthCheck.function_scoped_fixture])

#: Numbers where the numerics break: zero, signs, tiny, huge, non-finite.
NASTY_FLOATS = st.sampled_from([0.0, -0.0, 1e-300, -1.0, 1e300, 1e-11, 1e39, 1e6,
                                math.inf, -math.inf, math.nan, 0.5, 2.0, 1000.0])
PLAUSIBLE = st.floats(min_value=1e-4, max_value=1e4)  # reaches the checks after typing
SCALARS = st.one_of(
    PLAUSIBLE,
    NASTY_FLOATS,
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-10**20, max_value=10**20),
    st.booleans(),
    st.text(max_size=8),
    st.sampled_from(["optimal", "cancellation", "symmetric_optimum", "hinf", "d", "q"]),
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.sampled_from(["d", "q", "num", "den", "w1",
                                                             "order", "gain", "x"]),
                                            inner, max_size=3)),
    max_leaves=8)

#: Parameter names of the methods (so mutations reach the read_cfg code).
PARAM_KEYS = ["bandwidth", "rule", "a", "small_time_constant", "Kp", "Ki", "gamma",
              "backoff", "reduce_order", "weights", "poles", "sigma", "sigma_factor",
              "alpha", "beta", "K1", "K2", "lag_time_constant", "response_time",
              "integral_bandwidth", "Q", "R", "current_limit", "voltage_limit"]
SCENARIO_KEYS = ["kind", "duration", "plant_step", "keep_traces", "trace_step", "iq_ref",
                 "step_time", "initial_speed", "inverter", "speed_loop"]

W1 = {"num": [0.66225, 117.4499], "den": [1.0, 0.0117]}


@st.composite
def mutated_specs(draw) -> dict:
    data = copy.deepcopy(BASE)
    method = draw(st.sampled_from(METHODS))
    params = {"hinf": {"weights": {"d": {"w1": W1}, "q": {"w1": W1}}},
              "ilq": {"poles": -1000.0}, "pi_lag": {"bandwidth": 1000.0,
                                                    "lag_time_constant": 2e-4},
              "tc": {"K1": 800.0, "K2": 800.0}}.get(method, {})
    data["controller"] = {"method": method, method: params}
    for _ in range(draw(st.integers(1, 3))):
        where = draw(st.sampled_from(["motor", "drive", "param", "scenario", "requirements",
                                      "top"]))
        value = draw(VALUES)
        if where in ("motor", "drive") and not isinstance(data.get(where), dict):
            where = "top"  # replaced whole by an earlier mutation
        if where == "scenario" and not (isinstance(data.get("scenario", []), list)
                                        and all(isinstance(s, dict)
                                                for s in data.get("scenario", []))):
            where = "top"
        if where == "motor":
            data["motor"][draw(st.sampled_from(MOTOR_KEYS[1:]))] = value
        elif where == "drive":
            data["drive"][draw(st.sampled_from(DRIVE_KEYS))] = value
        elif where == "param":
            params[draw(st.sampled_from(PARAM_KEYS))] = value
        elif where == "scenario":
            scenarios = data.setdefault("scenario", [])
            if not scenarios:
                scenarios.append({"kind": "current_step"})
            scenarios[0][draw(st.sampled_from(SCENARIO_KEYS))] = value
        elif where == "requirements":
            data["requirements"] = {draw(st.sampled_from(
                ["min_phase_margin_deg", "max_overshoot_pct", "bogus"])): value}
        else:
            data[draw(st.sampled_from(["title", "motor", "drive", "controller",
                                       "scenario"]))] = value
    return data


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::UserWarning")  # design advice on accepted specs
@FUZZ
@given(mutated_specs())
def test_mutated_spec_gives_a_spec_or_a_message(data):
    try:
        spec = spec_from_dict(data, file="fuzz.toml")
    except CctError as err:
        text = str(err)
        assert text.startswith("fuzz.toml: ") and "expected" in text, text
    else:
        assert spec.motor.R > 0 and spec.drive.sample_time > 0


TOKENS = st.sampled_from(["[", "]", "{", "}", "[[", "]]", "=", ",", ".", '"', "'", "\n",
                          "#", " ", "motor", "drive", "controller", "R", "vdc", "method",
                          "1", "-1", "1e300", "nan", "inf", "true", '"pi"', "0.5", "x",
                          '"""', "\\", "\x00", "é"])


@FUZZ
@given(st.lists(TOKENS, max_size=60), st.sampled_from(["", to_toml(BASE)]))
def test_random_toml_text_gives_a_spec_or_a_message(tmp_path_factory, tokens, prefix):
    path = tmp_path_factory.mktemp("fuzz") / "s.toml"
    path.write_text(prefix + "".join(tokens), encoding="utf-8", errors="surrogatepass")
    try:
        load_spec(path)
    except CctError as err:
        assert str(err).startswith(f"{path}: "), str(err)
