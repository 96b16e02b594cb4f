"""No traceback on hostile random motors through ``cct design``
(toolbox/ARCHITECTURE.md "Errors and exit codes": no traceback reaches a user).

Motors and drives drawn far outside the plausible range (zero, negative,
tiny, huge and non-finite numbers mixed with plausible ones) with every
linear method, through the CLI in process (click's CliRunner). The contract
of toolbox/ARCHITECTURE.md ("Errors and exit codes"): exit 0 (pass) or 1 (a design that fails; its outputs written),
or 2 with ``cct: error:`` and a message naming the spec file and a key path
(``motor.R``, ``drive.sample_time``, ``controller.pi.bandwidth``, ...) with
nothing written. Never a Python traceback, never another exit code.

Derandomised and bounded: most draws are refused while the spec is read (a
few ms); the plausible ones run the whole pipeline on a 100-period scenario.
One test per method, 3 examples each (24 in all): it was one test of 25
examples with the method drawn, which drew 6 of the 8 methods (ip and tc
never); now every method gets its examples by construction, at the same cost,
and the eight tests, tens of seconds together, spread over pytest-xdist's
workers.
"""

from __future__ import annotations

import importlib.util
import math
import re
import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from toolbox.cli import main

from test_random_motors import METHODS, _controller

#: slow: a cct subprocess per random motor
pytestmark = pytest.mark.slow

HOSTILE = Path(__file__).parents[1] / "hostile"

PROFILE = settings(max_examples=3, deadline=None, derandomize=True,
                   suppress_health_check=[HealthCheck.too_slow])

#: numbers where numerics break, mixed with the plausible range of each key
NASTY = st.sampled_from([0.0, -1.0, 1e-300, 1e300, 1e39, math.inf, -math.inf, math.nan])


def _value(lo: float, hi: float):
    """Plausible (log-uniform in [lo, hi]) 7 times in 8, else hostile: with
    nine keys about a third of the draws are plausible throughout and reach
    the design, analysis, verification, report and header."""
    plausible = st.floats(math.log(lo), math.log(hi)).map(math.exp)
    return st.integers(0, 7).flatmap(lambda k: NASTY if k == 0 else plausible)


@st.composite
def hostile_specs(draw, method: str):
    motor = {"R": draw(_value(0.01, 10.0)), "Ld": draw(_value(1e-5, 0.1)),
             "Lq": draw(_value(1e-5, 0.1)), "flux": draw(_value(1e-3, 0.5)),
             "pole_pairs": draw(st.integers(0, 7).flatmap(
                 lambda k: st.sampled_from([0, -3, 10 ** 9]) if k == 0 else st.integers(1, 12))),
             "J": draw(_value(1e-5, 1.0)), "friction": 0.0}
    drive = {"vdc": draw(_value(12.0, 800.0)), "sample_time": draw(_value(25e-6, 500e-6)),
             "delay_samples": 1}
    Ts = drive["sample_time"]
    # the method's parameters scaled to the (possibly hostile) motor, as in
    # test_random_motors; hostile numbers propagate into them too
    try:
        ctrl = _controller(method, motor, Ts if math.isfinite(Ts) and Ts > 0 else 1e-4)
    except (ZeroDivisionError, OverflowError):
        ctrl = {method: {}}
    i_ref = 0.1 * (drive["vdc"] if math.isfinite(drive["vdc"]) else 100.0)
    step = {"kind": "current_step", "iq_ref": min(abs(i_ref), 1e3), "step_time": 0.0,
            "duration": 100 * (Ts if math.isfinite(Ts) and 1e-6 < Ts < 1e-2 else 1e-4)}
    return {"title": "hostile random motor", "motor": motor, "drive": drive,
            "controller": {"method": method, **ctrl}, "scenario": [step]}


def _load_hostile_helpers():
    """tests/hostile/hostile_helpers.py (its spec-dict TOML writer) from its
    file: tests/hostile is on sys.path only once a test there was collected."""
    spec = importlib.util.spec_from_file_location("hostile_helpers",
                                                  HOSTILE / "hostile_helpers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


to_toml = _load_hostile_helpers().to_toml


@pytest.mark.parametrize("method", METHODS)
@PROFILE
@given(draws=st.data())
def test_cct_design_answers_with_an_exit_code_not_a_traceback(method, draws):
    data = draws.draw(hostile_specs(method), label="spec")
    with tempfile.TemporaryDirectory(prefix="cct_cli_") as tmp:
        spec = Path(tmp) / "spec.toml"
        spec.write_text(to_toml(data))
        out = Path(tmp) / "out"
        res = CliRunner().invoke(main, ["design", str(spec), "--out", str(out), "-q"])
        text = res.output
        event(f"exit {res.exit_code}")
        assert res.exception is None or isinstance(res.exception, SystemExit), (
            f"traceback: {res.exception!r}\n{text}")
        assert "Traceback" not in text, text
        assert res.exit_code in (0, 1, 2), (res.exit_code, text)
        if res.exit_code == 2:
            # the file, then a dotted key path of the spec, then what was expected
            assert re.search(rf"cct: error: {re.escape(str(spec))}: (\d+ errors:\s+)?"
                             r"(motor|drive|controller|scenario)[\w.\[\]]*: expected ", text), text
            assert not out.exists(), "exit 2 must write nothing"
        else:
            assert (out / "controller.json").is_file(), text
