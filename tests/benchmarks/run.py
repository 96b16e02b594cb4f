"""All benchmarks in one run (same machine, same moment), what a user feels
first: ``cct design`` warm and cold and ``cct --help`` (``bench_cli``),
campaign samples per second (``bench_campaign``, in-process and on a
LocalCluster), the closed-loop simulator against a plain C loop and its
peers (``bench_sim``), then the H-infinity design against SLICOT
(``bench_hinf``). ``python tests/benchmarks/run.py`` from the repository root.

Routes are timed alternately (A B A B ..., medians and interquartile ranges of
the per-round ratios) on the process CPU clock (the machine may be shared: see
``_timing``); BLAS is pinned to one thread (small problems)."""

from __future__ import annotations

import os
import platform
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _timing import pin_blas_threads  # noqa: E402

pin_blas_threads(1)  # before numpy is imported (by the benchmarks below)

import bench_campaign  # noqa: E402
import bench_cli  # noqa: E402
import bench_hinf  # noqa: E402
import bench_sim  # noqa: E402


def main() -> None:
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    bench_cli.main()
    print()
    bench_campaign.main(1000)
    print()
    bench_sim.main()
    print()
    bench_hinf.main()


if __name__ == "__main__":
    main()
