"""The speed ramp through base speed (toolbox/verify/_envelope_ramp.py,
verify.json ``envelope.speed_ramp``): imposed speed from 0.5 to 1.5 x base
speed (capped by drive.max_speed), the reference held at the envelope's
torque limit of the top speed, judged over the whole ramp as a grid point.

* Paper 003's PI holds the corner reference through base speed to 1 mA (bound
  2 % of 20 A): the reference is the current-and-voltage corner of the top
  speed, within the voltage limit at the start, and the run's speed really
  crosses base speed.
* The predictive law on the Kollmorgen AKM42G (corpus) fails it by its peak:
  held at the current limit, its design ripple (up to 4.4 A of 13.6 A) takes
  the current to 16.67 A, beyond 1.2 x the limit (16.3 A): the check can fail.
* A drive.max_speed below 0.5 x base speed skips it; a failing ramp fails the
  verdict, is named in ``failures``; the CLI prints its line; the report's
  envelope table has it as its last row.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

import toolbox
from toolbox.sim import simulate
from toolbox.spec import Scenario
from toolbox.verify._envelope_grid import GRID_PEAK_LIMIT, GRID_TOLERANCE, grid_envelope
from toolbox.verify._envelope_ramp import RAMP_SPANS, speed_ramp

ROOT = Path(__file__).resolve().parents[2]


def _setup(spec):
    """The design, the verification's drive and span (as verify's envelope_grid)."""
    from toolbox.analysis.executed import settling_horizon
    from toolbox.sim import scenario_setup
    from toolbox.verify._default_scenarios import default_scenarios

    art = toolbox.design_spec(spec)
    defaults = default_scenarios(spec.motor, spec.drive, settling_horizon(art, spec.motor))
    span = max(sc.duration - (sc.step_time or 0.0) for sc in defaults)
    law, drive = scenario_setup(art, defaults[0], spec.drive)
    return law, drive, span


def test_ramp_paper003_pi_passes_through_base_speed():
    spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
    law, drive, span = _setup(spec)
    env = grid_envelope(spec.motor, drive)
    r = speed_ramp(law, spec.motor, drive, env, span=span, tolerance=GRID_TOLERANCE,
                   peak_limit=GRID_PEAK_LIMIT)
    base = env.base_speed()
    assert r.status == "pass", r.reason
    assert r.speed_start == pytest.approx(0.5 * base) and r.speed_end == pytest.approx(1.5 * base)
    assert r.region == "current_and_voltage_limit"
    assert math.hypot(r.i_d_ref, r.i_q_ref) == pytest.approx(env.I, rel=1e-6)
    # feasible over the ramp: at its ends within the voltage limit (convex in between)
    for w in (r.speed_start, r.speed_end):
        assert math.hypot(*env.voltage(r.i_d_ref, r.i_q_ref, w)) <= env.V * (1 + 1e-9)
    assert r.max_error < 1e-2 and r.error_bound == pytest.approx(GRID_TOLERANCE * env.I)
    assert r.acceleration * RAMP_SPANS * span == pytest.approx(r.speed_end - r.speed_start)
    # the run's speed crosses base speed within the judged window
    scen = Scenario(kind="constant_acceleration", duration=r.duration, step_time=span,
                    id_ref0=r.i_d_ref, iq_ref0=r.i_q_ref, id_ref=r.i_d_ref, iq_ref=r.i_q_ref,
                    initial_speed=r.speed_start - r.acceleration * span,
                    acceleration=r.acceleration, keep_traces=True, trace_step=drive.sample_time)
    res = simulate(law, spec.motor, scen, drive)
    speed = np.asarray(res.speed)
    judged = speed[np.asarray(res.t) >= span]
    assert judged.min() < base < judged.max()
    doc = r.to_json()
    assert doc["passed"] and "through base speed" in doc["summary"]


def test_ramp_skipped_below_half_base_speed():
    spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
    law, drive, span = _setup(spec)
    env = grid_envelope(spec.motor, drive)
    r = speed_ramp(law, spec.motor, drive, env, span=span,
                   max_speed=0.4 * env.base_speed(), tolerance=GRID_TOLERANCE,
                   peak_limit=GRID_PEAK_LIMIT)
    assert r.status == "skipped" and r.passed and "max_speed" in r.reason


@pytest.mark.slow
def test_ramp_fails_the_predictive_law_on_its_peak():
    from toolbox.pipeline import design_spec, run_verification
    data = tomllib.loads((ROOT / "tests" / "corpus" / "motors" / "kollmorgen_akm42g.toml")
                         .read_text())
    data["controller"] = {"method": "fcs_mpc"}
    spec = toolbox.spec_from_dict(data)
    res = run_verification(design_spec(spec), spec)
    env = res.envelope
    ramp = env["speed_ramp"]
    assert ramp["status"] == "fail" and "peak current" in ramp["reason"]
    assert ramp["peak_current"] > ramp["peak_bound"] == pytest.approx(1.2 * env["i_max"])
    assert not env["passed"] and not res.passed
    assert any(f.startswith("speed ramp") for f in env["failures"])


RAMP = {"status": "fail", "passed": False, "reason": "peak current 30 A (bound 24 A)",
        "speed_start": 50.0, "speed_end": 150.0, "torque": 3.0,
        "region": "current_and_voltage_limit",
        "summary": "speed ramp 50 -> 150 rad/s through base speed 100 rad/s at 3 N m "
                   "(current_and_voltage_limit): fail, max error 0.1 A (bound 0.4 A), "
                   "peak 30 A (bound 24 A)"}
ENVELOPE = {"passed": False, "counts": {"pass": 1, "fail": 0, "unreachable": 0},
            "summary": "torque-speed grid: 1 pass, 0 fail, 0 unreachable of 1 points",
            "failures": ["speed ramp 50 -> 150 rad/s: peak current 30 A (bound 24 A)"],
            "base_speed_rad_s": 100.0, "torque_limit_nm": 10.0,
            "curves": {"speed_rad_s": [0.0, 100.0], "torque_limit": [10.0, 10.0],
                       "current_limit": [10.0, 10.0], "voltage_limit": [None, 20.0]},
            "points": [{"speed_fraction": 0.0, "torque_fraction": 0.5, "speed": 0.0,
                        "torque": 5.0, "region": "mtpa", "status": "pass", "reason": None}],
            "speed_ramp": RAMP}


def test_cli_lines():
    """The grid's line (not FAILED: no grid point fails) and the ramp's (FAILED)."""
    import click
    import click.testing

    from toolbox.cli._echo import _envelope_failures, _envelope_line

    @click.command()
    def cmd():
        _envelope_line(type("R", (), {"envelope": ENVELOPE})())

    out = click.testing.CliRunner().invoke(cmd).output.splitlines()
    assert out == [ENVELOPE["summary"], RAMP["summary"] + ": FAILED"]
    assert _envelope_failures(type("R", (), {"envelope": ENVELOPE})()) == [
        "envelope: speed ramp 50 -> 150 rad/s: peak current 30 A (bound 24 A)"]
