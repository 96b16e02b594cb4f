"""What ``cct`` does when something other than bad input stops it.

toolbox/ARCHITECTURE.md "Errors and exit codes": bad input is a
:class:`~toolbox.errors.CctError` (exit 2); everything else that escapes a
command is handled here, so that no traceback ever reaches a user:

* an unexpected exception (a bug) is one line on stderr naming the command
  and the stage it was in, the exception's type and message, and a file that
  holds the full traceback (exit 3, :data:`EXIT_INTERNAL`);
* Ctrl-C (``SIGINT``) is one line and exit 130, ``SIGTERM`` one line and
  exit 143 (128 + the signal number, as shells report them). ``SIGTERM``
  raises :class:`Terminated` in the main thread, so the ``except
  BaseException`` / ``finally`` cleanups of the output writers
  (``toolbox._io.write_set``: the ``.<out>.stage.XXXXXXXX`` directory) run
  exactly as they do for Ctrl-C.
"""

from __future__ import annotations

import os
import signal
import sys
import tempfile
import threading
import traceback
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator
from .._version import toolbox_version

__all__ = ["EXIT_INTERNAL", "EXIT_INTERRUPTED", "EXIT_TERMINATED", "Terminated",
           "internal_error_message", "location", "signal_handlers", "where"]

#: Exit code of an internal error (a bug): distinct from 0 pass, 1 a
#: requirement fails, 2 bad input.
EXIT_INTERNAL = 3
#: 128 + SIGINT, 128 + SIGTERM.
EXIT_INTERRUPTED = 128 + signal.SIGINT
EXIT_TERMINATED = 128 + signal.SIGTERM

#: Longest exception text echoed on the one-line message (the traceback file
#: holds all of it).
MAX_ECHO = 200


class Terminated(BaseException):
    """Raised in the main thread by ``SIGTERM`` (a ``BaseException``, as
    ``KeyboardInterrupt`` is, so that ``except Exception`` does not swallow it
    and cleanups run)."""


@dataclass
class _Where:
    """The command running and the stage it is in (for the one-line message)
    and its output directory (where the traceback file goes when writable)."""

    command: str | None = None
    stage: str | None = None
    out_dir: str | None = None

    def reset(self) -> None:
        self.command = self.stage = self.out_dir = None


#: Set by the command wrapper (command, output directory) and by the
#: progress bar (stage); read by the top-level handler.
where = _Where()


def location() -> str:
    """``design (analysis)``: the command and its stage, as far as known."""
    if where.command is None:
        return "cct"
    if where.stage and where.stage != where.command:
        return f"{where.command} ({where.stage})"
    return where.command


def _one_line(text: str) -> str:
    line = " ".join(text.split())
    return line if len(line) <= MAX_ECHO else line[:MAX_ECHO - 3] + "..."


def _traceback_file(text: str) -> str | None:
    """Write ``text`` to a new ``cct-traceback-*.txt`` file and return its
    path: in the output directory when it exists and is writable, else in the
    temporary directory; None when neither can be written."""
    dirs = []
    if where.out_dir:
        out = Path(where.out_dir)
        if out.is_dir() and os.access(out, os.W_OK | os.X_OK):
            dirs.append(str(out))
    dirs.append(None)  # tempfile's default directory
    for directory in dirs:
        try:
            fd, path = tempfile.mkstemp(prefix="cct-traceback-", suffix=".txt", dir=directory)
        except OSError:
            continue
        try:
            with os.fdopen(fd, "w", encoding="utf-8", errors="backslashreplace") as fh:
                fh.write(text)
        except OSError:
            continue
        return path
    return None


def internal_error_message(err: BaseException) -> str:
    """Write the traceback of ``err`` to a file and return the one line for
    stderr: ``cct: internal error in <command (stage)>: <Type>: <what>; the
    traceback is in <file>; please report``."""
    text = "".join(traceback.format_exception(type(err), err, err.__traceback__))
    try:
        version = toolbox_version()
    except Exception:  # the report must not fail on its own
        version = "unknown"
    header = (f"cct {' '.join(sys.argv[1:])}\nin {location()}\ntoolbox {version}, "
              f"Python {sys.version.split()[0]}\n\n")
    path = _traceback_file(header + text)
    what = _one_line(str(err))
    name = type(err).__name__ + (f": {what}" if what else "")
    kept = (f"the traceback is in {path}" if path is not None
            else "the traceback could not be written")
    return f"cct: internal error in {location()}: {name}; {kept}; please report"


def _raise_terminated(signum, frame) -> None:
    raise Terminated()


@contextmanager
def signal_handlers() -> Iterator[None]:
    """Explicit dispositions while a command runs, restored afterwards:
    ``SIGINT`` raises ``KeyboardInterrupt`` (a parent's ``SIG_IGN`` does not
    leak in), ``SIGTERM`` raises :class:`Terminated`. Only the main thread
    may set handlers; elsewhere (a test runner's worker thread) nothing
    changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for signum, handler in ((signal.SIGINT, signal.default_int_handler),
                            (signal.SIGTERM, _raise_terminated)):
        try:
            previous[signum] = signal.signal(signum, handler)
        except (ValueError, OSError):  # not settable here: keep what there is
            pass
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)
