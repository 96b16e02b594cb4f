"""Campaign execution: chunks on Dask, one Parquet file per chunk, resume.

Layout of a campaign directory ``OUT``::

    OUT/campaign.json        manifest: schema, campaign hash, samples, build
    OUT/controller.json      the design (made once, on the client)
    OUT/chunks/rows-000000004000-000000004500.parquet
                             the measurements of rows 4000 .. 4499 (atomic write)
    OUT/results.parquet      every row, ordered by sample (written at the end)
    OUT/summary.json         yield, failure reasons, sensitivity, worst cases
    OUT/report.html          the campaign report

A chunk file is written by the client (workers return rows; they need no
shared file system) through :func:`toolbox._io.write_atomic`: a temporary
name, fsync, rename. A chunk is named by its row range, not by a chunk
number: a run first lists the valid chunk files (readable, of this
campaign's hash, with as many rows as their range) and evaluates only the
rows no file covers, split into chunks of :func:`chunk_size` rows. The
chunk size, the number of samples (or motors), the requirements, ``gate``
and ``min_yield`` are no part of the hash: a resume may chunk differently,
extending ``samples`` runs only the new rows, and new bounds re-judge the
stored measurements (:func:`toolbox.campaign._evaluate.judge_rows`, at the
end phase, never on a worker). Since a sample's row depends on
``(spec, seed, index)`` only, the final table is the one an uninterrupted
run gives. A chunk lost with a killed worker is re-run by the scheduler; a
chunk whose task raised is submitted again, up to :data:`CHUNK_ATTEMPTS`
times in a run, then written as error rows (:func:`judge_error_rows`), which
the next run evaluates again.

The end phase streams: the chunk files are read one at a time, judged and
appended to ``results.parquet`` (one row group each) while exact counters
take the yields, the failure counts per grid point and the worst cases
(:class:`toolbox.campaign._summary.Accumulator`); the rank correlations and
the report's figures use one seeded subsample of at most
:data:`toolbox.campaign._summary.SUBSAMPLE` rows, stratified so that its
failing share is the table's. The client's memory does not grow with the
number of rows (one byte per motor aside).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable


from .._io import remove_stale, write_atomic
from ..errors import InfrastructureError, SpecError
from ._cluster import (BuildMismatch, check_workers, connect, dask_log, disk_errors, one_line,
                       parse_address, probe_scheduler, worker_build)
from ._evaluate import Plan, evaluate_chunk, make_plan, warm_up
from ._store import (assemble, build, chunk_path, covering, gaps, spec_hash, split, stored,
                     write_chunk)

__all__ = ["CAMPAIGN_SCHEMA", "CampaignRun", "run_campaign", "campaign_hash", "read_results",
           "valid_chunks", "chunk_path", "chunk_size", "evaluate_serial", "CHUNK_ATTEMPTS"]

CAMPAIGN_SCHEMA = "cct.campaign/3"
#: Files of a campaign directory besides ``chunks/``.
OUTPUT_NAMES = ("campaign.json", "controller.json", "results.parquet", "summary.json",
                "report.html", "dask.log")
#: Times a chunk is submitted in one run before its rows are written as
#: error rows (a task that raised, or a ``KilledWorker`` after Dask's own
#: ``distributed.scheduler.allowed-failures`` worker deaths). The next run
#: evaluates error rows again.
CHUNK_ATTEMPTS = 3
#: Automatic chunk size: about this many tasks per worker thread ...
TASKS_PER_THREAD = 4
#: ... within these bounds (rows): below, the per-task cost (scheduling,
#: one batch per operating point, a Parquet file) dominates; above, a lost
#: task loses too much and the client holds too large a chunk.
MIN_CHUNK, MAX_CHUNK = 250, 10_000


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
        Chunk files the table is made of, chunks evaluated now (error chunks
        included), valid chunk files found on disk and used.
    seconds : float
        Wall time of the simulation phase (start-up included).
    startup_seconds : float
        Of which: cluster start or connection, plan broadcast and the
        workers' warm-up (kernel loaded), before the first chunk is submitted.
    chunk_size : int or None
        Rows per chunk of this run (None: nothing to run).
    error_rows : int
        Rows of chunks that failed :data:`CHUNK_ATTEMPTS` times (judged failing).
    end_seconds : float
        Wall time of the end phase (results.parquet, summary, report).
    files : list of Path
    """

    out_dir: Path
    summary: dict
    chunks_total: int
    chunks_run: int
    chunks_resumed: int
    seconds: float
    startup_seconds: float = 0.0
    chunk_size: int | None = None
    error_rows: int = 0
    end_seconds: float = 0.0
    files: list = field(default_factory=list)

    @property
    def table(self):
        """Every row of ``results.parquet`` (read now)."""
        return read_results(self.out_dir)

    @property
    def passed(self) -> bool:
        """The yield reaches ``campaign.min_yield`` (always, when none is given)."""
        return bool(self.summary["meets_min_yield"])


#: ``[campaign]`` keys that change no measured row (left out of the hash).
_NOT_ROWS = ("min_yield", "gate", "chunk_size", "samples", "motors")
#: Top-level spec tables that change no measured row: the title, and the
#: requirements (the rows are judged at the end phase; a design that depends
#: on them is covered by the executed controller).
_NOT_ROWS_TOP = ("title", "requirements")


def campaign_hash(spec, artifact=None) -> str:
    """Hash of what determines the measured rows: the resolved spec, the
    executed controller of ``artifact`` (method, sample time, delay, axes,
    decoupling, fcs weights; not its provenance), the row schema version and
    the toolbox build (version and source hash: rows of another build are
    never mixed in). Left out, since they change no measured row: the title,
    ``[requirements]`` (re-judged from the stored measurements), and
    ``campaign.samples``/``motors`` (row ``i`` depends on ``(seed, i)``
    only: extending a campaign keeps its rows), ``chunk_size``, ``gate`` and
    ``min_yield``."""
    raw = {k: v for k, v in spec.raw.items() if k not in _NOT_ROWS_TOP}
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


def chunk_size(spec, threads: int) -> int:
    """Rows per chunk: ``campaign.chunk_size`` when the spec gives it, else
    ``ceil(samples / (TASKS_PER_THREAD x threads))`` within
    ``[MIN_CHUNK, MAX_CHUNK]`` (and at most ``samples``): a few tasks per
    worker thread for balance, whatever the campaign's size.

    Examples: 1,000 samples on 2 threads: 250 rows (4 chunks); 10^6 on 2
    threads: 10,000 (100 chunks); 10^7 on 64 threads: 10,000 (1,000 files).
    """
    cfg = spec.campaign
    given = (spec.raw.get("campaign") or {}).get("chunk_size")
    if given is not None:
        return int(cfg.chunk_size)
    auto = -(-cfg.samples // (TASKS_PER_THREAD * max(1, int(threads))))
    return max(1, min(cfg.samples, max(MIN_CHUNK, min(MAX_CHUNK, auto))))


def valid_chunks(out_dir: str | Path, spec, artifact=None) -> set[tuple[int, int]]:
    """Row ranges ``(start, stop)`` of ``spec``'s campaign (for ``artifact``)
    already evaluated in ``out_dir`` (error rows not included)."""
    return {(c.start, c.stop) for c in stored(Path(out_dir), campaign_hash(spec, artifact))
            if c.error is None}


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
    cfg = spec.campaign
    write_atomic(path, json.dumps({
        "schema": CAMPAIGN_SCHEMA, "campaign": digest, "samples": cfg.samples,
        "seed": cfg.seed, "version": build()["toolbox"], "source": build()["source"],
        "spec_sha256": spec_hash(spec), "spec": spec.raw}, indent=1, sort_keys=True,
        default=str) + "\n")


def evaluate_serial(plan: Plan, ranges, on_chunk: Callable[[int, int, dict], None],
                    on_error: Callable[[int, int, str], None] | None = None) -> float:
    """Evaluate the row ``ranges`` in this process (no Dask), in order; a
    range that raises :data:`CHUNK_ATTEMPTS` times goes to ``on_error``
    (re-raised without one). Returns the warm-up time (s)."""
    t0 = time.perf_counter()
    warm_up(plan)
    startup = time.perf_counter() - t0
    for start, stop in ranges:
        for attempt in range(1, CHUNK_ATTEMPTS + 1):
            try:
                rows = evaluate_chunk(plan, start, stop)
            except Exception as err:
                if on_error is None:
                    raise
                if attempt == CHUNK_ATTEMPTS:
                    on_error(start, stop, one_line(err)[:500])
            else:
                on_chunk(start, stop, rows)
                break
    return startup


def _lost(address: str, err: BaseException | None = None) -> InfrastructureError:
    why = f" ({one_line(err)[:300]})" if err is not None else ""
    return InfrastructureError(f"lost the Dask scheduler at {address} during the campaign{why}",
                               hint="the chunks written are kept; rerun the same command on "
                                    "a working scheduler to resume (dask's log: OUT/dask.log)")


#: Seconds between checks that the scheduler connection is alive while no
#: chunk finishes.
LOST_CHECK = 1.0


def _evaluate_dask(plan: Plan, ranges_for: Callable[[int], list], on_chunk, on_error,
                   scheduler: str | None, workers: int | None, digest: str) -> tuple[float, int]:
    """Evaluate on Dask the ranges ``ranges_for(worker threads)`` returns; returns
    ``(start-up time (s), rows per chunk)``.

    An existing scheduler is probed and connected with deadlines and its
    workers' toolbox build is checked before anything is sent
    (:mod:`._cluster`). At most a window of chunks (twice the worker threads,
    at least 4) is in flight: the scheduler never holds a million tasks, and
    the client writes each chunk as it arrives. A chunk whose task raised is
    submitted again up to :data:`CHUNK_ATTEMPTS` times, then goes to
    ``on_error`` (error rows; the others go on). A scheduler lost mid-run
    (its connection closed, the client no longer running) ends the run with
    :class:`InfrastructureError`; the chunks written are kept.
    """
    from dask.distributed import Client, LocalCluster

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
        ranges = ranges_for(threads)
        size = max((b - a for a, b in ranges), default=0)
        window = max(4, 2 * threads)
        try:
            plan_f = [client.scatter(plan, broadcast=True, hash=False)]
            client.run(warm_up, plan)
        except (OSError, TimeoutError) as err:
            raise _lost(address, err) from None
        startup = time.perf_counter() - t0
        pending = list(ranges)[::-1]
        attempts: dict[tuple, int] = {}
        futures = {}
        arrived = threading.Event()  # set when a future finishes

        def submit():
            r = pending.pop()
            attempts[r] = attempts.get(r, 0) + 1
            if plan_f[0].status != "finished":  # its last holder died: send it again
                plan_f[0] = client.scatter(plan, broadcast=True, hash=False)
            fut = client.submit(evaluate_chunk, plan_f[0], r[0], r[1], retries=0, pure=False,
                                key=f"cct-rows-{digest[:12]}-{r[0]}-{r[1]}-{attempts[r]}")
            futures[fut] = r
            fut.add_done_callback(lambda _f: arrived.set())

        try:
            while pending and len(futures) < window:
                submit()
            while futures:
                done = [f for f in futures if f.done()]
                if not done:
                    if not arrived.wait(LOST_CHECK) and client.status != "running":
                        raise _lost(address)
                    arrived.clear()
                    continue
                for fut in done:
                    r = futures.pop(fut)
                    try:
                        rows = fut.result()
                    except BuildMismatch as err:
                        raise InfrastructureError(
                            str(err), hint="install the same build of the toolbox on every "
                            "worker and restart them") from None
                    except Exception as err:  # the task raised, its workers kept dying, ..
                        fut.release()
                        if client.status != "running":
                            raise _lost(address, err) from None
                        if attempts[r] < CHUNK_ATTEMPTS:
                            pending.append(r)
                        else:
                            on_error(r[0], r[1], one_line(err)[:500])
                    else:
                        fut.release()
                        on_chunk(r[0], r[1], rows)
                while pending and len(futures) < window:
                    submit()
        except (OSError, TimeoutError) as err:  # the connection itself failed
            raise _lost(address, err) from None
        return startup, size
    finally:
        _close(client, cluster)


def _close(client, cluster) -> None:
    """Close the client (and the LocalCluster) without waiting on a dead
    scheduler: bounded, and never raising over the error being reported."""
    try:
        client.close(timeout=5)
    except Exception:  # a scheduler already gone: nothing to close cleanly
        pass
    if cluster is not None:
        cluster.close()


def run_campaign(spec, out_dir: str | Path, *, scheduler: str | None = None,
                 workers: int | None = None, artifact=None,
                 progress: Callable[[int, int], None] | None = None,
                 report: bool = True) -> CampaignRun:
    """Run (or resume, or extend) the ``[campaign]`` of ``spec`` into ``out_dir``.

    Parameters
    ----------
    spec : toolbox.spec.Spec
        A spec with a ``[campaign]`` table.
    out_dir : str or Path
        Campaign directory (module docstring); rows already there for the
        same campaign are kept and skipped, whatever their chunking.
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
    InfrastructureError
        The cluster or the output disk is not usable, the scheduler was lost
        mid-run, or every chunk failed (nothing to judge).
    """
    if spec.campaign is None:
        raise SpecError("campaign", "a [campaign] table (missing)", file=spec.source)
    cfg = spec.campaign
    out_dir = Path(out_dir)
    remote = scheduler not in (None, "local", "serial")
    if remote:  # bad address: exit 2; nobody answering: exit 4, before the design
        probe_scheduler(parse_address(scheduler)[0])
    if artifact is None:
        from ..pipeline import design_spec

        artifact = design_spec(spec)
    elif abs(artifact.sample_time - spec.drive.sample_time) > 1e-12 * spec.drive.sample_time:
        raise SpecError("--controller", f"a design for drive.sample_time = "
                        f"{spec.drive.sample_time:g} s", artifact.sample_time,
                        hint="the controller runs at the spec's sample time")
    digest = campaign_hash(spec, artifact)
    with disk_errors(out_dir, "creating"):
        out_dir.mkdir(parents=True, exist_ok=True)
        _manifest(out_dir, spec, digest)
        # temporaries of a run killed while writing (write_atomic, assemble)
        remove_stale(out_dir, OUTPUT_NAMES)
        chunks = out_dir / "chunks"
        if chunks.is_dir():
            names = {m.group(1) for e in chunks.iterdir()
                     if (m := re.fullmatch(r"\.(rows-\d{12}-\d{12}\.parquet)\.\w{8}", e.name))}
            remove_stale(chunks, names)
    found = stored(out_dir, digest)
    for old in [c for c in found if c.error is not None]:  # error rows: evaluated again
        with disk_errors(out_dir, "removing"):
            old.path.unlink(missing_ok=True)
    kept = [c for c in found if c.error is None]
    todo = gaps([(c.start, c.stop) for c in kept], cfg.samples)
    samples_done = cfg.samples - sum(b - a for a, b in todo)
    if progress:
        progress(int(samples_done), cfg.samples)
    ran: list[tuple[int, int]] = []
    errors: list[tuple[int, int, str]] = []

    def on_chunk(start: int, stop: int, rows: dict) -> None:
        nonlocal samples_done
        with disk_errors(out_dir, "writing chunk"):
            write_chunk(out_dir, start, stop, rows, digest)
        ran.append((start, stop))
        samples_done += stop - start
        if progress:
            progress(int(samples_done), cfg.samples)

    def on_error(start: int, stop: int, message: str) -> None:
        nonlocal samples_done
        from ._sampling import draw_samples

        with disk_errors(out_dir, "writing chunk"):
            write_chunk(out_dir, start, stop, draw_samples(cfg, spec.motor, start, stop),
                         digest, error=message)
        ran.append((start, stop))
        errors.append((start, stop, message))
        samples_done += stop - start
        if progress:
            progress(int(samples_done), cfg.samples)

    t0 = time.perf_counter()
    startup, size = 0.0, None
    if todo:
        if scheduler == "serial":
            size = chunk_size(spec, 1)
            startup = evaluate_serial(make_plan(spec, artifact), split(todo, size), on_chunk,
                                      on_error)
        else:  # one simulation thread per Dask thread (the worker's --nthreads)
            plan = make_plan(spec, artifact, threads=1, build=worker_build())
            with dask_log(out_dir):
                startup, size = _evaluate_dask(plan, lambda t: split(todo, chunk_size(spec, t)),
                                               on_chunk, on_error, scheduler, workers, digest)
    seconds = time.perf_counter() - t0
    n_run = sum(b - a for a, b in ran)
    pieces = covering(stored(out_dir, digest), cfg.samples)
    if all(c.error is not None for c, _lo, _hi in pieces):
        first = min(errors) if errors else (0, 0, "?")
        raise InfrastructureError(
            f"every chunk failed on the workers after {CHUNK_ATTEMPTS} attempts each (rows "
            f"{first[0]}..{first[1] - 1}: {first[2][:300]})",
            hint="nothing could be judged; check the workers' logs, then rerun the same "
                 "command")
    t1 = time.perf_counter()
    with disk_errors(out_dir, "writing"):
        results, acc = assemble(out_dir, spec, artifact, digest, pieces)
    from ._summary import write_outputs

    sub = acc.subsample(results)
    summary = acc.summarize(sub, spec, artifact)
    summary["timing"] = {"seconds": seconds, "startup_seconds": startup,
                         "chunks_run": len(ran), "samples_run": n_run, "chunk_size": size,
                         "samples_per_s": (n_run / (seconds - startup)
                                           if ran and seconds > startup else None)}
    with disk_errors(out_dir, "writing"):
        files = [results] + write_outputs(out_dir, sub, summary, spec, artifact,
                                          report=report)
    return CampaignRun(out_dir=out_dir, summary=summary, chunks_total=len(pieces),
                       chunks_run=len(ran), chunks_resumed=len(kept), seconds=seconds,
                       startup_seconds=startup, chunk_size=size,
                       error_rows=int(summary["error_rows"]),
                       end_seconds=time.perf_counter() - t1, files=files)
