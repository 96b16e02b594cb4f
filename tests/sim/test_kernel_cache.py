"""The kernel's disk cache follows every source compiled into it (numba issue
#1833: numba keys a cached function on its own file only, so an edit of a
helper module left the old machine code in use)."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest
from numba.core.registry import CPUDispatcher

from toolbox.sim import _kernel

SIM = Path(_kernel.__file__).parent


def test_kernel_sources_cover_what_it_compiles_in():
    """Every module _kernel imports from the sim package (helpers compiled
    in, constants frozen in) and every file defining one of its compiled
    functions is in KERNEL_SOURCES: a new dependency must join the digest."""
    imported, todo = set(), ["_kernel.py"]
    while todo:                   # the kernel's parts import each other: follow them
        tree = ast.parse((SIM / todo.pop()).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                name = f"{node.module}.py"
                if name not in imported:
                    imported.add(name)
                    todo.append(name)
    compiled = {Path(inspect.getsourcefile(f.py_func)).name
                for f in vars(_kernel).values() if isinstance(f, CPUDispatcher)}
    parts = {"_kernel_layout.py", "_kernel_plant.py", "_kernel_metrics.py",
             "_kernel_steps.py", "_kernel_pwm.py", "_kernel_cv.py", "_kernel_sense.py"}
    assert imported == {"_inverter.py", "_metrics.py"} | parts
    assert compiled == {"_kernel.py", "_inverter.py"} | parts - {"_kernel_layout.py"}
    assert set(_kernel.KERNEL_SOURCES) == imported | compiled
    assert {f"{p}.py" for p in _kernel._KERNEL_PARTS} == compiled - {"_inverter.py"}


def test_digest_follows_each_source(tmp_path, monkeypatch):
    """The recorded key changes with the contents of each of KERNEL_SOURCES
    (copies edited one at a time) and with nothing else."""
    for name in _kernel.KERNEL_SOURCES:
        (tmp_path / name).write_bytes((SIM / name).read_bytes())
    monkeypatch.setattr(_kernel, "__file__", str(tmp_path / "_kernel.py"))
    keys = {_kernel.sources_digest()}
    assert _kernel.sources_digest() in keys                  # deterministic
    for name in _kernel.KERNEL_SOURCES:
        with open(tmp_path / name, "a") as f:
            f.write("# edited\n")
        keys.add(_kernel.sources_digest())
    assert len(keys) == 1 + len(_kernel.KERNEL_SOURCES)


def test_stale_indexes_are_dropped_once(tmp_path):
    """Without a stamp, or with another digest, the indexes of the kernel and
    its parts go (their data files and _inverter's own indexes stay) and the
    digest is recorded; with the recorded digest nothing is touched."""
    names = ["_kernel.run-810.py311.nbi", "_kernel.run-810.py311.1.nbc",
             "_inverter.svm_times-77.py311.nbi"]
    parts = ["_kernel_steps._steps-60.py311.nbi"]           # a part of the kernel
    for name in names + parts:
        (tmp_path / name).write_bytes(b"x")
    _kernel._drop_stale_cache(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        names[1:] + ["_kernel.sources.key"])
    assert (tmp_path / "_kernel.sources.key").read_text() == _kernel.sources_digest()

    (tmp_path / names[0]).write_bytes(b"x")          # compiled again, same sources
    _kernel._drop_stale_cache(tmp_path)
    assert (tmp_path / names[0]).exists()

    (tmp_path / "_kernel.sources.key").write_text("0" * 64)   # a source changed
    _kernel._drop_stale_cache(tmp_path)
    assert not (tmp_path / names[0]).exists()
    assert (tmp_path / "_kernel.sources.key").read_text() == _kernel.sources_digest()


def test_unusable_cache_directory_raises_nothing(tmp_path):
    """A cache path that cannot be a directory (here under a regular file;
    likewise one that cannot be written) raises nothing at import: numba
    caches nowhere there either."""
    (tmp_path / "file").write_bytes(b"")
    _kernel._drop_stale_cache(tmp_path / "file" / "cache")
    assert (tmp_path / "file").is_file()


@pytest.mark.slow
def test_sim_imports_with_the_jit_disabled():
    """With NUMBA_DISABLE_JIT=1 (numba's own debugging switch) the kernel is
    plain Python: importing toolbox.sim must not reach for a dispatcher's cache."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", "import toolbox.sim"], env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr


_VARIANT_PROBE = r"""
import json, math
from toolbox.artifact import Decoupling
from toolbox.sim import _kernel, _kernel_pwm, _kernel_steps
from toolbox.sim._simulate import ControlLaw, DriveParams, discrete_pi, simulate
from toolbox.spec import Motor, Scenario

M = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4, J=1.11e-3)
TS = 1e-4
law = ControlLaw(d=discrete_pi(M.Ld * 2000.0, M.R * 2000.0, TS),
                 q=discrete_pi(M.Lq * 2000.0, M.R * 2000.0, TS), sample_time=TS,
                 decoupling=Decoupling.from_motor(M))
drive = DriveParams(vdc=150.0, sample_time=TS, delay_samples=1, v_limit="circle",
                    v_max=150.0 / math.sqrt(2.0))
res = simulate(law, M, Scenario(kind="unloaded_start", duration=2e-3, iq_ref=10.0), drive)
(sig,) = _kernel._periods.signatures
print(json.dumps({
    "final": res.metrics["final_value"],
    "entries": {repr(v): [len(e[0].signatures), len(e[1].signatures)]
                for v, e in _kernel.ENTRIES.items()},
    "run": [str(s[-4:]) for s in _kernel._run.signatures],
    "frames": sorted({str(s[6]) for s in _kernel_steps._steps.signatures}),
    "helpers": {f.__name__: len(f.signatures) for f in (
        _kernel_steps._steps, _kernel_steps._steps_flux, _kernel_pwm._svm_period,
        _kernel_pwm._carrier_period, _kernel_pwm._carrier_half, _kernel._fcs_choice)},
    "expm1": "@expm1" in _kernel._periods.inspect_llvm(sig),
}))
"""


@pytest.mark.slow
def test_average_constant_run_compiles_no_other_variant(tmp_path):
    """In a fresh interpreter with an empty numba cache (``NUMBA_CACHE_DIR``: every
    function is compiled, none loaded), a constant-parameter, linear-law,
    average-inverter simulation compiles its own variant only: the other
    entries of ``_kernel.ENTRIES`` (complex-vector law, flux-state plant,
    switching inverters, stationary-frame hold) have no signature, nor have
    the flux-state plant loop, the switching inverters' period functions and
    the predictive choice; the plant loop is compiled for the rotor-frame
    hold only; the period loop is compiled once, without the complex-vector
    law (inlined, it would bring its ``expm1``)."""
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    out = subprocess.run([sys.executable, "-c", _VARIANT_PROBE], env=env, cwd=SIM.parents[1],
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.splitlines()[-1])
    assert 9.0 < got["final"] < 11.0           # the 10 A step ran
    default = repr((None, None, None, None))
    assert got["entries"].pop(default) == [1, 0]
    assert len(got["entries"]) == 11 and all(n == [0, 0] for n in got["entries"].values())
    assert got["run"] == ["(none, none, none, none)"]
    assert got["frames"] == ["Literal[int](0)"]  # the rotor-frame hold only
    assert got["helpers"].pop("_steps") == 2     # with and without a load torque
    assert got["helpers"] == {"_steps_flux": 0, "_svm_period": 0, "_carrier_period": 0,
                              "_carrier_half": 0, "_fcs_choice": 0}
    assert not got["expm1"]


def _lock_is_held(path) -> bool:
    """Whether another open file description holds ``flock`` on ``path``."""
    import fcntl
    import os

    fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return False
    except BlockingIOError:
        return True
    finally:
        os.close(fd)


def test_an_entry_first_call_holds_the_cache_directory_lock():
    """An entry point's first call in a process (numba loads or compiles the
    kernel then, and writes its cache index) holds the ``flock`` on the
    numba cache directory, so that processes compiling different variants
    at once (xdist or Dask workers on a cold cache) never number two cache
    entries alike (``_kernel._first_call_locked``: one index then pointed
    at the other variant's machine code); a compiled entry's call takes no
    lock (the simulations of a batch run in parallel)."""
    cache = _kernel._ENTRY.stats.cache_path

    class Entry:
        stats = _kernel._ENTRY.stats

        def __init__(self, signatures):
            self.signatures = signatures

        def __call__(self, x):
            return x, _lock_is_held(cache)

    assert _kernel._first_call_locked(Entry([]), 3) == (3, True)
    assert _kernel._first_call_locked(Entry(["compiled"]), 4) == (4, False)
    assert not _lock_is_held(cache)   # released after the call
