"""The ``cct`` process entry: run the command, then end the process without
the interpreter's teardown.

A ``cct design`` imports about 1,200 modules (numpy, scipy, numba, llvmlite,
jinja2, typst, ...); clearing them and collecting their objects at
interpreter exit took 0.32-0.39 s of a 2.4-3.0 s command (measured on
``designs/003_azaiz2007_hinf.toml``), time in which nothing is left to do:
every output is written (atomically) and closed before the command returns.
:func:`run` does what the exit must keep (the ``atexit`` handlers, which hold
the libraries' own clean-ups: ``tempfile`` finalizers, logging, Dask's
cluster shutdown; flushing stdout and stderr) and then ``os._exit``. With a
non-daemon thread still running (which Python would wait for) it exits the
ordinary way. The click command object stays the API for in-process callers
(tests' ``CliRunner``): only the console script and ``python -m
toolbox.cli`` end this way.
"""

from __future__ import annotations

import atexit
import os
import sys
import threading

from ._main import main


def run() -> None:
    """The ``cct`` console script (:data:`main` with ``prog_name="cct"``)."""
    try:
        main(prog_name="cct")
    except SystemExit as stop:
        _end(stop.code)
    _end(0)


def _end(code) -> None:
    """Exit with ``code`` (``SystemExit``'s: None, an int, or a message for
    stderr and status 1) after the ``atexit`` handlers and a flush of the
    standard streams, skipping the interpreter's teardown."""
    if code is None:
        status = 0
    elif isinstance(code, int):
        status = code
    else:
        print(code, file=sys.stderr)
        status = 1
    if any(t.is_alive() and not t.daemon for t in threading.enumerate()
           if t is not threading.main_thread()):
        sys.exit(status)  # the interpreter joins them, as it would have
    atexit._run_exitfuncs()  # noqa: SLF001 (CPython's own exit sequence, step 1)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing to flush to
            pass
    os._exit(status)
