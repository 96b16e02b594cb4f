"""Scenario validation: bad tables raise SpecError with the exact message and
the key path of the offending entry."""

import math

import pytest

from toolbox.errors import SpecError
from toolbox.spec import Scenario

CASES = [
    ({"kind": "current_step", "duraton": 1},
     'scenario[2].duraton: expected a known scenario key, got "duraton" '
     '(did you mean "duration"?)'),
    ({"duration": -1},
     "scenario[2].duration: expected a number > 0 (s), got -1"),
    ({"kind": "speedstep"},
     "scenario[2].kind: expected one of current_step, constant_acceleration, "
     "unloaded_start, load_step, speed_step, sinusoidal_torque, got \"speedstep\" "
     '(did you mean "speed_step"?)'),
    ({"plant_step": 1e-3},
     "scenario[2].plant_step: expected a number <= the sample time (0.0001 s), got "
     "0.001 (the plant is integrated at least once per period)"),
    ({"iq_ref": math.nan},
     "scenario[2].iq_ref: expected a finite number, got nan"),
    ({"plant_scale": {"Lx": 2}},
     'scenario[2].plant_scale.Lx: expected a plant parameter (R, Ld, Lq, flux, '
     'pole_pairs, J, friction), got "Lx"'),
    ({"plant_values": {"R": -0.5}},
     "scenario[2].plant_values.R: expected a finite number > 0, got -0.5"),
    ({"inverter": "svn"},
     'scenario[2].inverter: expected one of average, svm, fcs_mpc, got "svn" '
     '(did you mean "svm"?)'),
    ({"step_time": 3, "duration": 1},
     "scenario[2].step_time: expected a number >= 0 and < duration (1 s), got 3"),
    ({"iq_ref": "10"},
     'scenario[2].iq_ref: expected a number, got "10"'),
    ({"kind": "current_step", "acceleration": 100.0},
     'scenario[2].acceleration: expected no acceleration unless kind = '
     '"constant_acceleration", got 100.0 (the speed follows the mechanics for this kind)'),
]


@pytest.mark.parametrize("table, message", CASES)
def test_bad_scenario_messages(table, message):
    with pytest.raises(SpecError) as info:
        Scenario.from_dict(table, key="scenario[2]", sample_time=1e-4)
    assert str(info.value) == message
    assert info.value.key == message.split(":")[0]


def test_good_scenario_roundtrip_and_frozen():
    sc = Scenario.from_dict({"kind": "constant_acceleration", "duration": 0.04,
                             "iq_ref": 10, "acceleration": 5000,
                             "plant_scale": {"Ld": 0.5}}, sample_time=1e-4)
    assert sc.acceleration == 5000 and sc.plant_scale["Ld"] == 0.5
    with pytest.raises(Exception):
        sc.duration = 1.0
    with pytest.raises(TypeError):
        sc.plant_scale["Ld"] = 2.0
    hash(sc)


def test_scenario_pickles_copies_and_serialises():
    """Scenarios travel to worker processes and into verify.json."""
    import copy
    import dataclasses
    import json
    import pickle
    sc = Scenario(kind="current_step", plant_scale={"Ld": 0.5}, plant_values={"R": 0.7})
    assert pickle.loads(pickle.dumps(sc)) == sc
    assert copy.deepcopy(sc) == sc
    d = json.loads(json.dumps(dataclasses.asdict(sc)))
    assert Scenario.from_dict(d) == sc


def test_default_plant_step_follows_a_fast_sample_time():
    """A drive sampled faster than 1 us does not fail on the default plant step
    (a key the user never wrote); an explicit one above the period still does."""
    sc = Scenario.from_dict({"kind": "current_step", "iq_ref": 1.0, "duration": 1e-3},
                            key="scenario[0]", sample_time=5e-7)
    assert sc.plant_step == 5e-7
    sc = Scenario.from_dict({"kind": "current_step", "iq_ref": 1.0, "duration": 1e-3},
                            key="scenario[0]", sample_time=1e-4)
    assert sc.plant_step == 1e-6
    with pytest.raises(SpecError, match=r"scenario\[0\]\.plant_step"):
        Scenario.from_dict({"kind": "current_step", "plant_step": 1e-6, "duration": 1e-3},
                           key="scenario[0]", sample_time=5e-7)
