"""toolbox/ARCHITECTURE.md documents the contracts the code keeps.

It must name (in backticks) every key of the reference artifact
reports/003_azaiz2007_hinf/controller.json (outside the embedded spec, whose
format README.md documents), every top-level key of its analysis.json and
verify.json, every registered design method and every error class. A key
added to the artifact without documentation fails here.
"""

from __future__ import annotations

import inspect
import json
import re
from pathlib import Path

import pytest

import toolbox.errors
from toolbox.spec import registered_methods

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "toolbox" / "ARCHITECTURE.md"
REPORT = ROOT / "reports" / "003_azaiz2007_hinf"


def _named() -> set[str]:
    """Words in backticks in ARCHITECTURE.md (split on non-identifier chars so
    that `{A, B, C, D}` or `margins.d` name each part)."""
    text = re.sub(r"```.*?```", "", DOC.read_text(), flags=re.S)   # fenced blocks
    out = set()
    for chunk in re.findall(r"`([^`]+)`", text):
        out.update(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", chunk))
    return out


def _keys(value, top: bool = True) -> set[str]:
    """Every dict key in a JSON value (the top-level ``spec`` subtree excluded)."""
    out = set()
    if isinstance(value, dict):
        for k, v in value.items():
            out.add(k)
            if not (top and k == "spec"):
                out |= _keys(v, False)
    elif isinstance(value, list):
        for v in value:
            out |= _keys(v, False)
    return out


def test_artifact_keys_documented():
    """Every key of the reference controller.json appears in the document."""
    art = json.loads((REPORT / "controller.json").read_text())
    keys = _keys(art)
    assert len(keys) > 60          # the walk reached the nested keys
    missing = sorted(keys - _named())
    assert not missing, f"toolbox/ARCHITECTURE.md does not name the artifact keys {missing}"


@pytest.mark.parametrize("name", ["analysis.json", "verify.json"])
def test_output_top_level_keys_documented(name):
    """Top-level keys of the reference analysis.json and verify.json are named."""
    data = json.loads((REPORT / name).read_text())
    missing = sorted(set(data) - _named())
    assert not missing, f"toolbox/ARCHITECTURE.md does not name the {name} keys {missing}"


def test_methods_and_error_classes_documented():
    """Every registered design method and every error class is named."""
    errors = {n for n, c in inspect.getmembers(toolbox.errors, inspect.isclass)
              if issubclass(c, Exception) and c.__module__ == "toolbox.errors"}
    assert {"CctError", "SpecError", "DesignInfeasible"} <= errors
    missing = sorted((set(registered_methods()) | errors) - _named())
    assert not missing, f"toolbox/ARCHITECTURE.md does not name {missing}"


def test_checker_can_fail():
    """A key absent from the document is reported (the checks are not vacuous)."""
    assert "no_such_key_xyz" not in _named()
    assert "worst_freq_rad_s" in _named()
