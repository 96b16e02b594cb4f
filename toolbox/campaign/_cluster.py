"""Reaching a Dask cluster so that every failure is one message and exit 4.

A campaign that a release is gated on must tell "the design fails" (exit 1)
and "the input is wrong" (exit 2) from "the cluster is not usable" (exit 4,
:class:`toolbox.errors.InfrastructureError`). This module does the checks,
each bounded in time:

1. :func:`parse_address`: ``tcp://host:port`` (or ``host:port``); another
   scheme (``http://``), a missing or invalid port is bad input (exit 2).
2. :func:`probe_scheduler`: a raw socket connects and reads the Dask
   handshake, which a scheduler sends as soon as it accepts (a length-prefixed
   msgpack frame naming ``compression`` and ``pickle-protocol``). Refused,
   silent within :data:`PROBE_TIMEOUT` (an HTTP server on the port waits for
   a request; dask's own ``Client(timeout=)`` can then hang,
   dask/distributed#8071) or another protocol (an SSH banner): exit 4.
3. :func:`connect`: ``Client(address)`` in a daemon thread joined with a
   deadline, so that no connection attempt can outlive :data:`CONNECT_TIMEOUT`.
4. :func:`check_workers`: ``wait_for_workers`` with a timeout, then
   ``client.run(worker_build)`` on every worker: the toolbox must be
   importable there and be the client's build (version and
   :func:`toolbox._version.source_hash`); otherwise both builds are named.
5. :func:`disk_errors`: an ``OSError`` writing ``--out`` (full, read-only,
   quota, I/O error) becomes exit 4 naming the path; a path through a regular
   file stays bad input (exit 2).
6. :func:`dask_log`: while a campaign runs, the ``distributed`` logger (its
   reconnection attempts and tracebacks when the scheduler is lost) writes
   to ``OUT/dask.log`` instead of stderr, so that a failure is the one line
   of :class:`InfrastructureError`.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import re
import socket
import struct
import threading
import time
from pathlib import Path

from .._version import source_hash, toolbox_version
from ..errors import InfrastructureError, SpecError

__all__ = ["parse_address", "probe_scheduler", "connect", "check_workers", "worker_build",
           "disk_errors", "dask_log", "one_line",
           "BuildMismatch", "PROBE_TIMEOUT", "CONNECT_TIMEOUT",
           "WORKER_TIMEOUT"]

#: Seconds to wait for the scheduler's handshake on a raw socket.
PROBE_TIMEOUT = 10.0
#: Seconds for the whole Client connection (after the probe).
CONNECT_TIMEOUT = 15.0
#: Seconds to wait for the workers to register.
WORKER_TIMEOUT = 30.0
#: Seconds for the build check (client.run) on the workers.
RUN_TIMEOUT = 60.0

_HOST_PORT = re.compile(r"^(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.\-]+):(?P<port>[^:/]*)$")


def parse_address(address: str) -> tuple[str, str, int]:
    """``(normalised address, host, port)`` of a scheduler address.

    Raises
    ------
    SpecError
        (exit 2) a scheme other than ``tcp://``, no port, a port that is not
        an integer in 1 .. 65535, or anything after the port.

    Examples
    --------
    >>> parse_address("tcp://127.0.0.1:8786")
    ('tcp://127.0.0.1:8786', '127.0.0.1', 8786)
    >>> parse_address("10.0.0.5:8786")[0]
    'tcp://10.0.0.5:8786'
    """
    expected = "tcp://host:port of a running Dask scheduler, 'local' or 'serial'"
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme != "tcp":
        hint = ("the scheduler's port speaks the Dask protocol, not HTTP (the dashboard, "
                "port 8787, is not the scheduler)" if scheme in ("http", "https")
                else "only tcp:// is supported")
        raise SpecError("--scheduler", expected, address, hint=hint)
    m = _HOST_PORT.match(rest)
    if m is None:
        raise SpecError("--scheduler", expected, address,
                        hint="give the port: a scheduler listens on 8786 by default, "
                             "e.g. tcp://host:8786")
    port = m.group("port")
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise SpecError("--scheduler", expected, address,
                        hint="the port is an integer from 1 to 65535")
    host = m.group("host").strip("[]")
    return f"tcp://{m.group('host')}:{int(port)}", host, int(port)


def _hint(address: str) -> str:
    return (f"start one with `dask scheduler --port {address.rsplit(':', 1)[1]}` and workers "
            f"with `dask worker {address} --nthreads 1`, or run without --scheduler "
            "(a LocalCluster on this machine)")


def probe_scheduler(address: str, timeout: float | None = None) -> None:
    """Check that a Dask scheduler answers at ``address`` (module docstring, 2).

    Raises
    ------
    InfrastructureError
        Connection refused or unresolvable, nothing received within
        ``timeout`` seconds, or bytes that are not a Dask handshake.
    """
    timeout = PROBE_TIMEOUT if timeout is None else timeout
    _norm, host, port = parse_address(address)
    deadline = time.monotonic() + timeout
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except socket.timeout:
        raise InfrastructureError(f"no Dask scheduler at {address}: the connection was not "
                                  f"accepted within {timeout:g} s",
                                  hint=_hint(address)) from None
    except OSError as err:
        raise InfrastructureError(f"no Dask scheduler at {address}: "
                                  f"{err.strerror or err}", hint=_hint(address)) from None
    data = b""
    try:
        with sock:
            while True:
                need = 8 if len(data) < 8 else 8 + struct.unpack("<Q", data[:8])[0]
                if len(data) >= need and len(data) >= 8:
                    break
                if need > 1 << 16:  # a handshake is about 60 bytes
                    break
                left = deadline - time.monotonic()
                if left <= 0:
                    raise socket.timeout
                sock.settimeout(left)
                chunk = sock.recv(4096)
                if not chunk:
                    break
                data += chunk
    except socket.timeout:
        raise InfrastructureError(
            f"{address} accepts connections but sent no Dask handshake within {timeout:g} s "
            + ("(nothing at all: another kind of server, e.g. HTTP, or a hung scheduler)"
               if not data else f"(only {len(data)} bytes)"),
            hint="check the address and port of the scheduler; " + _hint(address)) from None
    except OSError as err:
        raise InfrastructureError(f"{address}: the connection failed while reading the Dask "
                                  f"handshake: {err.strerror or err}",
                                  hint=_hint(address)) from None
    if not (b"pickle-protocol" in data or b"compression" in data):
        shown = data[:40].decode("ascii", "replace")
        shown = "".join(c if c.isprintable() else "." for c in shown)
        raise InfrastructureError(
            f"{address} is not a Dask scheduler: it answered {shown!r}"
            + (" and closed the connection" if len(data) < 8 else ""),
            hint="check the address and port of the scheduler; " + _hint(address))


def connect(address: str, timeout: float | None = None):
    """A ``distributed.Client`` connected to ``address`` within ``timeout`` s.

    The probe runs first; the Client is then made in a daemon thread that is
    abandoned at the deadline (it cannot block the exit).
    """
    from dask.distributed import Client  # lazy: dask.distributed, 439 modules

    timeout = CONNECT_TIMEOUT if timeout is None else timeout
    probe_scheduler(address)
    box: dict = {}

    def make():
        try:
            box["client"] = Client(address, timeout=timeout, set_as_default=False)
        except BaseException as err:  # reported by the caller's thread
            box["error"] = err

    t = threading.Thread(target=make, name="cct-connect", daemon=True)
    t.start()
    t.join(timeout + 5.0)
    if t.is_alive() or ("client" not in box and "error" not in box):
        raise InfrastructureError(f"the Dask scheduler at {address} did not complete the "
                                  f"connection within {timeout + 5:g} s",
                                  hint="is it overloaded or of another dask version? "
                                       + _hint(address))
    if "error" in box:
        err = box["error"]
        raise InfrastructureError(f"could not connect to the Dask scheduler at {address}: "
                                  f"{type(err).__name__}: {err}", hint=_hint(address))
    return box["client"]


def worker_build() -> tuple[str, str]:
    """``(toolbox version, source hash)`` of this process (run on each worker)."""
    return toolbox_version(), source_hash()


class BuildMismatch(RuntimeError):
    """A worker's toolbox build differs from the client's (raised on the worker)."""


def _build_text(build) -> str:
    version, digest = build
    return f"toolbox {version} (source {digest[:12]})"


def mismatch_message(worker: str, theirs, ours) -> str:
    """One line naming both builds."""
    return (f"worker {worker} runs {_build_text(theirs)}, this client "
            f"{_build_text(ours)}")


_MISMATCH_HINT = ("install the same build of the toolbox on every worker and the client "
                  "(pip install the same wheel or checkout) and restart the workers")


def check_workers(client, address: str, n: int | None = None,
                  timeout: float | None = None) -> dict:
    """Wait for ``n`` workers (at least one) and check their toolbox build.

    Returns
    -------
    dict
        ``{worker address: (version, source hash)}``.

    Raises
    ------
    InfrastructureError
        Too few workers within ``timeout`` s, a worker that cannot import the
        toolbox, or one of another build (both builds named).
    """
    timeout = WORKER_TIMEOUT if timeout is None else timeout
    want = n or 1
    try:
        client.wait_for_workers(want, timeout=timeout)
    except (TimeoutError, OSError) as err:
        have = len(client.scheduler_info().get("workers", {})) if client.status == "running" \
            else 0
        raise InfrastructureError(
            f"{'no Dask worker' if have == 0 else f'only {have} of {want} Dask workers'} "
            f"joined the scheduler at {address} within {timeout:g} s",
            hint=f"start workers with `dask worker {address} --nthreads 1` (each with this "
                 "package installed)" + (f"; {type(err).__name__}: {err}"
                                         if not isinstance(err, TimeoutError) else "")) from None
    ours = worker_build()
    box: dict = {}

    def run():
        try:
            box["result"] = client.run(worker_build, on_error="return")
        except BaseException as err:
            box["error"] = err

    t = threading.Thread(target=run, name="cct-worker-check", daemon=True)
    t.start()
    t.join(RUN_TIMEOUT)
    if t.is_alive():
        raise InfrastructureError(f"the workers of {address} did not answer the toolbox "
                                  f"check within {RUN_TIMEOUT:g} s",
                                  hint="restart the workers")
    if "error" in box:
        err = box["error"]
        raise InfrastructureError(_import_text(err, "the workers"), hint=_MISMATCH_HINT)
    builds = {}
    for worker, value in sorted(box["result"].items()):
        if isinstance(value, BaseException):
            raise InfrastructureError(_import_text(value, f"worker {worker}"),
                                      hint=_MISMATCH_HINT)
        builds[worker] = tuple(value)
        if tuple(value) != ours:
            raise InfrastructureError(mismatch_message(worker, value, ours),
                                      hint=_MISMATCH_HINT)
    return builds


def _import_text(err: BaseException, who: str) -> str:
    text = f"{type(err).__name__}: {err}"
    if isinstance(err, ImportError) or "toolbox" in str(err):
        return f"{who} cannot import the toolbox ({text})"
    return f"{who} failed the toolbox check ({text})"


#: errno values of a disk that cannot take the output (exit 4).
_DISK_ERRNOS = {errno.ENOSPC, errno.EROFS, errno.EDQUOT, errno.EACCES, errno.EPERM,
                errno.EIO, errno.EFBIG}
_DISK_WORDS = {errno.ENOSPC: "the disk is full", errno.EDQUOT: "the disk quota is exceeded",
               errno.EROFS: "the file system is read-only",
               errno.EACCES: "permission denied", errno.EPERM: "permission denied",
               errno.EIO: "an I/O error", errno.EFBIG: "the file is too large"}


@contextlib.contextmanager
def disk_errors(out_dir: Path, what: str = "writing"):
    """Turn an ``OSError`` of the output directory into exit 4 (a disk that
    cannot take the output) or exit 2 (a path through a regular file)."""
    try:
        yield
    except OSError as err:
        if err.errno in _DISK_ERRNOS:
            where = err.filename or out_dir
            raise InfrastructureError(
                f"cannot write the campaign to {out_dir}: {_DISK_WORDS[err.errno]} "
                f"({what} {where})",
                hint="free space or choose a writable --out; the chunks already "
                     "written are kept and a rerun resumes from them") from None
        blocking = next((p for p in [Path(out_dir), *Path(out_dir).parents]
                         if p.exists() and not p.is_dir()), None)
        if blocking is not None or err.errno in (errno.ENOTDIR, errno.EEXIST):
            raise SpecError("--out", "a directory path (creatable)", str(out_dir),
                            hint=f"{blocking} is a file, not a directory"
                            if blocking is not None else err.strerror) from None
        raise


def one_line(err: BaseException) -> str:
    """``Type: message`` of ``err`` on one line (dask's messages span several)."""
    return " ".join(f"{type(err).__name__}: {err}".split())


class _QuietFileHandler(logging.FileHandler):
    def handleError(self, record):  # noqa: N802 - logging's name
        """A log that cannot be written (disk full) is dropped silently."""


@contextlib.contextmanager
def dask_log(out_dir: Path):
    """Send the loggers of ``distributed`` and ``tornado`` that have handlers
    (dask's logging configuration gives ``distributed``,
    ``distributed.client``, ... their own stderr handler) to
    ``out_dir/dask.log`` (opened at the first record); restore them when the
    block succeeds (after an error the log stays in the file: the client's
    background tasks may still report the failure)."""
    import distributed  # noqa: F401 - applies dask's logging configuration first

    handler = _QuietFileHandler(Path(out_dir) / "dask.log", delay=True)
    handler.setFormatter(logging.Formatter("%(asctime)s - %(name)s - %(levelname)s - "
                                           "%(message)s"))
    saved = {}
    for name in list(logging.root.manager.loggerDict):
        if name.split(".")[0] in ("distributed", "tornado"):
            logger = logging.getLogger(name)
            if logger.handlers:
                saved[name] = logger.handlers[:]
                logger.handlers = [handler]
    yield
    # restored on success only: after a lost scheduler the client's
    # reconnection task keeps logging until the process exits
    for name, handlers in saved.items():
        logging.getLogger(name).handlers = handlers
    handler.close()
