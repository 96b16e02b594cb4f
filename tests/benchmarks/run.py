"""All benchmarks in one run (same machine, same moment): H-infinity design and
closed-loop simulation. ``python tests/benchmarks/run.py`` from the repository root."""

from __future__ import annotations

import os
import platform
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import bench_hinf  # noqa: E402
import bench_sim  # noqa: E402


def main() -> None:
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    bench_hinf.main()
    print()
    bench_sim.main()


if __name__ == "__main__":
    main()
