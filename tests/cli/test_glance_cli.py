"""The CLI's verdict at a glance: fcs_mpc's margins are the baseline PI's."""

from __future__ import annotations

import types

from toolbox.cli._main import _summary


def _out(method):
    m = {"gain_margin_db": -3.871, "phase_margin_deg": -63.96, "stability_margin": 0.1}
    art = types.SimpleNamespace(method=method, margins={"d": m, "q": m})
    return types.SimpleNamespace(warnings=[], verification=None, notice=None, artifact=art,
                                 analysis=None, header_refused=None)


def test_fcs_mpc_margins_printed_as_baseline(capsys):
    _summary(_out("fcs_mpc"))
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == ("d axis (baseline PI, informational, not executed): GM -3.871 dB, "
                        "PM -63.96 deg, Mm 0.1")
    _summary(_out("pi"))
    assert capsys.readouterr().out.startswith("d axis (sampled loop): GM -3.871 dB")


def test_design_overrides_name_the_overridden_key(tmp_path):
    """--method and --set override the spec before validation; an error on an
    overridden key names the override; nothing is written."""
    from pathlib import Path

    from click.testing import CliRunner

    from toolbox.cli import main

    spec = str(Path(__file__).parents[2] / "designs" / "003_azaiz2007_hinf.toml")
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["design", spec, "--out", str(out), "--method", "pi",
                                    "--set", "motor.R=-1", "--set", "drive.vdc=abc"])
    assert res.exit_code == 2 and not out.exists()
    assert "motor.R: expected a number > 0 (ohm), got -1 (from --set motor.R=-1)" in res.output
    assert 'drive.vdc: expected a number > 0 (V), got "abc" (from --set drive.vdc=abc)' in res.output
    res = CliRunner().invoke(main, ["design", spec, "--out", str(out), "--method", "pii"])
    assert res.exit_code == 2 and 'from --method "pii"; did you mean "pi"?' in res.output
    res = CliRunner().invoke(main, ["design", spec, "--out", str(out), "--set", "motor.R"])
    assert res.exit_code == 2 and "--set: expected key.path=value" in res.output


def test_overrides_are_toml_values():
    from toolbox.spec._overrides import apply_overrides, parse_override

    assert parse_override("controller.pi.bandwidth=1500") == (
        ["controller", "pi", "bandwidth"], 1500)
    assert parse_override("requirements.parameter_drift.R=[0.8, 1.5]")[1] == [0.8, 1.5]
    assert parse_override("drive.voltage_limit=hexagon")[1] == "hexagon"
    assert parse_override('title="a = b"')[1] == "a = b"
    data = {"controller": {"method": "hinf", "hinf": {"gamma": 1.0}},
            "scenario": [{"duration": 0.1}]}
    got = apply_overrides(data, [("--method", 'controller.method="pi"'),
                                 ("--set", "controller.pi.bandwidth=1500"),
                                 ("--set", "scenario.0.duration=0.2")])
    assert got["controller"] == {"method": "pi", "pi": {"bandwidth": 1500}}
    assert got["scenario"][0]["duration"] == 0.2 and data["scenario"][0]["duration"] == 0.1


def test_compare_lists_refused_specs_and_ranks(tmp_path):
    """compare designs what it can: a bad spec and one of another motor are
    listed as refused with file and reason (exit 1, table printed, JSON
    written); the robustness column counts the drift box as cct design does and
    the stress sweep the sets of analysis.json; the notes and failure
    summaries are wrapped at 100 columns and no numpy warning reaches stderr."""
    import json
    from pathlib import Path

    from click.testing import CliRunner

    from toolbox.analysis import SWEEP_SETS
    from toolbox.cli import main

    designs = Path(__file__).parents[2] / "designs"
    good = designs / "000_lepioufle1992_tci.toml"
    bad = tmp_path / "bad.toml"
    bad.write_text(good.read_text().replace("[drive]", "[drive]\nbogus = 1"))
    other = designs / "003_azaiz2007_pi.toml"
    out = tmp_path / "cmp.json"
    res = CliRunner().invoke(
        main, ["compare", "-q", str(good), str(bad), str(other), "--json", str(out)])
    assert res.exit_code == 1, res.output
    assert "RuntimeWarning" not in res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].split()[:3] == ["rank", "method", "BW"]
    assert any(line.startswith("rank: passing designs first") for line in lines), lines
    refused = [line for line in lines if line.startswith("REFUSED")]
    assert len(refused) == 2 and f"{bad}: drive.bogus" in refused[0]
    assert str(other) in refused[1]
    # below the header and row; a refusal keeps its "file: key:" on its first line
    assert all(len(line) <= 100 + (len(str(bad)) if line.startswith("REFUSED") else 0)
               for line in lines[2:]), lines
    rows = json.loads(out.read_text())
    designed = [r for r in rows if "refused" not in r]
    assert len(designed) == 1 and designed[0]["rank"] == 1
    assert designed[0]["robustness"]["n_sets"] == 565    # the drift box, as cct design
    assert designed[0]["n_sets"] == SWEEP_SETS + 129     # the report's stress sweep
    assert [r["spec"] for r in rows if "refused" in r] == [str(bad), str(other)]
