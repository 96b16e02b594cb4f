"""File input and output that a hostile file system cannot turn into a crash.

Output: :func:`write_atomic` (one file) and :func:`write_set` (several files
swapped in together). Input: :func:`read_limited` refuses anything that is not
a regular file (a FIFO would block, ``/dev/zero`` would exhaust memory) and
anything above a size cap; :func:`check_text_depth` and :func:`check_data_depth`
bound the nesting depth of TOML/JSON without recursion, so a 100,000-deep
document is an error message instead of a ``RecursionError``.
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import os
import re
import shutil
import stat
import sys
import tempfile
from pathlib import Path
from typing import Any, Collection, Mapping

from .errors import CctError

__all__ = ["MAX_DEPTH", "MAX_INPUT_BYTES", "check_data_depth", "check_text_depth",
           "read_limited", "remove_stale", "write_atomic", "write_set"]

#: Largest spec or JSON document read (bytes). The largest reference
#: controller.json is about 22 kB; a spec is a few kB.
MAX_INPUT_BYTES = 1 << 20

#: Deepest nesting of tables/arrays (and dotted-key levels) accepted. The
#: deepest legitimate path is about 7 levels
#: (``controller.hinf.weights.q.w1.num[0]``; ``axes.q.reduced.law.A[0][0]``).
MAX_DEPTH = 32


def write_atomic(path: str | Path, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` so that readers see the old file or the new
    one, never a half-written one (temporary file in the same directory,
    fsync, then ``os.replace``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    raw = data.encode("utf-8") if isinstance(data, str) else data
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.chmod(tmp, 0o666 & ~umask)  # as an ordinary open() would create it
        with os.fdopen(fd, "wb") as fh:
            fh.write(raw)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


# ---------------------------------------------------------------- reading


def read_limited(path: str | Path, error: type[CctError], *,
                 limit: int = MAX_INPUT_BYTES, what: str = "file") -> bytes:
    """Read a regular file of at most ``limit`` bytes.

    The file type is checked with ``stat`` before opening and again with
    ``fstat`` after an ``O_NONBLOCK`` open (the path may be swapped in
    between), so a FIFO, a device such as ``/dev/zero`` or a directory is
    refused at once instead of blocking or filling memory.

    Parameters
    ----------
    path : str or Path
        The file.
    error : type
        The :class:`~toolbox.errors.CctError` subclass to raise (``SpecError``
        for specs, ``ArtifactError`` for controller.json).
    limit : int
        Size cap in bytes.
    what : str
        What the file should be, for the message ("a spec file").

    Raises
    ------
    CctError
        Of class ``error``, naming the file: missing, unreadable, not a
        regular file, or larger than ``limit``.
    """
    name = str(path)
    try:
        _check_regular(os.stat(name), name, error, what)
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as err:
        raise error("", f"a readable {what}", err.strerror or str(err), file=name) from None
    try:
        info = os.fstat(fd)
        _check_regular(info, name, error, what)
        if info.st_size > limit:
            raise error("", f"a {what} of at most {limit} bytes", f"{info.st_size} bytes",
                        file=name)
        chunks, total = [], 0
        while True:  # read one byte past the cap: the file may grow after fstat
            chunk = os.read(fd, min(1 << 16, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
            if total > limit:
                raise error("", f"a {what} of at most {limit} bytes", "a larger file",
                            file=name)
    except OSError as err:
        raise error("", f"a readable {what}", err.strerror or str(err), file=name) from None
    finally:
        os.close(fd)
    return b"".join(chunks)


def _check_regular(info: os.stat_result, name: str, error: type[CctError], what: str) -> None:
    if not stat.S_ISREG(info.st_mode):
        kind = ("a directory" if stat.S_ISDIR(info.st_mode)
                else "a FIFO" if stat.S_ISFIFO(info.st_mode)
                else "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode)
                else "a socket" if stat.S_ISSOCK(info.st_mode) else "a special file")
        raise error("", f"a regular {what}", kind, file=name)


# One token of TOML or JSON text. Strings and comments are skipped whole so
# that brackets and dots inside them do not count; key-like runs (bare keys,
# numbers, with the blanks between them) continue a dotted chain, a run of
# anything else ends it (one token per run: the scan's cost is per token).
# An unterminated string runs to the end of its line (or of the text for a
# multi-line one, or a lone backslash at the very end): every string alternative
# always matches, so the scan never backtracks and stays linear (a failed match
# at each quote was quadratic: '"' + '\\"' * k + '\\' took 1.8 s at k = 8000).
_TOKEN = re.compile(r'''
    (?P<string>"""(?:[^\\]|\\.)*?(?:"""|\\?\Z)|\'\'\'.*?(?:\'\'\'|\Z)
             |"(?:[^"\\\n]|\\.)*(?:"|(?=\n)|\\?\Z)|'[^'\n]*(?:'|(?=\n)|\Z))
  | (?P<comment>\#[^\n]*)
  | (?P<open>[\[{])
  | (?P<close>[\]}])
  | (?P<dot>\.)
  | (?P<word>[A-Za-z0-9_+\-: \t]+)
  | (?P<other>[^"\'\#\[\]{}.A-Za-z0-9_+\-: \t]+)
''', re.S | re.X)


def check_text_depth(text: str, error: type[CctError], *, limit: int = MAX_DEPTH,
                     file: str | None = None) -> None:
    """Refuse TOML/JSON text nested deeper than ``limit``, before parsing.

    ``tomllib`` and ``json`` recurse (or go quadratic on dotted keys), so the
    text is scanned first: the depth at a point is the number of open
    brackets/braces plus the dots of the current dotted key (``a.b.c``).
    The count is conservative (a float's decimal point counts as one level).

    Raises
    ------
    CctError
        Of class ``error``, with the line where the limit is passed.
    """
    depth = chain = 0
    for m in _TOKEN.finditer(text):
        kind = m.lastgroup
        if kind == "open":
            depth += 1
            chain = 0
        elif kind == "close":
            depth = max(depth - 1, 0)
            chain = 0
        elif kind == "dot":
            chain += 1
        elif kind in ("word", "string"):
            pass  # a dotted key may have spaces and quoted parts: a . "b" . c
        else:
            chain = 0
        if depth + chain > limit:
            line = text.count("\n", 0, m.start()) + 1
            raise error("", f"nesting at most {limit} levels deep",
                        f"deeper nesting at line {line}", file=file)


def check_data_depth(data: Any, error: type[CctError], *, limit: int = MAX_DEPTH,
                     file: str | None = None) -> None:
    """Refuse parsed data (dicts and lists) nested deeper than ``limit``.

    Iterative (explicit stack), so it is safe on any depth; used for data
    given directly as Python objects (``spec_from_dict``), which no text scan
    has seen.
    """
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        value, key, depth = stack.pop()
        if depth > limit:
            raise error(key, f"nesting at most {limit} levels deep", "deeper nesting",
                        file=file)
        if isinstance(value, Mapping):
            stack.extend((v, f"{key}.{k}" if key else str(k), depth + 1)
                         for k, v in value.items())
        elif isinstance(value, (list, tuple)):
            stack.extend((v, f"{key}[{i}]", depth + 1) for i, v in enumerate(value))


# ---------------------------------------------------------------- output sets


def write_set(files: Mapping[str, str | bytes], out_dir: str | Path, *,
              drop: Collection[str] = ()) -> list[Path]:
    """Write several files so that ``out_dir`` holds the old set or the new
    set, never a mix (a kill -9 or Ctrl-C at any point included).

    The files are written and fsynced into a staging directory next to
    ``out_dir`` (``.<name>.stage.XXXXXXXX``), the other files of ``out_dir``
    are hard-linked into it (except those named in ``drop``), and the staging
    directory is swapped in: one ``renameat2(RENAME_EXCHANGE)`` on Linux,
    else two renames with the old set parked in ``.<name>.old.XXXXXXXX``
    (restored by the next run if a kill falls between them). Temporaries of
    earlier interrupted runs are removed first (:func:`remove_stale`).

    A directory that is the user's own rather than a design directory (the
    working directory, or one with subdirectories or many files) is never
    swapped; its files are written by :func:`_write_in_place` instead.

    Parameters
    ----------
    files : Mapping
        File name (no directories) -> text or bytes.
    out_dir : str or Path
        Target directory (created when missing).
    drop : collection of str
        Names in ``out_dir`` not carried over into the new set (outputs that
        the new set supersedes, e.g. a report of an older design).

    Returns
    -------
    list of Path
        The written files, in sorted order.
    """
    out = Path(out_dir)
    if out.is_symlink():  # swap the directory the link points to, keep the link
        out = out.resolve()
    out = Path(os.path.abspath(out))  # "." and ".." have no name to swap
    parent = out.parent
    parent.mkdir(parents=True, exist_ok=True)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(20, "Not a directory", str(out))
    with output_lock(out):
        return _write_set_locked(files, out, drop)


@contextlib.contextmanager
def output_lock(out: Path):
    """Hold an advisory lock (``flock``) on the directory holding ``out``: runs
    writing there are serialised (the second waits, saying so on stderr; the
    write phase takes milliseconds), so the temporaries found while holding it
    are a dead run's, never a live one's (:func:`remove_stale`). The kernel
    releases the lock when its holder dies; no lock file is left behind."""
    fd = os.open(out.parent, os.O_RDONLY | os.O_DIRECTORY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            sys.stderr.write(f"cct: another run is writing in {out.parent}; waiting for it\n")
            sys.stderr.flush()
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _write_set_locked(files: Mapping[str, str | bytes], out: Path,
                      drop: Collection[str]) -> list[Path]:
    """:func:`write_set` with the output lock held."""
    parent = out.parent
    remove_stale(out, set(files) | set(drop))
    if out.exists() and not _swappable(out):
        return _write_in_place(files, out, drop)
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.stage.", dir=parent))
    try:
        os.chmod(stage, 0o777 & ~_umask())  # mkdtemp makes 0700; as mkdir would
        for name, data in sorted(files.items()):
            _write_synced(stage / name, data)
        if out.exists():
            _carry_over(out, stage, set(files) | set(drop))
        _fsync_dir(stage)
        _swap(stage, out)
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    return [out / name for name in sorted(files)]


#: A directory with more entries than this, or with subdirectories, is the
#: user's own (a project root, the home directory): it is never swapped.
MAX_CARRY_OVER = 64


def _swappable(out: Path) -> bool:
    """Whether ``out`` may be replaced by a swapped-in directory: not the
    working directory or one of its parents (the shell would be left in a
    deleted directory), and holding only a few plain files."""
    cwd = Path.cwd()
    if out == cwd or out in cwd.parents:
        return False
    entries = list(out.iterdir())
    return len(entries) <= MAX_CARRY_OVER and not any(
        e.is_dir() and not e.is_symlink() for e in entries)


def _write_in_place(files: Mapping[str, str | bytes], out: Path,
                    drop: Collection[str]) -> list[Path]:
    """Fallback for a directory that is not swapped (see :func:`_swappable`):
    every file is written and fsynced to a temporary first, superseded
    outputs are removed, then the temporaries are renamed in, controller.json
    last (readers key on it). A kill can only fall in the short rename loop;
    the temporaries it leaves are removed by the next run."""
    temps: dict[str, str] = {}
    try:
        for name, data in sorted(files.items()):
            fd, tmp = tempfile.mkstemp(prefix=f".{name}.", dir=out)
            temps[name] = tmp
            os.chmod(tmp, 0o666 & ~_umask())
            with os.fdopen(fd, "wb") as fh:
                fh.write(data.encode("utf-8") if isinstance(data, str) else data)
                fh.flush()
                os.fsync(fh.fileno())
        for name in drop:
            if name not in files:
                (out / name).unlink(missing_ok=True)
        for name in sorted(temps, key=lambda n: n == "controller.json"):
            os.replace(temps.pop(name), out / name)
    except BaseException:
        for tmp in temps.values():
            Path(tmp).unlink(missing_ok=True)
        raise
    _fsync_dir(out)
    return [out / name for name in sorted(files)]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _carry_over(out: Path, stage: Path, skip: set[str]) -> None:
    """Hard-link (or copy) the files of ``out`` not in ``skip`` into ``stage``
    (``out`` holds no subdirectories: see :func:`_swappable`)."""
    for entry in out.iterdir():
        if entry.name in skip or _is_temporary(entry.name, skip):
            continue
        target = stage / entry.name
        try:
            os.link(entry, target, follow_symlinks=False)
        except OSError:
            shutil.copy2(entry, target, follow_symlinks=False)


def _write_synced(path: Path, data: str | bytes) -> None:
    raw = data.encode("utf-8") if isinstance(data, str) else data
    with open(path, "wb") as fh:
        fh.write(raw)
        fh.flush()
        os.fsync(fh.fileno())


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass  # some file systems do not sync directories; the renames still order
    finally:
        os.close(fd)


def _swap(stage: Path, out: Path) -> None:
    """Put ``stage`` in place of ``out`` (renames only; no window with a mix)."""
    if not out.exists():
        os.rename(stage, out)
    elif _exchange(stage, out):
        shutil.rmtree(stage, ignore_errors=True)  # stage now holds the old set
    else:
        old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old.", dir=out.parent))
        os.rename(out, old / "set")  # briefly no set at all, never a mixed one
        try:
            os.rename(stage, out)
        except BaseException:
            os.rename(old / "set", out)
            raise
        shutil.rmtree(old, ignore_errors=True)
    _fsync_dir(out.parent)


def _exchange(a: Path, b: Path) -> bool:
    """Atomically exchange two paths (Linux ``renameat2``); False if unsupported."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    rc = renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange)
    return rc == 0


_STALE = re.compile(r"^\.(?P<base>.+)\.[A-Za-z0-9_]{8}$")


def _is_temporary(name: str, names: Collection[str]) -> bool:
    """``.<name>.XXXXXXXX``: a :func:`write_atomic` temporary of one of ``names``."""
    m = _STALE.fullmatch(name)
    return bool(m) and m.group("base") in names


def remove_stale(out: str | Path, names: Collection[str] = ()) -> None:
    """Remove temporaries of interrupted runs: ``.<out>.stage.XXXXXXXX`` and
    ``.<out>.old.XXXXXXXX`` next to ``out``, and ``.<file>.XXXXXXXX`` inside
    it for each file of ``names`` (left by :func:`write_atomic` after a kill).

    An ``.old`` directory whose set never reached ``out`` (killed between the
    two renames) is restored first, so the last complete set survives.
    """
    out = Path(out)
    parent = out.parent
    prefix = f".{out.name}."
    try:
        siblings = list(parent.iterdir())
    except OSError:
        return
    for entry in siblings:
        rest = entry.name[len(prefix):] if entry.name.startswith(prefix) else ""
        if not re.fullmatch(r"(?:stage|old)\.[A-Za-z0-9_]{8}", rest) or not entry.is_dir():
            continue
        if rest.startswith("old.") and (entry / "set").is_dir() and not out.exists():
            os.rename(entry / "set", out)  # killed mid-swap: the old set comes back
        shutil.rmtree(entry, ignore_errors=True)
    if out.is_dir():
        for entry in out.iterdir():
            if _is_temporary(entry.name, names) and entry.is_file() and not entry.is_symlink():
                entry.unlink(missing_ok=True)
