"""Campaign execution: chunks on Dask, one Parquet file per chunk, resume.

Layout of a campaign directory ``OUT``::

    OUT/campaign.json        manifest: schema, campaign hash, samples, chunks
    OUT/controller.json      the design (made once, on the client)
    OUT/chunks/chunk-000042.parquet   the rows of chunk 42 (atomic write)
    OUT/results.parquet      every row, ordered by sample (written at the end)
    OUT/summary.json         yield, failure reasons, sensitivity, worst cases
    OUT/report.html          the campaign report

A chunk file is written by the client (workers return rows; they need no
shared file system) through :func:`toolbox._io.write_atomic`: a temporary
name, fsync, rename. A run first lists the valid chunk files (readable, of
this campaign's hash, with the expected sample range) and submits only the
missing chunks: an interrupted campaign resumes, and since a sample's row
depends on ``(spec, seed, index)`` only, the final table is the one an
uninterrupted run gives. A chunk lost with a killed worker is re-run by the
scheduler (Dask reschedules the tasks of a lost worker; ``retries`` covers
a task that raised).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .._io import remove_stale, write_atomic
from .._version import source_hash, toolbox_version
from ..errors import InfrastructureError, SpecError
from ._cluster import (BuildMismatch, check_workers, connect, disk_errors, parse_address,
                       probe_scheduler, worker_build)
from ._evaluate import Plan, chunk_range, evaluate_chunk, make_plan, warm_up
from ._summary import summarize, write_outputs
from ._report import report_columns

__all__ = ["CAMPAIGN_SCHEMA", "CampaignRun", "run_campaign", "campaign_hash", "read_results",
           "valid_chunks", "chunk_path", "evaluate_serial"]

CAMPAIGN_SCHEMA = "cct.campaign/2"
#: Files of a campaign directory besides ``chunks/``.
OUTPUT_NAMES = ("campaign.json", "controller.json", "results.parquet", "summary.json",
                "report.html")
#: Times a chunk whose task raised is submitted again before the campaign
#: gives up on it (Dask's own ``retries`` come on top).
CHUNK_ATTEMPTS = 3


def build() -> dict:
    """The toolbox build that computes the rows: ``{"toolbox": version,
    "source": source hash}`` (:func:`toolbox._version.source_hash`)."""
    return {"toolbox": toolbox_version(), "source": source_hash()}


def spec_hash(spec) -> str:
    """SHA-256 of the resolved spec as given (title and campaign table included)."""
    return hashlib.sha256(json.dumps(spec.raw, sort_keys=True, default=str)
                          .encode()).hexdigest()


@dataclass
class CampaignRun:
    """What :func:`run_campaign` did.

    Attributes
    ----------
    out_dir : Path
    table : pyarrow.Table
        Every row, ordered by sample (read from ``results.parquet`` when
        asked: a large campaign is never held in memory whole).
    summary : dict
        As written to ``summary.json``.
    chunks_total, chunks_run, chunks_resumed : int
        Chunks of the campaign, run now, found valid on disk.
    seconds : float
        Wall time of the simulation phase (start-up included).
    startup_seconds : float
        Of which: cluster start or connection, plan broadcast and the
        workers' warm-up (kernel loaded), before the first chunk is submitted.
    files : list of Path
    """

    out_dir: Path
    summary: dict
    chunks_total: int
    chunks_run: int
    chunks_resumed: int
    seconds: float
    startup_seconds: float = 0.0
    files: list = field(default_factory=list)

    @property
    def table(self):
        """Every row of ``results.parquet`` (read now)."""
        return read_results(self.out_dir)

    @property
    def passed(self) -> bool:
        """The yield reaches ``campaign.min_yield`` (always, when none is given)."""
        return bool(self.summary["meets_min_yield"])


#: ``[campaign]`` keys that change no row (left out of the campaign hash).
_NOT_ROWS = ("min_yield", "gate", "chunk_size")


def campaign_hash(spec, artifact=None) -> str:
    """Hash of what determines the rows: the resolved spec (campaign table
    included), the executed controller of ``artifact`` (method, sample time,
    delay, axes, decoupling, fcs weights; not its provenance), the row
    schema version and the toolbox build (version and source hash: rows of
    another build are never mixed in). The title, ``campaign.min_yield``,
    ``campaign.gate`` and ``campaign.chunk_size`` do not change a row and are
    left out (changing them keeps the rows; another chunk size re-runs the
    chunks, whose ranges differ)."""
    raw = {k: v for k, v in spec.raw.items() if k != "title"}
    if isinstance(raw.get("campaign"), dict):
        raw["campaign"] = {k: v for k, v in raw["campaign"].items() if k not in _NOT_ROWS}
    executed = None
    if artifact is not None:
        data = artifact.to_json()
        executed = {k: data[k] for k in ("method", "sample_time", "delay_samples", "axes",
                                         "decoupling", "fcs")}
    data = json.dumps({"schema": CAMPAIGN_SCHEMA, "spec": raw, "controller": executed,
                       "build": build()}, sort_keys=True, default=str)
    return hashlib.sha256(data.encode()).hexdigest()


def chunk_path(out_dir: Path, chunk: int) -> Path:
    """The Parquet file of ``chunk``."""
    return Path(out_dir) / "chunks" / f"chunk-{chunk:06d}.parquet"


def _to_arrow(rows: dict[str, np.ndarray], meta: dict):
    import pyarrow as pa  # lazy: pyarrow, 21 modules

    arrays = {}
    for name, v in rows.items():
        v = np.asarray(v)
        arrays[name] = pa.array(v.tolist() if v.dtype == object else v,
                                type=pa.string() if v.dtype == object else None)
    table = pa.table(arrays)
    return table.replace_schema_metadata({b"cct": json.dumps(meta).encode()})


def _chunk_meta(digest: str, cfg, chunk: int) -> dict:
    start, stop = chunk_range(cfg, chunk)
    return {"campaign": digest, "chunk": chunk, "start": start, "stop": stop, **build()}


def _write_chunk(out_dir: Path, chunk: int, rows: dict, digest: str, cfg) -> None:
    import pyarrow.parquet as pq  # lazy: pyarrow.parquet, 34 modules

    table = _to_arrow(rows, _chunk_meta(digest, cfg, chunk))
    buf = io.BytesIO()
    pq.write_table(table, buf)
    write_atomic(chunk_path(out_dir, chunk), buf.getvalue())


def _chunk_valid(path: Path, chunk: int, digest: str, cfg) -> bool:
    import pyarrow.parquet as pq  # lazy: pyarrow.parquet, 34 modules

    try:
        meta = json.loads(pq.read_schema(path).metadata[b"cct"])
        start, stop = chunk_range(cfg, chunk)
        return (meta == _chunk_meta(digest, cfg, chunk)
                and pq.read_metadata(path).num_rows == stop - start)
    except Exception:  # unreadable, truncated or foreign: run the chunk again
        return False


def valid_chunks(out_dir: str | Path, spec, artifact=None) -> set[int]:
    """Chunks of ``spec``'s campaign (for ``artifact``) already complete in ``out_dir``."""
    digest, cfg = campaign_hash(spec, artifact), spec.campaign
    return {c for c in range(cfg.n_chunks)
            if chunk_path(Path(out_dir), c).is_file()
            and _chunk_valid(chunk_path(Path(out_dir), c), c, digest, cfg)}


def read_results(out_dir: str | Path):
    """``results.parquet`` of a finished campaign, as a pyarrow Table."""
    import pyarrow.parquet as pq  # lazy: pyarrow.parquet, 34 modules

    return pq.read_table(Path(out_dir) / "results.parquet")


def _manifest(out_dir: Path, spec, digest: str) -> None:
    path = out_dir / "campaign.json"
    if path.is_file():
        try:
            old = json.loads(path.read_text())
        except (OSError, ValueError):
            old = {}
        if old.get("campaign") != digest:
            ours = build()
            theirs = {"toolbox": old.get("version", "?"), "source": old.get("source", "?")}
            if theirs != ours:
                raise SpecError(
                    "--out", "a new directory or one of the same campaign and toolbox build "
                    "(resume)", str(out_dir),
                    hint=f"its rows were computed by toolbox {theirs['toolbox']} (source "
                    f"{str(theirs['source'])[:12]}), this is toolbox {ours['toolbox']} "
                    f"(source {ours['source'][:12]}): rows of two builds are never mixed; "
                    "choose another --out, or resume with the build that started it")
            raise SpecError("--out", "a new directory or one of the same campaign (resume)",
                            str(out_dir), hint="it holds the results of another spec, "
                            "campaign table or controller; choose another --out or delete it")
        return
    cfg = spec.campaign
    write_atomic(path, json.dumps({
        "schema": CAMPAIGN_SCHEMA, "campaign": digest, "samples": cfg.samples,
        "chunk_size": cfg.chunk_size, "chunks": cfg.n_chunks, "seed": cfg.seed,
        "version": toolbox_version(), "source": source_hash(), "spec_sha256": spec_hash(spec),
        "spec": spec.raw}, indent=1, sort_keys=True, default=str) + "\n")


def evaluate_serial(plan: Plan, chunks, on_chunk: Callable[[int, dict], None]) -> float:
    """Evaluate ``chunks`` in this process (no Dask), in order; returns the
    warm-up time (s)."""
    t0 = time.perf_counter()
    warm_up(plan)
    startup = time.perf_counter() - t0
    for c in chunks:
        on_chunk(c, evaluate_chunk(plan, c))
    return startup


def _evaluate_dask(plan: Plan, chunks, on_chunk, scheduler: str | None, workers: int | None,
                   digest: str) -> float:
    """Evaluate ``chunks`` on Dask; returns the start-up time (s).

    An existing scheduler is probed and connected with deadlines and its
    workers' toolbox build is checked before anything is sent
    (:mod:`._cluster`). At most a window of chunks (twice the worker threads,
    at least 4) is in flight: the scheduler never holds a million tasks, and
    the client writes each chunk as it arrives. A chunk whose task raised
    (after Dask's own retries) is submitted again up to
    :data:`CHUNK_ATTEMPTS` times; a chunk that still fails does not stop the
    others, and the campaign then ends with :class:`InfrastructureError`
    naming it (its rows are missing; a rerun resumes).
    """
    from dask.distributed import Client, LocalCluster, as_completed  # lazy: 439 modules

    t0 = time.perf_counter()
    cluster = None
    if scheduler in (None, "local"):
        n = workers or os.cpu_count() or 1
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None,
                               scheduler_kwargs={"dashboard": False})
        client = Client(cluster)
        address = "the LocalCluster"
    else:
        address = parse_address(scheduler)[0]
        client = connect(address)
    try:
        if cluster is None:
            check_workers(client, address, workers)
        threads = sum(w.get("nthreads", 1) for w in
                      client.scheduler_info()["workers"].values()) or 1
        window = max(4, 2 * threads)
        plan_f = [client.scatter(plan, broadcast=True, hash=False)]
        client.run(warm_up, plan)
        startup = time.perf_counter() - t0
        pending = list(chunks)[::-1]
        attempts: dict[int, int] = {}
        failed: dict[int, str] = {}
        futures = {}

        def submit(seq):
            c = pending.pop()
            attempts[c] = attempts.get(c, 0) + 1
            if plan_f[0].status != "finished":  # its last holder died: send it again
                plan_f[0] = client.scatter(plan, broadcast=True, hash=False)
            fut = client.submit(evaluate_chunk, plan_f[0], c, retries=3, pure=False,
                                key=f"cct-chunk-{digest[:12]}-{c}-{attempts[c]}")
            futures[fut] = c
            seq.add(fut)

        queue = as_completed()
        while pending and len(futures) < window:
            submit(queue)
        for fut in queue:
            c = futures.pop(fut)
            try:
                rows = fut.result()
            except BuildMismatch as err:
                raise InfrastructureError(str(err), hint="install the same build of the "
                                          "toolbox on every worker and restart them") from None
            except (OSError, TimeoutError) as err:
                raise InfrastructureError(f"lost the Dask scheduler at {address}: "
                                          f"{type(err).__name__}: {err}",
                                          hint="the chunks written are kept: rerun the "
                                          "same command to resume") from None
            except Exception as err:  # the task raised (or its workers kept dying)
                fut.release()
                if attempts[c] < CHUNK_ATTEMPTS:
                    pending.append(c)
                else:
                    failed[c] = f"{type(err).__name__}: {err}"
            else:
                fut.release()
                on_chunk(c, rows)
            while pending and len(futures) < window:
                submit(queue)
        if failed:
            first = min(failed)
            raise InfrastructureError(
                f"{len(failed)} chunk(s) failed on the workers after {CHUNK_ATTEMPTS} "
                f"attempts each (chunk {first}: {failed[first][:200]})",
                hint="the other chunks are written; rerun the same command to retry the "
                     "missing ones")
        return startup
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_campaign(spec, out_dir: str | Path, *, scheduler: str | None = None,
                 workers: int | None = None, artifact=None,
                 progress: Callable[[int, int], None] | None = None,
                 report: bool = True) -> CampaignRun:
    """Run (or resume) the ``[campaign]`` of ``spec`` into ``out_dir``.

    Parameters
    ----------
    spec : toolbox.spec.Spec
        A spec with a ``[campaign]`` table.
    out_dir : str or Path
        Campaign directory (module docstring); chunks already there for the
        same campaign are kept and skipped.
    scheduler : str, optional
        ``None``/``"local"``: a Dask LocalCluster on this machine (127.0.0.1,
        one single-threaded worker process per core, or ``workers``);
        ``"tcp://host:8786"``: an existing Dask cluster; ``"serial"``: this
        process, no Dask (the reference the Dask runs are tested against).
    workers : int, optional
        LocalCluster workers; for an existing cluster, wait for this many.
    artifact : ControllerArtifact, optional
        The design (e.g. a candidate made from another spec, loaded with
        :func:`toolbox.pipeline.load_artifact`); default: designed from
        ``spec`` (once, here). Its sample time must be the spec's.
    progress : callable, optional
        ``progress(samples_done, samples_total)`` after each chunk.
    report : bool
        Write ``report.html``.

    Returns
    -------
    CampaignRun

    Raises
    ------
    SpecError
        No ``[campaign]`` table, ``out_dir`` holds another campaign (other
        spec or controller), or ``artifact`` has another sample time.
    """
    if spec.campaign is None:
        raise SpecError("campaign", "a [campaign] table (missing)", file=spec.source)
    cfg = spec.campaign
    out_dir = Path(out_dir)
    remote = scheduler not in (None, "local", "serial")
    if remote:  # bad address: exit 2; nobody answering: exit 4, before the design
        probe_scheduler(parse_address(scheduler)[0])
    if artifact is None:
        from ..pipeline import design_spec  # lazy: scipy.linalg + design, ~225 modules

        artifact = design_spec(spec)
    elif abs(artifact.sample_time - spec.drive.sample_time) > 1e-12 * spec.drive.sample_time:
        raise SpecError("--controller", f"a design for drive.sample_time = "
                        f"{spec.drive.sample_time:g} s", artifact.sample_time,
                        hint="the controller runs at the spec's sample time")
    digest = campaign_hash(spec, artifact)
    with disk_errors(out_dir, "creating"):
        out_dir.mkdir(parents=True, exist_ok=True)
        _manifest(out_dir, spec, digest)
        # temporaries of a run killed while writing (write_atomic, _assemble)
        remove_stale(out_dir, OUTPUT_NAMES)
        if (out_dir / "chunks").is_dir():
            remove_stale(out_dir / "chunks", {chunk_path(out_dir, c).name
                                              for c in range(cfg.n_chunks)})
    done = valid_chunks(out_dir, spec, artifact)
    todo = [c for c in range(cfg.n_chunks) if c not in done]
    samples_done = sum(chunk_range(cfg, c)[1] - chunk_range(cfg, c)[0] for c in done)
    if progress:
        progress(int(samples_done), cfg.samples)

    def on_chunk(c: int, rows: dict) -> None:
        nonlocal samples_done
        with disk_errors(out_dir, "writing chunk"):
            _write_chunk(out_dir, c, rows, digest, cfg)
        samples_done += len(rows["sample"])
        if progress:
            progress(int(samples_done), cfg.samples)

    t0 = time.perf_counter()
    startup = 0.0
    if todo:
        if scheduler == "serial":
            startup = evaluate_serial(make_plan(spec, artifact), todo, on_chunk)
        else:  # one simulation thread per Dask thread (the worker's --nthreads)
            plan = make_plan(spec, artifact, threads=1, build=worker_build())
            startup = _evaluate_dask(plan, todo, on_chunk, scheduler, workers, digest)
    seconds = time.perf_counter() - t0
    n_run = sum(chunk_range(cfg, c)[1] - chunk_range(cfg, c)[0] for c in todo)
    with disk_errors(out_dir, "writing"):
        results = _assemble(out_dir, spec, digest)
    table = _read_for_summary(results, spec, artifact)
    summary = summarize(table, spec, artifact)
    summary["timing"] = {"seconds": seconds, "startup_seconds": startup,
                         "chunks_run": len(todo), "samples_run": n_run,
                         "samples_per_s": (n_run / (seconds - startup)
                                           if todo and seconds > startup else None)}
    with disk_errors(out_dir, "writing"):
        files = [results] + write_outputs(out_dir, table, summary, spec, artifact,
                                          report=report)
    return CampaignRun(out_dir=out_dir, summary=summary,
                       chunks_total=cfg.n_chunks, chunks_run=len(todo),
                       chunks_resumed=len(done), seconds=seconds, startup_seconds=startup,
                       files=files)


def _assemble(out_dir: Path, spec, digest: str) -> Path:
    """Stream the chunk files, in sample order, into ``results.parquet``
    (temporary name, fsync, rename: readers never see half a file), one row
    group per chunk; memory holds one chunk at a time."""
    import pyarrow.parquet as pq  # lazy: pyarrow.parquet, 34 modules

    cfg = spec.campaign
    final = out_dir / "results.parquet"
    meta = {b"cct": json.dumps({"campaign": digest, "spec_sha256": spec_hash(spec),
                                "seed": cfg.seed, "samples": cfg.samples,
                                **build()}).encode()}
    fd, tmp = tempfile.mkstemp(prefix=".results.parquet.", dir=out_dir)
    os.close(fd)
    writer = None
    try:
        for c in range(cfg.n_chunks):
            path = chunk_path(out_dir, c)
            if not _chunk_valid(path, c, digest, cfg):  # pragma: no cover - a bug if reached
                raise RuntimeError(f"campaign: chunk {c} missing after the run")
            table = pq.read_table(path).replace_schema_metadata(meta)
            if writer is None:
                writer = pq.ParquetWriter(tmp, table.schema)
            writer.write_table(table)
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
    return final


def _read_for_summary(results: Path, spec, artifact):
    """The columns the summary and the report use (not every metric)."""
    import pyarrow.parquet as pq  # lazy: pyarrow.parquet, 34 modules

    names = pq.read_schema(results).names
    return pq.read_table(results, columns=report_columns(names, spec, artifact))
