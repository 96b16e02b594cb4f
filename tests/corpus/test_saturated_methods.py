"""Every method on defaults on the saturated corpus motors (``[motor.saturation]``
or ``flux_map`` in ``tests/corpus/motors``; toolbox/ARCHITECTURE.md "Saturated
motors"): what ``cct design SPEC --method M`` does, through the Python API
(design, analysis, verification on the default scenarios, header).

The outcome of each (motor, method) is recorded exactly: a design listed in
``FAILS`` must fail those checks and no other (the reason, measured with the
corpus files as they are, is next to it); every other design must pass.
Either way a change of outcome fails the test, so a fix says so.

Why the failures (measured, SyR-e THOR, tests/corpus/motors/flux_maps/README.md):
the designs use the incremental inductances at the rated MTPA point (22 A:
Ld 3.58 mH, Lq 10.0 mH); the default q step to 11 A with i_d = 0 runs where
they are Ld 6.19 mH, Lq 14.2 mH with a 1.9-2.0 mH cross term, and the map's
q flux there is 0.289 V s against Lq i_q = 0.110 V s of the nominal model
(at 133 rad/s electrical a 24 V d-axis back-EMF the decoupling does not
cancel). Laws with a slow low-frequency branch (pi_lag's lag, hinf's
weights) then reach the 5 % band after the ``default.reach`` bound; tc (no
integrator) keeps a static error (0.48 A, 4.4 %) at speed; cv overshoots by
16.5-18.7 % on all three steps (4.8 % on the constant-parameter motor
tangent at the step's end, (0, 11 A), 0 % on the nominal one: the q
inductance changes along the step, 33.7 mH near 0 A to 14.2 mH at 11 A);
tune (its q loop at 45 deg phase margin, overshoot 67-70 % on the saturated
plant) reaches the band 0.3 ms after the bound at standstill. pi, ip, tci, ilq, lq, robust_pi and fcs_mpc pass.

On the Baldor PM-SyRM every method passes, on its algebraic model and on its
measured map, except tune on the algebraic model: the same q loop at 45 deg
(overshoot 45 %, the 5 % band at 8.4 ms against the 8.0 ms bound at
standstill); on the measured map tune passes.

The torque-speed grid and the speed ramp through base speed (on
``toolbox.plant.SaturatedEnvelope``'s references) run on every design; their
outcomes are not recorded here (test_saturated_corpus.py records the Baldor
PI's: slow transients of the decoupling's saturated-flux error at speed):
each failing point is named and the verdict follows them.

Time: a design is 11-35 s on the shared 2-core machine (the first of a fresh
cache compiles the flux kernel, minutes), tune 100-170 s; the THOR row took
219 s under load; hence ``slow``.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

import toolbox
from toolbox.pipeline import build_outputs
from toolbox.spec import METHODS

MOTOR_DIR = Path(__file__).parent / "motors"
SATURATED = sorted(p.stem for p in MOTOR_DIR.glob("*.toml")
                   if "[motor.saturation]" in p.read_text() or "flux_map" in p.read_text())
#: tune (an optimisation over the drift box, 100-170 s a motor) runs on the two
#: motors where it fails; on the Baldor measured map it passes (measured, 166 s)
TUNE_ON = ("syre_thor_5kw_pmsyrm", "baldor_ecs101m0h7ef4_pmsyrm")

_Q11_SPEED = "q step to 11 A at 133.2 rad/s (0.5 x speed scale)"
#: (motor, method) -> {scenario: [failed checks]}, the reason in the module docstring
FAILS: dict[tuple[str, str], dict[str, list[str]]] = {
    ("syre_thor_5kw_pmsyrm", "pi_lag"): {_Q11_SPEED: ["default.reach"]},   # 11.9 ms vs 5.9 ms
    ("syre_thor_5kw_pmsyrm", "hinf"): {_Q11_SPEED: ["default.reach"]},     # 10.5 ms vs 5.9 ms
    ("syre_thor_5kw_pmsyrm", "tc"): {_Q11_SPEED: ["default.finite"]},      # static error 4.4 %
    ("syre_thor_5kw_pmsyrm", "cv"): {                                     # overshoot 16-19 %
        "q step to 11 A (0.5 x current scale) at standstill": ["default.reach"],
        "q step to 11 A, unloaded start": ["default.reach"],
        _Q11_SPEED: ["default.reach"]},
    ("syre_thor_5kw_pmsyrm", "tune"): {                                   # 8.9 ms vs 8.6 ms
        "q step to 11 A (0.5 x current scale) at standstill": ["default.reach"]},
    ("baldor_ecs101m0h7ef4_pmsyrm", "tune"): {                            # 8.4 ms vs 8.0 ms
        "q step to 6.2 A (0.5 x current scale) at standstill": ["default.reach"]},
}


def _spec(motor: str, method: str):
    """The motor's spec with ``method`` and no method parameters (``file`` makes
    a ``flux_map`` path relative to the spec's folder)."""
    path = MOTOR_DIR / f"{motor}.toml"
    data = tomllib.loads(path.read_text())
    data["controller"] = {"method": method}
    return toolbox.spec_from_dict(data, file=str(path))


def _cases():
    for motor in SATURATED:
        for method in METHODS:
            if method == "tune" and motor not in TUNE_ON:
                continue
            yield pytest.param(motor, method, id=f"{motor}-{method}")


def test_the_sweep_covers_every_method_and_the_recorded_failures_exist():
    assert "syre_thor_5kw_pmsyrm" in SATURATED and len(SATURATED) >= 3
    assert set(METHODS) >= {m for _, m in FAILS}
    assert {m for m, _ in FAILS} <= set(SATURATED)


@pytest.mark.slow
@pytest.mark.parametrize("motor, method", list(_cases()))
def test_saturated_motor_every_method_on_defaults(motor, method):
    spec = _spec(motor, method)
    assert spec.motor.magnetics is not None
    out = build_outputs(spec, analysis=True, verification=True, report=False, header=True)
    failed = {s.name: sorted(k for k, c in s.checks.items() if not c["pass"])
              for s in out.verification.scenarios if not s.passed}
    margins = {k: c.get("reason") for k, c in out.verification.margin_checks.items()
               if not c["pass"]}
    assert not margins, margins                  # stability and drift box hold everywhere
    assert out.header_refused is None and out.header is not None and out.header.strip()
    expected = FAILS.get((motor, method), {})
    assert failed == expected, (failed, expected)
    # the torque-speed grid and the speed ramp run on the saturated envelope's
    # references; each failing point is named and the verdict follows them
    env = out.verification.envelope
    assert "skipped" not in env and "speed_ramp" in env
    grid_named = [f for f in env["failures"] if not f.startswith("speed ramp")]
    assert len(grid_named) == env["counts"]["fail"]
    assert out.passed == (not expected and env["passed"])
