"""Fixtures of the export tests: one gcc run per distinct build in a session.

Many tests compile the same header with the same driver and options (each
test checks another property of one binary); ``export_c_helpers`` keeps each
clean build once, in a directory of this run's temporary tree that every
pytest-xdist worker of the run shares (pytest removes it with the run's
other temporary files), so a later test with equal inputs copies the binary
instead of running gcc again. A build with diagnostics or errors is never
shared.
"""

from __future__ import annotations

import os

import pytest

import export_c_helpers


@pytest.fixture(scope="session", autouse=True)
def gcc_build_cache(tmp_path_factory):
    base = tmp_path_factory.getbasetemp()
    # under pytest-xdist each worker's base is <the run's base>/popen-gwN
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    export_c_helpers.BUILD_CACHE = root / "gcc-builds"
    yield
    export_c_helpers.BUILD_CACHE = None
