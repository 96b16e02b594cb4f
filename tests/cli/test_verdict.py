"""Verdicts you can trust, a pass must mean something (toolbox/ARCHITECTURE.md
"verify.json", "Errors and exit codes"): default
checks without requirements, numbers recomputed from the executed law, an
unstable loop is exit 1 with every output but controller.h, NaN metrics are
failures with reasons, compare exits 1 when a design fails."""

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import toolbox
from toolbox.analysis import compute_margins
from toolbox.cli import main

DESIGNS = Path(__file__).parents[2] / "designs"
NOTICE = "no requirements given; default checks only"
#: Paper 003's motor and drive; a PI by cancellation at 1000 rad/s (sound).
BASE = ('[motor]\ncatalog = "azaiz2007"\n[drive]\nvdc = 150\nsample_time = 1e-4\n'
        'delay_samples = 1\n[controller]\nmethod = "pi"\n[controller.pi]\n')
STEP = ('[[scenario]]\nkind = "current_step"\nduration = {duration}\niq_ref = 5.0\n'
        'step_time = 0.001\n')


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def design_dir(tmp_path: Path, text: str, name: str = "d") -> Path:
    """controller.json with its MARGINS, as `cct design` stores them, without
    the slow sweep/certificate/report stages (verify reads only this file)."""
    spec_path = tmp_path / f"{name}.toml"
    spec_path.write_text(text)
    spec = toolbox.load_spec(spec_path)
    art = toolbox.design_spec(spec)
    art = art.with_margins({ax: m.to_json()
                            for ax, m in compute_margins(art, spec.motor).items()})
    out = tmp_path / name
    out.mkdir()
    (out / "controller.json").write_text(art.dumps())
    return out


@pytest.fixture(scope="module")
def unstable_design(tmp_path_factory):
    """A PI at 1e6 rad/s with Ts = 100 us: the design exists, its sampled loop
    is unstable (spectral radius about 10)."""
    tmp = tmp_path_factory.mktemp("unstable")
    spec = tmp / "fast.toml"
    spec.write_text(BASE + "bandwidth = 1e6\n")
    out = tmp / "out"
    return spec, out, run("design", spec, "--out", out)


def test_unstable_loop_exits_1_without_header(unstable_design):
    """Exit 1 (a design that fails), not 2 (bad input): every output but
    controller.h is written so the report shows why."""
    spec, out, res = unstable_design
    assert res.exit_code == 1, res.output
    for name in ("controller.json", "analysis.json", "verify.json", "report.html",
                 "report.pdf"):
        assert (out / name).stat().st_size > 0, name
    assert not (out / "controller.h").exists()
    assert "controller.h not written" in res.output
    assert "expected a law whose sampled loop (ZOH plant, computation delay) is stable" \
        in res.output
    verify = json.loads((out / "verify.json").read_text())
    assert verify["passed"] is False
    assert verify["stability"]["q"]["stable"] is False
    assert verify["margin_requirements"]["default.stable"]["reason"].startswith(
        "the executed sampled loop of the d and q axis is unstable")
    analysis = json.loads((out / "analysis.json").read_text())
    assert analysis["stability"]["d"]["stable"] is False


def test_export_refuses_unstable_loop_naming_the_file(unstable_design):
    _, out, _ = unstable_design
    res = run("export", out, "-o", out / "x.h")
    assert res.exit_code == 2
    assert (f"cct: error: {out / 'controller.json'}: axes.d.law: expected a law whose "
            "sampled loop") in res.output
    assert not (out / "x.h").exists()


def test_no_requirements_notice_in_design_output_and_report(unstable_design):
    _, out, res = unstable_design
    assert f"cct: notice: {NOTICE}" in res.output
    assert json.loads((out / "verify.json").read_text())["notice"] == NOTICE
    assert NOTICE in (out / "report.html").read_text()


def test_no_requirements_notice_in_verify(tmp_path):
    out = design_dir(tmp_path, BASE + "bandwidth = 1000.0\n" + STEP.format(duration=0.02))
    res = run("verify", out)
    assert res.exit_code == 0, res.output
    assert f"cct: notice: {NOTICE}" in res.output
    data = json.loads((out / "verify.json").read_text())
    assert data["notice"] == NOTICE and data["warnings"] == []
    assert data["stability"]["q"]["stable"] is True
    checks = data["scenarios"][0]["requirements"]
    assert {"default.reach", "default.bounded_current", "default.bounded_speed",
            "default.finite"} <= set(checks)


def test_tampered_controller_json_fails_verify(tmp_path):
    """law.A diagonal set to 1.2 (it once passed with "PM 47.31" while the
    simulated error was 182 A). Verify recomputes from the executed law: the
    loop is unstable, exit 1, and the stored margins are called out."""
    out = design_dir(tmp_path, BASE + "bandwidth = 1000.0\n" + STEP.format(duration=0.02))
    path = out / "controller.json"
    data = json.loads(path.read_text())
    for axis in ("d", "q"):
        A = np.array(data["axes"][axis]["law"]["A"], float)
        np.fill_diagonal(A, 1.2)
        data["axes"][axis]["law"]["A"] = A.tolist()
    path.write_text(json.dumps(data))
    res = run("verify", out)
    assert res.exit_code == 1, res.output
    assert f"cct: warning: {path}: margins.q." in res.output
    assert "recomputed from the executed law (axes.q.law)" in res.output
    assert "q axis: UNSTABLE" in res.output
    verify = json.loads((out / "verify.json").read_text())
    assert verify["stability"]["q"]["stable"] is False
    assert verify["warnings"]
    # the report shows the recomputed verdict too, and fails the same way
    res = run("report", out)
    assert res.exit_code == 1, res.output
    assert "disagrees with" in (out / "report.html").read_text()


def test_unsettled_metric_fails_with_reason_in_strict_json(tmp_path):
    """The run ends 0.2 ms after the step: the 5 % time cannot be computed.
    Today's crash ('Out of range float values are not JSON compliant: nan')
    becomes exit 1 with a reason and strict JSON."""
    text = (BASE + "bandwidth = 1000.0\n[requirements]\nmax_response_time = 0.01\n"
            + STEP.format(duration=0.0012))
    out = design_dir(tmp_path, text)
    res = run("verify", out)
    assert res.exit_code == 1, res.output
    raw = (out / "verify.json").read_text()
    assert "NaN" not in raw
    check = json.loads(raw)["scenarios"][0]["requirements"]["max_response_time"]
    assert check["value"] is None and check["pass"] is False
    assert "could not be computed" in check["reason"]
    assert "default.reach: the q current never stayed within" in res.output


def test_compare_exits_1_when_a_design_fails(tmp_path, unstable_design):
    """A sound PI and the unstable one on the same motor and drive: the table
    is printed and written, the failing design is named, exit 1."""
    spec, _, _ = unstable_design
    out = tmp_path / "c.json"
    res = run("compare", DESIGNS / "003_azaiz2007_pi.toml", spec, "--json", out)
    assert res.exit_code == 1, res.output
    rows = json.loads(out.read_text())
    assert [r["passed"] for r in rows] == [True, False]
    assert any("default.stable" in f for f in rows[1]["failures"])
    assert f"FAIL  {spec}: default.stable" in res.output


def test_gallery_exits_1_when_a_design_fails(tmp_path, unstable_design):
    """Every design's outputs are written; the failing one is named; exit 1."""
    spec, _, _ = unstable_design
    designs = tmp_path / "designs"
    designs.mkdir()
    (designs / "fast.toml").write_text(spec.read_text())
    res = run("gallery", "--designs", designs, "--out", tmp_path / "reports")
    assert res.exit_code == 1, res.output
    assert "FAIL  fast.toml" in res.output
    assert (tmp_path / "reports" / "fast" / "report.html").exists()
    assert not (tmp_path / "reports" / "fast" / "controller.h").exists()


def test_report_says_why_a_check_failed(unstable_design):
    """The report's check table carries the reason of each failure."""
    _, out, _ = unstable_design
    html = (out / "report.html").read_text()
    assert "default.stable" in html
    assert "the executed sampled loop of the d and q axis is unstable" in html


def test_verify_fails_a_header_exported_from_another_controller_json(tmp_path):
    """QA finding: after controller.json changed, `cct verify` passed the new law
    while controller.h still held the old one. The header carries the law's
    sha256 (ARCHITECTURE.md, controller.h); a header from another controller.json
    is a failed verdict (exit 1) until `cct export` rewrites it."""
    out = design_dir(tmp_path, BASE + "bandwidth = 1000.0\n" + STEP.format(duration=0.02))
    assert run("export", out).exit_code == 0
    res = run("verify", out)
    assert res.exit_code == 0, res.output
    header = json.loads((out / "verify.json").read_text())["header"]
    assert header["matches"] is True and len(header["law_sha256"]) == 64
    # a 1 % change of one output coefficient: still a sound (stable) law
    path = out / "controller.json"
    data = json.loads(path.read_text())
    data["axes"]["q"]["law"]["C"][0][0] *= 1.01
    path.write_text(json.dumps(data))
    res = run("verify", out)
    assert res.exit_code == 1, res.output
    assert "FAIL  controller.h: exported from another controller.json" in res.output
    assert "q axis: stable" in res.output
    verify = json.loads((out / "verify.json").read_text())
    assert verify["passed"] is False and verify["header"]["matches"] is False
    assert verify["header"]["law_sha256"] == header["law_sha256"]
    assert run("export", out).exit_code == 0
    assert run("verify", out).exit_code == 0
