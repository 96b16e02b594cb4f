"""CLI contract: exit codes, messages, nothing written on bad input."""

from pathlib import Path

import pytest
from click.testing import CliRunner

from toolbox.cli import main

BAD = Path(__file__).parents[1] / "spec" / "bad"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_motors_lists_catalog_with_key_figures():
    res = run("motors")
    assert res.exit_code == 0
    # paper 003 motor: tau_q = Lq/R = 4.67 ms, k_T = 1.5 * 4 * 0.12 = 0.72 N m/A
    line = next(l for l in res.output.splitlines() if l.startswith("azaiz2007"))
    assert "4.67" in line and "0.72" in line
    assert "R = 0.4 ohm assumed" in res.output


def test_check_prints_resolved_spec(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text('title = "t"\n[motor]\ncatalog = "azaiz2007"\nR = 0.7\n'
                    '[drive]\nvdc = 150\nsample_time = 1e-4\n'
                    '[controller]\nmethod = "pi"\n[controller.pi]\nbandwidth = 1000\n')
    res = run("check", spec)
    assert res.exit_code == 0, res.output
    assert "R = 0.7" in res.output          # explicit key overrides the catalog
    assert "Lq = 0.0028" in res.output      # catalog default


def test_bad_spec_exits_2_and_writes_nothing(tmp_path):
    out = tmp_path / "out"
    res = run("design", BAD / "negative_R.toml", "--out", out)
    assert res.exit_code == 2
    assert "motor.R: expected a number > 0 (ohm), got -0.6" in res.output
    assert not out.exists()


def test_derive_formats():
    spec = Path(__file__).parents[2] / "designs" / "003_azaiz2007_hinf.toml"
    for flag, marker in ((None, "di_q/dt"), ("--latex", r"\begin{align}"),
                         ("--markdown", "$$")):
        res = run("derive", spec, *([flag] if flag else []))
        assert res.exit_code == 0, res.output
        assert marker in res.output
    # numbers for the paper 003 motor: R/Lq = 214.286 1/s (eq (50))
    assert "214.286" in run("derive", spec).output


def test_missing_design_dir_exits_2(tmp_path):
    res = run("verify", tmp_path / "nothing")
    assert res.exit_code == 2
    assert "controller.json: expected a design directory with controller.json" in res.output


@pytest.mark.parametrize("preset", [None, "3"])
def test_cli_runs_single_threaded_blas_unless_told(preset):
    """``import toolbox.cli`` (the cct entry point) sets OPENBLAS_NUM_THREADS=1
    before numpy loads (small matrices: threads only cost); a value
    the user exported is kept."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if preset is not None:
        env["OPENBLAS_NUM_THREADS"] = preset
    code = ("import sys, os, toolbox.cli\n"
            "assert 'numpy' not in sys.modules\n"
            "print(os.environ['OPENBLAS_NUM_THREADS'])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120, env=env)
    assert out.stdout.strip() == (preset or "1")
