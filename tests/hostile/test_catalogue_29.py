"""The hostile catalogue of "every failure is a clear message".

Each value below once ended in a traceback (``OverflowError``,
``ZeroDivisionError``, ``LinAlgError``, ``ValueError`` from deep inside the
design, analysis or report) or was silently accepted. Now each is refused at
``cct check`` time (exit 2, the file and the key named, what was expected and
what was found; nothing written by ``cct design``), or gives a clean verdict.
The bounds are derived once (toolbox/spec/_bounds.py: ``MOTOR_RANGES``,
``RATE_TS``, ``SCALE_RANGE``, the Nyquist speed) and read by check and design
alike (toolbox/ARCHITECTURE.md "Reliability rules").
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from hostile_helpers import run_cli, spec_dict, to_toml

BIG = 10 ** 400  # TOML and JSON parse it as a Python int: float(BIG) overflows
STEP = {"kind": "current_step", "duration": 0.02}


def _pi(**params) -> dict:
    return {"method": "pi", "pi": params}


def _scenario(**keys) -> list:
    return [{**STEP, **keys}]


#: (id, spec sections, key path named, words of the expectation)
SPEC_CASES = [
    # a 400-digit integer in any numeric key
    ("R_400_digits", dict(motor={"R": BIG}), "motor.R", "expected a number > 0 (ohm)"),
    ("J_400_digits", dict(motor={"J": BIG}), "motor.J", "expected a number > 0"),
    ("pole_pairs_400_digits", dict(motor={"pole_pairs": BIG}), "motor.pole_pairs",
     "expected an integer >= 1 of magnitude at most 2**53"),
    ("pole_pairs_5000", dict(motor={"pole_pairs": 5000}), "motor.pole_pairs",
     "expected an integer from 1 to 1000"),
    ("vdc_400_digits", dict(drive={"vdc": BIG}), "drive.vdc", "expected a number > 0 (V)"),
    ("delay_400_digits", dict(drive={"delay_samples": BIG}), "drive.delay_samples",
     "expected an integer >= 0"),
    ("R_ll_400_digits", dict(motor={"R_ll": BIG}), "motor.R_ll",
     "expected a number > 0 (ohm) or a string with a unit"),
    ("requirement_400_digits", dict(requirements={"min_phase_margin_deg": BIG}),
     "requirements.min_phase_margin_deg", "expected a number >= 0 (deg)"),
    ("speed_loop_400_digits", dict(scenario=[{"kind": "speed_step", "duration": 0.02,
                                               "speed_loop": {"kp": BIG}}]),
     "scenario[0].speed_loop.kp", "expected a finite number >= 0"),
    ("bandwidth_400_digits", dict(controller=_pi(bandwidth=BIG)), "controller.pi.bandwidth",
     "expected a number > 0 (rad/s)"),
    ("duration_400_digits", dict(scenario=_scenario(duration=BIG)), "scenario[0].duration",
     "expected a finite number"),
    ("seed_400_digits", dict(scenario=_scenario(seed=BIG)), "scenario[0].seed",
     "expected an integer >= 0 of magnitude at most 2**53"),
    ("plant_values_400_digits", dict(scenario=_scenario(plant_values={"R": BIG})),
     "scenario[0].plant_values.R", "expected a finite number > 0"),
    # PI
    ("pi_bandwidth_1e300", dict(controller=_pi(bandwidth=1e300)), "controller.pi.bandwidth",
     "expected a number between 0.001 and 1e+07 rad/s"),
    ("pi_bandwidth_1e-300", dict(controller=_pi(bandwidth=1e-300)),
     "controller.pi.bandwidth", "expected a number between 0.001 and 1e+07 rad/s"),
    ("pi_response_time_1e300", dict(controller=_pi(response_time=1e300)),
     "controller.pi.response_time", "expected a time between"),
    ("pi_response_time_1e-300", dict(controller=_pi(response_time=1e-300)),
     "controller.pi.response_time", "expected a time between"),
    ("pi_explicit_1e9", dict(controller=_pi(Kp=1e9, Ki=1e9)), "controller.pi.Kp",
     "a number between 1.4e-06 and 1.4e+04 V/A (the rate K / L between 1e-07 and 1000 / "
     "drive.sample_time), got 1000000000.0"),
    ("pi_explicit_Ki_1e20", dict(controller=_pi(Kp=1.0, Ki=1e20)), "controller.pi.Ki",
     "V/(A s) (the rate sqrt(K / L) between"),
    ("complex_vector_integral_bandwidth_1e300",
     dict(controller=_pi(rule="complex_vector", bandwidth=1000.0, integral_bandwidth=1e300)),
     "controller.pi.integral_bandwidth", "expected a number between"),
    ("pi_lag_time_constant_1e300",
     dict(controller={"method": "pi_lag", "pi_lag": {"lag_time_constant": 1e300}}),
     "controller.pi_lag.lag_time_constant", "expected a time between"),
    ("symmetric_optimum_small_time_constant_1e300",
     dict(controller=_pi(rule="symmetric_optimum", small_time_constant=1e300)),
     "controller.pi.small_time_constant", "expected a time between"),
    # total compensation
    ("tc_K_1e300", dict(controller={"method": "tc", "tc": {"K1": 1e300, "K2": 1e300}}),
     "controller.tc.K1", "expected a number between 0.001 and 1e+07 1/s"),
    ("tc_poles_1e300", dict(controller={"method": "tc", "tc": {"poles": [-1e300]}}),
     "controller.tc.poles", "expected a number between"),
    ("tci_natural_frequency_1e300",
     dict(controller={"method": "tci", "tci": {"natural_frequency": 1e300, "damping": 1.0}}),
     "controller.tci.natural_frequency", "expected a number between 0.001 and 1e+07 rad/s"),
    ("tci_K22_1e300", dict(controller={"method": "tci", "tci": {
        "K11": 800.0, "K12": 1e5, "K21": 800.0, "K22": 1e300}}),
     "controller.tci.K22", "1/s^2 (the rate sqrt(K) between"),
    # LQ (cct check itself crashed in Bryson's weights)
    ("lq_bandwidth_1e300", dict(controller={"method": "lq", "lq": {"bandwidth": 1e300}}),
     "controller.lq.bandwidth", "expected a number between"),
    ("lq_current_limit_1e-300",
     dict(controller={"method": "lq", "lq": {"current_limit": 1e-300}}),
     "controller.lq.current_limit", "expected a current limit between"),
    ("lq_voltage_limit_1e300",
     dict(controller={"method": "lq", "lq": {"voltage_limit": 1e300}}),
     "controller.lq.voltage_limit", "expected a voltage limit between"),
    # scenarios
    ("initial_speed_1e300", dict(scenario=_scenario(initial_speed=1e300)),
     "scenario[0].initial_speed", "expected a mechanical speed below the Nyquist"),
    ("acceleration_1e300", dict(scenario=[{"kind": "constant_acceleration",
                                           "duration": 0.02, "acceleration": 1e300}]),
     "scenario[0].acceleration", "expected an acceleration whose final speed"),
    ("duration_1e-300", dict(scenario=_scenario(duration=1e-300)), "scenario[0].duration",
     "expected at least one controller period"),
    # a scenario's true plant by the rules of [motor]
    ("plant_values_R_1e-300", dict(scenario=_scenario(plant_values={"R": 1e-300})),
     "scenario[0].plant_values.R", "expected a plausible stator resistance"),
    ("plant_values_Ld_1e300", dict(scenario=_scenario(plant_values={"Ld": 1e300})),
     "scenario[0].plant_values.Ld", "expected a plausible d-axis inductance"),
    ("plant_values_pole_pairs_4.5", dict(scenario=_scenario(plant_values={"pole_pairs": 4.5})),
     "scenario[0].plant_values.pole_pairs", "expected an integer from 1 to 1000"),
    ("plant_scale_Lq_1e-12", dict(scenario=_scenario(plant_scale={"Lq": 1e-12})),
     "scenario[0].plant_scale.Lq", "expected a plausible q-axis inductance"),
    # C prefix: re.match's $ accepted a trailing newline
    ("prefix_newline", dict(export={"prefix": "m\n"}), "export.prefix",
     "expected a C identifier prefix"),
]


def _toml(sections: dict) -> str:
    """The spec as TOML text; strings with control characters escaped (the
    helpers' writer keeps them raw, which TOML refuses before our check)."""
    export = sections.get("export")
    text = to_toml(spec_dict(**{k: v for k, v in sections.items() if k != "export"}))
    if export:
        text += "[export]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in export.items())
    return text


@pytest.mark.parametrize("name, sections, key, words", SPEC_CASES,
                         ids=[c[0] for c in SPEC_CASES])
def test_cct_check_refuses_by_key(write_spec, name, sections, key, words):
    path = write_spec(_toml(sections))
    res = run_cli("check", path)
    assert res.exit_code == 2, res.output
    assert res.output.startswith(f"cct: error: {path}: {key}: expected "), res.output
    assert words in res.output, res.output
    assert "Traceback" not in res.output and "internal error" not in res.output
    assert len(res.output) < 1000, res.output  # echoed values are cut


@pytest.mark.parametrize("name", ["R_400_digits", "pi_explicit_1e9", "lq_current_limit_1e-300",
                                  "tci_natural_frequency_1e300", "plant_values_pole_pairs_4.5",
                                  "duration_1e-300"])
def test_cct_design_refuses_and_writes_nothing(write_spec, tmp_path, name):
    sections, key = next((c[1], c[2]) for c in SPEC_CASES if c[0] == name)
    path = write_spec(_toml(sections))
    out = tmp_path / "out"
    res = run_cli("design", path, "--out", out)
    assert res.exit_code == 2, res.output
    assert f"{key}: expected" in res.output and "Traceback" not in res.output
    assert not out.exists()


@pytest.mark.parametrize("sections", [
    # L/R = 1.4e-3 sample times: in range; slow: its plant step is tiny (about 4 CPU-s)
    pytest.param(dict(motor={"R": 1e4}), id="R_1e4", marks=pytest.mark.slow),
    # slow, but a drive; its full cct design (the scenarios' verification and
    # the report over a 1 s sample time) costs ~10 CPU-s: marked slow
    pytest.param(dict(drive={"sample_time": 1.0}), id="sample_time_1", marks=pytest.mark.slow),
])
def test_plausible_extremes_give_a_verdict_not_a_crash(write_spec, tmp_path, sections):
    """The exact ZOH of the coupled loop overflowed (0 x inf) at the box corners of
    the MIMO analysis and eigvals raised LinAlgError; now the design is made and
    judged (these loops fail their checks: exit 1)."""
    path = write_spec(spec_dict(**sections))
    res = run_cli("check", path)
    assert res.exit_code == 0, res.output
    res = run_cli("design", path, "--out", tmp_path / "out", "-q")
    assert res.exit_code in (0, 1), res.output
    assert "Traceback" not in res.output and "internal error" not in res.output
    assert "RuntimeWarning" not in res.output
    assert (tmp_path / "out" / "controller.json").exists()


def test_sample_frequency_400_digits(write_spec):
    data = spec_dict()
    del data["drive"]["sample_time"]
    data["drive"]["sample_frequency"] = BIG
    path = write_spec(data)
    res = run_cli("check", path)
    assert res.exit_code == 2, res.output
    assert res.output.startswith(f"cct: error: {path}: drive.sample_frequency: expected a "
                                 "number > 0 (Hz), got 1000")


def test_500k_character_key_gives_a_short_message(write_spec):
    path = write_spec(spec_dict(motor={"x" * 500_000: 1.0}))
    res = run_cli("check", path)
    assert res.exit_code == 2
    assert f"cct: error: {path}: motor.xxxx" in res.output
    assert "... (500006 characters): expected a known key of [motor]" in res.output
    assert len(res.output) < 1000


def test_500k_character_value_gives_a_short_message(write_spec):
    path = write_spec(spec_dict(controller={"method": "y" * 500_000}))
    res = run_cli("check", path)
    assert res.exit_code == 2 and "controller.method: expected one of" in res.output
    assert "... (500000 characters)" in res.output and len(res.output) < 2000


# ---------------------------------------------------------------- design directories


@pytest.fixture(scope="module")
def design_dir(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("catalogue")
    spec = root / "spec.toml"
    spec.write_text(to_toml(spec_dict()))
    out = root / "design"
    res = run_cli("design", spec, "--out", out, "-q")
    assert res.exit_code == 0, res.output
    return out


def _copy(design_dir: Path, tmp_path: Path) -> Path:
    out = tmp_path / "d"
    out.mkdir()
    for p in design_dir.iterdir():
        (out / p.name).write_bytes(p.read_bytes())
    return out


@pytest.mark.parametrize("command", ["verify", "export", "report"])
def test_controller_sample_time_infinity_is_an_artifact_error(design_dir, tmp_path, command):
    out = _copy(design_dir, tmp_path)
    text = (out / "controller.json").read_text()
    data = json.loads(text)
    data["sample_time"] = "INF"
    # json.dumps would refuse inf: write the JSON token Infinity as a user could
    (out / "controller.json").write_text(json.dumps(data).replace('"INF"', "Infinity"))
    res = run_cli(command, out)
    assert res.exit_code == 2, res.output
    assert (f"cct: error: {out / 'controller.json'}: sample_time: expected a finite number "
            "> 0 (s), got inf") in res.output
    assert "Traceback" not in res.output


@pytest.mark.parametrize("where, value, key", [
    ("law_entry", BIG, "axes.d.law.A"),
])
def test_controller_400_digit_matrix_entry(design_dir, tmp_path, where, value, key):
    out = _copy(design_dir, tmp_path)
    data = json.loads((out / "controller.json").read_text())
    data["axes"]["d"]["law"]["A"][0][0] = value
    (out / "controller.json").write_text(json.dumps(data))
    res = run_cli("verify", out)
    assert res.exit_code == 2, res.output
    assert f"{key}: expected a matrix" in res.output and "Traceback" not in res.output


@pytest.mark.parametrize("sweep, key", [
    ({"worst": [1, 2]}, "sweep.worst"),
    ({"worst": {"d": {"gain_margin_db": 3.0}}}, "sweep.worst.d.gain_margin_db"),
    ({"worst": {"d": {"gain_margin_db": {"value": "x", "params": {}}}}},
     "sweep.worst.d.gain_margin_db.value"),
    ({"unstable_examples": {"a": 1}}, "sweep.unstable_examples"),
    ({"unstable_examples": [3]}, "sweep.unstable_examples[0]"),
    ({"worst_spectral_radius": [1.0]}, "sweep.worst_spectral_radius"),
    ({"n_sets": 1, "speeds_rad_s": "fast"}, "sweep.speeds_rad_s"),
])
def test_wrong_shaped_sweep_is_an_artifact_error(design_dir, tmp_path, sweep, key):
    out = _copy(design_dir, tmp_path)
    data = json.loads((out / "analysis.json").read_text())
    data["sweep"] = sweep
    (out / "analysis.json").write_text(json.dumps(data))
    before = (out / "report.html").read_bytes()
    res = run_cli("report", out)
    assert res.exit_code == 2, res.output
    assert f"cct: error: {out / 'analysis.json'}: {key}: expected" in res.output
    assert "Traceback" not in res.output
    assert (out / "report.html").read_bytes() == before  # nothing rewritten


def test_wrong_shaped_mimo_box_is_an_artifact_error(design_dir, tmp_path):
    out = _copy(design_dir, tmp_path)
    data = json.loads((out / "analysis.json").read_text())
    data["mimo_over_box"]["worst_params"] = {"R": "x2"}
    (out / "analysis.json").write_text(json.dumps(data))
    res = run_cli("report", out)
    assert res.exit_code == 2, res.output
    assert "mimo_over_box.worst_params.R: expected a number" in res.output


@pytest.mark.parametrize("prefix", ["motor1\n", "motor1_\n", "m\r"])
def test_export_prefix_option_with_a_newline(design_dir, tmp_path, prefix):
    out = _copy(design_dir, tmp_path)
    res = run_cli("export", out, "--prefix", prefix, "-o", tmp_path / "m.h")
    assert res.exit_code == 2, res.output
    assert "cct: error: --prefix: expected a C identifier prefix" in res.output
    assert "export.prefix" in res.output
    assert len(res.output.strip().splitlines()) == 1  # the newline is shown escaped
    assert not (tmp_path / "m.h").exists()


# ---------------------------------------------------------------- integrity


def _tamper(design_dir: Path, tmp_path: Path, change) -> Path:
    out = _copy(design_dir, tmp_path)
    data = json.loads((out / "controller.json").read_text())
    change(data)
    (out / "controller.json").write_text(json.dumps(data))
    return out


def _retime(data: dict, ts: float) -> None:
    """Another sample time, consistent inside the law (every dt)."""
    data["sample_time"] = ts
    for axis in data["axes"].values():
        for view in (axis, axis.get("full_order") or {}, axis.get("reduced") or {}):
            if "law" in view:
                view["law"]["dt"] = ts


@pytest.mark.parametrize("command", ["export", "verify"])
def test_sample_time_other_than_the_spec_is_refused(design_dir, tmp_path, command):
    out = _tamper(design_dir, tmp_path, lambda d: _retime(d, 2e-4))
    before = (out / "controller.h").read_bytes()
    res = run_cli(command, out)
    assert res.exit_code == 2, res.output
    assert (f"cct: error: {out / 'controller.json'}: sample_time: expected the stored spec's "
            "drive.sample_time (0.0001 s), got 0.0002") in res.output
    assert (out / "controller.h").read_bytes() == before


@pytest.mark.parametrize("command", ["export", "verify"])
def test_delay_other_than_the_spec_is_refused(design_dir, tmp_path, command):
    out = _tamper(design_dir, tmp_path, lambda d: d.update(delay_samples=2))
    res = run_cli(command, out)
    assert res.exit_code == 2, res.output
    assert (f"{out / 'controller.json'}: delay_samples: expected the stored spec's "
            "drive.delay_samples (1), got 2") in res.output


@pytest.mark.parametrize("command", ["verify", "export", "report"])
def test_spec_changed_after_design_is_refused(design_dir, tmp_path, command):
    """A valid but different stored spec (R 0.6 -> 0.7): the digest of
    provenance.spec_sha256 no longer holds."""
    def change(d):
        d["spec"]["motor"]["R"] = 0.7

    out = _tamper(design_dir, tmp_path, change)
    res = run_cli(command, out)
    assert res.exit_code == 2, res.output
    assert (f"{out / 'controller.json'}: provenance.spec_sha256: expected the sha256 of the "
            "stored spec") in res.output
    assert "changed after cct design" in res.output


def test_antiwindup_that_diverges_in_saturation_is_refused_for_export(design_dir, tmp_path):
    """x' = (A - aw C) x at full saturation: aw = 3 / C on the PI's integrator
    (A = 1) gives 1 - 3 = -2, spectral radius 2."""
    def change(d):
        law = d["axes"]["d"]["law"]
        assert law["A"] == [[1.0]], law["A"]
        d["axes"]["d"]["antiwindup"] = [[3.0 / law["C"][0][0]]]

    out = _tamper(design_dir, tmp_path, change)
    target = tmp_path / "h.h"
    res = run_cli("export", out, "-o", target)
    assert res.exit_code == 2, res.output
    assert (f"{out / 'controller.json'}: axes.d.antiwindup: expected a back-calculation gain "
            "aw whose saturated recursion x' = (A - aw C) x is stable (spectral radius < 1), "
            'got "spectral radius 2"') in res.output
    assert not target.exists()


def test_hand_edited_header_fails_verify(design_dir, tmp_path):
    """The law sha256 line is intact but a coefficient was edited: the whole
    regenerated header is compared (exit 1, the line named)."""
    out = _copy(design_dir, tmp_path)
    lines = (out / "controller.h").read_text().split("\n")
    k = next(i for i, line in enumerate(lines) if "V_MAX_PER_VDC" in line and "#define" in line)
    lines[k] = lines[k] + " /* tuned on the bench */"
    (out / "controller.h").write_text("\n".join(lines))
    res = run_cli("verify", out, "-q")
    assert res.exit_code == 1, res.output
    assert (f"FAIL  controller.h: differs from the header regenerated from controller.json at "
            f"line {k + 1}") in res.output
    header = json.loads((out / "verify.json").read_text())["header"]
    assert header == {"file": "controller.h", "law_sha256": header["law_sha256"],
                      "matches": False, "text_matches": False, "first_difference_line": k + 1}
    # the header as exported (another prefix included) matches again
    assert run_cli("export", out, "--prefix", "motor1_").exit_code == 0
    res = run_cli("verify", out, "-q")
    assert res.exit_code == 0, res.output
    assert json.loads((out / "verify.json").read_text())["header"]["matches"] is True
