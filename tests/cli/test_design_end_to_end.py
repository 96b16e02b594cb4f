"""`cct design` end to end on reference designs: every output, exit codes,
determinism, hostile strings, and `cct verify/report/export` on the result.

Paper 000's total compensation *with integrators* is the reference design here:
the plain total compensation (``000_lepioufle1992_tc``) keeps the static current
error of eq (17) under its +10 % speed-measurement scenario, which the default
reach check (`default.reach`, README.md "Commands") reports honestly as a failure (exit 1)."""

import json
import re
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from toolbox.cli import main

DESIGNS = Path(__file__).parents[2] / "designs"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def tc_design(tmp_path_factory):
    out = tmp_path_factory.mktemp("tc")
    res = run("design", DESIGNS / "000_lepioufle1992_tci.toml", "--out", out, "-q")
    return out, res


def test_design_writes_every_output(tc_design):
    out, res = tc_design
    assert res.exit_code == 0, res.output
    for name in ("controller.json", "analysis.json", "verify.json", "controller.h",
                 "report.html", "report.pdf"):
        assert (out / name).stat().st_size > 0, name
    artifact = json.loads((out / "controller.json").read_text())
    assert artifact["schema"] == "cct.controller/2"
    assert set(artifact["margins"]) == {"d", "q"}
    for key in ("gain_margin_db", "gain_crossover_rad_s", "phase_margin_deg",
                "phase_crossover_rad_s", "disk_margin", "stability_margin",
                "sensitivity_peak", "bandwidth_rad_s", "static_error"):
        assert key in artifact["margins"]["q"], key
    verify = json.loads((out / "verify.json").read_text())
    assert verify["schema"] == "cct.verify/1" and len(verify["scenarios"]) == 2
    assert (out / "report.pdf").read_bytes().startswith(b"%PDF")


def test_outputs_are_deterministic(tc_design, tmp_path):
    """Same spec, same bytes, apart from the creation timestamp."""
    out, _ = tc_design
    res = run("design", DESIGNS / "000_lepioufle1992_tci.toml", "--out", tmp_path, "-q")
    assert res.exit_code == 0
    stamp = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\+00:00")
    for name in ("controller.json", "analysis.json", "verify.json", "controller.h",
                 "report.html"):
        a = stamp.sub("T", (out / name).read_text())
        b = stamp.sub("T", (tmp_path / name).read_text())
        assert a == b, name


def test_verify_report_export_read_the_artifact(tc_design, tmp_path):
    out, _ = tc_design
    work = tmp_path / "d"
    shutil.copytree(out, work)
    assert run("verify", work).exit_code == 0
    assert run("report", work).exit_code == 0
    header = tmp_path / "x.h"
    assert run("export", work, "--format", "c", "-o", header).exit_code == 0
    assert "#ifndef" in header.read_text()
    res = run("export", work, "--format", "json")
    assert json.loads(res.output)["method"] == "tci"


def test_failed_requirement_exits_1_with_outputs(tmp_path):
    spec = (DESIGNS / "000_lepioufle1992_tci.toml").read_text().replace(
        "[requirements]\n", "[requirements]\nmin_phase_margin_deg = 170\n")
    path = tmp_path / "strict.toml"
    path.write_text(spec)
    res = run("design", path, "--out", tmp_path / "o", "-q")
    assert res.exit_code == 1
    assert (tmp_path / "o" / "report.html").exists()
    verify = json.loads((tmp_path / "o" / "verify.json").read_text())
    assert verify["margin_requirements"]["min_phase_margin_deg"]["pass"] is False
    assert "170" in verify["margin_requirements"]["min_phase_margin_deg"]["reason"]


def test_hostile_title_is_inert(tmp_path):
    hostile = '<script>alert(1)</script> */ #error x /* "; rm -rf / $(reboot) ??='
    spec = (DESIGNS / "000_lepioufle1992_tci.toml").read_text()
    spec = re.sub(r'^title = .*$', "title = " + json.dumps(hostile), spec, flags=re.M)
    path = tmp_path / "hostile.toml"
    path.write_text(spec)
    res = run("design", path, "--out", tmp_path / "o", "-q")
    assert res.exit_code == 0, res.output
    html = (tmp_path / "o" / "report.html").read_text()
    assert "<script>alert(1)</script>" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    header = (tmp_path / "o" / "controller.h").read_text()
    assert "*/ #error" not in header


def test_report_reuses_stored_analysis(tc_design, tmp_path, monkeypatch):
    """`cct report` reads analysis.json instead of analysing again (no stage
    re-derives what an earlier one produced); without it, it analyses."""
    import toolbox.pipeline

    out, _ = tc_design
    work = tmp_path / "d"
    shutil.copytree(out, work)

    def forbidden(*args, **kwargs):
        raise AssertionError("analysis ran again")

    monkeypatch.setattr(toolbox.pipeline, "analyse", forbidden)
    assert run("report", work).exit_code == 0
    (work / "analysis.json").unlink()
    # the top-level handler turns the escaped AssertionError into exit 3 and one
    # line (toolbox/ARCHITECTURE.md "Errors and exit codes"): analysis ran again
    res = run("report", work)
    assert res.exit_code == 3
    assert ("cct: internal error in report (analysis): AssertionError: analysis ran again"
            in res.output)
