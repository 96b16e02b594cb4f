"""What a user waits for: ``cct design`` of paper 003's H-infinity spec, warm
(caches filled by an earlier run) and cold (empty toolbox and numba caches:
a fresh machine's first design), and ``cct --help``.

Each figure is the median of ``n`` runs of the installed ``cct`` in a
subprocess: wall time and the child's CPU time (user + system). On a shared
machine the wall time includes waits for a core; the CPU time does not.
Run: ``python tests/benchmarks/bench_cli.py [n]`` from the repository root.
"""

from __future__ import annotations

import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "designs" / "003_azaiz2007_hinf.toml"


def _cct() -> list[str]:
    exe = Path(sys.executable).with_name("cct")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "toolbox.cli"]


def _run(args: list[str], env: dict) -> tuple[float, float]:
    """(wall s, CPU s) of one child run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(_cct() + args, env=env, check=False, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def time_command(args: list[str], n: int, cold: bool = False) -> tuple[float, float]:
    """Median (wall, CPU) seconds of ``n`` runs; ``cold``: fresh caches each run."""
    walls, cpus = [], []
    for _ in range(n):
        env = dict(os.environ)
        tmp = None
        if cold:
            tmp = tempfile.mkdtemp(prefix="bench-cold-")
            env.update(CCT_CACHE_DIR=os.path.join(tmp, "cct"),
                       NUMBA_CACHE_DIR=os.path.join(tmp, "numba"))
        wall, cpu = _run(args, env)
        walls.append(wall)
        cpus.append(cpu)
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
    return statistics.median(walls), statistics.median(cpus)


def main(n: int = 5) -> None:
    out = tempfile.mkdtemp(prefix="bench-design-")
    design = ["design", str(SPEC), "--out", out, "-q"]
    _run(design, dict(os.environ))                       # fill the caches
    print(f"user-facing commands (median of {n} runs: wall / CPU):")
    for name, args, cold, k in (("cct --help", ["--help"], False, n),
                                ("cct design 003 H-infinity, warm", design, False, n),
                                ("cct design 003 H-infinity, cold caches", design, True,
                                 max(1, n // 2))):
        wall, cpu = time_command(args, k, cold)
        print(f"  {name:<42} {wall:7.2f} s / {cpu:7.2f} s")
    shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
