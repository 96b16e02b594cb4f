"""Campaign throughput benchmark (issue 14): samples per second.

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
4. scaling: the serial campaign at 500, 1000, 2000, 4000 samples.

Run: ``python tests/benchmarks/bench_campaign.py [samples]`` from the
repository root (default 2000 samples). The machine is shared: repeat a
route when a number looks off.
"""

from __future__ import annotations

import os
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


def main(samples: int = 2000) -> None:
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


if __name__ == "__main__":  # the LocalCluster spawns processes: guard needed
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
