"""H-infinity refusals are typed (toolbox/ARCHITECTURE.md "Errors and exit
codes"): infeasibility is a DesignInfeasible, and the caller branches on the
class and its data, never on message text."""

import tomllib
from pathlib import Path

import pytest

import toolbox
from toolbox.design import _hinf_gamma as HG
from toolbox.errors import DesignInfeasible, SpecError

DESIGNS = Path(__file__).parents[2] / "designs"


def hinf_spec(gamma):
    data = tomllib.loads((DESIGNS / "003_azaiz2007_hinf.toml").read_text())
    data["controller"]["hinf"]["gamma"] = gamma
    return toolbox.spec_from_dict(data)


def test_gamma_below_optimum_is_design_infeasible():
    """Paper 003's problem at gamma = 0.8 < 0.9518 (q-axis optimum): the spec is
    valid but infeasible, so DesignInfeasible (still a SpecError: exit 2)."""
    with pytest.raises(DesignInfeasible) as info:
        toolbox.design_spec(hinf_spec(0.8))
    assert isinstance(info.value, SpecError)
    assert info.value.key == "controller.hinf.gamma"


def test_axis_error_carries_condition_as_data():
    """The per-axis error is a GammaBelowOptimum with the failed condition and
    the best gamma as attributes; moving it to a file or key keeps them."""
    spec = hinf_spec(0.8)
    from toolbox.design.hinf import design_hinf_axis
    from toolbox.plant import axis_plants
    with pytest.raises(HG.GammaBelowOptimum) as info:
        design_hinf_axis(axis_plants(spec.motor)["q"], **spec.controller.cfg.weights["q"],
                         gamma=0.8, sample_time=spec.drive.sample_time, axis="q")
    err = info.value
    assert err.axis == "q" and err.condition and err.condition in str(err)
    assert err.best == pytest.approx(0.9518, abs=5e-5)   # paper 003: gamma_opt(q) = 0.9518
    moved = err.with_file("x.toml")
    assert (type(moved), moved.condition, moved.best) == (type(err), err.condition, err.best)
    assert str(moved).startswith("x.toml: controller.hinf.gamma: ")


def test_bad_gamma_value_stays_a_plain_spec_error():
    """A malformed gamma is bad input, not an infeasible design."""
    with pytest.raises(SpecError) as info:
        toolbox.design_spec(hinf_spec(-1.0))
    assert not isinstance(info.value, DesignInfeasible)
