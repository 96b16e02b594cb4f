"""The example campaign's failure analysis finds its drivers (README "Campaigns").

designs/campaigns/003_azaiz2007_hinf.toml with 100 of its 1000 motors (1,800
rows, in-process): its two failure modes pull in opposite directions with
the speed-sensor offset (overshoot grows with it, the rise time misses
with a negative one), so the pooled pass/fail indicator hides it. Ranked
per failure mode and weighted by each mode's failures, the drivers must be
the speed offset and the speed, the grid cells over those two axes must
span a wide range of failure rates, and the scatter's shared subsample
must show the table's failing share.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from toolbox.campaign import run_campaign
from toolbox.campaign._summary import stratified_subset
from toolbox.cli import main
from toolbox.spec import load_spec

pytestmark = pytest.mark.slow   # the example campaign end to end

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "designs" / "campaigns" / "003_azaiz2007_hinf.toml"


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("example")
    text = EXAMPLE.read_text()
    assert "\nmotors = 1000\n" in text
    path = tmp / "example_100.toml"
    path.write_text(text.replace("\nmotors = 1000\n", "\nmotors = 100\n"))
    spec = load_spec(path)
    return spec, path, run_campaign(spec, tmp / "out", scheduler="serial")


def test_drivers_per_failure_mode(example):
    _spec, _path, run = example
    sm = run.summary
    modes = sm["sensitivity_by_mode"]
    over, rise = "iq_step: max_overshoot_pct", "iq_step: max_rise_time"
    assert set(sm["failure_reasons"]) == {over, rise}
    rho = {m: {e["parameter"]: e["rank_correlation"] for e in modes[m]} for m in modes}
    # opposite signs: overshoot with a positive offset and high speed, the
    # rise time with a negative offset and low speed
    assert rho[over]["speed_offset"] > 0.2 and rho[over]["speed"] > 0.2
    assert rho[rise]["speed_offset"] < -0.15 and rho[rise]["speed"] < -0.15
    assert modes[over][0]["parameter"] == "speed_offset"
    pooled = {e["parameter"]: e["rank_correlation"] for e in sm["sensitivity"]}
    assert abs(pooled["speed_offset"]) < 0.5 * rho[over]["speed_offset"]  # it cancels
    assert sm["drivers"][:2] == ["speed_offset", "speed"]
    cells = sm["cells"]
    assert cells["axes"] == ["speed_offset", "speed"]
    rates = [c["fail_rate"] for c in cells["cells"]]
    assert len(rates) == 9 and min(rates) < 0.05 and max(rates) > 0.4
    # the cells are the per-point counts pooled over the delay axis
    t = run.table
    off, spd = t.column("speed_offset").to_numpy(), t.column("speed").to_numpy()
    failed = ~t.column("passed").to_numpy(zero_copy_only=False)
    for c in cells["cells"]:
        sel = (off == c["speed_offset"]) & (spd == c["speed"])
        assert c["n"] == sel.sum() and c["failed"] == failed[sel].sum()


def test_scatter_shows_the_failing_share(example):
    """The scatter's points are one stratified subset of all rows: its red
    share is the table's to within half a point in 4000."""
    _spec, _path, run = example
    failed = ~run.table.column("passed").to_numpy(zero_copy_only=False)
    pick = stratified_subset(failed, 1000)
    assert pick.size == 1000 and len(set(pick)) == 1000
    assert abs(failed[pick].mean() - failed.mean()) <= 0.5 / 1000
    html = (run.out_dir / "report.html").read_text()
    assert "Samples over the two strongest drivers" in html
    assert "Failure rate by speed_offset and speed" in html


def test_example_worst_sample_reproduced_by_cct_design(example, tmp_path):
    """The worst failing sample at the design's delay (a spec cannot carry
    another delay without a redesign), written as worst/ writes it,
    reproduces its campaign metrics through cct design exactly; every file
    of worst/ is a spec without [campaign]."""
    from toolbox.campaign._summary import worst_spec

    spec, _path, run = example
    for name in run.summary["worst_specs"]:
        assert load_spec(run.out_dir / name).campaign is None
    t = run.table
    ratio = t.column("worst_ratio").to_numpy()
    delay = t.column("delay_samples").to_numpy()
    failed = ~t.column("passed").to_numpy(zero_copy_only=False)
    i = int(np.argmax(np.where(failed & (delay == 1), ratio, -np.inf)))
    row = {c: t.column(c)[i].as_py() for c in t.column_names}
    spec_file = tmp_path / "worst.toml"
    spec_file.write_text(worst_spec(spec, row))
    res = CliRunner().invoke(main, ["design", str(spec_file), "--out", str(tmp_path / "d"),
                                    "-q"])
    assert res.exit_code == 1, res.output  # it fails its requirement again
    metrics = json.loads((tmp_path / "d" / "verify.json").read_text())["scenarios"][0]["metrics"]
    for m in ("overshoot_pct", "rise_time_10_90", "mse_iq"):
        assert metrics[m] == row[f"iq_step.{m}"], m
