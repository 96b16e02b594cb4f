"""``import toolbox`` and ``cct --help`` stay light (toolbox/ARCHITECTURE.md
"Caches and lazy imports").

python-control imports matplotlib.pyplot and scipy.signal (about 1 s on the
reference machine); sympy, cvxpy and numba cost as much again. They must be
imported only by the stage that uses them. The check is on which modules are
loaded, never on time (timings are for the benchmarks), so it is exact and
machine independent. It runs in a fresh interpreter because this test
process has long since imported everything.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("control", "matplotlib", "sympy", "cvxpy", "numba", "scipy", "slycot",
         "dask", "distributed", "pyarrow")  # the last three: cct campaign


def _loaded_after(code: str) -> set[str]:
    """Top-level packages from HEAVY that are in sys.modules after running ``code``."""
    probe = (f"{code}\nimport sys, json\n"
             f"print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & {set(HEAVY)!r})))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True, timeout=120)
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize("code", [
    "import toolbox",
    "import toolbox.spec; toolbox.spec.load_spec",
    "from toolbox.cli import main\n"
    "try:\n    main(['--help'], prog_name='cct')\nexcept SystemExit:\n    pass",
    "from toolbox.cli import main\n"
    "try:\n    main(['design', '--help'], prog_name='cct')\nexcept SystemExit:\n    pass",
    "from toolbox.cli import main\n"
    "try:\n    main(['campaign', '--help'], prog_name='cct')\nexcept SystemExit:\n    pass",
    "import toolbox.campaign",
])
@pytest.mark.slow
def test_light_imports(code):
    """None of the heavy packages is imported by the entry points."""
    assert _loaded_after(code) == set()


def test_lazy_names_resolve():
    """The lazily exported names are the real objects and listed by dir()."""
    import toolbox
    import toolbox.design
    from toolbox.artifact import ControllerArtifact
    from toolbox.design.pi import design_pi
    from toolbox.pipeline import design_spec
    assert toolbox.ControllerArtifact is ControllerArtifact
    assert toolbox.design_spec is design_spec
    assert toolbox.design.design_pi is design_pi
    assert {"ControllerArtifact", "design_spec"} <= set(dir(toolbox))
    for name in toolbox.__all__:
        assert getattr(toolbox, name) is not None
    for name in toolbox.design.__all__:
        assert getattr(toolbox.design, name) is not None
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        toolbox.nope  # noqa: B018


@pytest.mark.slow
def test_check_imports_only_the_named_method():
    """Reading a PI spec imports toolbox.design.pi, not the H-infinity module."""
    code = ("import sys, toolbox\n"
            "toolbox.load_spec('designs/003_azaiz2007_pi.toml')\n"
            "assert 'toolbox.design.pi' in sys.modules\n"
            "assert 'toolbox.design.hinf' not in sys.modules\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120,
                   cwd=__import__("pathlib").Path(__file__).resolve().parents[1])


@pytest.mark.slow
def test_design_analysis_and_report_equations_need_no_sympy_or_cvxpy(tmp_path):
    """With the on-disk cache warm (toolbox/_cache.py), designing paper 003's
    H-infinity controller, its certificate (Clarabel called directly) and the
    report's typeset equations import neither sympy nor cvxpy; the
    first process, on an empty cache, fills it. matplotlib is not checked here
    (the report's equations typeset with it on a cold cache); the tests below
    check the whole ``cct design``."""
    code = ("import json, sys\n"
            "from toolbox.spec import load_spec\n"
            "from toolbox.pipeline import design_spec\n"
            "from toolbox.analysis import largest_certified_scale\n"
            "from toolbox.report import _equations\n"
            "s = load_spec('designs/003_azaiz2007_hinf.toml')\n"
            "art = design_spec(s)\n"
            "largest_certified_scale(art, s.motor, s.drive, tol=0.5)\n"
            "rows = _equations(s)\n"
            "assert len(rows) == 6 and all(r['svg'] for r in rows)\n"
            "print(json.dumps(sorted(m for m in ('sympy', 'cvxpy') if m in sys.modules)))\n")
    env = {**__import__("os").environ, "CCT_CACHE_DIR": str(tmp_path)}
    root = __import__("pathlib").Path(__file__).resolve().parents[1]

    def loaded() -> list[str]:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True, timeout=300, cwd=root, env=env)
        return json.loads(out.stdout.strip().splitlines()[-1])

    assert loaded() == ["sympy"]  # empty cache: derived and typeset once
    assert sorted(p.name.split("-")[0] for p in tmp_path.iterdir()) == [
        "dq_model", "dq_numeric", "report_equations"]
    assert loaded() == []


#: Not on the path of ``cct design``: python-control and what it
#: pulls in (scipy.signal, matplotlib.pyplot), and cvxpy. slycot is: the
#: H-infinity design computes its norms with SLICOT ab13dd (~15 ms to import
#: after numpy and scipy, toolbox/ARCHITECTURE.md "H-infinity numerics").
NOT_ON_DESIGN_PATH = ("control", "scipy.signal", "matplotlib", "cvxpy")
#: Every design of designs/ (H-infinity included) is made without python-control.
DESIGNS = tuple(sorted(p.stem for p in
                       (Path(__file__).resolve().parents[1] / "designs").glob("*.toml")))


#: Designs made by the test below on a smaller model set: the tune design of designs/ costs
#: ~20 CPU-s (its optimisation over 41 models at 4 speeds, then a 2,000-point
#: dense check), while the question here is which modules its code loads. The
#: smaller set (R alone over a narrower box, one speed, no Latin-hypercube
#: sets, 10 dense points; both delays and the tuned decoupling kept) runs the
#: same functions - optimisation, worst-case search, dense check, header - at
#: about a fifth of the cost.
SMALLER = {"003_azaiz2007_tune": {"parameter_box": {"R": [0.9, 1.1]}, "n_speeds": 1,
                                  "samples": 0, "check_samples": 10}}


def _heavy_after_each(steps: dict[str, str]) -> dict[str, list[str]]:
    """Modules of NOT_ON_DESIGN_PATH loaded after each step of ``steps`` (name ->
    code), run in this order in one fresh interpreter (repo root): a module a
    step loads is listed from that step on."""
    probe = ["import sys, json", "seen = {}"]
    for name, code in steps.items():
        probe += [code, f"seen[{name!r}] = [m for m in {NOT_ON_DESIGN_PATH!r} if m in sys.modules]"]
    probe.append("print(json.dumps(seen))")
    root = __import__("pathlib").Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-c", "\n".join(probe)], capture_output=True,
                         text=True, check=True, timeout=600, cwd=root)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cct_design(spec: str, out_dir) -> str:
    """Code running ``cct design designs/<spec>.toml --out out_dir -q`` (exit 0 or 1)."""
    return ("from toolbox.cli import main\n"
            f"try:\n    main(['design', 'designs/{spec}.toml', '--out', {str(out_dir)!r}, '-q'],"
            " prog_name='cct')\n"
            "except SystemExit as e:\n    assert e.code in (0, 1, None), e.code\n")


@pytest.mark.slow
def test_designs_headers_and_cct_design_need_no_python_control(tmp_path):
    """None of NOT_ON_DESIGN_PATH is imported by: every design of
    designs/ and its C header (made with toolbox.lti), then ``cct design`` of
    paper 003's PI and of its H-infinity design, every stage (analysis,
    verification, header, report). One interpreter runs the three steps in
    turn (a fresh one costs a second of imports); each step's modules are
    listed, so a failure names the step that first loaded one."""
    designs = ("import tomllib\n"
               "from toolbox.spec import load_spec, spec_from_dict\n"
               "from toolbox.pipeline import design_spec\n"
               "from toolbox.export import write_header\n"
               f"for name in {DESIGNS!r}:\n"
               f"    if name in {SMALLER!r}:\n"
               "        with open(f'designs/{name}.toml', 'rb') as f:\n"
               "            data = tomllib.load(f)\n"
               f"        data['controller']['tune'].update({SMALLER!r}[name])\n"
               "        s = spec_from_dict(data)\n"
               "    else:\n"
               "        s = load_spec(f'designs/{name}.toml')\n"
               "    write_header(design_spec(s), s.motor, s.drive)\n")
    steps = {"designs and headers": designs,
             "cct design 003 PI": _cct_design("003_azaiz2007_pi", tmp_path / "pi"),
             "cct design 003 H-infinity": _cct_design("003_azaiz2007_hinf", tmp_path / "hinf")}
    assert _heavy_after_each(steps) == {name: [] for name in steps}


@pytest.mark.slow
def test_cct_design_of_a_constant_motor_needs_no_scipy_optimize(tmp_path):
    """``cct design`` of paper 003's H-infinity design (constant parameters),
    every stage, in a fresh interpreter: scipy.optimize (0.25 s of start-up)
    is not imported; a saturated motor's envelope imports it
    (``plant.envelope_of``)."""
    code = (_cct_design("003_azaiz2007_hinf", tmp_path / "hinf")
            + "import sys\nprint('scipy.optimize' in sys.modules)\n")
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=600, cwd=root)
    assert out.stdout.strip().splitlines()[-1] == "False"
