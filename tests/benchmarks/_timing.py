"""Timing helpers shared by the benchmarks.

* :func:`pin_blas_threads` must run before numpy is first imported: the
  problems here are tiny (matrices of order <= 10), where a multi-threaded
  BLAS only adds variance (one ``mixsyn`` call once took 9 s under OpenBLAS
  thread contention).
* :func:`interleaved` times the routes alternately in one run (A B A B ...),
  so that a slow spell of the shared machine hits every route alike;
  :func:`ratio` reports the per-round ratio A_i/B_i as its median and
  interquartile range, the spread the printed claims must respect.
* The clock is the process's CPU time (``time.process_time``), not the wall
  clock: on a shared machine the wall time of a single-threaded route also
  counts the time the process waited for a core. That waiting is what made
  the "slow spells" (docs/performance.md) (the simulator at 70-85 ns per plant step for
  tens of calls while its CPU time stayed at ~48 ns: the load average was 4-6
  on 2 cores, other processes held them; wall/CPU reached 2-3). Reproduced
  once the kernel ran at ~29 ns per step of CPU time: 60 consecutive 1 s
  simulations, with 5-8 runnable processes on the 2 cores, took a median
  58 ns per step of wall time (max 80) while their CPU time stayed within
  28.7-32.5 ns, no steal time in /proc/stat; 60 more beside a pytest run
  (5-9 runnable) took 100-183 ns of wall time and 28.7-31.8 ns of CPU time.
  ``bench_sim`` prints both per call. A multi-threaded route (the parallel batch) must be timed on the
  wall clock.
"""

from __future__ import annotations

import gc
import os
import statistics
import time
from typing import Callable, Mapping

BLAS_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
            "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")


def pin_blas_threads(n: int = 1) -> None:
    """Set the BLAS/OpenMP thread counts (only effective before ``import numpy``)."""
    for key in BLAS_ENV:
        os.environ[key] = str(n)


def interleaved(routes: Mapping[str, Callable[[], object]], rounds: int,
                repeat: int = 1, quiet_gc: bool = False) -> dict[str, list[float]]:
    """Run every route ``repeat`` times per round, in turn; return each route's
    CPU seconds per call, one value per round.

    A route may return its own elapsed seconds as a ``float`` (e.g. a C
    program timing its inner loop with its own CPU clock); anything else it
    returns is ignored and the process CPU time is measured here.

    ``quiet_gc``: collect Python's garbage once before the rounds and keep
    the cyclic collector off through all of them (as ``timeit`` does for its
    run), so that a collection of what the other routes (or the harness:
    ``subprocess``) left behind is not charged to the route that happens to
    trigger it. Measured: in ``bench_sim`` a route calling
    ``simulate()`` after the C subprocesses took a median 0.3-0.4 ms more
    per call (1.5 % of a 1 s simulation) than the same kernel call without
    the collector. Once, not before every turn: a full collection (~17 ms
    through ~115k objects with numba loaded, memory-bound) leaves the core
    slower for the next ~8 ms (a 50 ms simulation repeated right after one:
    1.52, 1.45, 1.44, ... 1.31 ms from the 7th call on, as without it), so
    the in-process route timed next paid 0.8-1.1 ms per 1 s simulation
    (3-4 %), while a C route's process start-up ran before its own clock.
    """
    times: dict[str, list[float]] = {name: [] for name in routes}
    gc_was_on = gc.isenabled()
    if quiet_gc:
        gc.collect()
        gc.disable()
    try:
        for _ in range(rounds):
            for name, func in routes.items():
                t0 = time.process_time()
                own = 0.0
                for _ in range(repeat):
                    r = func()
                    own += r if isinstance(r, float) else 0.0
                cpu = time.process_time() - t0
                times[name].append((own if own else cpu) / repeat)
    finally:
        if quiet_gc and gc_was_on:
            gc.enable()
    return times


def quartiles(values: list[float]) -> tuple[float, float, float]:
    """(25 %, median, 75 %) of ``values``."""
    if len(values) == 1:
        return values[0], values[0], values[0]
    q1, q2, q3 = statistics.quantiles(values, n=4, method="inclusive")
    return q1, q2, q3


def ratio(a: list[float], b: list[float]) -> tuple[float, float, float]:
    """Quartiles (25 %, median, 75 %) of the per-round ratio a_i / b_i."""
    return quartiles([x / y for x, y in zip(a, b)])


def fmt_ratio(a: list[float], b: list[float], digits: int = 2) -> str:
    """``median [q25, q75] (n rounds)`` of a_i / b_i."""
    lo, med, hi = ratio(a, b)
    return f"{med:.{digits}f} [IQR {lo:.{digits}f}..{hi:.{digits}f}] ({len(a)} rounds)"


def fmt_time(values: list[float], scale: float = 1.0, unit: str = "s") -> str:
    """``median [q25..q75] unit`` of a route's times."""
    lo, med, hi = quartiles(values)
    return f"{med * scale:9.4g} {unit} [IQR {lo * scale:.4g}..{hi * scale:.4g}]"
