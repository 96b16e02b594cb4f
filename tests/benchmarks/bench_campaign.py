"""Campaign throughput benchmark: samples per second.

Campaign: the test campaign of tests/campaign (PI on paper 003's motor, one
20 ms i_q step per sample, R, Ld, Lq, flux drawn, a grid of 8 operating
points, one batch per point and chunk; each
sample also gets its per-axis loop margins). Routes, each on a fresh output
directory, the design made once beforehand:

1. serial batch: ``toolbox.sim.simulate_batch`` alone on the same plants
   (the numba kernel on one thread per core, no draws, margins, Parquet or
   Dask): the simulator's ceiling;
2. the campaign in this process (``scheduler="serial"``: draws, simulation
   on all cores, margins, judging, Parquet);
3. the campaign on a LocalCluster with 1 and 2 single-thread workers (the
   numba batch runs on one thread per task there: the cluster's parallelism
   is its workers); the rate excludes the start-up (cluster start, plan
   broadcast, workers' warm-up), printed beside it;
4. scaling: the serial campaign at 500, 1000, 2000, 4000 samples;
5. the client's memory: the campaign of N samples on a LocalCluster of 2
   workers (chunk size automatic), each N in a fresh client process that
   reads its own peak resident set (``getrusage(RUSAGE_SELF)``: the workers
   are other processes; the LocalCluster's scheduler runs in the client and
   is counted) after the run, and its resident set after the design and the
   cluster start-up (the baseline); peak minus baseline is what the rows
   cost. The end phase streams (one chunk at a time, exact counters, a
   subsample of at most 10^5 rows for the rank correlations and figures), so
   the growth must not follow N once the chunk size and the subsample reach
   their caps (10,000 and 10^5 rows: from 10^5 samples on 2 workers).
   Default N: 10^4, 10^5 and 2 x 10^5 (about 10 min on 2 idle cores, 35 on
   a loaded machine); ``--memory 1000000`` runs 10^6 (37 min on 2 loaded
   cores: client peak 361 MB, README.md "Benchmarks").

Run: ``python tests/benchmarks/bench_campaign.py [samples] [--memory N ...]``
from the repository root (default 2000 samples). The machine is shared:
repeat a route when a number looks off.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _timing import pin_blas_threads  # noqa: E402

pin_blas_threads(1)

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "campaign"))


def main(samples: int = 2000, memory=(10**4, 10**5, 2 * 10**5)) -> None:
    from campaign_helpers import write_spec
    from toolbox.campaign import draw_samples, make_plan, run_campaign
    from toolbox.pipeline import design_spec
    from toolbox.sim import simulate_batch
    from toolbox.spec import load_spec

    tmp = Path(tempfile.mkdtemp(prefix="bench-campaign-"))

    def spec_of(n: int, chunk: int):
        d = tmp / f"spec-{n}-{chunk}"
        d.mkdir(exist_ok=True)
        return load_spec(write_spec(d, samples=n, chunk_size=chunk))

    spec = spec_of(samples, 250)
    artifact = design_spec(spec)
    plan = make_plan(spec, artifact)
    _slug, scenario, law, drive = plan.runs[0]
    cols = draw_samples(spec.campaign, spec.motor, 0, samples)
    motors = [spec.motor.with_overrides({k: float(cols[k][i]) for k in ("R", "Ld", "Lq", "flux")})
              for i in range(samples)]
    simulate_batch(law, motors[:8], scenario, drive)  # compile / load the cache
    t0 = time.perf_counter()
    simulate_batch(law, motors, scenario, drive, chunk=250)
    serial_batch = samples / (time.perf_counter() - t0)

    runs = iter(range(10**6))

    def campaign(n: int, chunk: int, scheduler, workers=None):
        out = tmp / f"out-{next(runs)}"  # a fresh directory: nothing resumed
        run = run_campaign(spec_of(n, chunk), out, scheduler=scheduler, workers=workers,
                           artifact=artifact, report=False)
        assert run.chunks_run == run.chunks_total
        return n / (run.seconds - run.startup_seconds), run.startup_seconds

    rows = [("serial batch (simulate_batch only, all cores)", (serial_batch, 0.0)),
            ("campaign in-process (scheduler='serial')", campaign(samples, 250, "serial"))]
    for w in (1, 2):
        rows.append((f"campaign LocalCluster, {w} worker(s)", campaign(samples, 250, None, w)))
    print(f"campaign benchmark: {samples} samples of one 20 ms closed-loop step, "
          f"chunks of 250, {os.cpu_count()} cores")
    for name, (rate, startup) in rows:
        print(f"  {name:<48} {rate:8.0f} samples/s   (start-up {startup:5.2f} s)")
    print("scaling (in-process campaign, chunks of 250):")
    for n in (500, 1000, 2000, 4000, 8000):
        t0 = time.perf_counter()
        rate, _ = campaign(n, 250, "serial")
        print(f"  {n:>6} samples: {rate:7.0f} samples/s, {time.perf_counter() - t0:6.2f} s "
              "total (with Parquet assembly and summary)")
    if memory:
        client_memory(memory)


def _rss_mb() -> float:
    """Resident set of this process now (MB), from /proc (Linux) or the peak."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _one_client(samples: int, out: str) -> None:
    """Child process: the LocalCluster campaign of ``samples`` rows; prints JSON."""
    from campaign_helpers import write_spec
    from toolbox.campaign import run_campaign
    from toolbox.pipeline import design_spec
    from toolbox.spec import load_spec

    d = Path(out) / "spec"
    d.mkdir(parents=True, exist_ok=True)
    path = write_spec(d, samples=samples, chunk_size=1)
    path.write_text(path.read_text().replace("chunk_size = 1\n", ""))  # automatic
    spec = load_spec(path)
    artifact = design_spec(spec)
    baseline = {}

    def progress(done, total):
        if "mb" not in baseline and done > 0:
            baseline["mb"] = _rss_mb()  # after start-up and the first chunk
        if done == total:
            baseline["sim_end_mb"] = _rss_mb()  # the last chunk written

    t0 = time.perf_counter()
    run = run_campaign(spec, Path(out) / "run", workers=2, artifact=artifact, report=True,
                       progress=progress)
    total = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps({"samples": samples, "peak_mb": peak, "baseline_mb": baseline.get("mb"),
                      "sim_end_mb": baseline.get("sim_end_mb"),
                      "seconds": total, "sim_seconds": run.seconds - run.startup_seconds,
                      "end_seconds": run.end_seconds, "chunk_size": run.chunk_size,
                      "chunks": run.chunks_run, "yield": run.summary["yield"]}))


def client_memory(sizes) -> None:
    """Item 5 of the module docstring: one fresh client process per size."""
    print("client memory, LocalCluster with 2 workers, automatic chunk size "
          "(peak resident set of the client process; baseline: after start-up and the "
          "first chunk):")
    rows = []
    for n in sizes:
        out = tempfile.mkdtemp(prefix=f"bench-campaign-mem-{n}-")
        res = subprocess.run([sys.executable, __file__, "--one-client", str(n), out],
                             capture_output=True, text=True, env={**os.environ,
                             "PYTHONPATH": str(ROOT)})
        if res.returncode != 0:
            print(f"  {n:>8} samples: failed\n{res.stderr[-2000:]}")
            continue
        r = json.loads(res.stdout.strip().splitlines()[-1])
        rows.append(r)
        print(f"  {n:>8} samples: client peak {r['peak_mb']:6.0f} MB (baseline "
              f"{r['baseline_mb']:5.0f} MB, growth {r['peak_mb'] - r['baseline_mb']:5.0f} MB); "
              f"{r['chunks']} chunks of {r['chunk_size']}; simulation "
              f"{r['sim_seconds']:7.1f} s ({1e3 * r['sim_seconds'] / n:.2f} ms/sample, "
              f"{n / r['sim_seconds']:.0f} samples/s), end phase {r['end_seconds']:5.1f} s")
    from toolbox.campaign._run import MAX_CHUNK, TASKS_PER_THREAD
    from toolbox.campaign._summary import SUBSAMPLE

    # from this size on the client holds the same bounded amounts whatever N:
    # one chunk of MAX_CHUNK rows and a subsample of SUBSAMPLE rows
    capped = max(SUBSAMPLE, TASKS_PER_THREAD * 2 * MAX_CHUNK)
    big = 10**6
    at_caps = [r for r in rows if r["samples"] >= capped]
    if rows:
        per = rows[-1]["sim_seconds"] / rows[-1]["samples"]
        print(f"  the client's rows are bounded from {capped} samples on (chunks of "
              f"{MAX_CHUNK} rows, a subsample of {SUBSAMPLE} rows; 1 byte per motor aside); "
              f"a 10^6-sample simulation takes about {per * big / 60:.0f} min on these 2 "
              f"workers ({1e3 * per:.2f} ms/sample)")
    if len(at_caps) >= 2:
        a, b = at_caps[0], at_caps[-1]
        slope = (b["peak_mb"] - a["peak_mb"]) / (b["samples"] - a["samples"])
        est = b["peak_mb"] + max(slope, 0.0) * (big - b["samples"])
        print(f"  peak growth between {a['samples']} and {b['samples']} samples: "
              f"{1e6 * slope:+.1f} MB per 10^6 samples; extrapolated client peak at 10^6 "
              f"samples: {est:.0f} MB (limit 500 MB)")

if __name__ == "__main__":  # the LocalCluster spawns processes: guard needed
    if len(sys.argv) > 1 and sys.argv[1] == "--one-client":
        _one_client(int(sys.argv[2]), sys.argv[3])
    elif "--memory" in sys.argv:
        k = sys.argv.index("--memory")
        client_memory([int(v) for v in sys.argv[k + 1:]])
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
