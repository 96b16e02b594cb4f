"""A tampered controller.json or analysis.json is an ArtifactError naming the
file and the key path inside it, never a KeyError, AttributeError or
TypeError from deeper code.

Found by fuzzing: a fcs_mpc artifact without ``gains.alpha`` (now the typed ``fcs.alpha``) (KeyError 'alpha'
in the verification), ``margins`` holding a number (AttributeError in the
CLI summary), ``requirements`` of analysis.json holding a list (TypeError in
the report), deep nesting (RecursionError in json).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from toolbox.artifact import ControllerArtifact
from toolbox.errors import ArtifactError
from toolbox.pipeline import design_spec, load_analysis, spec_of_artifact
from toolbox.spec import METHODS

from hostile_helpers import ROOT, run_cli, spec_dict

FILE = "out/controller.json"


@pytest.fixture(scope="module")
def pi_json() -> str:
    return design_spec(spec_dict()).dumps()


@pytest.fixture(scope="module")
def fcs_json() -> str:
    return design_spec(ROOT / "designs" / "002_cormerais2002_fcs_mpc.toml").dumps()


def _refused(data, message: str) -> None:
    with pytest.raises(ArtifactError) as info:
        ControllerArtifact.from_json(data, file=FILE)
    assert str(info.value) == f"{FILE}: {message}"


@pytest.mark.parametrize("name, message", [
    ("alpha", 'fcs.alpha: expected a finite number >= 0 (the fcs_mpc law reads it), '
              'got "nothing (missing)"'),
    ("gamma", 'fcs.gamma: expected a finite number >= 0 (the fcs_mpc law reads it), '
              'got "nothing (missing)"'),
])
def test_fcs_gain_missing(fcs_json, name, message):
    data = json.loads(fcs_json)
    del data["fcs"][name]
    _refused(data, message)


def test_fcs_gain_wrong_type(fcs_json):
    data = json.loads(fcs_json)
    data["fcs"]["beta"] = "1"
    _refused(data, 'fcs.beta: expected a finite number >= 0 (the fcs_mpc law reads it), '
                   'got "1"')


@pytest.mark.parametrize("margins, message", [
    ({"d": 5}, "margins.d: expected an object (MARGINS), got 5"),
    ({"d": {"gain_margin_db": [1, 2]}},
     'margins.d.gain_margin_db: expected a number, "inf", "-inf", "nan" or null, got [1, 2]'),
    ({"q": {"stable": "yes"}}, 'margins.q.stable: expected true, false or null, got "yes"'),
    ({"x": {}}, 'margins.x: expected one of the axes "d", "q", got "unknown key"'),
])
def test_margins_wrong_type(pi_json, margins, message):
    data = json.loads(pi_json)
    data["margins"] = margins
    _refused(data, message)


def test_margins_as_written_are_accepted(pi_json):
    data = json.loads(pi_json)
    data["margins"] = {"d": {"gain_margin_db": "inf", "stable": True, "bandwidth_rad_s": None,
                             "phase_margin_deg": 60.0, "domain": "discrete",
                             "gain_margins_db": [[28.8, 10712.5]]}}
    assert ControllerArtifact.from_json(data).margins["d"]["gain_margin_db"] == "inf"


def test_unknown_method(pi_json):
    data = json.loads(pi_json)
    data["method"] = "magic"
    _refused(data, "method: expected one of " + ", ".join(METHODS) + ', got "magic"')


def test_missing_law_matrix(pi_json):
    data = json.loads(pi_json)
    del data["axes"]["q"]["law"]["A"]
    _refused(data, "axes.q.law.A: expected a matrix (missing)")


def test_deep_nesting_in_data(pi_json):
    data = json.loads(pi_json)
    node = data["provenance"]
    for _ in range(10_000):  # deeper than the recursion limit
        node["x"] = {}
        node = node["x"]
    with pytest.raises(ArtifactError) as info:
        ControllerArtifact.from_json(data, file=FILE)
    assert "expected nesting at most 32 levels deep" in str(info.value)
    assert str(info.value).startswith(f"{FILE}: provenance.x.x.")


def test_stored_spec_error_names_its_path_in_controller_json(pi_json):
    data = json.loads(pi_json)
    data["spec"]["motor"]["R"] = -1.0
    art = ControllerArtifact.from_json(data, file=FILE)
    with pytest.raises(ArtifactError) as info:
        spec_of_artifact(art, file=FILE)
    assert str(info.value) == f"{FILE}: spec.motor.R: expected a number > 0 (ohm), got -1.0"


def _analysis_dir(tmp_path: Path, pi_json: str, requirements) -> tuple[Path, ControllerArtifact]:
    art = ControllerArtifact.loads(pi_json)
    (tmp_path / "controller.json").write_text(pi_json)
    (tmp_path / "analysis.json").write_text(json.dumps({
        "schema": "cct.analysis/1", "method": art.method, "sample_time": art.sample_time,
        "requirements": requirements}))
    return tmp_path, art


@pytest.mark.parametrize("requirements, message", [
    ([1, 2], 'requirements: expected an object, got "list"'),
    ({"min_phase_margin_deg": 40}, 'requirements.min_phase_margin_deg: expected an object '
                                   'with quantity, bound, value, unit, pass, got "int"'),
    ({"min_phase_margin_deg": {"pass": "yes"}},
     'requirements.min_phase_margin_deg.pass: expected true or false, got "yes"'),
    ({"min_phase_margin_deg": {"pass": True, "value": "60"}},
     'requirements.min_phase_margin_deg.value: expected a number or null, got "60"'),
])
def test_tampered_analysis_requirements(tmp_path, pi_json, requirements, message):
    out, art = _analysis_dir(tmp_path, pi_json, requirements)
    with pytest.raises(ArtifactError) as info:
        load_analysis(out, art)
    assert str(info.value) == f"{out / 'analysis.json'}: {message}"


def test_cli_report_on_tampered_analysis_exits_2(tmp_path, pi_json):
    out, _ = _analysis_dir(tmp_path, pi_json, [1, 2])
    res = run_cli("report", out)
    assert res.exit_code == 2
    assert f"cct: error: {out / 'analysis.json'}: requirements: expected an object" in res.output
    assert not (out / "report.html").exists()


@pytest.mark.parametrize("command", ["verify", "report", "export"])
def test_cli_on_tampered_controller_exits_2(tmp_path, fcs_json, command):
    data = json.loads(fcs_json)
    del data["fcs"]["alpha"]
    (tmp_path / "controller.json").write_text(json.dumps(data))
    res = run_cli(command, tmp_path)
    assert res.exit_code == 2, res.output
    assert f"cct: error: {tmp_path / 'controller.json'}: fcs.alpha: expected" in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["controller.json"]
