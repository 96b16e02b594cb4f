"""``[campaign]`` validation follows the spec conventions (toolbox/ARCHITECTURE.md
"Campaigns", "Spec file").

Unknown keys are errors naming the file and the dotted key path with a
did-you-mean; values are range-checked; the CLI turns them into exit 2 and
writes nothing.
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from toolbox.cli import main
from toolbox.errors import SpecError
from toolbox.spec import load_spec

from campaign_helpers import SPEC, write_spec


def _load(tmp_path, replace: tuple[str, str] | None = None, extra: str = ""):
    text = SPEC.format(samples=400, chunk_size=100) + extra
    if replace:
        assert replace[0] in text  # the edit must apply, or the test proves nothing
        text = text.replace(*replace)
    path = tmp_path / "c.toml"
    path.write_text(text)
    return load_spec(path)


def test_valid_table(tmp_path):
    spec = _load(tmp_path)
    cfg = spec.campaign
    assert (cfg.samples, cfg.seed, cfg.chunk_size, cfg.n_chunks) == (400, 3, 100, 4)
    assert [p.name for p in cfg.parameters] == ["R", "Ld", "Lq", "flux"]
    assert cfg.parameters[1].distribution == "truncnormal"
    assert cfg.correlation[0] == ("Ld", "Lq")
    assert cfg.operating_points == (("speed", (0.0, 100.0)), ("speed_offset", (0.0, 5.0)),
                                    ("delay_samples", (1, 2)))
    assert cfg.n_operating_points == 8


def test_spec_without_campaign_has_none(tmp_path):
    head = SPEC.split("[campaign]")[0]
    path = tmp_path / "plain.toml"
    path.write_text(head)
    assert load_spec(path).campaign is None


@pytest.mark.parametrize("edit, key, fragment", [
    (("samples = 400", "sample = 400"), "campaign.sample", 'did you mean "samples"'),
    (('low = 1.0\nhigh = 1.4', 'low = 1.0\nhihg = 1.4'), "campaign.parameters.R.hihg",
     'did you mean "high"'),
    (("[campaign.parameters.R]", "[campaign.parameters.Rs]"), "campaign.parameters.Rs",
     'did you mean "R"'),
    (('distribution = "uniform"\nlow = 1.0', 'distribution = "uniforn"\nlow = 1.0'),
     "campaign.parameters.R.distribution", 'did you mean "uniform"'),
    (("samples = 400", "samples = 0"), "campaign.samples", "an integer >= 1"),
    (("speed_offset = [0.0, 5.0]", "speed_ofset = [0.0, 5.0]"),
     "campaign.operating_points.speed_ofset", 'did you mean "speed_offset"'),
    (("delay_samples = [1, 2]", "delay_samples = [1, 2.5]"),
     "campaign.operating_points.delay_samples", "integers in 0 .. 10"),
    (("speed = [0.0, 100.0]", "speed = [0.0, 0.0]"), "campaign.operating_points.speed",
     "distinct values"),
    (("seed = 3", "seed = 1.5"), "campaign.seed", "an integer"),
    (("low = 1.0\nhigh = 1.4", "low = 1.4\nhigh = 1.0"), "campaign.parameters.R.high",
     "a number > low"),
    (("low = 1.0\nhigh = 1.4", "low = -0.1\nhigh = 1.4"), "campaign.parameters.R.low",
     "> 0"),
    (("mean = 0.95\nstd = 0.02", "mean = 0.95\nstd = 0.3"), "campaign.parameters.flux.mean",
     "truncnormal"),
])
def test_bad_values(tmp_path, edit, key, fragment):
    with pytest.raises(SpecError) as info:
        _load(tmp_path, edit)
    text = str(info.value)
    assert str(tmp_path / "c.toml") in text
    assert f"{key}:" in text
    assert fragment in text


@pytest.mark.parametrize("matrix, fragment", [
    ("[[1.0, 0.8], [0.7, 1.0]]", "symmetric"),
    ("[[1.0, 1.2], [1.2, 1.0]]", "positive definite"),
    ("[[1.0, 0.8]]", "2 x 2 matrix"),
])
def test_bad_correlation(tmp_path, matrix, fragment):
    with pytest.raises(SpecError, match=fragment):
        _load(tmp_path, ("matrix = [[1.0, 0.8], [0.8, 1.0]]", f"matrix = {matrix}"))


def test_correlation_of_undrawn_parameter(tmp_path):
    with pytest.raises(SpecError, match=r"campaign\.correlation\.parameters.*got \"J\""):
        _load(tmp_path, ('parameters = ["Ld", "Lq"]', 'parameters = ["Ld", "J"]'))


def test_measured_table(tmp_path):
    spec = _load(tmp_path, extra='[campaign.measured]\ncolumns = ["R", "flux"]\n'
                                 'rows = [[0.6, 0.12], [0.65, 0.118]]\n')
    assert spec.campaign.measured_columns == ("R", "flux")
    assert spec.campaign.measured_rows == ((0.6, 0.12), (0.65, 0.118))
    with pytest.raises(SpecError, match=r"campaign\.measured\.rows\[1\]: expected a list of 2"):
        _load(tmp_path, extra='[campaign.measured]\ncolumns = ["R", "flux"]\n'
                              'rows = [[0.6, 0.12], [0.65]]\n')
    with pytest.raises(SpecError, match=r"campaign\.measured\.rows\[1\]: expected physical"):
        _load(tmp_path, extra='[campaign.measured]\ncolumns = ["R", "flux"]\n'
                              'rows = [[0.6, 0.12], [-0.65, 0.1]]\n')


def test_unknown_scenario_name(tmp_path):
    with pytest.raises(SpecError, match=r'campaign\.scenarios: .*did you mean "iq step"'):
        _load(tmp_path, ("seed = 3", 'seed = 3\nscenarios = ["iq stp"]'))


def test_cli_bad_campaign_exit_2_writes_nothing(tmp_path):
    path = write_spec(tmp_path)
    path.write_text(path.read_text().replace("samples = 400", "sampels = 400"))
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(out), "-q"])
    assert res.exit_code == 2, res.output
    assert "campaign.sampels" in res.output and 'did you mean "samples"' in res.output
    assert not out.exists()


def test_cli_needs_campaign_table(tmp_path):
    path = tmp_path / "plain.toml"
    path.write_text(SPEC.split("[campaign]")[0])
    res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "campaign: expected a [campaign] table (missing)" in res.output


def test_cct_check_round_trips_the_campaign(tmp_path):
    """``cct check`` prints [campaign]; its output loads back to the same table."""
    path = write_spec(tmp_path)
    res = CliRunner().invoke(main, ["check", str(path)])
    assert res.exit_code == 0, res.output
    assert "[campaign]" in res.output
    again = tmp_path / "resolved.toml"
    again.write_text(res.output)
    assert load_spec(again).campaign == load_spec(path).campaign


def test_motors_key_and_gate(tmp_path):
    """motors = M runs M motors at every grid point (M x 8 rows); one of
    motors / samples; gate is one of three."""
    spec = _load(tmp_path, ("samples = 400", 'motors = 30\ngate = "per_motor"'))
    cfg = spec.campaign
    assert (cfg.samples, cfg.n_motors, cfg.complete_motors, cfg.gate) == (240, 30, 30,
                                                                          "per_motor")
    legacy = _load(tmp_path).campaign
    assert (legacy.n_motors, legacy.complete_motors, legacy.gate) == (50, 50, "per_sample")
    with pytest.raises(SpecError, match="campaign.motors: expected one of motors"):
        _load(tmp_path, ("samples = 400", "samples = 400\nmotors = 3"))
    with pytest.raises(SpecError, match='campaign.gate: .*did you mean "per_motor"'):
        _load(tmp_path, ("samples = 400", 'samples = 400\ngate = "per_motr"'))
