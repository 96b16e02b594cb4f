"""Structured robust tuner (``method = "tune"``): wall time and its growth with the models.

Problem: designs/003_azaiz2007_tune.toml (paper 003's motor, Ts = 100 us, one
period of delay, the hard goal with the design delay and one period more).
The grid model set grows with ``samples`` (Latin-hypercube sets besides the
nominal point and the 32 corners), each at 4 speeds; every other setting is
the design file's (4 starts, 200 Nelder-Mead evaluations per start, a dense
check of 2,000 points + corners). Printed per size: the tuner's wall and
process CPU time, its evaluations, the cost of one candidate evaluation
(both delays' ``MultiModelLoops.disk_margins`` plus the nominal response
times; median of 20) and the result (slower axis' 5 % response, worst
margin), so the growth can be read apart from the optimiser's path, which
changes with the set.

Run: ``python tests/benchmarks/bench_tune.py [samples ...]`` from the
repository root (default 0 8 24 56: 33, 41, 57, 89 models).
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from dataclasses import replace

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _timing import pin_blas_threads  # noqa: E402

pin_blas_threads(1)  # small matrices: threads only add variance (before numpy)

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from toolbox.design import robust_pi as RP  # noqa: E402
from toolbox.design import tune as T  # noqa: E402
from toolbox.spec import load_spec  # noqa: E402

SPEC = os.path.join(ROOT, "designs", "003_azaiz2007_tune.toml")


def evaluation_cost(spec, cfg, art, repeats: int = 20) -> float:
    """Median seconds of one candidate evaluation on the grid set (both delays)."""
    models = RP.model_set(spec.motor, cfg.models)
    loops = [models.loops(spec.drive.sample_time, d, T.N_SEARCH)
             for d in T._delays(spec, cfg)]
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for L in loops:
            np.min(L.disk_margins(art))
        T.nominal_response_times(art, spec.motor)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(sizes=(0, 8, 24, 56)) -> None:
    spec = load_spec(SPEC)
    base = spec.controller.cfg
    print("structured tuner (method = \"tune\"), paper 003's motor, delay 1 and 2")
    print(f"{'models':>7} {'pairs':>6} {'wall s':>8} {'cpu s':>8} {'evals':>6} "
          f"{'eval ms':>8} {'t5 max ms':>10} {'worst margin':>13} {'added':>6}")
    for n in sizes:
        cfg = replace(base, models=replace(base.models, samples=int(n)))
        t0, c0 = time.perf_counter(), time.process_time()
        res = T.tune(spec, cfg)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        n_models = res["grid_models"]
        per = evaluation_cost(spec, cfg, res["artifact"])
        print(f"{n_models:>7} {n_models * len(res['speeds']):>6} {wall:>8.1f} {cpu:>8.1f} "
              f"{res['evaluations']:>6} {per * 1e3:>8.1f} "
              f"{max(res['response_time_5pct']) * 1e3:>10.3g} "
              f"{res['worst_disk_margin']:>13.3f} {res['active_models']:>6}", flush=True)


if __name__ == "__main__":
    main(tuple(int(a) for a in sys.argv[1:]) or (0, 8, 24, 56))
