"""Campaigns on Dask: LocalCluster, and a real cluster that loses a worker
(toolbox/ARCHITECTURE.md "Campaigns": no lost work, same table on any cluster).

A ``dask scheduler`` and two ``dask worker`` processes (no nanny, so a killed
worker stays dead) are started on 127.0.0.1 only; the first finished chunk
kills one worker with SIGKILL while the others are queued or running. The
scheduler reschedules the lost worker's tasks on the survivor: the table
must be complete and equal, exactly, to the LocalCluster run and to the
in-process run (a row depends on its sample only). Every process is started
in its own session and killed at teardown; waits are bounded.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from toolbox.campaign import run_campaign

#: slow: real Dask clusters
pytestmark = pytest.mark.slow

#: Seconds to wait for the scheduler file / the workers to register.
START_TIMEOUT = 60


def _dask(*args: str, log: Path) -> subprocess.Popen:
    exe = Path(sys.executable).parent / "dask"
    cmd = [str(exe), *args] if exe.exists() else [sys.executable, "-m", "dask", *args]
    return subprocess.Popen(cmd, stdout=log.open("wb"), stderr=subprocess.STDOUT,
                            start_new_session=True, env={**os.environ, "PYTHONPATH":
                            str(Path(__file__).resolve().parents[2])})


@pytest.fixture
def cluster(tmp_path):
    """``(address, [worker processes])`` of a loopback scheduler and two workers."""
    sched_file = tmp_path / "scheduler.json"
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                   "--scheduler-file", str(sched_file), log=tmp_path / "scheduler.log")]
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not sched_file.exists():
            assert time.monotonic() < deadline, (tmp_path / "scheduler.log").read_text()
            assert procs[0].poll() is None, (tmp_path / "scheduler.log").read_text()
            time.sleep(0.2)
        time.sleep(0.2)  # the file is written whole, but be sure it is complete
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        workers = [_dask("worker", "--scheduler-file", str(sched_file), "--host", "127.0.0.1",
                         "--nthreads", "1", "--no-nanny", "--no-dashboard",
                         "--death-timeout", "60", "--name", f"w{k}",
                         log=tmp_path / f"worker{k}.log") for k in range(2)]
        procs += workers
        yield address, workers
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=30)


def test_local_cluster_equals_serial(designed, serial_run, tmp_path):
    """The default engine (LocalCluster, 2 workers) gives the in-process table, exactly."""
    spec, artifact = designed
    run = run_campaign(spec, tmp_path / "local", workers=2, artifact=artifact, report=False)
    assert run.chunks_run == 4
    assert run.table.equals(serial_run.table)


def test_killed_worker_chunks_are_retried(designed, serial_run, cluster, tmp_path):
    """16 chunks of 25 on two single-thread workers. At the first finished chunk
    a monitor client asks the scheduler which worker is running a chunk and
    that worker is killed (SIGKILL): its running chunk can only reach the
    table by being run again on the survivor."""
    from campaign_helpers import write_spec
    from dask.distributed import Client

    from toolbox.spec import load_spec

    spec = load_spec(write_spec(tmp_path, chunk_size=25))
    artifact = designed[1]
    address, workers = cluster
    killed = []
    monitor = Client(address, timeout=30)
    try:
        def kill_busy(done, total):
            if done == 0 or killed:
                return
            processing = monitor.processing()
            # read after processing(): a worker that registered late (a loaded
            # machine) is then known; before, it raised KeyError on its address
            info = monitor.scheduler_info()["workers"]
            for addr, keys in processing.items():
                chunks = [k for k in keys if "cct-rows" in str(k)]
                if chunks and not killed and addr in info:
                    k = int(info[addr]["name"][1:])
                    workers[k].send_signal(signal.SIGKILL)
                    workers[k].wait(timeout=30)
                    killed.append((done, k, chunks))

        run = run_campaign(spec, tmp_path / "remote", scheduler=address, workers=2,
                           artifact=artifact, progress=kill_busy, report=False)
    finally:
        monitor.close()
    assert killed, "no worker was running a chunk at any progress report"
    done, k, running = killed[0]
    assert done < spec.campaign.samples and running  # killed mid-campaign, mid-chunk
    assert workers[k].poll() is not None and workers[1 - k].poll() is None
    assert run.chunks_run == spec.campaign.n_chunks
    np.testing.assert_array_equal(run.table.column("sample").to_numpy(),
                                  np.arange(spec.campaign.samples))
    # the same rows as the uninterrupted in-process run (chunks of 100)
    assert run.table.equals(serial_run.table)
