"""The C text comes from jinja2 templates shipped with the package (toolbox/ARCHITECTURE.md
"controller.h", Text)."""

from __future__ import annotations

import tomllib
from pathlib import Path

from toolbox.export.c_header import TEMPLATES

ROOT = Path(__file__).parents[2]


def test_templates_are_package_data():
    """An installed (non-editable) toolbox must carry the templates: both exist
    and pyproject's package-data names them."""
    names = {p.name for p in TEMPLATES.glob("*.c.j2")}
    assert {"float.c.j2", "fixed.c.j2"} <= names
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    globs = data["tool"]["setuptools"]["package-data"]["toolbox.export"]
    assert any(Path("templates", n).match(g) for g in globs for n in names)
