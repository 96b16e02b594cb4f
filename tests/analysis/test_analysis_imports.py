"""The analysis stage imports neither python-control nor scipy.signal nor
scipy.stats (together 1 to 2 s of every ``cct`` process) nor scipy.optimize
(0.25 s; its Brent root and minimum are ``analysis._scalar``'s):
toolbox/ARCHITECTURE.md "Caches and lazy imports".

Its linear systems come from ``toolbox.lti``, its Latin hypercube from
``toolbox.analysis._sampling``; python-control stays the independent route of
the tests. Checked on the source (function-level imports included), so the
check does not depend on what other stages happen to import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ANALYSIS = Path(__file__).resolve().parents[2] / "toolbox" / "analysis"
FORBIDDEN = ("control", "scipy.signal", "scipy.stats", "scipy.optimize")


def _imported(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names |= {f"{node.module}.{a.name}" for a in node.names}
    return names


@pytest.mark.parametrize("path", sorted(ANALYSIS.glob("*.py")), ids=lambda p: p.name)
def test_no_heavy_imports(path):
    bad = {n for n in _imported(path) for f in FORBIDDEN if n == f or n.startswith(f + ".")}
    assert not bad, f"{path.name} imports {sorted(bad)}"
