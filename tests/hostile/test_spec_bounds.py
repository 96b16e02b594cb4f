"""Implausible numbers are refused with the key and the plausible range.

Each case once reached the numerics: flux = 0 divided by zero in the
analysis, R = 1e300 / Ld = 1e-300 / max_speed = 1e300 broke the eigenvalue
solvers (LinAlgError), plant_step = 1e-11 and 10,000 scenarios of 60 s ran
for days, sample_time = 1e-7 with traces ran out of memory. The full message
is pinned: it is what the user reads.
"""

from __future__ import annotations

import pytest

from toolbox.errors import SpecError
from toolbox.spec import SpecErrors, load_spec, spec_from_dict
from toolbox.spec._bounds import MAX_PLANT_STEPS, MAX_SCENARIOS, MAX_TRACE_ROWS

from hostile_helpers import run_cli, spec_dict

STEP = {"kind": "current_step", "duration": 0.02}

CASES = [
    ("flux_zero", dict(motor={"flux": 0.0}),
     "motor.flux: expected a plausible PM flux linkage between 1e-06 and 100 Wb, got 0.0"),
    ("R_huge", dict(motor={"R": 1e300}),
     "motor.R: expected a plausible stator resistance between 1e-06 and 10000 ohm, "
     "got 1e+300"),
    ("Ld_tiny", dict(motor={"Ld": 1e-300}),
     "motor.Ld: expected a plausible d-axis inductance between 1e-09 and 10 H, got 1e-300"),
    ("Lq_huge", dict(motor={"Lq": 11.0}),
     "motor.Lq: expected a plausible q-axis inductance between 1e-09 and 10 H, got 11.0"),
    ("flux_huge", dict(motor={"flux": 1e3}),
     "motor.flux: expected a plausible PM flux linkage between 1e-06 and 100 Wb, got 1000.0"),
    ("max_speed_huge", dict(drive={"max_speed": 1e300}),
     "drive.max_speed: expected a mechanical speed below the Nyquist electrical speed "
     "pi / (pole_pairs sample_time) = 7854 rad/s, got 1e+300"),
    # just above Nyquist: 4 pole pairs x 8000 rad/s x 1e-4 s = 3.2 rad per period > pi
    ("max_speed_above_nyquist", dict(drive={"max_speed": 8000.0}),
     "drive.max_speed: expected a mechanical speed below the Nyquist electrical speed "
     "pi / (pole_pairs sample_time) = 7854 rad/s, got 8000.0"),
    ("vdc_huge", dict(drive={"vdc": 1e39}),
     "drive.vdc: expected a plausible DC-link voltage of at most 100000 V, got 1e+39"),
    ("sample_time_tiny", dict(drive={"sample_time": 1e-8}),
     "drive.sample_time: expected a plausible controller sample time between 1e-07 and "
     "1 s, got 1e-08"),
    ("sample_time_huge", dict(drive={"sample_time": 2.0}),
     "drive.sample_time: expected a plausible controller sample time between 1e-07 and "
     "1 s, got 2.0"),
    # L/R = 0.0028 / 1e-6 = 2800 s = 2.8e7 sample times is allowed; 1e-9 H / 1 ohm
    # is 1e-9 s = 1e-5 sample times, below 1e-3
    ("tau_below_a_sample", dict(motor={"R": 1.0, "Ld": 1e-9}),
     'motor.Ld: expected an electrical time constant Ld/R between 0.001 and 1e+09 sample '
     'times (1e-07 .. 1e+05 s), got "Ld/R = 1e-09 s" (check the units of R, L and '
     'drive.sample_time)'),
    # Lq/R = 10 / 1e-6 = 1e7 s = 1e11 sample times (Ld/R = 1.4e7 sample times is fine)
    # (J = 1e-5 kg m^2: plausible for the 10 H motor, toolbox/spec/_bounds.py
    # check_inertia)
    ("tau_above_1e9_samples", dict(motor={"R": 1e-6, "Lq": 10.0, "J": 1e-5}),
     'motor.Lq: expected an electrical time constant Lq/R between 0.001 and 1e+09 sample '
     'times (1e-07 .. 1e+05 s), got "Lq/R = 1e+07 s" (check the units of R, L and '
     'drive.sample_time)'),
    ("plant_step_1e-11", dict(scenario=[{**STEP, "plant_step": 1e-11}]),
     "scenario[0].plant_step: expected a plant integration step >= 1e-09 s, got 1e-11"),
    ("too_many_scenarios", dict(scenario=[{**STEP, "duration": 60.0}] * 10_000),
     'scenario: expected at most 1000 [[scenario]] tables, got "10000 tables"'),
    # 100 x 60 s at the default 1 us plant step = 6e9 RK4 steps > 2e9
    ("plant_steps_total", dict(scenario=[{**STEP, "duration": 60.0}] * 100),
     'scenario: expected at most 2e+09 plant integration steps over all scenarios '
     '(duration / plant_step, summed), got "6e+09 steps" (shorten the scenarios or raise '
     'plant_step)'),
    # 2 s of traces at 1e-7 s = 2e7 rows (about 7.5 GB at peak) > the 2e6-row bound
    ("traces_at_1e-7", dict(drive={"sample_time": 1e-7}, motor={"R": 0.6},
                            scenario=[{**STEP, "duration": 2.0, "plant_step": 1e-7,
                                       "keep_traces": True}]),
     'scenario: expected at most 2e+06 kept trace rows over all scenarios (duration / '
     '(sample_time x decimation), about 0.75 GB of memory), got "2e+07 rows" (set '
     'keep_traces = false or a coarser trace_step)'),
]


@pytest.mark.parametrize("name, sections, message", CASES, ids=[c[0] for c in CASES])
def test_implausible_value_is_refused_by_name(name, sections, message):
    with pytest.raises(SpecError) as info:
        spec_from_dict(spec_dict(**sections), file="s.toml")
    assert str(info.value) == f"s.toml: {message}"
    assert not isinstance(info.value, SpecErrors)  # one error, one line


@pytest.mark.parametrize("sections", [
    # the bounds themselves are allowed (with an inertia plausible for the
    # motor's torque, toolbox/spec/_bounds.py check_inertia)
    dict(motor={"flux": 1e-6, "R": 1e-6, "Ld": 1e-9, "Lq": 1e-9, "J": 1e-9}),
    dict(motor={"R": 1e4, "Ld": 10.0, "Lq": 10.0, "J": 1e-5}),
    dict(drive={"vdc": 1e5}),
    dict(drive={"max_speed": 7800.0}),                # just below Nyquist (7854 rad/s)
    dict(scenario=[{**STEP, "duration": 0.5, "plant_step": 1e-9}]),  # 5e8 steps
    dict(scenario=[{**STEP, "duration": 60.0}] * 33),  # 1.98e9 steps, just under 2e9
], ids=["flux_min", "R_L_max", "vdc_max", "below_nyquist", "plant_step_min",
        "steps_just_under"])
def test_values_at_the_bounds_are_accepted(sections):
    """The bounds refuse only what is outside them (so the tests above can fail)."""
    spec = spec_from_dict(spec_dict(**sections))
    assert spec.motor.R > 0


def test_work_bounds_are_consistent_with_the_module_constants():
    assert (MAX_SCENARIOS, MAX_PLANT_STEPS, MAX_TRACE_ROWS) == (1000, 2e9, 2e6)


def test_all_errors_are_reported_at_once():
    data = spec_dict(motor={"R": -1.0, "Lq": "2.8e-3"}, drive={"vdc": 0.0},
                     requirements={"min_phase_margin_deg": "forty"})
    with pytest.raises(SpecErrors) as info:
        spec_from_dict(data, file="s.toml")
    assert str(info.value) == (
        "s.toml: 4 errors:\n"
        "  motor.R: expected a number > 0 (ohm), got -1.0\n"
        '  motor.Lq: expected a number > 0 (H), got "2.8e-3"\n'
        "  drive.vdc: expected a number > 0 (V), got 0.0\n"
        '  requirements.min_phase_margin_deg: expected a number >= 0 (deg), got "forty"')
    assert [e.key for e in info.value.errors] == [
        "motor.R", "motor.Lq", "drive.vdc", "requirements.min_phase_margin_deg"]
    assert info.value.key == "motor.R"  # the first error, for code that reads one


def test_plausibility_errors_of_both_sections_are_reported_together():
    with pytest.raises(SpecErrors) as info:
        spec_from_dict(spec_dict(motor={"flux": 0.0}, drive={"vdc": 1e39}))
    assert [e.key for e in info.value.errors] == ["motor.flux", "drive.vdc"]


def test_motor_only_file_names_every_missing_section(write_spec):
    path = write_spec('[motor]\ncatalog = "azaiz2007"\nR = -0.6\n')
    with pytest.raises(SpecErrors) as info:
        load_spec(path)
    # [controller] is read only against a valid motor and drive (method
    # parameters are checked against the motor), so it is reported next time
    assert str(info.value) == (
        f"{path}: 2 errors:\n"
        "  motor.R: expected a number > 0 (ohm), got -0.6\n"
        "  drive: expected a [drive] table (missing)")


@pytest.mark.parametrize("sections, key", [
    (dict(motor={"flux": 0.0}), "motor.flux"),
    (dict(motor={"R": 1e300}), "motor.R"),
    (dict(motor={"Ld": 1e-300}), "motor.Ld"),
    (dict(drive={"max_speed": 1e300}), "drive.max_speed"),
    (dict(scenario=[{**STEP, "plant_step": 1e-11}]), "scenario[0].plant_step"),
], ids=["flux0", "R1e300", "Ld1e-300", "max_speed1e300", "plant_step1e-11"])
def test_cli_design_exits_2_fast_and_writes_nothing(write_spec, tmp_path, sections, key,
                                                    monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("the spec reached the design stage")

    # refused while reading: no design, analysis or simulation ever starts
    monkeypatch.setattr("toolbox.pipeline.build_outputs", never)
    out = tmp_path / "out"
    res = run_cli("design", write_spec(spec_dict(**sections)), "--out", out)
    assert res.exit_code == 2, res.output
    assert f"spec.toml: {key}: expected" in res.output
    assert "Traceback" not in res.output
    assert not out.exists()
