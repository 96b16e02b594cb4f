"""Suite-wide set-up: Hypothesis draws the same examples in any test order.

Hypothesis (6.170 here) mixes into its generation numeric constants mined from
the *local* modules loaded at draw time (every ``toolbox`` module that is
imported; site-packages and test files are left out). The examples of a
``derandomize=True`` test therefore depended on which toolbox modules earlier
tests happened to import: running under pytest-xdist, or one directory
alone, drew other motors than the full serial run (one of them broke a
property test that the serial order never reached). Importing every toolbox
module before the first test makes that pool the same in every order and
every worker, so each derandomised test is one fixed set of examples again.

Then the objects alive at that point (every module imported by the
collection and by that import: python-control, matplotlib, scipy, sympy,
numba, the toolbox) are frozen out of the cyclic garbage collector (``gc.freeze``):
they live as long as the process anyway, and each full collection walked
all of them again (measured: 2.3 s of a 32 s serial run of tests/analysis,
22 full collections of ~0.1 s; 1.0 s with the freeze). Garbage made by the
tests is collected as before: only the objects alive at the freeze are
exempt, and reference counting still frees any of them that is dropped
outside a cycle.
"""

from __future__ import annotations

import gc
import importlib
import os
import pkgutil
import sys

# The same BLAS regime as the cct command (toolbox/cli/__init__.py): the
# toolbox's matrices are small, and OpenBLAS threads in each of the suite's
# pytest-xdist workers oversubscribe the cores (measured: one in-process
# analysis of paper 003 took 0.45 s with the default threads on a busy
# 2-core machine, 0.26 s with one). Read when numpy first loads OpenBLAS,
# which no pytest plugin does before this file.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# Bytecode is cached even where PYTHONDONTWRITEBYTECODE is set (the shared
# machine's environment sets it): without the cache each
# pytest-xdist worker compiles and assertion-rewrites every test module and
# compiles the toolbox again (collection 5.1 s of CPU instead of 2.9 s per
# process), and so does every interpreter a test starts (cct, the import
# probes, dask workers; ~0.15 s each for `cct design`). The files go to
# __pycache__ (ignored by git; written atomically, so concurrent workers are
# safe). Set before pytest-xdist starts its workers, which inherit both.
sys.dont_write_bytecode = False
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)

import pytest

# collections while pytest imports the libraries and the test modules (every
# object made there lives as long as the process): one in 20,000 net
# allocations instead of 700
gc.set_threshold(20_000, 10, 10)

_loaded = False


def _import_all_toolbox_modules() -> None:
    import toolbox

    for info in pkgutil.walk_packages(toolbox.__path__, "toolbox."):
        if not info.name.endswith(".__main__"):
            importlib.import_module(info.name)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item) -> None:
    # once per process that runs tests (not in pytest-xdist's controller)
    global _loaded
    if not _loaded:
        _loaded = True
        _import_all_toolbox_modules()
        gc.collect()  # nothing unreachable is frozen (it would never be freed)
        gc.freeze()
