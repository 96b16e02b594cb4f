"""Failures during a campaign: chunks that raise, and a scheduler lost mid-run.

* A chunk whose task raises is submitted again, at most ``CHUNK_ATTEMPTS``
  (3) times in a run, then its rows are written as error rows (judged
  failing, failure mode ``error``) and the other chunks go on; the next run
  evaluates the error rows again. The fault is injected through
  :func:`campaign_helpers.flaky_evaluate`, which logs every attempt to a
  directory (the LocalCluster's worker processes import it like the client:
  multiprocessing passes ``sys.path`` on), so the attempts are counted
  across processes.
* A real ``dask scheduler`` and two workers (subprocesses in their own
  session, 127.0.0.1 only) run ``cct campaign`` (a subprocess too: its
  stderr is what a CI log shows); the scheduler is killed (SIGKILL) once the
  first chunk file is on disk: exit 4, one line, no traceback, the chunks
  written kept; a rerun on a new scheduler resumes from them and the table
  is the in-process one. Every wait is bounded.
"""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from campaign_helpers import flaky_evaluate, write_spec
from click.testing import CliRunner

from toolbox.campaign import CHUNK_ATTEMPTS, run_campaign, valid_chunks
from toolbox.cli import main
from toolbox.spec import load_spec

pytestmark = pytest.mark.slow   # real Dask schedulers and workers, killed mid-run

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT = 60


def _attempts(log: Path) -> dict[int, int]:
    return {int(p.name): len(p.read_text().splitlines()) for p in log.iterdir()}


@pytest.mark.parametrize("scheduler", ["serial", "local"])
def test_failing_chunk_becomes_error_rows_after_the_limit(designed, serial_run, tmp_path,
                                                          monkeypatch, scheduler):
    """Rows 200 .. 299 always raise: 3 attempts (not one more), then 100 error
    rows; rows 100 .. 199 raise twice and pass at the third attempt. The
    other rows are the in-process run's; a rerun without the fault
    evaluates only the error rows and gives the uninterrupted table."""
    from toolbox.campaign import _run

    spec, artifact = designed
    log = tmp_path / "log"
    log.mkdir()
    monkeypatch.setattr(_run, "evaluate_chunk", functools.partial(
        flaky_evaluate, str(log), {200: CHUNK_ATTEMPTS + 5, 100: 2}))
    out = tmp_path / "out"
    run = run_campaign(spec, out, scheduler=scheduler, workers=2, artifact=artifact,
                       report=False)
    assert CHUNK_ATTEMPTS == 3
    assert _attempts(log) == {0: 1, 100: 3, 200: 3, 300: 1}
    assert run.error_rows == 100 and run.summary["error_rows"] == 100
    t, ref = run.table, serial_run.table
    passed = t.column("passed").to_numpy(zero_copy_only=False)
    failure = t.column("failure").to_numpy(zero_copy_only=False)
    assert not passed[200:300].any()
    assert all(f.startswith("error = RuntimeError: injected fault at rows 200..299")
               for f in failure[200:300])
    assert t.column("iq_step.overshoot_pct").null_count == 100
    np.testing.assert_array_equal(t.column("R").to_numpy()[200:300],
                                  ref.column("R").to_numpy()[200:300])  # the draws are kept
    keep = np.r_[0:200, 300:400]
    assert t.take(keep).equals(ref.take(keep))
    assert run.summary["failure_reasons"]["error"] == 100
    assert run.summary["passed"] == int(ref.column("passed").to_numpy(
        zero_copy_only=False)[keep].sum())
    assert valid_chunks(out, spec, artifact) == {(0, 100), (100, 200), (300, 400)}
    monkeypatch.undo()
    again = run_campaign(spec, out, scheduler="serial", artifact=artifact, report=False)
    assert (again.chunks_resumed, again.chunks_run, again.error_rows) == (3, 1, 0)
    assert again.table.equals(ref)


def test_cli_error_rows_exit_codes(designed, tmp_path, monkeypatch):
    """Error rows count as failing: the gate met anyway -> exit 0 with a
    warning; missed -> exit 4 (a broken run, not a failed qualification),
    one line naming the error."""
    from toolbox.campaign import _run

    log = tmp_path / "log"
    log.mkdir()
    monkeypatch.setattr(_run, "evaluate_chunk", functools.partial(
        flaky_evaluate, str(log), {8: 99}))
    for min_yield, code in ((0.01, 0), (0.9, 4)):
        path = write_spec(tmp_path, samples=16, chunk_size=8)
        path.write_text(path.read_text().replace("seed = 3\n", f"seed = 3\nmin_yield = "
                                                 f"{min_yield}\n"))
        res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(tmp_path / f"o{code}"),
                                        "--scheduler", "serial", "-q", "--no-report"])
        assert res.exit_code == code, res.output
        assert "Traceback" not in res.output
        lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
        assert len(lines) == 1, res.stderr
        assert "8 samples could not be evaluated" in lines[0]
        assert "injected fault at rows 8..15" in lines[0]
        assert lines[0].startswith("cct: warning:" if code == 0 else
                                   "cct: infrastructure error:")


def _dask(*args: str, log: Path) -> subprocess.Popen:
    exe = Path(sys.executable).parent / "dask"
    cmd = [str(exe), *args] if exe.exists() else [sys.executable, "-m", "dask", *args]
    return subprocess.Popen(cmd, stdout=log.open("wb"), stderr=subprocess.STDOUT,
                            start_new_session=True, env={**os.environ, "PYTHONPATH": str(ROOT)})


def _stop(p: subprocess.Popen) -> None:
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGKILL)
    p.wait(timeout=30)


def _start_cluster(tmp_path: Path, tag: str, procs: list) -> tuple[str, subprocess.Popen]:
    """A loopback scheduler and two single-thread workers; ``(address, scheduler)``."""
    sched_file = tmp_path / f"scheduler-{tag}.json"
    sched = _dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                  "--scheduler-file", str(sched_file), log=tmp_path / f"scheduler-{tag}.log")
    procs.append(sched)
    deadline = time.monotonic() + START_TIMEOUT
    while not sched_file.exists():
        assert time.monotonic() < deadline and sched.poll() is None, \
            (tmp_path / f"scheduler-{tag}.log").read_text()
        time.sleep(0.2)
    time.sleep(0.3)
    address = json.loads(sched_file.read_text())["address"]
    for k in range(2):
        procs.append(_dask("worker", address, "--host", "127.0.0.1", "--nthreads", "1",
                           "--no-nanny", "--no-dashboard", "--death-timeout", "60",
                           log=tmp_path / f"worker-{tag}-{k}.log"))
    return address, sched


def _cct(*args: str) -> list[str]:
    return [sys.executable, "-m", "toolbox.cli", *args]


def test_scheduler_lost_mid_run_exit_4_and_resume(designed, tmp_path):
    """Kill the scheduler once the first chunk is written: exit 4 within a
    bounded time, one line on stderr, no traceback; the chunks written are
    kept and a rerun on a new scheduler resumes from them."""
    spec_path = write_spec(tmp_path, samples=2400, chunk_size=40)
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs: list = []
    try:
        address, sched = _start_cluster(tmp_path, "a", procs)
        cli = subprocess.Popen(_cct("campaign", str(spec_path), "--out", str(out), "-q",
                                    "--no-report", "--scheduler", address, "--workers", "2"),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
        procs.append(cli)
        deadline = time.monotonic() + 240
        while not list((out / "chunks").glob("rows-*.parquet")) if (out / "chunks").is_dir() \
                else True:
            assert time.monotonic() < deadline and cli.poll() is None, cli.communicate()
            time.sleep(0.05)
        os.killpg(sched.pid, signal.SIGKILL)
        killed = time.monotonic()
        stdout, stderr = cli.communicate(timeout=120)
        waited = time.monotonic() - killed
        text = stderr.decode()
        assert cli.returncode == 4, (stdout, text)
        assert "Traceback" not in text
        lines = [ln for ln in text.splitlines() if ln.strip()]
        assert len(lines) == 1, text
        assert lines[0].startswith(f"cct: infrastructure error: lost the Dask scheduler at "
                                   f"{address}") and "rerun the same command" in lines[0]
        assert waited < 60  # the connection checks are once a second
        kept = list((out / "chunks").glob("rows-*.parquet"))
        assert 0 < len(kept) < 60  # partial results kept
        assert not (out / "results.parquet").exists()
        for p in procs[1:3]:
            _stop(p)

        address2, _ = _start_cluster(tmp_path, "b", procs)
        res = subprocess.run(_cct("campaign", str(spec_path), "--out", str(out),
                                  "--no-report", "--scheduler", address2, "--workers", "2"),
                             capture_output=True, env=env, timeout=600)
        assert res.returncode in (0, 1), res.stderr.decode()
        assert f"{len(kept)} resumed" in res.stdout.decode()
    finally:
        for p in reversed(procs):
            _stop(p)
    spec = load_spec(spec_path)
    ref = run_campaign(spec, tmp_path / "serial", scheduler="serial", artifact=designed[1],
                       report=False)
    assert pq.read_table(out / "results.parquet").equals(ref.table)
