"""Shared helpers of the hostile-input tests (bad input found by fuzzing;
toolbox/ARCHITECTURE.md "Reliability rules").

A module of its own name, not conftest.py: ``from conftest import ...``
resolves to whichever conftest module was imported first (tests/analysis,
tests/report, ...), so it broke when another directory ran first.

Every case here once gave a traceback, a hang or a half-written output; each
test pins the message the user now gets instead (the file, the key path, what
was expected and what was found).
"""

from __future__ import annotations

import copy
import os
import subprocess
import sys
from pathlib import Path

from click.testing import CliRunner

from toolbox.cli import main

ROOT = Path(__file__).parents[2]

#: A valid, fast spec (paper 003's motor, PI by pole-zero cancellation).
BASE = {
    "title": "hostile base",
    "motor": {"catalog": "azaiz2007"},
    "drive": {"vdc": 150.0, "sample_time": 1e-4},
    "controller": {"method": "pi", "pi": {"bandwidth": 1000.0}},
}


def spec_dict(**sections) -> dict:
    """BASE with sections updated: ``spec_dict(motor={"R": 1e300})`` merges
    into [motor] (and [drive]); other sections are replaced whole."""
    data = copy.deepcopy(BASE)
    for name, value in sections.items():
        if name in ("motor", "drive") and isinstance(value, dict):
            data[name].update(value)
        else:
            data[name] = value
    return data


def to_toml(data: dict) -> str:
    """Minimal TOML writer for the spec dicts of these tests (tables, numbers,
    strings, booleans, lists of numbers, arrays of tables)."""
    lines: list[str] = []

    def value(v) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, float):
            return repr(v)  # inf, -inf and nan are TOML floats too
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        return repr(v)

    def table(prefix: str, d: dict) -> None:
        plain = {k: v for k, v in d.items() if not isinstance(v, dict)
                 and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))}
        if prefix:
            lines.append(f"[{prefix}]")
        lines.extend(f"{k} = {value(v)}" for k, v in plain.items())
        for k, v in d.items():
            if isinstance(v, dict):
                table(f"{prefix}.{k}" if prefix else k, v)
            elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                for item in v:
                    lines.append(f"[[{prefix + '.' if prefix else ''}{k}]]")
                    lines.extend(f"{a} = {value(b)}" for a, b in item.items())

    table("", data)
    return "\n".join(lines) + "\n"


def run_cli(*args):
    """``cct ARGS`` in process; returns click's Result (exit_code, output)."""
    return CliRunner().invoke(main, [str(a) for a in args])


def cct_subprocess(*args, timeout: float = 120, **kwargs) -> subprocess.CompletedProcess:
    """``python -m toolbox.cli ARGS`` in a child process (for timeouts and signals)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "toolbox.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, env=env, **kwargs)
