"""The campaign engine without Dask: draws, judging, resume, outputs, CLI
(toolbox/ARCHITECTURE.md "Campaigns").

The Dask runs (LocalCluster, a real scheduler with a killed worker) are in
test_campaign_dask.py and are compared with the serial table made here.
"""

from __future__ import annotations

import json

import numpy as np
import pyarrow.parquet as pq
import pytest
from campaign_helpers import write_spec
from click.testing import CliRunner
from scipy.stats import spearmanr

from toolbox.campaign import chunk_path, draw_samples, run_campaign, valid_chunks
from toolbox.cli import main
from toolbox.errors import SpecError
from toolbox.spec import load_spec

#: slow: campaigns end to end (the 400-sample reference run and more, each sample a design and simulations)
pytestmark = pytest.mark.slow


def test_draws_do_not_depend_on_chunking(designed):
    """Sample i draws from SeedSequence([seed, i]): any sub-range gives the same values, exactly."""
    spec, _ = designed
    whole = draw_samples(spec.campaign, spec.motor, 0, 300)
    part = draw_samples(spec.campaign, spec.motor, 137, 211)
    for name, values in part.items():
        np.testing.assert_array_equal(values, whole[name][137:211], err_msg=name)
    other_seed = draw_samples(type(spec.campaign)(**{**spec.campaign.__dict__, "seed": 4}),
                              spec.motor, 0, 300)
    assert not np.array_equal(other_seed["R"], whole["R"])


def test_distributions_and_correlation(designed):
    """Marginals stay in their supports; the copula sets the rank correlation.

    Over 4000 motors (one row each, point 0): Ld, Lq: normal copula with
    r = 0.8, hence Spearman 6/pi asin(r/2) = 0.786. With n = 4000 the
    standard error of Spearman's rho is about (1 - rho^2)/sqrt(n) = 0.006;
    tolerance 0.03 (5 sigma). Uncorrelated pairs (R, flux): |rho| < 0.06
    (about 4 sigma of 1/sqrt(n)).
    """
    spec, _ = designed
    m = spec.motor
    P = spec.campaign.n_operating_points
    rows = draw_samples(spec.campaign, m, 0, 4000 * P)
    assert set(np.unique(rows["speed"])) == {0.0, 100.0}
    points = set(zip(rows["speed"], rows["speed_offset"], rows["delay_samples"]))
    assert len(points) == 8 and rows["delay_samples"].dtype.kind == "i"
    d = {k: v[rows["point"] == 0] for k, v in rows.items()}
    np.testing.assert_array_equal(d["motor"], np.arange(4000))
    assert np.all((d["R"] >= m.R * 1.0) & (d["R"] <= m.R * 1.4))
    assert np.all((d["Ld"] >= m.Ld * 0.7) & (d["Ld"] <= m.Ld * 1.0))
    assert np.all((d["Lq"] >= m.Lq * 0.5) & (d["Lq"] <= m.Lq * 1.0))
    flux = d["flux"] / m.flux  # normal(0.95, 0.02): mean within 4 standard errors
    assert abs(flux.mean() - 0.95) < 4 * 0.02 / np.sqrt(4000)
    assert abs(flux.std() - 0.02) < 0.002
    assert spearmanr(d["Ld"], d["Lq"])[0] == pytest.approx(6 / np.pi * np.arcsin(0.4), abs=0.03)
    assert abs(spearmanr(d["R"], d["flux"])[0]) < 0.06


def test_every_motor_at_every_point(designed):
    """Row i is motor i // P at point i % P: a motor's rows share its drawn
    parameters exactly and cover the grid once, whatever range is drawn."""
    from toolbox.campaign._sampling import point_values

    spec, _ = designed
    cfg = spec.campaign
    P = cfg.n_operating_points
    d = draw_samples(cfg, spec.motor, 13, 13 + 5 * P)  # starts mid-motor
    np.testing.assert_array_equal(d["motor"], np.arange(13, 13 + 5 * P) // P)
    np.testing.assert_array_equal(d["point"], np.arange(13, 13 + 5 * P) % P)
    for motor in np.unique(d["motor"]):
        sel = d["motor"] == motor
        for name in ("R", "Ld", "Lq", "flux"):
            assert np.unique(d[name][sel]).size == 1, name
    for i in range(len(d["sample"])):
        for key, value in point_values(cfg, d["point"][i]).items():
            assert d[key][i] == value
    full = draw_samples(cfg, spec.motor, 16, 24)  # motor 2 whole
    assert sorted(full["point"]) == list(range(P))


def test_measured_rows_are_drawn(tmp_path):
    """Each sample takes one measured motor; a scale draw multiplies its value."""
    path = write_spec(tmp_path, extra='[campaign.measured]\ncolumns = ["Ld", "J"]\n'
                                      'rows = [[1.3e-3, 0.01], [1.5e-3, 0.02]]\n')
    spec = load_spec(path)
    d = draw_samples(spec.campaign, spec.motor, 0, 200)
    row = d["measured_row"]
    assert set(np.unique(row)) == {0, 1}
    np.testing.assert_array_equal(d["J"], np.where(row == 0, 0.01, 0.02))
    ratio = d["Ld"] / np.where(row == 0, 1.3e-3, 1.5e-3)  # truncnormal scale in [0.7, 1]
    assert np.all((ratio >= 0.7 - 1e-12) & (ratio <= 1.0 + 1e-12))


def test_table_complete_and_judged(serial_run, designed):
    """One row per sample, and ``passed`` recomputed independently from the columns."""
    spec, _ = designed
    t = serial_run.table
    assert t.num_rows == 400
    np.testing.assert_array_equal(t.column("sample").to_numpy(), np.arange(400))
    col = {c: t.column(c).to_numpy(zero_copy_only=False) for c in t.column_names}
    ok = ((col["iq_step.overshoot_pct"] <= 5.0) & (col["iq_step.rise_time_10_90"] <= 0.006)
          & (np.minimum(col["margin.d.phase_margin_deg"], col["margin.q.phase_margin_deg"]) >= 55)
          & np.isfinite(col["iq_step.final_value"]))
    np.testing.assert_array_equal(col["passed"], ok)
    assert 0 < (~ok).sum() < 400  # the bounds make some samples fail (both branches tested)
    failing = np.nonzero(~ok)[0]
    assert all(col["failure"][i] for i in failing)
    assert not any(col["failure"][i] for i in np.nonzero(ok)[0])
    assert np.all(col["worst_ratio"][failing] > 1) and np.all(col["worst_ratio"][ok] <= 1)
    sm = serial_run.summary
    assert sm["passed"] == ok.sum() and sm["yield"] == pytest.approx(ok.mean())
    assert sum(sm["failure_reasons"].values()) >= (~ok).sum()


def test_chunk_size_does_not_change_rows(designed, serial_run, tmp_path):
    """Another chunking (one chunk of 400 instead of four of 100) gives the same rows.

    Exact equality: each closed loop is integrated on its own in the batch
    kernel and the margins are computed elementwise, so a row depends on its
    sample only (if this ever needs a tolerance, something shares state).
    """
    spec = load_spec(write_spec(tmp_path, chunk_size=400))
    run = run_campaign(spec, tmp_path / "one", scheduler="serial", artifact=designed[1],
                       report=False)
    assert run.chunks_total == 1
    assert run.table.equals(serial_run.table)


def test_interrupted_campaign_resumes(designed, serial_run, tmp_path):
    """Kill after two chunks (the progress callback raises), then resume: only the
    missing chunks run and the table equals the uninterrupted one. A truncated
    chunk file is not trusted and is run again."""
    spec, artifact = designed
    out = tmp_path / "c"
    calls = []

    def stop_after_two(done, total):
        calls.append(done)
        if done >= 200:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_campaign(spec, out, scheduler="serial", artifact=artifact, progress=stop_after_two)
    assert valid_chunks(out, spec, artifact) == {(0, 100), (100, 200)}
    assert not (out / "results.parquet").exists()
    first = chunk_path(out, 100, 200)
    first.write_bytes(first.read_bytes()[:-100])  # a damaged file is redone
    assert valid_chunks(out, spec, artifact) == {(0, 100)}
    stale = [out / "chunks" / ".rows-000000000200-000000000300.parquet.k9Xa01bc",
             out / ".results.parquet.zz12ab34"]
    for path in stale:  # temporaries of a write killed midway
        path.write_bytes(b"PAR1 half")
    run = run_campaign(spec, out, scheduler="serial", artifact=artifact, report=False)
    assert not any(path.exists() for path in stale)
    assert (run.chunks_resumed, run.chunks_run) == (1, 3)
    assert run.table.equals(serial_run.table)
    again = run_campaign(spec, out, scheduler="serial", artifact=artifact, report=False)
    assert (again.chunks_resumed, again.chunks_run) == (4, 0)
    assert pq.read_table(out / "results.parquet").equals(serial_run.table)


def test_other_campaign_in_out_dir_refused(designed, serial_run, tmp_path):
    """Rows of another campaign are never mixed in: another seed (or any
    row-changing key) is refused; min_yield and the title change no row."""
    import shutil

    out = shutil.copytree(serial_run.out_dir, tmp_path / "copy")
    path = write_spec(tmp_path)
    path.write_text(path.read_text().replace("seed = 3", "seed = 4"))
    with pytest.raises(SpecError, match="another spec, campaign table or controller"):
        run_campaign(load_spec(path), out, scheduler="serial", artifact=designed[1])
    path = write_spec(tmp_path)
    path.write_text(path.read_text().replace("seed = 3", "seed = 3\nmin_yield = 0.5")
                    .replace('title = "campaign test', 'title = "renamed campaign test'))
    again = run_campaign(load_spec(path), out, scheduler="serial",
                         artifact=designed[1], report=False)
    assert (again.chunks_resumed, again.chunks_run) == (4, 0)
    assert again.summary["min_yield"] == 0.5


def test_extending_samples_reuses_rows(designed, serial_run, tmp_path):
    """samples is no part of the hash: 400 -> 520 runs only rows 400 .. 519
    (one chunk of 120, the explicit chunk_size of 100 split them 100 + 20)
    and the table equals a fresh 520-row run's; 400 -> 300 runs nothing and
    gives the first 300 rows."""
    import shutil

    spec, artifact = designed
    out = shutil.copytree(serial_run.out_dir, tmp_path / "copy")
    more = run_campaign(load_spec(write_spec(tmp_path, samples=520)),
                        out, scheduler="serial", artifact=artifact, report=False)
    assert (more.chunks_resumed, more.chunks_run) == (4, 2)
    assert valid_chunks(out, load_spec(write_spec(tmp_path, samples=520)), artifact) == {
        (0, 100), (100, 200), (200, 300), (300, 400), (400, 500), (500, 520)}
    fresh = run_campaign(load_spec(write_spec(tmp_path, samples=520, chunk_size=520)),
                         tmp_path / "fresh", scheduler="serial", artifact=artifact,
                         report=False)
    assert more.table.equals(fresh.table)
    assert more.table.slice(0, 400).equals(serial_run.table)
    less = run_campaign(load_spec(write_spec(tmp_path, samples=300)), out, scheduler="serial",
                        artifact=artifact, report=False)
    assert less.chunks_run == 0 and less.table.equals(serial_run.table.slice(0, 300))
    assert less.summary["motors"] == 38  # 300 rows of 8 points: 37 complete motors
    assert less.summary["yields"]["per_motor"]["n"] == 37


def test_resume_rechunks(designed, serial_run, tmp_path):
    """The chunk size is no part of the hash: a campaign interrupted after
    two chunks of 100 resumes with chunks of 150 (rows 200 .. 349, 350 .. 399),
    and the table is the uninterrupted one."""
    spec, artifact = designed
    out = tmp_path / "c"

    def stop(done, total):
        if done >= 200:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_campaign(spec, out, scheduler="serial", artifact=artifact, progress=stop)
    spec150 = load_spec(write_spec(tmp_path, chunk_size=150))
    run = run_campaign(spec150, out, scheduler="serial", artifact=artifact, report=False)
    assert (run.chunks_resumed, run.chunks_run, run.chunk_size) == (2, 2, 150)
    assert valid_chunks(out, spec150, artifact) == {(0, 100), (100, 200), (200, 350),
                                                     (350, 400)}
    assert run.table.equals(serial_run.table)


@pytest.mark.parametrize("samples, threads, given, expected", [
    (400, 1, None, 250),            # 400 / 4 = 100, raised to MIN_CHUNK
    (1000, 2, None, 250),           # 1000 / (4 x 2)
    (100, 4, None, 100),            # never more than the campaign
    (40_000, 2, None, 5000),
    (1_000_000, 2, None, 10_000),   # capped: 100 chunks
    (10_000_000, 64, None, 10_000),
    (1_000_000, 2, 777, 777),       # the spec's own chunk_size wins
])
def test_chunk_size_from_samples_and_workers(tmp_path, samples, threads, given, expected):
    from toolbox.campaign import chunk_size

    path = write_spec(tmp_path, samples=samples, chunk_size=given or 1)
    if given is None:
        path.write_text(path.read_text().replace("chunk_size = 1\n", ""))
    assert chunk_size(load_spec(path), threads) == expected


def test_new_requirements_rejudge_stored_rows(designed, serial_run, tmp_path):
    """The requirements are no part of the hash: a tighter overshoot bound
    runs no chunk, and passed is the stored metrics judged again (checked
    here from the columns, independently of judge_rows)."""
    import shutil

    out = shutil.copytree(serial_run.out_dir, tmp_path / "copy")
    path = write_spec(tmp_path)
    path.write_text(path.read_text().replace("max_overshoot_pct = 5.0",
                                             "max_overshoot_pct = 1.0"))
    run = run_campaign(load_spec(path), out, scheduler="serial", artifact=designed[1],
                       report=False)
    assert run.chunks_run == 0
    t = run.table
    col = {c: t.column(c).to_numpy(zero_copy_only=False) for c in t.column_names}
    ok = ((col["iq_step.overshoot_pct"] <= 1.0) & (col["iq_step.rise_time_10_90"] <= 0.006)
          & (np.minimum(col["margin.d.phase_margin_deg"], col["margin.q.phase_margin_deg"]) >= 55)
          & np.isfinite(col["iq_step.final_value"]))
    np.testing.assert_array_equal(col["passed"], ok)
    assert ok.sum() < serial_run.summary["passed"]  # the bound bites: rows re-judged
    assert any("bound 1)" in f for f in col["failure"])


def test_outputs_and_report(serial_run):
    """summary.json, results.parquet, controller.json and an escaped report with figures."""
    out = serial_run.out_dir
    summary = json.loads((out / "summary.json").read_text())
    assert summary["samples"] == 400 and len(summary["worst_cases"]) == 10
    assert summary["worst_cases"][0]["worst_ratio"] >= summary["worst_cases"][-1]["worst_ratio"]
    assert {e["parameter"] for e in summary["sensitivity"]} == {"R", "Ld", "Lq", "flux", "speed",
                                                                "speed_offset", "delay_samples"}
    assert json.loads((out / "controller.json").read_text())["method"] == "pi"
    html = (out / "report.html").read_text()
    assert "campaign test &lt;on&gt; paper 003" in html and "<on>" not in html
    for fig in ("fig-scatter", "fig-parallel", "fig-sensitivity", "fig-margins", "fig-ratio"):
        assert f'id="{fig}"' in html
    assert html.count("<svg") >= 6
    assert "Worst cases" in html and "Yield" in html


def test_cli_campaign_exit_codes(designed, tmp_path):
    """Exit 0 without min_yield, 1 when the yield is below it (outputs written)."""
    path = write_spec(tmp_path, samples=100, chunk_size=50)
    res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(tmp_path / "a"),
                                    "--scheduler", "serial"])
    assert res.exit_code == 0, res.output
    assert "13 motors x 8 operating points = 100 samples" in res.output
    assert "2 chunks run (50 rows each), 0 resumed" in res.output
    assert "per-sample yield" in res.output and "per-motor yield (12 motors" in res.output
    # progress on stderr (no terminal here: one line per tenth), then the files
    assert "- campaign: 50/100 samples" in res.stderr and "- campaign: 100/100" in res.stderr
    assert "wrote " in res.stderr and "results.parquet" in res.stderr
    text = path.read_text().replace("seed = 3", "seed = 3\nmin_yield = 1.0")
    path.write_text(text)
    res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(tmp_path / "b"),
                                    "--scheduler", "serial", "-q"])
    summary = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert summary["failed"] > 0  # or exit 1 would not be tested
    assert res.exit_code == 1, res.output
    assert "min_yield 1 on the per-sample yield's 95 % lower bound" in res.output
    assert "FAIL" in res.output
    res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(tmp_path / "c"),
                                    "--scheduler", "nowhere"])
    assert res.exit_code == 2 and "--scheduler" in res.output


def test_rows_match_single_simulations(designed, serial_run):
    """A row's metrics are those of simulating that sample alone at its operating
    point (initial speed, speed-sensor offset, computation delay): the grouping
    by operating point maps every sample to its own point. Exact equality: the
    same kernel on the same inputs."""
    from dataclasses import replace

    from toolbox.campaign import make_plan
    from toolbox.sim import simulate_batch

    spec, artifact = designed
    _slug, scenario, law, drive = make_plan(spec, artifact).runs[0]
    t = serial_run.table
    picked = set()
    for i in range(t.num_rows):
        row = {c: t.column(c)[i].as_py() for c in t.column_names}
        point = (row["speed"], row["speed_offset"], row["delay_samples"])
        if point in picked:
            continue
        picked.add(point)
        motor = spec.motor.with_overrides({k: row[k] for k in ("R", "Ld", "Lq", "flux")})
        sc = replace(scenario, initial_speed=row["speed"], speed_offset=row["speed_offset"])
        res = simulate_batch(law, [motor], sc, replace(drive, delay_samples=row["delay_samples"]))
        for m in ("rise_time_10_90", "overshoot_pct", "mse_iq", "final_value"):
            assert res.metrics[m][0] == row[f"iq_step.{m}"] or (
                np.isnan(res.metrics[m][0]) and row[f"iq_step.{m}"] is None), (i, m)
    assert len(picked) == 8


def test_candidate_controller(serial_run, tmp_path):
    """--controller simulates another design (a candidate) on the same campaign:
    other rows, another campaign hash (its chunks are never mixed with the
    spec's own design), and a design for another sample time is refused."""
    import shutil

    spec_path = write_spec(tmp_path)
    text = spec_path.read_text()
    runner = CliRunner()
    candidate = tmp_path / "candidate.toml"
    candidate.write_text(text.replace("bandwidth = 600.0", "bandwidth = 400.0"))
    res = runner.invoke(main, ["design", str(candidate), "--out", str(tmp_path / "d400"),
                               "--only-controller", "-q"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["campaign", str(spec_path), "--out", str(tmp_path / "c400"),
                               "--controller", str(tmp_path / "d400"), "--scheduler", "serial",
                               "-q", "--no-report"])
    assert res.exit_code in (0, 1), res.output
    rows = pq.read_table(tmp_path / "c400" / "results.parquet")
    assert rows.num_rows == 400
    slow = rows.column("iq_step.rise_time_10_90").to_numpy()
    fast = serial_run.table.column("iq_step.rise_time_10_90").to_numpy()
    assert np.nanmedian(slow) > 1.3 * np.nanmedian(fast)  # 400 vs 600 rad/s: about 1.5 x
    out = shutil.copytree(serial_run.out_dir, tmp_path / "copy")
    res = runner.invoke(main, ["campaign", str(spec_path), "--out", str(out), "--controller",
                               str(tmp_path / "d400"), "--scheduler", "serial", "-q"])
    assert res.exit_code == 2 and "another spec, campaign table or controller" in res.output
    other_ts = tmp_path / "ts.toml"
    other_ts.write_text(text.replace("sample_time = 1e-4", "sample_time = 5e-5"))
    res = runner.invoke(main, ["design", str(other_ts), "--out", str(tmp_path / "d_ts"),
                               "--only-controller", "-q"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["campaign", str(spec_path), "--out", str(tmp_path / "c_ts"),
                               "--controller", str(tmp_path / "d_ts"), "--scheduler", "serial"])
    assert res.exit_code == 2 and "--controller: expected a design for drive.sample_time" in res.output
    assert not (tmp_path / "c_ts").exists()


@pytest.mark.parametrize("bounds, passed", [
    ("min_phase_margin_deg = 1\n", 40),         # every sample passes
    ("max_rise_time = 1e-6\n", 0),               # below one sample period: none passes
])
def test_yield_extremes(designed, tmp_path, bounds, passed):
    """All pass or all fail: the summary and report are still written (no
    sensitivity can be ranked: the correlations are null, not NaN)."""
    path = write_spec(tmp_path, samples=40, chunk_size=20)
    text = path.read_text()
    head, rest = text.split("[requirements]\n", 1)
    rest = rest.split("[[scenario]]", 1)[1]
    path.write_text(head + "[requirements]\n" + bounds + "[[scenario]]" + rest)
    run = run_campaign(load_spec(path), tmp_path / "out", scheduler="serial",
                       artifact=designed[1])
    sm = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert sm["passed"] == passed and sm["samples"] == 40
    assert all(e["rank_correlation"] is None for e in sm["sensitivity"])
    assert "Yield" in (tmp_path / "out" / "report.html").read_text()
    assert run.passed  # no min_yield: the exit code does not depend on the yield


def test_yields_recomputed_from_the_table(serial_run, designed):
    """Per-motor: a motor passes when all its 8 rows pass; per-point: the
    yield at each grid point, the figure is the worst point's lower bound."""
    from toolbox.campaign import wilson_interval

    spec, _ = designed
    t = serial_run.table
    motor = t.column("motor").to_numpy()
    point = t.column("point").to_numpy()
    passed = t.column("passed").to_numpy(zero_copy_only=False)
    ys = serial_run.summary["yields"]
    good = [all(passed[motor == m]) for m in range(50)]
    assert ys["per_motor"]["n"] == 50 and ys["per_motor"]["passed"] == sum(good)
    assert ys["per_motor"]["yield_95"] == list(wilson_interval(sum(good), 50))
    assert ys["per_motor"]["yield"] <= ys["per_sample"]["yield"]
    per_point = [passed[point == p].mean() for p in range(8)]
    assert [e["yield"] for e in ys["per_point"]["points"]] == per_point
    lows = [wilson_interval(int(passed[point == p].sum()), 50)[0] for p in range(8)]
    assert ys["per_point"]["yield_95"][0] == min(lows)
    assert serial_run.summary["gate"] == "per_sample"
    assert serial_run.summary["gate_lower_95"] == ys["per_sample"]["yield_95"][0]
    # each failure mode ranked on its own; the grid cells count them
    modes = serial_run.summary["sensitivity_by_mode"]
    assert set(modes) == set(serial_run.summary["failure_reasons"])
    for mode, count in serial_run.summary["failure_reasons"].items():
        assert sum(e["failures"].get(mode, 0) for e in ys["per_point"]["points"]) == count


@pytest.mark.parametrize("gate", ["per_sample", "per_motor", "per_point"])
def test_gate_on_lower_bound(designed, serial_run, tmp_path, gate):
    """min_yield is held against the chosen yield's 95 % lower bound; the gate
    and min_yield change no row (the chunks are kept)."""
    import shutil

    out = shutil.copytree(serial_run.out_dir, tmp_path / "copy")
    y = serial_run.summary["yields"][gate]
    lo, mid = y["yield_95"][0], y["yield"]
    for min_yield, meets in ((lo * 0.999, True), ((lo + mid) / 2, False)):
        path = write_spec(tmp_path)
        path.write_text(path.read_text().replace(
            "seed = 3", f'seed = 3\nmin_yield = {min_yield!r}\ngate = "{gate}"'))
        run = run_campaign(load_spec(path), out, scheduler="serial", artifact=designed[1],
                           report=False)
        assert (run.chunks_resumed, run.chunks_run) == (4, 0)
        assert run.summary["gate"] == gate and run.passed is meets


def test_provenance_pinned(serial_run, designed, tmp_path, monkeypatch):
    """Version and source hash in every chunk's and results.parquet's metadata
    (with seed and spec hash); a resume under another build is refused with
    both builds named."""
    import shutil

    from toolbox._version import source_hash, toolbox_version
    from toolbox.campaign import _store

    meta = json.loads(pq.read_schema(serial_run.out_dir / "results.parquet").metadata[b"cct"])
    assert meta["toolbox"] == toolbox_version() and meta["source"] == source_hash()
    assert meta["seed"] == 3 and len(meta["spec_sha256"]) == 64
    chunk = json.loads(pq.read_schema(chunk_path(serial_run.out_dir, 200, 300)).metadata[b"cct"])
    assert (chunk["toolbox"], chunk["source"], chunk["start"]) == (toolbox_version(),
                                                                   source_hash(), 200)
    out = shutil.copytree(serial_run.out_dir, tmp_path / "copy")
    monkeypatch.setattr(_store, "source_hash", lambda: "f" * 64)
    spec, artifact = designed
    with pytest.raises(SpecError) as info:
        run_campaign(spec, out, scheduler="serial", artifact=artifact)
    text = str(info.value)
    assert f"computed by toolbox {toolbox_version()} (source {source_hash()[:12]})" in text
    assert f"this is toolbox {toolbox_version()} (source ffffffffffff)" in text


def test_worst_cases_as_ready_to_run_specs(serial_run, designed, tmp_path):
    """worst/sample-NNNNNN.toml: the spec without [campaign], the drawn motor as
    the scenario's true plant and the operating point; cct design reproduces
    the row's metrics exactly (a failing sample at the design's own delay)."""
    from toolbox.campaign._summary import worst_spec

    out = serial_run.out_dir
    names = serial_run.summary["worst_specs"]
    assert len(names) == 5 and all((out / n).is_file() for n in names)
    assert all(load_spec(out / n).campaign is None for n in names)
    t = serial_run.table
    passed = t.column("passed").to_numpy(zero_copy_only=False)
    delay = t.column("delay_samples").to_numpy()
    i = int(np.nonzero(~passed & (delay == 1))[0][0])
    row = {c: t.column(c)[i].as_py() for c in t.column_names}
    path = tmp_path / "one.toml"
    path.write_text(worst_spec(designed[0], row))
    spec = load_spec(path)
    sc = spec.scenarios[0]
    assert spec.campaign is None
    assert sc.plant_values == {k: row[k] for k in ("R", "Ld", "Lq", "flux")}
    assert (sc.initial_speed, sc.speed_offset) == (row["speed"], row["speed_offset"])
    res = CliRunner().invoke(main, ["design", str(path), "--out", str(tmp_path / "d"), "-q"])
    assert res.exit_code == 1, res.output  # the sample fails its requirement again
    metrics = json.loads((tmp_path / "d" / "verify.json").read_text())["scenarios"][0]["metrics"]
    for m in ("overshoot_pct", "rise_time_10_90", "mse_iq"):
        assert metrics[m] == row[f"iq_step.{m}"], m
    html = (out / "report.html").read_text()
    assert "Per motor (every point)" in html and "Failure rate by operating point" in html
    assert "Drivers of each failure mode" in html and names[0] in html
