"""What every ``cct`` command shares: the exit codes, the -q option, the
handler turning bad input into one line and exit 2, and atomic file output.

toolbox/ARCHITECTURE.md "Errors and exit codes"; the top-level handler of
unexpected errors is the group's (:class:`toolbox.cli._main._Cct`).
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import click

from ..errors import CctError, SpecError
from ._failsafe import where
from .._io import write_atomic

#: -q/--quiet of the long-running commands: the bar goes, the summary stays.
_QUIET = click.option("--quiet", "-q", is_flag=True,
                      help="No progress bar (the result summary is still printed).")

EXIT_OK, EXIT_REQUIREMENT, EXIT_BAD_INPUT = 0, 1, 2


def _spec_errors(func):
    """Turn any CctError into a one-line message and exit code 2; record the
    command and its output directory for the top-level handler
    (:class:`toolbox.cli._main._Cct`)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        where.command = func.__name__
        out_dir = kwargs.get("out_dir") or kwargs.get("design_dir")
        where.out_dir = str(out_dir) if out_dir is not None else None
        try:
            return func(*args, **kwargs)
        except CctError as err:
            click.echo(f"cct: error: {err}", err=True)
            sys.exit(EXIT_BAD_INPUT)

    return wrapper


def _write_file(path: str | Path, data: str | bytes, option: str) -> None:
    """Write one output file atomically; an unusable path is bad input (exit 2)."""
    try:
        write_atomic(path, data)
    except OSError as err:
        # mkdir reports "File exists" for a parent that is a regular file: name it
        blocking = next((p for p in Path(path).parents if p.exists() and not p.is_dir()), None)
        hint = (f"{blocking} is a file, not a directory" if blocking is not None
                else err.strerror or str(err))
        raise SpecError(option, "a writable file path (its directory must be creatable)",
                        str(path), hint=hint) from None
