"""Exit codes a release gate can use: 2 bad input, 4 infrastructure.

Servers are started on 127.0.0.1 only and stop by themselves: a tiny HTTP
server and a banner-sending TCP server (threads), a real ``dask scheduler``
with workers that lack the toolbox or run another build of it (subprocesses
in their own session, killed at teardown). Every wait is bounded. The disk
failures are real where the machine allows it (a directory under /sys
cannot be created, even by root) and simulated otherwise (the atomic writer
raising ENOSPC / EROFS).
"""

from __future__ import annotations

import errno
import http.server
import json
import os
import shutil
import signal
import socket
import sys
import threading
import time
from pathlib import Path

import pytest
from campaign_helpers import write_spec
from click.testing import CliRunner

from toolbox.campaign import _cluster
from toolbox.cli import main

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT = 60


def _campaign(path, out, *extra):
    t0 = time.monotonic()
    res = CliRunner().invoke(main, ["campaign", str(path), "--out", str(out), "-q", *extra])
    return res, time.monotonic() - t0


def _one_line(res) -> str:
    """The CLI's message: one line, no traceback."""
    assert "Traceback" not in res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, res.stderr
    return lines[0]


@pytest.fixture
def small_spec(tmp_path):
    return write_spec(tmp_path, samples=16, chunk_size=8)


@pytest.mark.parametrize("address, fragment", [
    ("http://127.0.0.1:8786", "not HTTP"),
    ("tcp://127.0.0.1", "give the port"),
    ("127.0.0.1", "give the port"),
    ("tcp://127.0.0.1:99999", "1 to 65535"),
    ("tls://127.0.0.1:8786", "only tcp://"),
])
def test_bad_scheduler_address_exit_2(small_spec, tmp_path, address, fragment):
    res, _ = _campaign(small_spec, tmp_path / "out", "--scheduler", address)
    assert res.exit_code == 2, res.output
    line = _one_line(res)
    assert "--scheduler" in line and fragment in line
    assert not (tmp_path / "out").exists()


@pytest.fixture
def http_server():
    """An HTTP server on a loopback port: accepts, never speaks first."""
    srv = http.server.HTTPServer(("127.0.0.1", 0), http.server.BaseHTTPRequestHandler)
    srv.timeout = 1
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.2}, daemon=True)
    t.start()
    yield srv.server_address[1]
    srv.shutdown()
    srv.server_close()


@pytest.fixture
def banner_server():
    """A TCP server that sends an SSH banner on every connection (at most 5, 20 s)."""
    ls = socket.create_server(("127.0.0.1", 0))
    ls.settimeout(20)

    def serve():
        for _ in range(5):
            try:
                conn, _addr = ls.accept()
            except OSError:
                return
            with conn:
                conn.sendall(b"SSH-2.0-OpenSSH_9.2p1\r\n")
                time.sleep(0.5)

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    yield ls.getsockname()[1]
    ls.close()


@pytest.mark.slow
def test_http_server_on_scheduler_port_exit_4_within_30_s(small_spec, tmp_path, http_server):
    """The default deadlines are well under 30 s, and the run ends at the probe."""
    assert _cluster.PROBE_TIMEOUT + 1 < 30
    res, seconds = _campaign(small_spec, tmp_path / "out", "--scheduler",
                             f"tcp://127.0.0.1:{http_server}")
    assert res.exit_code == 4, res.output
    assert seconds < 30
    line = _one_line(res)
    assert "accepts connections but sent no Dask handshake" in line
    assert "dask scheduler" in line  # the hint


def test_banner_server_exit_4(small_spec, tmp_path, banner_server):
    res, seconds = _campaign(small_spec, tmp_path / "out", "--scheduler",
                             f"tcp://127.0.0.1:{banner_server}")
    assert res.exit_code == 4, res.output
    assert seconds < 30
    assert "is not a Dask scheduler: it answered 'SSH-2.0-OpenSSH" in _one_line(res)


def test_refused_port_exit_4(small_spec, tmp_path):
    s = socket.create_server(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nothing listens there now
    res, _ = _campaign(small_spec, tmp_path / "out", "--scheduler", f"tcp://127.0.0.1:{port}")
    assert res.exit_code == 4, res.output
    assert f"no Dask scheduler at tcp://127.0.0.1:{port}" in _one_line(res)


def _dask(*args: str, log: Path, pythonpath: Path) -> "subprocess.Popen":
    import subprocess

    exe = Path(sys.executable).parent / "dask"
    cmd = [str(exe), *args] if exe.exists() else [sys.executable, "-m", "dask", *args]
    return subprocess.Popen(cmd, stdout=log.open("wb"), stderr=subprocess.STDOUT,
                            start_new_session=True,
                            env={**os.environ, "PYTHONPATH": str(pythonpath)})


def _stop(p) -> None:
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGKILL)
    p.wait(timeout=30)


@pytest.mark.slow
def test_cluster_without_usable_workers_exit_4(small_spec, tmp_path, monkeypatch):
    """A real scheduler on 127.0.0.1: no worker, then a worker that cannot import
    the toolbox, then one of another build (a copy of the package with one
    file changed): exit 4 each time, with the builds named."""
    monkeypatch.setattr(_cluster, "WORKER_TIMEOUT", 3.0)
    sched_file = tmp_path / "scheduler.json"
    sched = _dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                  "--scheduler-file", str(sched_file), log=tmp_path / "scheduler.log",
                  pythonpath=ROOT)
    procs = [sched]
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not sched_file.exists():
            assert time.monotonic() < deadline and sched.poll() is None, \
                (tmp_path / "scheduler.log").read_text()
            time.sleep(0.2)
        time.sleep(0.3)
        address = json.loads(sched_file.read_text())["address"]

        res, _ = _campaign(small_spec, tmp_path / "o1", "--scheduler", address)
        assert res.exit_code == 4, res.output
        assert f"no Dask worker joined the scheduler at {address} within 3 s" in _one_line(res)

        def worker(pythonpath: Path, name: str):
            p = _dask("worker", address, "--host", "127.0.0.1", "--nthreads", "1",
                      "--no-nanny", "--no-dashboard", "--death-timeout", "60",
                      log=tmp_path / f"{name}.log", pythonpath=pythonpath)
            procs.append(p)
            return p

        fake = tmp_path / "no_toolbox" / "toolbox"
        fake.mkdir(parents=True)
        (fake / "__init__.py").write_text(
            'raise ModuleNotFoundError("No module named \'toolbox\'", name="toolbox")\n')
        w1 = worker(fake.parent, "w_missing")
        monkeypatch.setattr(_cluster, "WORKER_TIMEOUT", 60.0)
        res, _ = _campaign(small_spec, tmp_path / "o2", "--scheduler", address)
        assert res.exit_code == 4, res.output
        line = _one_line(res)
        assert "cannot import the toolbox" in line and "No module named 'toolbox'" in line
        _stop(w1)

        other = tmp_path / "other_build"
        shutil.copytree(ROOT / "toolbox", other / "toolbox",
                        ignore=shutil.ignore_patterns("__pycache__"))
        with (other / "toolbox" / "_version.py").open("a") as fh:
            fh.write("\n# another build\n")
        worker(other, "w_other")
        res, _ = _campaign(small_spec, tmp_path / "o3", "--scheduler", address)
        assert res.exit_code == 4, res.output
        line = _one_line(res)
        from toolbox._version import source_hash, toolbox_version

        assert f"this client toolbox {toolbox_version()} (source {source_hash()[:12]})" in line
        assert line.count("toolbox ") >= 2 and "runs toolbox" in line
        assert "same build" in line
        assert not (tmp_path / "o3" / "chunks").exists()  # nothing computed by it
    finally:
        for p in reversed(procs):
            _stop(p)


@pytest.mark.slow
@pytest.mark.parametrize("code, words", [(errno.ENOSPC, "the disk is full"),
                                         (errno.EROFS, "the file system is read-only")])
def test_disk_full_or_read_only_exit_4(designed, small_spec, tmp_path, monkeypatch, code, words):
    """The atomic writer of the chunk files fails: exit 4, one line; rerun resumes."""
    from toolbox.campaign import _store

    real = _store.write_atomic

    def failing(path, data):
        if "rows-" in str(path):
            raise OSError(code, os.strerror(code), str(path))
        return real(path, data)

    monkeypatch.setattr(_store, "write_atomic", failing)
    out = tmp_path / "out"
    res, _ = _campaign(small_spec, out, "--scheduler", "serial")
    assert res.exit_code == 4, res.output
    line = _one_line(res)
    assert f"cannot write the campaign to {out}: {words}" in line and "resumes" in line
    monkeypatch.setattr(_store, "write_atomic", real)
    res, _ = _campaign(small_spec, out, "--scheduler", "serial")
    assert res.exit_code == 0, res.output


@pytest.mark.skipif(not Path("/sys").is_dir(), reason="needs /sys")
def test_uncreatable_out_exit_4(small_spec):
    """A real refusal (as root too): a directory under /sys cannot be created."""
    out = Path("/sys/cct-campaign-test/out")
    res, _ = _campaign(small_spec, out, "--scheduler", "serial")
    assert res.exit_code == 4, res.output
    assert f"cannot write the campaign to {out}" in _one_line(res)


def test_out_through_a_file_is_bad_input(small_spec, tmp_path):
    (tmp_path / "file").write_text("x")
    res, _ = _campaign(small_spec, tmp_path / "file" / "out", "--scheduler", "serial")
    assert res.exit_code == 2, res.output
    assert "is a file, not a directory" in _one_line(res)
