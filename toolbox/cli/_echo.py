"""Terminal output of the ``cct`` commands: numbers, notices and warnings,
the drift-box verdict line, and long messages wrapped."""

from __future__ import annotations

import math
import textwrap

import click


def _notices(notice: str | None, warnings: list[str]) -> None:
    """The no-requirements notice and warnings, on stderr (stdout may be JSON)."""
    if notice:
        click.echo(f"cct: notice: {notice}", err=True)
    for w in warnings:
        click.echo(f"cct: warning: {w}", err=True)


def _robustness_line(result) -> None:
    """The drift-box verdict in one line, next to the margins (``DriftVerdict.summary``)."""
    rob = result.robustness
    if rob:
        from ..analysis import DriftVerdict  # lazy: scipy, ~580 modules (`cct --help`)

        text = DriftVerdict(**{k: rob[k] for k in DriftVerdict.__dataclass_fields__}).summary()
        if any(k in result.informational for k in ("default.robustness", "parameter_drift")):
            text += " (informational: the baseline PI does not run)"
        elif rob["n_unstable"]:
            text += ": FAILED"
        click.echo(text)


def _envelope_line(result) -> None:
    """The torque-speed grid in one line (verify.json ``envelope.summary``)
    and the speed ramp through base speed in another (``envelope.speed_ramp``)."""
    env = getattr(result, "envelope", None)
    if env:
        text = env.get("summary") or f"torque-speed grid: skipped ({env.get('skipped')})"
        ramp = env.get("speed_ramp") or {}
        grid_failed = (env["counts"].get("fail", 0) > 0 if "counts" in env
                       else not env.get("passed", True))
        click.echo(text + (": FAILED" if grid_failed else ""))
        if ramp:
            click.echo(ramp["summary"] + (": FAILED" if not ramp.get("passed", True) else ""))


def _envelope_failures(result) -> list[str]:
    """``envelope: <point>: <reason>`` for each failing grid point."""
    env = getattr(result, "envelope", None) or {}
    return [f"envelope: {f}" for f in env.get("failures", [])]


def _echo_wrapped(head: str, text: str, width: int = 100, file_key: bool = False) -> None:
    """``head`` + ``text`` wrapped at ``width`` columns, continuation lines indented
    (a failure summary may run to a thousand characters); with ``file_key`` the
    leading ``file: key:`` of an error message stays whole on its first line."""
    parts = text.split(": ", 2)
    if file_key and len(parts) == 3 and len(head) + len(parts[0]) + len(parts[1]) + 3 > width:
        click.echo(f"{head}{parts[0]}: {parts[1]}:")
        head, text = "      ", parts[2]
    click.echo(textwrap.fill(text, width=width, initial_indent=head,
                             subsequent_indent="      ", break_on_hyphens=False,
                             break_long_words=True))


def _fmt(value) -> str:
    """A metric for the terminal: 4 significant digits; a metric that could not be
    computed (NaN, e.g. a response that never settled) reads "not reached"."""
    if isinstance(value, float):
        return f"{value:.4g}" if math.isfinite(value) else "not reached"
    return str(value)
