"""The fuzzing list of bad inputs through the CLI: every case a clear exit 2
(toolbox/ARCHITECTURE.md "Reliability rules", "Errors and exit codes").

Audit of each fuzzed bad input against tests/hostile and tests/export (each
case traced to the CLI test that asserts it):

==============================  =============================================
case                            CLI test asserting exit 2 and the message
==============================  =============================================
flux = 0, R = 1e300,            test_spec_bounds.test_cli_design_exits_2_fast...
Ld = 1e-300, max_speed = 1e300
plant_step 1e-11                test_spec_bounds.test_cli_design_exits_2_fast...
gamma / backoff = 1e300,        test_method_bounds.test_cli_exit_2
symmetric optimum a = 1e300,
makeweight order 1e6
fcs_mpc gains.alpha missing     test_artifact_tamper.test_cli_on_tampered_controller...
analysis.json requirements      test_artifact_tamper.test_cli_report_on_tampered...
export -o under a file, /proc   test_outputs.test_export_under_a_regular_file, ..._into_proc
FIFO                            test_files.test_fifo_is_refused_without_blocking
deep controller.json (JSON)     test_files.test_deep_json_controller_is_an_artifact_error
vdc = 1e39                      tests/export/test_export_faults.test_vdc_1e39_through_the_cli
10,000 scenarios of 60 s        here (only spec_from_dict was tested)
5,000-coefficient weight        here (only spec_from_dict was tested)
sample_time 1e-7 with traces    here (only spec_from_dict was tested)
100,000-deep nested TOML        here (the CLI test checked the words; file + line)
cct check /dev/zero             here (the CLI test checked the exit code only)
margins tampered (AttributeError)  here (only ControllerArtifact.from_json)
deep nesting inside             here (only ControllerArtifact.from_json)
controller.json data
==============================  =============================================

Each test pins exit code 2, ``cct: error:``, the file and the key path in the
message, no traceback, and that nothing was written.
"""

from __future__ import annotations

import json

import pytest

from toolbox.pipeline import design_spec

from hostile_helpers import run_cli, spec_dict

STEP = {"kind": "current_step", "duration": 0.02}
W1 = {"num": [0.66225, 117.4499], "den": [1.0, 0.0117]}  # paper 003 eq (44)

SPEC_CASES = [
    ("10000_scenarios_of_60s", dict(scenario=[{**STEP, "duration": 60.0}] * 10_000),
     'scenario: expected at most 1000 [[scenario]] tables, got "10000 tables"'),
    ("weight_5000_coefficients",
     dict(controller={"method": "hinf", "hinf": {"weights": {
         "d": {"w1": W1}, "q": {"w1": {"num": [1.0] * 5000, "den": [1.0, 1.0]}}}}}),
     'controller.hinf.weights.q.w1.num: expected a list of at most 21 numbers, '
     'got "5000 numbers"'),
    ("sample_time_1e-7_with_traces",
     dict(drive={"sample_time": 1e-7}, motor={"R": 0.6},
          scenario=[{**STEP, "duration": 2.0, "plant_step": 1e-7, "keep_traces": True}]),
     "scenario: expected at most 2e+06 kept trace rows over all scenarios"),
]


@pytest.mark.parametrize("name, sections, message", SPEC_CASES,
                         ids=[c[0] for c in SPEC_CASES])
def test_cct_design_exit_2_names_the_key(write_spec, tmp_path, name, sections, message):
    path = write_spec(spec_dict(**sections))
    out = tmp_path / "out"
    res = run_cli("design", path, "--out", out)
    assert res.exit_code == 2, res.output
    assert f"cct: error: {path}: {message}" in res.output
    assert "Traceback" not in res.output
    assert not out.exists()


def test_100000_deep_toml_names_file_and_line(tmp_path):
    """tomllib recursed once per level (RecursionError); the linear pre-scan
    refuses the text before parsing, naming the file and the line (a key path
    would need the parse that is refused)."""
    path = tmp_path / "deep.toml"
    path.write_text("x = " + "[" * 100_000 + "]" * 100_000 + "\n")
    out = tmp_path / "out"
    res = run_cli("design", path, "--out", out)
    assert res.exit_code == 2, res.output
    assert (f'cct: error: {path}: expected nesting at most 32 levels deep, got "deeper '
            f'nesting at line 1"') in res.output
    assert "RecursionError" not in res.output and "Traceback" not in res.output
    assert not out.exists()


def test_cct_check_dev_zero_names_the_file():
    """/dev/zero was read to the end of memory (MemoryError)."""
    res = run_cli("check", "/dev/zero")
    assert res.exit_code == 2, res.output
    assert 'cct: error: /dev/zero: expected a regular spec file, got "a device"' in res.output


@pytest.fixture(scope="module")
def pi_json() -> str:
    return design_spec(spec_dict()).dumps()


ARTIFACT_CASES = [
    # margins holding a number: AttributeError in the CLI summary
    ("margins_number", lambda d: d.__setitem__("margins", {"d": 5}),
     "margins.d: expected an object (MARGINS), got 5"),
    # deeper than the recursion limit inside the data: RecursionError
    # (written as text: json.dumps itself recurses per level). The linear
    # pre-scan refuses the text before parsing it, so it locates the nesting by
    # line, not by key path: naming the key would mean parsing what is refused
    ("deep_provenance", lambda d: d["provenance"].__setitem__("x", DEEP_MARK),
     'expected nesting at most 32 levels deep, got "deeper nesting at line 1"'),
]
DEEP_MARK = "__deep__"
DEEP = 10_000


def _dumps(data: dict) -> str:
    deep = '{"x": ' * DEEP + "{}" + "}" * DEEP
    return json.dumps(data).replace(json.dumps(DEEP_MARK), deep)


@pytest.mark.parametrize("command", ["verify", "report", "export"])
@pytest.mark.parametrize("name, tamper, message", ARTIFACT_CASES,
                         ids=[c[0] for c in ARTIFACT_CASES])
def test_tampered_controller_json_exit_2_names_the_key(tmp_path, pi_json, command, name,
                                                       tamper, message):
    data = json.loads(pi_json)
    tamper(data)
    path = tmp_path / "controller.json"
    path.write_text(_dumps(data))
    res = run_cli(command, tmp_path)
    assert res.exit_code == 2, res.output
    assert f"cct: error: {path}: {message}" in res.output
    assert "Traceback" not in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["controller.json"]
