"""Outputs as a set: a design directory holds the old set or the new one.

Before: ``write_outputs`` replaced files one by one, so a kill -9 mid-write
left a new controller.json next to an old report.html, temporaries
``.controller.json.XXXXXXXX`` stayed forever, Ctrl-C printed a traceback,
and ``cct export -o`` under a regular file or in /proc raised
FileExistsError / FileNotFoundError.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from toolbox._io import remove_stale, write_set
from toolbox.pipeline import OUTPUT_FILES, write_outputs

from hostile_helpers import ROOT, run_cli, spec_dict, to_toml

#: The child rewrites the whole output set in a loop, generation after
#: generation, each file tagged with its generation; 4 MB per file makes one
#: set take tens of milliseconds, so kills land in the middle of writes.
WRITER = textwrap.dedent("""
    import sys
    from toolbox.pipeline import OUTPUT_FILES, write_outputs
    out, size = sys.argv[1], int(sys.argv[2])
    g = 0
    while True:
        g += 1
        tag = f"{g:08d}\\n"
        write_outputs({n: tag + "x" * size for n in OUTPUT_FILES}, out)
        print(g, flush=True)
""")


def _generations(out: Path) -> dict[str, str]:
    return {p.name: p.read_text()[:8] for p in out.iterdir()}


def _start_writer(out: Path, size: int = 4_000_000) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-c", WRITER, str(out), str(size)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)


def _wait_generations(proc: subprocess.Popen, n: int) -> None:
    for _ in range(n):  # each line: one complete set written
        line = proc.stdout.readline()
        assert line, proc.stderr.read()


@pytest.mark.slow
@pytest.mark.parametrize("extra_delay", [0.0, 0.013, 0.029, 0.047])
def test_kill_9_mid_write_leaves_one_complete_set(tmp_path, extra_delay):
    out = tmp_path / "out"
    proc = _start_writer(out)
    try:
        _wait_generations(proc, 2)
        time.sleep(extra_delay)  # different points inside the next set's write
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    gens = _generations(out)
    # the whole set is there, and every file has the same generation
    assert sorted(gens) == sorted(OUTPUT_FILES)
    assert len(set(gens.values())) == 1, gens
    # the next run removes what the killed one left (staging dir, old set)
    write_outputs({"controller.json": "new"}, out)
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert sorted(p.name for p in out.iterdir()) == ["controller.json"]


@pytest.mark.slow
def test_sigint_mid_write_leaves_one_complete_set_and_no_temporaries(tmp_path):
    out = tmp_path / "out"
    proc = _start_writer(out)
    try:
        _wait_generations(proc, 2)
        time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    gens = _generations(out)
    assert sorted(gens) == sorted(OUTPUT_FILES) and len(set(gens.values())) == 1
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # staging dir cleaned up


def test_new_controller_drops_old_outputs_and_keeps_user_files(tmp_path):
    out = tmp_path / "out"
    write_outputs({n: "old" for n in OUTPUT_FILES}, out)
    (out / "notes.txt").write_text("mine")
    write_outputs({"controller.json": "new"}, out)  # e.g. --only-controller
    assert sorted(p.name for p in out.iterdir()) == ["controller.json", "notes.txt"]
    assert (out / "notes.txt").read_text() == "mine"


def test_partial_update_keeps_the_rest_of_the_set(tmp_path):
    out = tmp_path / "out"
    write_outputs({n: "old" for n in OUTPUT_FILES}, out)
    write_outputs({"verify.json": "new"}, out)  # cct verify
    assert {p.name: p.read_text() for p in out.iterdir()} == {
        **{n: "old" for n in OUTPUT_FILES}, "verify.json": "new"}


def test_stale_temporaries_are_removed(tmp_path):
    out = tmp_path / "out"
    write_outputs({"controller.json": "a"}, out)
    (out / ".controller.json.k3j4h5g6").write_text("half")   # write_atomic after kill -9
    (out / ".bashrc.k3j4h5g6").write_text("not ours")        # not a temporary of ours
    (tmp_path / ".out.stage.a1b2c3d4").mkdir()
    (tmp_path / ".out.stage.a1b2c3d4" / "controller.json").write_text("half")
    write_outputs({"controller.json": "b"}, out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert sorted(p.name for p in out.iterdir()) == [".bashrc.k3j4h5g6", "controller.json"]


def test_set_parked_by_a_kill_between_renames_is_restored(tmp_path):
    """Without renameat2 the swap is two renames; a kill between them leaves
    the old set in ``.out.old.XXXXXXXX/set`` and no ``out``: the next run
    brings it back before writing."""
    out = tmp_path / "out"
    parked = tmp_path / ".out.old.zz99yy88" / "set"
    parked.mkdir(parents=True)
    (parked / "controller.json").write_text("old")
    (parked / "notes.txt").write_text("mine")
    remove_stale(out)
    assert (out / "notes.txt").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_write_set_into_a_regular_file_is_an_os_error(tmp_path):
    target = tmp_path / "file"
    target.write_text("x")
    with pytest.raises(NotADirectoryError):
        write_set({"a": "b"}, target)
    res = run_cli("design", _spec(tmp_path), "--out", target / "sub", "--only-controller")
    assert res.exit_code == 2
    # mkdir of the parent chain meets the regular file: EEXIST
    assert (f'cct: error: --out: expected a writable directory, got "{target / "sub"}" '
            "(File exists)") in res.output


def test_swap_without_renameat2(tmp_path, monkeypatch):
    """The two-rename fallback (non-Linux) gives the same result."""
    import toolbox._io as io

    monkeypatch.setattr(io, "_exchange", lambda a, b: False)
    out = tmp_path / "out"
    write_outputs({n: "old" for n in OUTPUT_FILES}, out)
    write_outputs({"controller.json": "new"}, out)
    assert {p.name: p.read_text() for p in out.iterdir()} == {"controller.json": "new"}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def _spec(tmp_path: Path) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(to_toml(spec_dict()))
    return path


@pytest.fixture
def design_dir(tmp_path) -> Path:
    out = tmp_path / "design"
    res = run_cli("design", _spec(tmp_path), "--out", out, "--only-controller", "-q")
    assert res.exit_code == 0, res.output
    return out


@pytest.mark.parametrize("fmt", ["c", "json"])
def test_export_under_a_regular_file(design_dir, tmp_path, fmt):
    blocker = tmp_path / "plain"
    blocker.write_text("x")
    target = blocker / "controller.h"
    res = run_cli("export", design_dir, "--format", fmt, "-o", target)
    assert res.exit_code == 2, res.output
    assert (f"cct: error: --output: expected a writable file path (its directory must be "
            f'creatable), got "{target}" ({blocker} is a file, not a directory)') in res.output
    assert "Traceback" not in res.output


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux /proc")
def test_export_into_proc(design_dir):
    res = run_cli("export", design_dir, "-o", "/proc/controller.h")
    assert res.exit_code == 2, res.output
    assert ('cct: error: --output: expected a writable file path (its directory must be '
            'creatable), got "/proc/controller.h"') in res.output


@pytest.mark.slow
def test_cct_design_sigint_exits_130_and_writes_nothing(tmp_path):
    """Ctrl-C during the design: exit 130, no output directory, no temporaries."""
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "toolbox.cli", "design", str(_spec(tmp_path)),
                             "--out", str(out)], stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = proc.stderr.readline()  # "  - design ...": the command is running
        assert "design" in line, line
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "cct: interrupted (no output half-written)" in err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spec.toml"]


def test_working_directory_is_written_in_place(tmp_path, monkeypatch):
    """``--out .``: the directory the shell is in is never swapped away."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "report.html").write_text("old")
    write_outputs({"controller.json": "new"}, ".")
    assert Path.cwd() == tmp_path and tmp_path.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["controller.json"]


def test_directory_with_subdirectories_is_written_in_place(tmp_path):
    out = tmp_path / "project"
    (out / "src").mkdir(parents=True)
    (out / "src" / "main.c").write_text("int main(void) { return 0; }\n")
    inode = out.stat().st_ino
    write_outputs({n: "new" for n in OUTPUT_FILES}, out)
    assert out.stat().st_ino == inode  # same directory, not a swapped-in copy
    assert (out / "src" / "main.c").exists()
    assert sorted(p.name for p in out.iterdir()) == sorted([*OUTPUT_FILES, "src"])


def test_concurrent_writers_are_serialised_and_keep_each_others_staging(tmp_path):
    """Two runs into one output directory: the second waits for the first
    (one line on stderr) instead of removing the first one's live staging
    directory as a stale temporary, then writes its own complete set."""
    from toolbox._io import output_lock
    out = tmp_path / "out"
    write_outputs({"controller.json": "a"}, out)
    live = tmp_path / ".out.stage.a1b2c3d4"           # the first run's staging, in use
    live.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    code = ("import sys; from toolbox.pipeline import write_outputs; "
            "write_outputs({'controller.json': 'b'}, sys.argv[1])")
    with output_lock(out):
        proc = subprocess.Popen([sys.executable, "-c", code, str(out)], env=env,
                                stderr=subprocess.PIPE, text=True)
        line = proc.stderr.readline()                  # it waits, and says so
        assert "another run is writing" in line
        assert proc.poll() is None and live.is_dir()
        live.rmdir()                                   # the first run finishes
    assert proc.wait(timeout=60) == 0
    assert (out / "controller.json").read_text() == "b"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
