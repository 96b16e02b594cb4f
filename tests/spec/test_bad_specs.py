"""Bad spec files get one exact, located message each (toolbox/ARCHITECTURE.md "Reliability rules").

The messages are part of the user interface: a change here is a change users
see, so the full text is pinned.
"""

import difflib
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

from toolbox.errors import SpecError
from toolbox.spec._fields import did_you_mean
from toolbox.spec import load_spec

BAD = Path(__file__).parent / "bad"

CASES = [
    ("code_injection.toml",
     'motor.R: expected a number > 0 (ohm), got "__import__(\'os\').system(\'echo pwned\')"'),
    ("delay_negative.toml",
     'drive.delay_samples: expected an integer >= 0, got -1'),
    ("ilq_sigma_below_bound.toml",
     'controller.ilq.sigma: expected sigma_d > the optimality bound of Takami eq (3), 2(a - s*) = 1142.86 1/s, got 100.0 (raise sigma, or set allow_non_optimal = true)'),
    ("inf_J.toml",
     'motor.J: expected a number > 0 (kg m^2), got inf'),
    ("motor_missing.toml",
     'motor: expected a [motor] table (missing)'),
    ("motor_typo.toml",
     'motor.Lqq: expected a known key of [motor] (did you mean "Lq"?)'),
    ("nan_flux.toml",
     'motor.flux: expected a number >= 0 (Wb), got nan'),
    ("negative_R.toml",
     'motor.R: expected a number > 0 (ohm), got -0.6'),
    ("other_method_table.toml",
     'controller.pi: expected a known key of [controller] (allowed keys: hinf, method)'),
    ("pi_negative_bandwidth.toml",
     'controller.pi.bandwidth: expected a number > 0 (rad/s), got -1000'),
    ("pole_pairs_float.toml",
     'motor.pole_pairs: expected an integer >= 1, got 4.5'),
    ("sample_time_zero.toml",
     'drive.sample_time: expected a number > 0 (s), got 0'),
    ("sample_vs_switching.toml",
     'drive.sample_time: expected a whole number of half PWM periods (1/(2 switching_frequency) = 0.000166667 s), got 0.0001 (sample once or twice per carrier period: sample_time = 0.000166667 s (sample_frequency = 6000 Hz))'),
    ("scenario_fcs_on_pi.toml",
     'scenario[0].inverter: expected "average" or "svm", got "fcs_mpc" (predictive switching needs controller.method = "fcs_mpc")'),
    ("scenario_negative_duration.toml",
     'scenario[0].duration: expected a number > 0 (s), got -0.01'),
    ("scenario_step_too_large.toml",
     'scenario[0].plant_step: expected a number <= the sample time (0.0001 s), got 0.001 (the plant is integrated at least once per period)'),
    ("scenario_unknown_kind.toml",
     'scenario[0].kind: expected one of current_step, constant_acceleration, unloaded_start, load_step, speed_step, sinusoidal_torque, got "current_stepp" (did you mean "current_step"?)'),
    ("string_number.toml",
     'motor.R: expected a number > 0 (ohm), got "0.6"'),
    ("tc_unstable_pole.toml",
     'controller.tc.poles: expected stable poles (negative real part, rad/s), got 800.0 (a pole at 800+0j makes the current loop unstable)'),
    ("toml_syntax.toml",
     'expected valid TOML, got "Expected \']\' at the end of a table declaration (at line 1, column 7)"'),
    ("unknown_catalog.toml",
     'motor.catalog: expected one of "azaiz2007", "cormerais2002", "lepioufle1992", "takami2004", got "azaiz2008" (did you mean "azaiz2007"?)'),
    ("unknown_method.toml",
     'controller.method: expected one of "pi", "ip", "pi_lag", "tc", "tci", "ilq", "lq", "hinf", "fcs_mpc", "robust_pi", "tune", "cv", got "hinfinity" (did you mean "hinf"?)'),
    ("unknown_top.toml",
     'titel: expected a known top-level key (did you mean "title"?)'),
    ("zero_L.toml",
     'motor.Ld: expected a number > 0 (H), got 0.0'),
]


@pytest.mark.parametrize("name, message", CASES, ids=[c[0] for c in CASES])
def test_bad_spec_message(name, message):
    path = BAD / name
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert str(info.value) == f"{path}: {message}"
    assert info.value.file == str(path)


def test_every_bad_file_has_a_case():
    assert sorted(p.name for p in BAD.glob("*.toml")) == sorted(c[0] for c in CASES)


def test_missing_file_is_a_spec_error(tmp_path):
    with pytest.raises(SpecError, match="expected a readable spec file"):
        load_spec(tmp_path / "nope.toml")


def test_values_are_never_evaluated(tmp_path, capsys):
    """A string that is Python code stays a string and is refused as a number."""
    with pytest.raises(SpecError):
        load_spec(BAD / "code_injection.toml")
    assert "pwned" not in capsys.readouterr().out


@settings(max_examples=100, deadline=None, derandomize=True)
@given(word=st.text("abcdeh_", max_size=40),
       choices=st.lists(st.text("abcdeh_", min_size=1, max_size=12), min_size=1, max_size=5))
def test_did_you_mean_is_difflibs_suggestion(word, choices):
    """The did-you-mean of every message is difflib's (cutoff 0.6) exactly:
    the length bound that spares difflib a long word never drops a match
    (words up to 40 characters against choices up to 12, so past the 7/3 bound)."""
    close = difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    assert did_you_mean(word, choices) == (f'did you mean "{close[0]}"?' if close else None)


def test_did_you_mean_of_a_huge_value_is_none():
    assert did_you_mean("current_step" * 50_000, ["current_step"]) is None
    assert did_you_mean("current_stepp", ["current_step"]) == 'did you mean "current_step"?'
