"""On-disk cache of results that depend only on source code.

:func:`~toolbox.plant.derive_dq_model` takes about 2.4 s of sympy work per
Park convention, redone by every ``cct`` process; the numeric functions
lambdified from it and the report's typeset equations cost another second
and the sympy and mathtext imports. Each depends only on the source of the
modules that compute it and on the versions of the packages it uses, so it
is cached on disk under a key hashing both:

``$XDG_CACHE_HOME/current-control-toolbox/<name>-<key>.pickle``
(``~/.cache`` when ``XDG_CACHE_HOME`` is unset; ``CCT_CACHE_DIR`` overrides
the directory, ``CCT_CACHE_DIR=off`` disables the cache).

Any edit of the derivation changes the key, so a stale result is never read.
A family of entries (the name up to its first ``-``: ``firmware``,
``steady_state``, ...) keeps at most :data:`MAX_ENTRIES` files, the least
recently used going first: the families keyed by content (the firmware
figures of each distinct header) would otherwise grow with every design.
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
from typing import Any, Callable, Sequence, Union
from ._io import write_atomic

__all__ = ["MAX_ENTRIES", "cache_dir", "cache_key", "cached", "template_bytecode_cache"]

_MAGIC = b"cct-cache v1"
_APP = "current-control-toolbox"
#: Files kept per family (module docstring): a few hundred kB to ~10 MB each.
MAX_ENTRIES = 256


def cache_dir() -> Path | None:
    """Directory of the cache, or None when disabled (``CCT_CACHE_DIR=off``)."""
    override = os.environ.get("CCT_CACHE_DIR")
    if override is not None:
        return None if override.strip().lower() in ("", "off", "0", "none") else Path(override)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / _APP


Sources = Union[str, Path, Sequence[Union[str, Path]]]


def cache_key(sources: Sources, packages: Sequence[str] = ("sympy",)) -> str:
    """SHA-256 (hex, 16 digits) of the source files and the packages' versions.

    The versions are read from the installed distributions' metadata, so that
    a cache hit imports none of the packages.
    """
    # lazy: importlib.metadata, 42 modules
    from importlib.metadata import PackageNotFoundError, version

    files = [sources] if isinstance(sources, (str, Path)) else list(sources)
    h = hashlib.sha256()
    for f in files:
        h.update(hashlib.sha256(Path(f).read_bytes()).digest())
    for name in packages:
        try:
            v = version(name)
        except PackageNotFoundError:
            v = "?"
        h.update(f"\0{name} {v}".encode())
    h.update(f"\0pickle {pickle.HIGHEST_PROTOCOL}".encode())
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
    payload = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    data = b"\n".join((_MAGIC + b" " + key.encode(),
                       hashlib.sha256(payload).hexdigest().encode(), payload))
    try:
        write_atomic(path, data)
    except OSError:
        pass  # read-only home, full disk: the derivation is simply redone next time


def cached(name: str, sources: Sources, compute: Callable[[], Any],
           check: Callable[[Any], bool], packages: Sequence[str] = ("sympy",)) -> Any:
    """``compute()``, through the on-disk cache.

    Parameters
    ----------
    name : str
        File-name stem of the entry (e.g. ``dq_model-amplitude``).
    sources : path or sequence of paths
        Sources whose hashes key the entry (every module the value depends on).
    compute : callable
        Produces the value when the cache has none.
    check : callable
        Accepts a loaded value (type check); a rejected one is recomputed.
    packages : sequence of str
        Distributions whose versions key the entry (those computing the value).
    """
    directory = cache_dir()
    if directory is None:
        return compute()
    key = cache_key(sources, packages)
    path = directory / f"{name}-{key}.pickle"
    value = _read(path, key)
    if value is not None and check(value):
        _touch(path)
        return value
    value = compute()
    _write(path, key, value)
    _prune(directory, name.split("-", 1)[0])
    return value


def _touch(path: Path) -> None:
    """Mark an entry as used now (its modification time orders the pruning)."""
    try:
        os.utime(path)
    except OSError:
        pass  # a read-only cache is still read


def _prune(directory: Path, family: str) -> None:
    """Remove the least recently used files of ``family`` beyond :data:`MAX_ENTRIES`.
    A file another process removes first, or reads while it goes, is not an
    error: a reader that misses an entry recomputes it."""
    def used(p: Path) -> float:
        try:
            return p.stat().st_mtime
        except OSError:
            return -1.0
    files = sorted(directory.glob(f"{family}-*.pickle"), key=used)
    for p in files[:max(len(files) - MAX_ENTRIES, 0)]:
        try:
            p.unlink()
        except OSError:
            pass


def template_bytecode_cache(owner: str | Path):
    """jinja2's on-disk cache of compiled templates, in :func:`cache_dir`.

    Compiling the header's and the reports' templates costs about 0.15 s per
    process. jinja2 keys an entry by the template's name and checks
    the template source's checksum and the Python bytecode version on load, and
    writes entries atomically (temporary file, rename). The compiled code also
    depends on the environment's options (delimiters, whitespace control), which
    jinja2 does not key: entries are therefore also keyed by the source of
    ``owner``, the module that builds the environment, and by jinja2's version.
    ``None`` (compile every time) when the cache is disabled or its directory
    cannot be created.
    """
    import jinja2  # lazy: jinja2 + markupsafe, 23 modules

    directory = cache_dir()
    if directory is None:
        return None
    try:
        (directory / "jinja").mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    key = cache_key(owner, packages=("jinja2",))
    return jinja2.FileSystemBytecodeCache(str(directory / "jinja"), f"%s-{key}.cache")
