"""Progress bars of the long-running commands.

``cct design``, ``verify``, ``report``, ``compare`` and ``gallery`` take from
one second to a minute; they show a :mod:`tqdm` bar on **stderr** (stdout
may carry JSON or the table) advancing over named steps. ``-q/--quiet``
disables the bar only: result summaries, warnings and failures are printed
by the commands themselves and are unaffected.

On a terminal the bar is redrawn in place; when stderr is not a terminal
(a log file, CI, a pipe) each step is one line ``  - [k/N] step ...``
instead, so that logs hold no carriage-return animation and a reader of
the stream sees a step as soon as it starts.

:class:`StepBar` also implements the ``progress(stage)`` callback of
:func:`toolbox.pipeline.build_outputs`: a call names the step that starts
(the previous one is then complete); a call with a name that is not one of
the planned steps is a message (e.g. "firmware header skipped: ...") and is
printed above the bar unless quiet.
"""

from __future__ import annotations

import sys
from typing import Iterable

from ._failsafe import where

__all__ = ["CountBar", "StepBar", "design_stages"]


def design_stages(analysis: bool, verification: bool, header: bool,
                  report: bool) -> tuple[str, ...]:
    """The stage names :func:`toolbox.pipeline.build_outputs` reports, in order."""
    flags = (("design", True), ("analysis", analysis), ("verification", verification),
             ("firmware header", header), ("report", report))
    return tuple(name for name, on in flags if on)


class StepBar:
    """A stderr progress bar over planned steps, silent when ``quiet``.

    Parameters
    ----------
    steps : iterable of str
        The planned step names, in order (the bar's total).
    quiet : bool
        Disable the bar (and the messages passed to it).
    desc : str, optional
        Prefix of the bar (e.g. the command).
    tty : bool, optional
        Draw a redrawn bar (True) or one line per step (False); default:
        whether stderr is a terminal.

    Use as a context manager; leaving it completes and removes the bar so
    that the summary printed afterwards stands alone.
    """

    def __init__(self, steps: Iterable[str], *, quiet: bool, desc: str = "cct",
                 tty: bool | None = None) -> None:
        from tqdm import tqdm  # imported here: `cct --help` stays light

        self.steps = tuple(steps)
        self.quiet = quiet
        self._prefix = desc
        self._started = 0
        # sys.stderr looked up now, not at import: click's test runner swaps it
        self._stream = sys.stderr
        self._lines = not (self._stream.isatty() if tty is None else tty)
        self._bar = tqdm(total=len(self.steps), file=self._stream,
                         disable=quiet or self._lines, leave=False,
                         unit="step", desc=desc, dynamic_ncols=True,
                         bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} "
                                    "steps [{elapsed}<{remaining}]")

    def __call__(self, step: str) -> None:
        """Start ``step`` (completing the previous one), or print a message."""
        if step not in self.steps:
            self.message(step)
            return
        where.stage = step  # named by the top-level handler if this step fails
        if self._started:
            self._bar.update(1)
        self._started += 1
        if self._lines and not self.quiet:
            print(f"  - [{self._started}/{len(self.steps)}] {step} ...", file=self._stream,
                  flush=True)
        self._bar.set_description_str(f"{self._prefix}: {step}")

    def message(self, text: str) -> None:
        """A line above the bar (stderr), unless quiet."""
        if not self.quiet:
            self._bar.write(f"  - {text}", file=self._stream)

    def close(self) -> None:
        """Complete and remove the bar."""
        if self._bar.n < self._bar.total and self._started:
            self._bar.update(self._bar.total - self._bar.n)
        self._bar.close()

    def __enter__(self) -> "StepBar":
        return self

    def __exit__(self, *exc) -> None:
        self.close()



class CountBar:
    """A stderr progress bar over a count (e.g. campaign samples), silent when ``quiet``.

    Called as ``bar(done, total)`` (the signature of
    :func:`toolbox.campaign.run_campaign`'s ``progress``); without a
    terminal it prints one line per tenth of the total instead of redrawing.
    """

    def __init__(self, *, quiet: bool, desc: str = "cct", unit: str = "sample",
                 tty: bool | None = None) -> None:
        from tqdm import tqdm  # imported here: `cct --help` stays light

        self.quiet = quiet
        self._stream = sys.stderr
        self._lines = not (self._stream.isatty() if tty is None else tty)
        self._desc = desc
        self._printed = -1
        self._bar = tqdm(total=None, file=self._stream, disable=quiet or self._lines,
                         leave=False, unit=unit, desc=desc, dynamic_ncols=True,
                         unit_scale=True)

    def __call__(self, done: int, total: int) -> None:
        if self._bar.total != total:
            self._bar.reset(total=total)
        self._bar.update(done - self._bar.n)
        tenth = 10 * done // max(total, 1)
        if self._lines and not self.quiet and tenth > self._printed:
            self._printed = tenth
            print(f"  - {self._desc}: {done}/{total} samples", file=self._stream, flush=True)

    def close(self) -> None:
        """Remove the bar."""
        self._bar.close()

    def __enter__(self) -> "CountBar":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
