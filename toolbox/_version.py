"""The toolbox version recorded in every artifact's provenance."""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

__all__ = ["toolbox_version", "source_hash"]


@functools.lru_cache(maxsize=1)
def toolbox_version() -> str:
    """Installed distribution version, ``"0+unknown"`` in a bare source tree.

    Read once per process: ``importlib.metadata`` scans the installed
    distributions on every call (~2 ms, a tenth of an H-infinity design), and the version cannot change while the process runs.
    """
    # lazy: importlib.metadata, 42 modules
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("current-control-toolbox")
    except PackageNotFoundError:  # running from a source tree
        return "0+unknown"


@functools.lru_cache(maxsize=1)
def source_hash() -> str:
    """SHA-256 of the toolbox package's source: every ``.py`` file under
    ``toolbox/`` (relative path and bytes, in sorted path order).

    Computed once per process. Two processes with the same hash run the same
    code, whatever their version string says (an editable install keeps its
    version while its files change): campaigns pin it (``toolbox.campaign``)
    so that no chunk computed by another build is mixed into a table.
    """
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py"), key=lambda p: p.relative_to(root).as_posix()):
        rel = path.relative_to(root).as_posix()
        if "__pycache__" in rel:
            continue
        data = path.read_bytes()
        h.update(f"{rel}\0{len(data)}\0".encode())
        h.update(data)
    return h.hexdigest()
