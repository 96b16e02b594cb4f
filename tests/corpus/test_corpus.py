"""A corpus of real motors, each designed with every method on defaults (README.md
"Defaults (no method parameters)").

``tests/corpus/motors/*.toml`` holds 38 motors in datasheet form (line-to-line
R and L, V/krpm or N m/A, rpm, kHz strings), from a 10 W gimbal motor at 12 V
to 150 kW traction machines at 800 V, surface and interior PM; each file
cites its source and marks every value the source does not print as assumed.
Three of them are saturated (a flux map or the algebraic saturation model):
their grid over every method is tests/corpus/test_saturated_methods.py.

Each case runs what ``cct design`` runs (design, analysis, verification on
the default scenarios, header) through the Python API and asserts the
exit-0 equivalent: ``DesignOutputs.passed`` (every default check of
verification, stability, no refused header) and a header (every method,
fcs_mpc included, exports one). Reports are built for one case only (they cost more than
the rest together).

Time: the full grid (33 motors x 9 methods) took 547 s on the shared 2-core
machine, over the CI budget; by default a representative grid runs (one
motor per class, every method: ``DEFAULT_MOTORS``), ``CCT_CORPUS=full``
runs all 33. Measured on the shared 2-core machine: the default grid (6 motors
x 9 methods, one report) 66-74 s (50 passed, 5 expected fcs failures: a band
wider than half the step is "not resolved" since the qa branch); the
full grid (CCT_CORPUS=full) 277 passed, 21 expected failures (18 fcs_mpc out of
reach, 3 in ``KNOWN``), 358 s alone, 674 s beside two other test runs.

Every design is also judged on the default drift box (toolbox/ARCHITECTURE.md
"Robustness verdict": R over -20..150 degC, Ld/Lq x0.8..1.1, flux over
temperature, speed-sensor errors, speeds up to the drive's maximum). Motors
whose files give the drive's top speed (``[drive] max_speed``: the Bolt, the
Camry 2007, the Model 3 rear motor) are judged up to it, the others up to
their rated speed; designs unstable there are listed in ``ROBUSTNESS_FAILS``
and must exit 1 (``passed`` false) with ``default.robustness`` alone failing,
naming the first unstable set and its speed.

Known failures are listed in ``KNOWN`` with the reason found; they are
``xfail(strict=True)``, so a fix makes the test say so. FCS-MPC cases whose
per-period ripple (``fcs_ripple``) is at least half the default step are
physically out of reach at the datasheet's sampling rate (the law holds one
of eight vectors for a whole period): a failure of those is reported as an
expected failure; every other fcs_mpc case must pass.
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

import pytest

import toolbox
from toolbox.pipeline import build_outputs
from toolbox.verify import default_scenarios
from toolbox.verify import fcs_ripple
from toolbox.sim._simulate import DriveParams

MOTOR_DIR = Path(__file__).parent / "motors"
MOTORS = sorted(p.stem for p in MOTOR_DIR.glob("*.toml"))
#: the saturated motors (a flux map or saturation model) have their own sweep over
#: every method with their recorded outcomes: tests/corpus/test_saturated_methods.py
SATURATED = tuple(m for m in MOTORS if any(k in (MOTOR_DIR / f"{m}.toml").read_text()
                                           for k in ("[motor.saturation]", "flux_map")))
METHODS = ("pi", "ip", "pi_lag", "tc", "tci", "ilq", "lq", "hinf", "fcs_mpc")
#: one motor per class: the 400 V automotive IPM, axial flux, industrial servo, small BLDC,
#: 48 V BLDC, hybrid traction IPM, traction IPM-SynRM judged up to its top speed
DEFAULT_MOTORS = ("automotive_ipmsm_400v", "emrax_228", "kollmorgen_akm42g", "maxon_ec45flat_50w",
                  "nanotec_db57m012", "toyota_prius2004_mg2", "tesla_model3_rear")
FULL = os.environ.get("CCT_CORPUS") == "full"

_EMF_RAMP = ("unloaded start: the back-EMF ramps with the speed and the type-1 loop "
             "(no EMF feedforward in the law) keeps a ramp error above the 5 % band")
#: (motor, method) -> reason (found by running the full grid)
KNOWN: dict[tuple[str, str], str] = {
    ("ipower_gm2804", "tc"): _EMF_RAMP + " (6.3 %: J = 1.2e-6 kg m^2, 2800 V/s per A)",
    ("gimbal_24v_7pp", "tc"): _EMF_RAMP + " (0.56 A step, J = 3e-6 kg m^2)",
    ("siemens_1fk7042", "pi_lag"): ("reach at half speed 4.0 ms against a bound of 3.5 ms: "
                                    "the 8 kHz lag of pi_lag on a 10 mH servo; marginal"),
}


_TOP_SPEED = ("unstable on the default drift box (toolbox/ARCHITECTURE.md \"Robustness verdict\") "
              "at the drive's top speed, {speed}: the corner R x0.843, Ld x0.8, Lq x0.8 of the "
              "hot, saturated motor with the decoupling's delayed, mismatched cross terms; the "
              "first-order cancellation PI and tc pass, every design with an integral zero at "
              "wc/4 (ip, tci, ilq, lq, hinf) or a lag (pi_lag) loses stability: exit 1 naming "
              "the set")
#: (motor, method) -> why the robustness verdict fails (and nothing else does): the
#: design exits 1 with ``default.robustness`` naming its first unstable set and speed
ROBUSTNESS_FAILS: dict[tuple[str, str], str] = {
    **{(m, k): _TOP_SPEED.format(speed=speed)
       for m, speed in (("tesla_model3_rear", "18,000 rpm (5655 rad/s electrical, 10 kHz)"),
                        ("toyota_camry2007", "14,000 rpm (5864 rad/s electrical, 10 kHz)"))
       for k in ("ip", "pi_lag", "tci", "ilq", "lq", "hinf")},
}

#: Designs whose only failure is the default torque-speed grid (toolbox/ARCHITECTURE.md
#: "Operating envelope") at 2 x base speed, deep in field weakening, where the
#: default design loses the current (settled error and peak beyond the limit):
#: findings of the grid, each named by the verdict; a regression elsewhere still fails.
_DEEP_FW = "loses the current at 2 x base speed in field weakening (torque-speed grid)"
ENVELOPE_FAILS: dict[tuple[str, str], str] = {
    ("emrax_228", "lq"): _DEEP_FW,
    ("kollmorgen_akm42g", "ip"): _DEEP_FW,
    ("kollmorgen_akm42g", "lq"): _DEEP_FW,
    ("tesla_model3_rear", "fcs_mpc"): "the predictive law settles 429 A off the torque-limited "
                                      "reference at 2 x base speed (torque-speed grid)",
}


def corpus_spec(motor: str, method: str):
    """The motor's spec with ``method`` and no method parameters (``file``: a
    ``flux_map`` path is relative to the spec's folder)."""
    path = MOTOR_DIR / f"{motor}.toml"
    data = tomllib.loads(path.read_text())
    data["controller"] = {"method": method}
    return toolbox.spec_from_dict(data, file=str(path))


def fcs_ripple_ratio(spec) -> float:
    """Design ripple of the default fcs_mpc law over the smallest default step (q axis)."""
    drive = DriveParams(vdc=spec.drive.vdc, sample_time=spec.drive.sample_time,
                        delay_samples=spec.drive.delay_samples,
                        v_limit=spec.drive.voltage_limit, inverter="fcs_mpc")
    r_hex, _ = drive.radii(spec.motor.torque_factor)
    ripple = fcs_ripple(r_hex, spec.drive.sample_time, min(spec.motor.Ld, spec.motor.Lq),
                        1.0, 0.0)
    step = min(s.iq_ref for s in default_scenarios(spec.motor, spec.drive))
    return ripple / step


def test_corpus_size_and_range():
    """At least 25 motors, 10 W gimbal to 150 kW traction, 12 V to 800 V, SPM and IPM."""
    assert len(MOTORS) >= 25
    specs = [corpus_spec(m, "pi") for m in MOTORS]
    vdc = [s.drive.vdc for s in specs]
    assert min(vdc) == 12.0 and max(vdc) == 800.0
    assert any(s.motor.Lq > 1.5 * s.motor.Ld for s in specs)       # interior PM
    assert any(s.motor.Lq == s.motor.Ld for s in specs)            # surface PM
    for path in MOTOR_DIR.glob("*.toml"):
        text = path.read_text()
        assert text.startswith("#") and "assumed" in text, f"{path.name}: cite the source"


def _cases():
    for motor in (MOTORS if FULL else DEFAULT_MOTORS):
        if motor in SATURATED:
            continue
        for method in METHODS:
            marks = []
            if (motor, method) in KNOWN:
                marks.append(pytest.mark.xfail(reason=KNOWN[motor, method], strict=True))
            yield pytest.param(motor, method, marks=marks, id=f"{motor}-{method}")


@pytest.mark.slow
@pytest.mark.parametrize("motor, method", list(_cases()))
def test_corpus_motor_designs_on_defaults(motor, method):
    spec = corpus_spec(motor, method)
    report = (motor, method) == ("automotive_ipmsm_400v", "pi")
    out = build_outputs(spec, analysis=True, verification=True, report=report, header=True)
    failed = {s.name: {k: c.get("reason") for k, c in s.checks.items() if not c["pass"]}
              for s in out.verification.scenarios if not s.passed}
    if (motor, method) in ROBUSTNESS_FAILS:
        # the only failure is the drift-box verdict, and it names the set and its speed
        assert not out.passed and not failed and out.header_refused is None
        bad = {k: c for k, c in out.verification.margin_checks.items() if not c["pass"]}
        assert list(bad) == ["default.robustness"], bad
        reason = bad["default.robustness"]["reason"]
        assert "first: R x" in reason and "rad/s electrical" in reason, reason
        assert out.verification.robustness["worst_disk_margin"] == 0.0
        return
    if (motor, method) in ENVELOPE_FAILS:
        # the only failures are grid points at 2 x base speed, each named with its reason
        assert not out.passed and not failed and out.header_refused is None
        bad = {k: c for k, c in out.verification.margin_checks.items() if not c["pass"]}
        assert not bad, bad
        env = out.verification.envelope
        fails = [p for p in env["points"] if p["status"] == "fail"]
        assert fails and all(p["speed_fraction"] == 2.0 and p["reason"] for p in fails), fails
        return
    env = out.verification.envelope or {}
    ramp = env.get("speed_ramp") or {}
    if (method == "fcs_mpc" and ramp.get("status") == "fail" and not failed
            and env["counts"]["fail"] == 0 and ramp["reason"].startswith("peak current")):
        # a finding of the speed ramp through base speed (toolbox/ARCHITECTURE.md
        # "Operating envelope"): held at the current limit, the predictive law's
        # design ripple takes the current past 1.2 x the limit (a drive's trip
        # margin); the only failure, named, and explained by that ripple
        assert not out.passed and out.header_refused is None
        bad = {k: c for k, c in out.verification.margin_checks.items() if not c["pass"]}
        assert not bad, bad
        assert ramp["peak_current"] <= env["i_max"] + env["design_band_a"], ramp
        assert any(f.startswith("speed ramp") for f in env["failures"])
        return
    if method == "fcs_mpc" and not out.passed:
        # a failure is accepted only where it is physically explained (module docstring)
        ratio = fcs_ripple_ratio(spec)
        if ratio >= 0.5:
            pytest.xfail(f"fcs_mpc: per-period ripple {ratio:.2f} x the default step at "
                         f"{1 / spec.drive.sample_time:.0f} Hz (physically out of reach)")
    assert out.passed, (failed, out.header_refused)
    assert out.header is not None and out.header.strip()
    if report:
        assert out.html and out.pdf
