"""No traceback reaches a user (toolbox/ARCHITECTURE.md "Errors and exit codes").

An internal error (a bug) is one line on stderr naming the command, its stage,
the exception and a file holding the traceback, exit 3; Ctrl-C exits 130 and
SIGTERM 143, each with one line, and neither leaves a staging directory
(``.<out>.stage.XXXXXXXX``) behind.

The faults are injected by a ``python -c`` wrapper that patches one function
of the toolbox and then calls ``toolbox.cli.main``: the production code has
no test hook.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from click.testing import CliRunner

from toolbox.cli import main

ROOT = Path(__file__).parents[2]

SPEC = """\
title = "failsafe"
[motor]
catalog = "azaiz2007"
[drive]
vdc = 150.0
sample_time = 1e-4
[controller]
method = "pi"
[controller.pi]
bandwidth = 1000.0
"""

#: Patches ``module.name`` with a function raising an unexpected exception,
#: then runs cct with the remaining arguments.
RAISE = textwrap.dedent("""
    import importlib, sys
    module, name = sys.argv[1], sys.argv[2]
    def boom(*args, **kwargs):
        raise ZeroDivisionError("float division by zero\\nsecond line of the message")
    setattr(importlib.import_module(module), name, boom)
    from toolbox.cli import main
    main(args=sys.argv[3:], prog_name="cct")
""")

#: Sends the signal named by argv[1] to the process itself while write_set is
#: filling its staging directory (the fsync of the staging directory), then
#: runs cct with the remaining arguments.
SIGNAL_IN_STAGE = textwrap.dedent("""
    import os, signal, sys
    import toolbox._io as io
    signum = getattr(signal, sys.argv[1])
    real = io._fsync_dir
    def fsync_dir(path):
        if ".stage." in str(path):
            assert any(path.iterdir())  # the new set is staged
            os.kill(os.getpid(), signum)
        real(path)
    io._fsync_dir = fsync_dir
    from toolbox.cli import main
    main(args=sys.argv[2:], prog_name="cct")
""")


def _env(tmp_path: Path) -> dict:
    return {**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmp_path / "tmp")}


def _run(tmp_path: Path, script: str, *args, **kwargs) -> subprocess.CompletedProcess:
    (tmp_path / "tmp").mkdir(exist_ok=True)
    return subprocess.run([sys.executable, "-c", script, *map(str, args)],
                          capture_output=True, text=True, timeout=300, env=_env(tmp_path),
                          cwd=tmp_path, **kwargs)


def _spec(tmp_path: Path) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(SPEC)
    return path


def _one_internal_line(stderr: str, where: str) -> Path:
    """The single internal-error line; returns the traceback file it names."""
    lines = [line for line in stderr.splitlines() if line.startswith("cct: ")]
    assert len(lines) == 1, stderr
    line = lines[0]
    assert "Traceback" not in stderr, stderr
    prefix = (f"cct: internal error in {where}: ZeroDivisionError: float division by zero "
              "second line of the message; the traceback is in ")
    assert line.startswith(prefix) and line.endswith("; please report"), line
    path = Path(line[len(prefix):-len("; please report")])
    assert path.name.startswith("cct-traceback-") and path.suffix == ".txt"
    text = path.read_text()
    assert "Traceback (most recent call last)" in text
    assert "ZeroDivisionError: float division by zero" in text
    return path


def test_internal_error_in_design_is_one_line_exit_3_traceback_in_a_file(tmp_path):
    out = tmp_path / "out"
    res = _run(tmp_path, RAISE, "toolbox.pipeline", "analyse",
               "design", _spec(tmp_path), "--out", out, "-q")
    assert res.returncode == 3, res.stderr
    # no output directory yet: the traceback goes to the temporary directory
    path = _one_internal_line(res.stderr, "design (analysis)")
    assert path.parent == tmp_path / "tmp"
    assert f"--out {out}" in path.read_text()  # the command line, for the report
    assert not out.exists()  # nothing written, no staging directory
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.toml", "tmp"]


def test_internal_error_traceback_goes_to_the_output_directory(tmp_path):
    out = tmp_path / "out"
    # the controller set to verify, made in this process (a fresh interpreter
    # for it would test nothing more); the failing verify runs in its own
    res = CliRunner().invoke(main, ["design", str(_spec(tmp_path)), "--out", str(out),
                                    "--only-controller", "-q"])
    assert res.exit_code == 0, res.output
    res = _run(tmp_path, RAISE, "toolbox.pipeline", "run_verification", "verify", out, "-q")
    assert res.returncode == 3, res.stderr
    path = _one_internal_line(res.stderr, "verify (verification)")
    assert path.parent == out


def test_internal_error_in_check_names_the_command(tmp_path):
    res = _run(tmp_path, RAISE, "toolbox.spec", "load_spec", "check", _spec(tmp_path))
    assert res.returncode == 3, res.stderr
    _one_internal_line(res.stderr, "check")
    assert res.stdout == ""


def test_internal_error_in_process_exits_3(tmp_path, monkeypatch):
    """Through click's runner too (notebooks, tests): exit 3, no exception escapes."""
    import toolbox.cli._main

    def boom(*args, **kwargs):
        raise RuntimeError("x" * 5000)

    monkeypatch.setattr(toolbox.cli._main, "load_spec", boom)  # the name `cct check` calls
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile
    monkeypatch.setattr(tempfile, "tempdir", None)  # re-read TMPDIR
    res = CliRunner().invoke(main, ["check", str(_spec(tmp_path))])
    assert res.exit_code == 3
    assert isinstance(res.exception, SystemExit)
    assert "cct: internal error in check: RuntimeError: xxx" in res.output
    assert len(res.output) < 500  # a long message is cut on the line, kept in the file
    files = list(tmp_path.glob("cct-traceback-*.txt"))
    assert len(files) == 1 and "x" * 5000 in files[0].read_text()


@pytest.mark.slow
@pytest.mark.parametrize("name, code, words", [
    ("SIGTERM", 143, "cct: terminated (no output half-written)"),
    ("SIGINT", 130, "cct: interrupted (no output half-written)"),
])
def test_signal_while_staging_cleans_the_stage(tmp_path, name, code, words):
    out = tmp_path / "out"
    res = _run(tmp_path, SIGNAL_IN_STAGE, name, "design", _spec(tmp_path), "--out", out,
               "--only-controller", "-q")
    assert res.returncode == code, res.stderr
    assert words in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1, res.stderr
    # no output directory, no .out.stage.XXXXXXXX, no traceback file
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.toml", "tmp"]
    assert not any((tmp_path / "tmp").iterdir())


@pytest.mark.slow
def test_signal_while_replacing_an_existing_set_keeps_the_old_one(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "controller.json").write_text("old")
    res = _run(tmp_path, SIGNAL_IN_STAGE, "SIGTERM", "design", _spec(tmp_path), "--out", out,
               "--only-controller", "-q")
    assert res.returncode == 143, res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "spec.toml", "tmp"]
    assert [p.name for p in out.iterdir()] == ["controller.json"]
    assert (out / "controller.json").read_text() == "old"


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.slow
@pytest.mark.parametrize("signum, code, words, preexec", [
    (signal.SIGTERM, 143, "cct: terminated (no output half-written)", None),
    # a parent (nohup, a CI runner, `cmd &` in a script) that ignores SIGINT:
    # cct sets its own disposition, so Ctrl-C still stops it cleanly
    (signal.SIGINT, 130, "cct: interrupted (no output half-written)", _ignore_sigint),
])
def test_signal_during_design(tmp_path, signum, code, words, preexec):
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "toolbox.cli", "design",
                             str(_spec(tmp_path)), "--out", str(out)],
                            stderr=subprocess.PIPE, text=True, env=_env(tmp_path),
                            preexec_fn=preexec)
    try:
        line = proc.stderr.readline()  # "  - [1/5] design ...": the command is running
        assert "design" in line, line
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, err
    assert words in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.toml"]


def test_handlers_are_restored_after_a_command(tmp_path):
    """In process (a notebook, a test), the command's handlers do not stay."""
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    CliRunner().invoke(main, ["check", str(_spec(tmp_path))])
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before
