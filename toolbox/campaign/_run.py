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
from .._version import toolbox_version
from ..errors import CctError, SpecError
from ._evaluate import Plan, chunk_range, evaluate_chunk, make_plan, warm_up

__all__ = ["CAMPAIGN_SCHEMA", "CampaignRun", "run_campaign", "campaign_hash", "read_results",
           "valid_chunks", "chunk_path", "evaluate_serial"]

CAMPAIGN_SCHEMA = "cct.campaign/1"
#: Files of a campaign directory besides ``chunks/``.
OUTPUT_NAMES = ("campaign.json", "controller.json", "results.parquet", "summary.json",
                "report.html")
#: Seconds to wait for workers of an existing cluster.
CONNECT_TIMEOUT = 30


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


def campaign_hash(spec, artifact=None) -> str:
    """Hash of what determines the rows: the resolved spec (campaign table
    included), the executed controller of ``artifact`` (method, sample time,
    delay, axes, decoupling, fcs weights; not its provenance) and the row
    schema version. The title and ``campaign.min_yield`` do not change a row
    and are left out (changing them keeps the chunks)."""
    raw = {k: v for k, v in spec.raw.items() if k != "title"}
    if isinstance(raw.get("campaign"), dict):
        raw["campaign"] = {k: v for k, v in raw["campaign"].items() if k != "min_yield"}
    executed = None
    if artifact is not None:
        data = artifact.to_json()
        executed = {k: data[k] for k in ("method", "sample_time", "delay_samples", "axes",
                                         "decoupling", "fcs")}
    data = json.dumps({"schema": CAMPAIGN_SCHEMA, "spec": raw, "controller": executed},
                      sort_keys=True, default=str)
    return hashlib.sha256(data.encode()).hexdigest()


def chunk_path(out_dir: Path, chunk: int) -> Path:
    """The Parquet file of ``chunk``."""
    return Path(out_dir) / "chunks" / f"chunk-{chunk:06d}.parquet"


def _to_arrow(rows: dict[str, np.ndarray], meta: dict):
    import pyarrow as pa

    arrays = {}
    for name, v in rows.items():
        v = np.asarray(v)
        arrays[name] = pa.array(v.tolist() if v.dtype == object else v,
                                type=pa.string() if v.dtype == object else None)
    table = pa.table(arrays)
    return table.replace_schema_metadata({b"cct": json.dumps(meta).encode()})


def _write_chunk(out_dir: Path, chunk: int, rows: dict, digest: str, cfg) -> None:
    import pyarrow.parquet as pq

    start, stop = chunk_range(cfg, chunk)
    table = _to_arrow(rows, {"campaign": digest, "chunk": chunk, "start": start, "stop": stop})
    buf = io.BytesIO()
    pq.write_table(table, buf)
    write_atomic(chunk_path(out_dir, chunk), buf.getvalue())


def _chunk_valid(path: Path, chunk: int, digest: str, cfg) -> bool:
    import pyarrow.parquet as pq

    try:
        meta = json.loads(pq.read_schema(path).metadata[b"cct"])
        start, stop = chunk_range(cfg, chunk)
        return (meta == {"campaign": digest, "chunk": chunk, "start": start, "stop": stop}
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
    import pyarrow.parquet as pq

    return pq.read_table(Path(out_dir) / "results.parquet")


def _manifest(out_dir: Path, spec, digest: str) -> None:
    path = out_dir / "campaign.json"
    if path.is_file():
        try:
            old = json.loads(path.read_text())
        except (OSError, ValueError):
            old = {}
        if old.get("campaign") != digest:
            raise SpecError("--out", "a new directory or one of the same campaign (resume)",
                            str(out_dir), hint="it holds the results of another spec, "
                            "campaign table or controller; choose another --out or delete it")
        return
    cfg = spec.campaign
    write_atomic(path, json.dumps({
        "schema": CAMPAIGN_SCHEMA, "campaign": digest, "samples": cfg.samples,
        "chunk_size": cfg.chunk_size, "chunks": cfg.n_chunks, "seed": cfg.seed,
        "version": toolbox_version(), "spec": spec.raw}, indent=1, sort_keys=True, default=str) + "\n")


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
    """Evaluate ``chunks`` on Dask; returns the start-up time (s)."""
    from dask.distributed import Client, LocalCluster, as_completed

    t0 = time.perf_counter()
    cluster = None
    if scheduler in (None, "local"):
        n = workers or os.cpu_count() or 1
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None,
                               scheduler_kwargs={"dashboard": False})
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except OSError as err:
            raise CctError("--scheduler", "the address of a running dask scheduler "
                           "(tcp://host:8786)", scheduler, hint=str(err)) from None
    try:
        if workers and cluster is None:
            client.wait_for_workers(workers, timeout=CONNECT_TIMEOUT)
        plan_f = client.scatter(plan, broadcast=True, hash=False)
        client.run(warm_up, plan)
        startup = time.perf_counter() - t0
        futures = {client.submit(evaluate_chunk, plan_f, c, retries=3, pure=False,
                                 key=f"cct-chunk-{digest[:12]}-{c}"): c for c in chunks}
        for fut in as_completed(futures):
            c = futures[fut]
            on_chunk(c, fut.result())
            fut.release()
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
    from ._summary import summarize, write_outputs

    if spec.campaign is None:
        raise SpecError("campaign", "a [campaign] table (missing)", file=spec.source)
    cfg = spec.campaign
    out_dir = Path(out_dir)
    if artifact is None:
        from ..pipeline import design_spec

        artifact = design_spec(spec)
    elif abs(artifact.sample_time - spec.drive.sample_time) > 1e-12 * spec.drive.sample_time:
        raise SpecError("--controller", f"a design for drive.sample_time = "
                        f"{spec.drive.sample_time:g} s", artifact.sample_time,
                        hint="the controller runs at the spec's sample time")
    digest = campaign_hash(spec, artifact)
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
        _write_chunk(out_dir, c, rows, digest, cfg)
        samples_done += len(rows["sample"])
        if progress:
            progress(int(samples_done), cfg.samples)

    t0 = time.perf_counter()
    startup = 0.0
    if todo:
        if scheduler == "serial":
            startup = evaluate_serial(make_plan(spec, artifact), todo, on_chunk)
        else:
            threads = 1 if scheduler in (None, "local") else None
            startup = _evaluate_dask(make_plan(spec, artifact, threads=threads), todo,
                                     on_chunk, scheduler, workers, digest)
    seconds = time.perf_counter() - t0
    n_run = sum(chunk_range(cfg, c)[1] - chunk_range(cfg, c)[0] for c in todo)
    results = _assemble(out_dir, spec, digest)
    table = _read_for_summary(results, spec, artifact)
    summary = summarize(table, spec, artifact)
    summary["timing"] = {"seconds": seconds, "startup_seconds": startup,
                         "chunks_run": len(todo), "samples_run": n_run,
                         "samples_per_s": (n_run / (seconds - startup)
                                           if todo and seconds > startup else None)}
    files = [results] + write_outputs(out_dir, table, summary, spec, artifact, report=report)
    return CampaignRun(out_dir=out_dir, summary=summary,
                       chunks_total=cfg.n_chunks, chunks_run=len(todo),
                       chunks_resumed=len(done), seconds=seconds, startup_seconds=startup,
                       files=files)


def _assemble(out_dir: Path, spec, digest: str) -> Path:
    """Stream the chunk files, in sample order, into ``results.parquet``
    (temporary name, fsync, rename: readers never see half a file), one row
    group per chunk; memory holds one chunk at a time."""
    import pyarrow.parquet as pq

    cfg = spec.campaign
    final = out_dir / "results.parquet"
    fd, tmp = tempfile.mkstemp(prefix=".results.parquet.", dir=out_dir)
    os.close(fd)
    writer = None
    try:
        for c in range(cfg.n_chunks):
            path = chunk_path(out_dir, c)
            if not _chunk_valid(path, c, digest, cfg):  # pragma: no cover - a bug if reached
                raise RuntimeError(f"campaign: chunk {c} missing after the run")
            table = pq.read_table(path).replace_schema_metadata(None)
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
    import pyarrow.parquet as pq

    from ._report import report_columns

    names = pq.read_schema(results).names
    return pq.read_table(results, columns=report_columns(names, spec, artifact))
