"""The ``cct`` process entry (``toolbox.cli.run``, toolbox/cli/_exit.py)
ends the process without the interpreter's teardown; what the ordinary exit
guarantees must still hold: the exit status of every path (0, 1 or 2 from a
command, click's own usage error 2), everything printed reaching a pipe,
``atexit`` handlers run, and a non-daemon thread still running waited for.
"""

from __future__ import annotations

import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

from click.testing import CliRunner

from toolbox.cli import main

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "designs" / "000_lepioufle1992_tc.toml"


def _cct(*args: str, prelude: str = "") -> subprocess.CompletedProcess:
    code = (f"import sys\n{prelude}\nfrom toolbox.cli import run\n"
            f"sys.argv = ['cct', *{list(args)!r}]\nrun()\n")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


def test_exit_statuses_and_output_survive_the_short_exit():
    ok = _cct("check", str(SPEC))
    assert ok.returncode == 0, ok.stderr
    # the whole resolved spec reached the pipe: the same text as in-process
    assert ok.stdout == CliRunner().invoke(main, ["check", str(SPEC)]).output
    assert len(ok.stdout) > 1000
    missing = _cct("check", "no/such/spec.toml")
    assert missing.returncode == 2 and "no/such/spec.toml" in missing.stderr
    usage = _cct("design")                    # click's usage error: missing argument
    assert usage.returncode == 2 and "Missing argument" in usage.stderr


def test_atexit_handlers_run_and_live_threads_are_waited_for():
    handler = _cct("--version", prelude="import atexit\n"
                   "atexit.register(lambda: print('atexit ran', flush=True))")
    assert handler.returncode == 0
    assert handler.stdout.splitlines() == [
        f"cct, version {version('current-control-toolbox')}", "atexit ran"]
    thread = _cct("--version", prelude="import threading, time\n"
                  "threading.Thread(target=lambda: (time.sleep(0.5), print('thread done', "
                  "flush=True))).start()")
    assert thread.returncode == 0
    assert thread.stdout.splitlines()[-1] == "thread done"
