"""Designs the toolbox must not hand to a user are refused with SpecError
(exit 2), naming the spec key and the remedy (toolbox/ARCHITECTURE.md "Reliability rules")."""

import tomllib
from pathlib import Path

import pytest
import toolbox
from toolbox.errors import SpecError

DESIGNS = Path(__file__).parents[2] / "designs"


def hinf_spec(gamma):
    data = tomllib.loads((DESIGNS / "003_azaiz2007_hinf.toml").read_text())
    data["controller"]["hinf"]["gamma"] = gamma
    return data


def test_gamma_below_optimum_quotes_best_over_both_axes():
    """One gamma serves both axes: the advice must be the larger optimum (q:
    0.9518, paper 003's problem; d alone would say 0.6463 and fail again)."""
    with pytest.raises(SpecError) as info:
        toolbox.design_spec(hinf_spec(0.8))
    assert info.value.key == "controller.hinf.gamma"
    assert "best achievable 0.9518 (both axes)" in str(info.value)
    assert "best per axis: d 0.6463, q 0.9518" in str(info.value)


def test_fixed_gamma_at_the_optimum_is_refused_not_exported():
    """At gamma = 1.00001 gamma_opt the q controller has a pole near -1e6 rad/s,
    far beyond pi/Ts = 31,416 rad/s: refused, with the remedy."""
    with pytest.raises(SpecError) as info:
        toolbox.design_spec(hinf_spec(1.00001 * 0.951825))
    assert "no pole faster than pi/Ts = 3.142e+04 rad/s" in str(info.value)
    assert 'gamma = "optimal"' in str(info.value)


@pytest.mark.parametrize("R", [1e-30])
def test_lq_with_extreme_weights_is_refused(R):
    """R = 1e-30 makes the CARE solution inaccurate (an unstable 'optimal'
    closed loop): refused instead of returned."""
    data = {"motor": {"catalog": "azaiz2007"}, "drive": {"vdc": 150, "sample_time": 1e-4},
            "controller": {"method": "lq", "lq": {"domain": "continuous",
                                                  "Q": [1.0, 1.0], "R": R}}}
    with pytest.raises(SpecError, match="controller.lq"):
        toolbox.design_spec(data)


def test_unstable_sampled_loop_is_analysed_not_refused():
    """A PI at 1e6 rad/s bandwidth with Ts = 100 us is unstable once sampled.
    It is not bad input (exit 2, nothing written) but a design that exists
    and fails (toolbox/ARCHITECTURE.md "Errors and exit codes": exit 1,
    outputs written): the analysis records the unstable axes (so
    `cct design` exits 1 and writes the report, see tests/cli/test_verdict.py)
    and only the firmware export is refused, naming the law's key."""
    from toolbox.errors import ExportRefused
    from toolbox.pipeline import refuse_unstable_export, unstable_axes

    spec = toolbox.spec_from_dict({
        "motor": {"catalog": "azaiz2007"}, "drive": {"vdc": 150, "sample_time": 1e-4},
        "controller": {"method": "pi", "pi": {"bandwidth": 1e6}}})
    art, analysis = toolbox.analyse(toolbox.design_spec(spec), spec)
    assert unstable_axes(analysis) == ["d", "q"]
    with pytest.raises(ExportRefused) as info:
        refuse_unstable_export(art, spec.motor, file="x/controller.json")
    assert str(info.value).startswith("x/controller.json: axes.d.law: expected a law whose "
                                      "sampled loop (ZOH plant, computation delay) is stable")
