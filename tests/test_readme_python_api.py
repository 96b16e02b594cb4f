"""The README's "Python API" notebook snippet runs as written (python-control)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).parents[1]


def test_readme_python_api_snippet_runs(monkeypatch):
    matplotlib.use("Agg")
    text = (ROOT / "README.md").read_text()
    snippet = re.search(r"<!-- python-api-snippet -->\n```python\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(ROOT)
    scope: dict = {}
    exec(compile(snippet, "README.md (Python API)", "exec"), scope)  # noqa: S102
    K, L, art = scope["K"], scope["L"], scope["artifact"]
    assert K.dt == art.sample_time                   # the executed law, not the design model
    from toolbox.analysis import compute_margins

    m = compute_margins(art, scope["spec"].motor)["q"]   # the report's margins
    assert scope["pm"] == pytest.approx(m.phase_margin_deg, rel=1e-2)
    assert 20 * math.log10(scope["gm"]) == pytest.approx(m.gain_margin_db, rel=1e-2)
    assert abs(scope["i_q"][-1] - 1.0) < 0.02


def test_to_statespace_domains():
    import toolbox

    art = toolbox.design_spec(ROOT / "designs" / "000_lepioufle1992_pi.toml")
    ax = art.axes["q"]
    assert ax.to_statespace().dt == art.sample_time
    assert ax.to_statespace(domain="continuous").dt is None
    with pytest.raises(ValueError, match="domain"):
        ax.to_statespace(domain="z")
