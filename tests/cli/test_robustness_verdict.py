"""Robustness in the default verdict (toolbox/ARCHITECTURE.md "Robustness
verdict"): `cct design` and `cct verify` print the drift-box line next to
the margins, a design unstable on the default drive box exits 1 naming the
first failing set and its speed, and verify.json records it."""

import json

from click.testing import CliRunner

from toolbox.cli import main

#: Paper 003's motor and drive, one short step; the PI bandwidth is filled in.
SPEC = ('[motor]\ncatalog = "azaiz2007"\n[drive]\nvdc = 150\nsample_time = 1e-4\n'
        'delay_samples = 1\nmax_speed = 230.0\n[controller]\nmethod = "pi"\n[controller.pi]\n'
        'bandwidth = {wc}\n[[scenario]]\nkind = "current_step"\nduration = 0.01\n'
        'iq_ref = 5.0\nstep_time = 0.001\n')
LINE = ("robustness (default drift box: R x0.843..1.511, Ld/Lq x0.8..1.1, flux x0.844..1.048, "
        "speed sensor +-2 %, +-1 % offset, 0..920 rad/s electrical): worst multiloop disk margin ")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def test_sound_design_prints_the_line_and_passes(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC.format(wc=1000.0))
    res = run("design", spec, "--out", tmp_path / "o", "-q")
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    i = next(k for k, x in enumerate(lines) if x.startswith("robustness ("))
    assert lines[i - 1].startswith("q axis (sampled loop): GM")   # next to the margins
    assert lines[i].startswith(LINE) and lines[i].endswith("unstable 0 / 565 sets")
    check = json.loads((tmp_path / "o" / "verify.json").read_text())[
        "margin_requirements"]["default.robustness"]
    assert check["pass"] is True and check["value"] == 0 and check["bound"] == 0
    assert check["robustness"]["box"]["R"] == [0.843, 1.511]
    assert check["robustness"]["worst_disk_margin"] > 0
    res = run("verify", tmp_path / "o")
    assert res.exit_code == 0 and LINE in res.stdout


def test_design_unstable_on_the_default_box_exits_1_naming_the_set(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC.format(wc=8800.0))   # stable at nominal only
    out = tmp_path / "o"
    res = run("design", spec, "--out", out, "-q")
    assert res.exit_code == 1, res.output
    assert LINE + "0.00, unstable " in res.stdout and res.stdout.count("FAILED") == 2
    lines = res.stdout.splitlines()
    start = next(k for k, x in enumerate(lines) if x.startswith("requirements: "))
    assert lines[start] == "requirements: FAILED 1 check:"
    assert all(len(x) <= 100 for x in lines[start:])  # wrapped, one check per item
    verdict = " ".join(x.strip() for x in lines[start + 1:])
    assert verdict.startswith("- default.robustness (the coupled sampled "
                              "loop is unstable for ")
    assert "first: R x0.843, Ld x0.8, Lq x0.8, flux x0.844, speed_gain x0.98" in verdict
    assert "rad/s electrical (largest closed-loop pole" in verdict
    data = json.loads((out / "verify.json").read_text())
    assert data["passed"] is False
    check = data["margin_requirements"]["default.robustness"]
    assert check["pass"] is False and check["value"] > 0 and check["bound"] == 0
    assert data["robustness"]["first_unstable"]["Ld"] == 0.8
    assert "speed_rad_s" in data["robustness"]["first_unstable"]
    res = run("verify", out)
    assert res.exit_code == 1
    assert "FAIL  default.robustness:" in res.stdout and "first: R x0.843" in res.stdout
