"""Verification reads the artifact and the spec's scenarios; requirements decide
pass/fail (toolbox/ARCHITECTURE.md "Errors and exit codes")."""

import pytest

from toolbox.design import design
from toolbox.sim import verify
from toolbox.spec import spec_from_dict

BASE = {"motor": {"catalog": "azaiz2007"},
        "drive": {"vdc": 150, "sample_time": 1e-4, "delay_samples": 1},
        "controller": {"method": "pi", "pi": {"bandwidth": 1000.0}}}


def _spec(scenarios, requirements=None):
    return spec_from_dict({**BASE, "scenario": scenarios, "requirements": requirements or {}})


def test_plant_scale_equals_explicit_values():
    """A scenario with plant_scale Lq x2 simulates the same plant as one with
    plant_values Lq = 2 Lq (regression: the scale was once applied twice).
    Same kernel, same plant: equal to float rounding (1e-12)."""
    step = {"kind": "current_step", "duration": 0.01, "iq_ref": 5.0}
    spec = _spec([{**step, "plant_scale": {"Lq": 2.0}},
                  {**step, "plant_values": {"Lq": 2 * 2.8e-3}}])
    a, b = verify(design(spec), spec).scenarios
    for name in ("rise_time_10_90", "final_value", "mse_iq"):
        assert a.metrics[name] == pytest.approx(b.metrics[name], rel=1e-12, abs=1e-15)


def test_margin_requirements_decide_verify():
    """A margin bound that the stored MARGINS miss fails verification too."""
    spec = _spec([{"kind": "current_step", "duration": 0.005, "iq_ref": 1.0}],
                 {"min_phase_margin_deg": 179.0})
    art = design(spec).with_margins({"d": {"phase_margin_deg": 60.0},
                                     "q": {"phase_margin_deg": "inf"}})
    res = verify(art, spec)
    assert not res.passed
    check = res.to_json()["margin_requirements"]["min_phase_margin_deg"]
    assert check["value"] == 60.0 and check["pass"] is False  # worst axis, "inf" read as a number


def test_speed_scenarios_report_speed_error_not_current():
    """In a speed step the static error is a speed (rad/s): it is checked by
    max_static_speed_error, never by the ampere bound."""
    spec = _spec([{"kind": "speed_step", "duration": 0.05, "speed_ref": 20.0,
                   "speed_loop": {"kp": 0.5, "ki": 5.0}}],
                 {"max_static_error_A": 1e-9, "max_static_speed_error": 5.0})
    (sc,) = verify(design(spec), spec).scenarios
    assert "static_error_abs" not in sc.metrics
    assert set(sc.checks) == {"max_static_speed_error"}
