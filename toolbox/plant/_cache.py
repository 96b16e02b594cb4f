"""On-disk cache of the symbolic dq derivation (issue 13).

:func:`~toolbox.plant.derive_dq_model` takes about 2.4 s of sympy work per
Park convention, redone by every ``cct`` process. Its result depends only on
the source of :mod:`toolbox.plant._symbolic` and on the sympy version, so it
is cached on disk under a key hashing both:

``$XDG_CACHE_HOME/current-control-toolbox/dq_model-<convention>-<key>.pickle``
(``~/.cache`` when ``XDG_CACHE_HOME`` is unset; ``CCT_CACHE_DIR`` overrides
the directory, ``CCT_CACHE_DIR=off`` disables the cache).

Any edit of the derivation changes the key, so a stale result is never read.
A file is written atomically (temporary file, fsync, rename), starts with a
header carrying the key and the SHA-256 of the payload, and is unpickled only
when both match: a truncated or corrupted file is ignored (and rewritten),
never an error. The cache directory is the user's own, trusted like numba's
cache of compiled functions; nothing from a spec file ever reaches it.
"""

from __future__ import annotations

import hashlib
import os
import pickle
from pathlib import Path
from typing import Any, Callable

__all__ = ["cache_dir", "cache_key", "cached"]

_MAGIC = b"cct-dq-model v1"
_APP = "current-control-toolbox"


def cache_dir() -> Path | None:
    """Directory of the cache, or None when disabled (``CCT_CACHE_DIR=off``)."""
    override = os.environ.get("CCT_CACHE_DIR")
    if override is not None:
        return None if override.strip().lower() in ("", "off", "0", "none") else Path(override)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / _APP


def cache_key(source_file: str | Path) -> str:
    """SHA-256 (hex, 16 digits) of the derivation's source and the sympy version."""
    import sympy

    h = hashlib.sha256(Path(source_file).read_bytes())
    h.update(f"\0sympy {sympy.__version__}\0pickle {pickle.HIGHEST_PROTOCOL}".encode())
    return h.hexdigest()[:16]


def _read(path: Path, key: str) -> Any | None:
    """The cached object, or None if missing, from another key or corrupted."""
    try:
        raw = path.read_bytes()
        header, digest, payload = raw.split(b"\n", 2)
    except (OSError, ValueError):
        return None
    if header != _MAGIC + b" " + key.encode() or \
            digest != hashlib.sha256(payload).hexdigest().encode():
        return None
    try:
        return pickle.loads(payload)
    except Exception:  # noqa: BLE001  (a payload from a foreign sympy: re-derive)
        return None


def _write(path: Path, key: str, value: Any) -> None:
    """Write atomically; a cache that cannot be written is not an error."""
    from .._io import write_atomic

    payload = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    data = b"\n".join((_MAGIC + b" " + key.encode(),
                       hashlib.sha256(payload).hexdigest().encode(), payload))
    try:
        write_atomic(path, data)
    except OSError:
        pass  # read-only home, full disk: the derivation is simply redone next time


def cached(name: str, source_file: str | Path, compute: Callable[[], Any],
           check: Callable[[Any], bool]) -> Any:
    """``compute()``, through the on-disk cache.

    Parameters
    ----------
    name : str
        File-name stem of the entry (e.g. ``dq_model-amplitude``).
    source_file : path
        Source whose hash keys the entry.
    compute : callable
        Produces the value when the cache has none.
    check : callable
        Accepts a loaded value (type check); a rejected one is recomputed.
    """
    directory = cache_dir()
    if directory is None:
        return compute()
    key = cache_key(source_file)
    path = directory / f"{name}-{key}.pickle"
    value = _read(path, key)
    if value is not None and check(value):
        return value
    value = compute()
    _write(path, key, value)
    return value
