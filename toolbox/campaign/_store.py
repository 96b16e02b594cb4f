"""Chunk files of a campaign directory and the streaming end phase.

A chunk file holds the measurements of a row range (``rows-START-STOP``,
Parquet, metadata ``cct``: campaign hash, range, build, and ``error`` for
error rows); :func:`stored` lists the valid ones, :func:`gaps` and
:func:`split` say what is left to run, :func:`covering` picks the pieces of
the final table (a valid chunk wherever one covers a row, error rows only
where none does) and :func:`assemble` streams them, judged, into
``results.parquet`` (module docstring of :mod:`toolbox.campaign._run`).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._io import write_atomic
from .._version import source_hash, toolbox_version
from ._evaluate import judge_error_rows, judge_rows, make_plan

__all__ = ["build", "spec_hash", "chunk_path", "write_chunk", "Stored", "stored", "gaps",
           "split", "covering", "assemble", "CHUNK_NAME"]

CHUNK_NAME = re.compile(r"rows-(\d{12})-(\d{12})\.parquet")


def build() -> dict:
    """The toolbox build that computes the rows: ``{"toolbox": version,
    "source": source hash}`` (:func:`toolbox._version.source_hash`)."""
    return {"toolbox": toolbox_version(), "source": source_hash()}


def spec_hash(spec) -> str:
    """SHA-256 of the resolved spec as given (title and campaign table included)."""
    return hashlib.sha256(json.dumps(spec.raw, sort_keys=True, default=str)
                          .encode()).hexdigest()


def chunk_path(out_dir: Path, start: int, stop: int) -> Path:
    """The Parquet file of rows ``start .. stop - 1``."""
    return Path(out_dir) / "chunks" / f"rows-{start:012d}-{stop:012d}.parquet"


def _to_arrow(rows: dict[str, np.ndarray], meta: dict | None = None, schema=None):
    import pyarrow as pa

    arrays = {}
    for name, v in rows.items():
        v = np.asarray(v)
        arrays[name] = pa.array(v.tolist() if v.dtype == object else v,
                                type=pa.string() if v.dtype == object else None)
    table = pa.table(arrays)
    if schema is not None:  # a chunk of error rows: null measurements
        n = table.num_rows
        table = pa.table({f.name: (table.column(f.name).cast(f.type)
                                   if f.name in arrays else pa.nulls(n, f.type))
                          for f in schema}, schema=schema)
    if meta is not None:
        table = table.replace_schema_metadata({b"cct": json.dumps(meta).encode()})
    return table


def _chunk_meta(digest: str, start: int, stop: int, error: str | None = None) -> dict:
    return {"campaign": digest, "start": start, "stop": stop, "error": error, **build()}


def write_chunk(out_dir: Path, start: int, stop: int, rows: dict, digest: str,
                 error: str | None = None) -> None:
    import pyarrow.parquet as pq

    table = _to_arrow(rows, _chunk_meta(digest, start, stop, error))
    buf = io.BytesIO()
    pq.write_table(table, buf)
    write_atomic(chunk_path(out_dir, start, stop), buf.getvalue())


@dataclass(frozen=True)
class Stored:
    start: int
    stop: int
    path: Path
    error: str | None


def stored(out_dir: Path, digest: str) -> list[Stored]:
    """The valid chunk files of campaign ``digest`` (readable, of this hash,
    as many rows as their range), by start."""
    import pyarrow.parquet as pq

    found = []
    folder = Path(out_dir) / "chunks"
    if not folder.is_dir():
        return found
    for path in sorted(folder.iterdir()):
        m = CHUNK_NAME.fullmatch(path.name)
        if m is None:
            continue
        start, stop = int(m.group(1)), int(m.group(2))
        try:
            meta = json.loads(pq.read_schema(path).metadata[b"cct"])
            ok = (meta == _chunk_meta(digest, start, stop, meta.get("error"))
                  and pq.read_metadata(path).num_rows == stop - start)
        except Exception:  # unreadable, truncated or foreign: run the rows again
            ok = False
        if ok:
            found.append(Stored(start, stop, path, meta.get("error")))
    return found


def gaps(ranges, samples: int) -> list[tuple[int, int]]:
    """``[0, samples)`` less the union of ``ranges``."""
    out, cursor = [], 0
    for start, stop in sorted(ranges):
        if start > cursor:
            out.append((cursor, min(start, samples)))
        cursor = max(cursor, stop)
        if cursor >= samples:
            break
    if cursor < samples:
        out.append((cursor, samples))
    return [(a, b) for a, b in out if b > a]


def split(ranges, size: int) -> list[tuple[int, int]]:
    return [(a, min(hi, a + size)) for lo, hi in ranges for a in range(lo, hi, size)]


def covering(found: list[Stored], samples: int) -> list[tuple[Stored, int, int]]:
    """``(file, lo, hi)`` pieces covering ``[0, samples)`` in order: a valid
    chunk file wherever one covers a row (the one reaching furthest), error
    rows only where none does."""
    good = [c for c in found if c.error is None]
    bad = [c for c in found if c.error is not None]
    out, cursor = [], 0
    while cursor < samples:
        here = [c for c in good if c.start <= cursor < c.stop]
        if here:
            c = max(here, key=lambda c: c.stop)
            hi = min(c.stop, samples)
        else:
            here = [c for c in bad if c.start <= cursor < c.stop]
            if not here:  # pragma: no cover - a bug if reached
                raise RuntimeError(f"campaign: row {cursor} missing after the run")
            c = max(here, key=lambda c: c.stop)
            nxt = min([g.start for g in good if g.start > cursor], default=samples)
            hi = min(c.stop, samples, nxt)
        out.append((c, cursor, hi))
        cursor = hi
    return out


def assemble(out_dir: Path, spec, artifact, digest: str, pieces):
    """Stream the chunk files' rows, in sample order, judged against the
    spec's requirements, into ``results.parquet`` (temporary name, fsync,
    rename: readers never see half a file), one row group per piece, feeding
    an :class:`~toolbox.campaign._summary.Accumulator`; memory holds one
    chunk at a time. Returns ``(path, accumulator)``."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from ._summary import Accumulator

    cfg = spec.campaign
    plan = make_plan(spec, artifact)
    slugs = [slug for slug, *_ in plan.runs]
    final = out_dir / "results.parquet"
    meta = {b"cct": json.dumps({"campaign": digest, "spec_sha256": spec_hash(spec),
                                "seed": cfg.seed, "samples": cfg.samples,
                                **build()}).encode()}
    good = next(c for c, _lo, _hi in pieces if c.error is None)
    measured = pq.read_schema(good.path)
    schema = pa.schema(list(measured.remove_metadata()) + [
        pa.field("passed", pa.bool_()), pa.field("failure", pa.string()),
        pa.field("worst_check", pa.string()), pa.field("worst_ratio", pa.float64())],
        metadata=meta)
    acc = Accumulator(spec, artifact)
    fd, tmp = tempfile.mkstemp(prefix=".results.parquet.", dir=out_dir)
    os.close(fd)
    writer = None
    try:
        writer = pq.ParquetWriter(tmp, schema)
        for c, lo, hi in pieces:
            table = pq.read_table(c.path).slice(lo - c.start, hi - lo)
            cols = {name: table.column(name).to_numpy(zero_copy_only=False)
                    for name in table.column_names}
            judged = (judge_rows(cols, slugs, plan.bounds) if c.error is None
                      else judge_error_rows(hi - lo, c.error))
            piece = _to_arrow({**cols, **judged}, schema=schema.remove_metadata())
            writer.write_table(piece.replace_schema_metadata(meta))
            acc.add(piece, error=c.error is not None)
        writer.close()
        writer = None
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, final)
    except BaseException:
        if writer is not None:
            writer.close()
        Path(tmp).unlink(missing_ok=True)
        raise
    return final, acc
