"""The toolbox version recorded in every artifact's provenance."""

from __future__ import annotations

import functools

__all__ = ["toolbox_version"]


@functools.lru_cache(maxsize=1)
def toolbox_version() -> str:
    """Installed distribution version, ``"0+unknown"`` in a bare source tree.

    Read once per process: ``importlib.metadata`` scans the installed
    distributions on every call (~2 ms, a tenth of an H-infinity design, issue
    13), and the version cannot change while the process runs.
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("current-control-toolbox")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"
