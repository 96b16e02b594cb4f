"""Fixtures of the hostile-input tests; the helpers are in hostile_helpers.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from hostile_helpers import to_toml


@pytest.fixture
def write_spec(tmp_path):
    """Write a spec dict (or TOML text) to a file and return its path."""

    def write(data, name: str = "spec.toml") -> Path:
        path = tmp_path / name
        path.write_text(data if isinstance(data, str) else to_toml(data))
        return path

    return write
