"""The toolbox version recorded in every artifact's provenance."""

from __future__ import annotations

__all__ = ["toolbox_version"]


def toolbox_version() -> str:
    """Installed distribution version, ``"0+unknown"`` in a bare source tree."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("current-control-toolbox")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"
