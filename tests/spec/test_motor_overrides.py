"""``Motor.with_overrides``: the one parameter type makes the simulator's
true plants and robustness sets (toolbox/ARCHITECTURE.md "Parameters and models")."""

import dataclasses

import pytest

from toolbox.errors import SpecError
from toolbox.spec import MOTOR_PARAMETER_KEYS, Motor

NOMINAL = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4, J=1.11e-3,
                friction=1.4e-3, convention="power", rated_current=10.0, catalog="x")


def test_values_then_scale_and_nothing_else_changes():
    """Values replace, then scales multiply (exact float arithmetic: one
    product, compared with ==); every other field, including the dq
    convention, is kept; the nominal motor is untouched."""
    m = NOMINAL.with_overrides({"R": 1.0, "Ld": 2e-3}, {"Ld": 1.5, "J": 2.0})
    assert isinstance(m, Motor)
    assert (m.R, m.Ld, m.J) == (1.0, 2e-3 * 1.5, 1.11e-3 * 2.0)
    assert (m.Lq, m.flux, m.pole_pairs, m.friction) == (2.8e-3, 0.12, 4, 1.4e-3)
    assert (m.convention, m.torque_factor, m.rated_current, m.catalog) == \
        ("power", 1.0, 10.0, "x")
    assert NOMINAL.R == 0.6 and NOMINAL.Ld == 1.4e-3


def test_no_overrides_is_the_same_motor():
    assert NOMINAL.with_overrides() == NOMINAL
    assert NOMINAL.with_overrides({}, {}) == NOMINAL


def test_keys_are_the_physical_parameters():
    physical = {f.name for f in dataclasses.fields(Motor)} - {
        "convention", "rated_current", "max_current", "rated_speed", "catalog",
        "magnetics"}  # a saturated motor's magnetic model, not an overridable number
    assert set(MOTOR_PARAMETER_KEYS) == physical


@pytest.mark.parametrize("table,arg", [("values", ({"Rs": 1.0}, None)),
                                       ("scale", (None, {"convention": 2.0}))])
def test_unknown_parameter_is_a_located_spec_error(table, arg):
    with pytest.raises(SpecError, match=rf"plant_{table}\.") as info:
        NOMINAL.with_overrides(*arg)
    assert "R, Ld, Lq, flux, pole_pairs, J, friction" in str(info.value)
