"""Verification: run a controller artifact through the spec's scenarios and judge it.

Reads only the artifact (the executed discrete laws, decoupling and model
parameters) and the spec's motor, drive, scenarios and requirements; nothing
is re-designed here. The stage (toolbox/ARCHITECTURE.md "Stages"): margins
and stability recomputed from the executed law (``toolbox.analysis``), the
drift-box verdict (:func:`toolbox.analysis.drift_verdict`), every scenario
simulated (``toolbox.sim``) and checked (the spec's requirements and the
default checks of :mod:`toolbox.verify._checks`), assembled as verify.json.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable

from toolbox.analysis import compute_margins, drift_verdict
from toolbox.analysis.executed import (INFORMATIONAL_METHODS, loop_stability,
                                       margin_disagreements, settling_horizon)
from toolbox.design import default_bandwidth
from toolbox.errors import SpecError
from toolbox.sim import DriveParams, SimResult, scenario_setup, simulate
from toolbox.spec import Motor, Scenario

from ._checks import LinearFigures, default_checks, fcs_ripple, finalise_check, step_facts
from ._default_scenarios import default_scenarios
from ._envelope_grid import (GRID_PEAK_LIMIT, GRID_TOLERANCE, grid_envelope, torque_speed_grid,
                             with_tangent_loops)
from ._envelope_ramp import speed_ramp
from ._fcs_metrics import ripple_band_step_times

__all__ = ["VERIFY_SCHEMA", "verify", "VerifyResult", "ScenarioOutcome", "NO_REQUIREMENTS",
           "ROBUSTNESS_CHECKS", "MAX_CHECK_TRACE_ROWS"]

VERIFY_SCHEMA = "cct.verify/1"


@dataclass
class ScenarioOutcome:
    """One scenario's metrics and checks (requirements and ``default.*``)."""

    name: str
    kind: str
    metrics: dict
    checks: dict
    result: SimResult | None = None

    @property
    def passed(self) -> bool:
        return all(c["pass"] for c in self.checks.values())

    def to_json(self) -> dict:
        return {"name": self.name, "kind": self.kind, "passed": self.passed,
                "metrics": {k: _finite_or_none(v) for k, v in self.metrics.items()},
                "requirements": {k: finalise_check(c) for k, c in self.checks.items()}}


@dataclass
class VerifyResult:
    """All scenario outcomes of a verification run.

    Attributes
    ----------
    method : str
    scenarios : list of ScenarioOutcome
    margin_checks : dict
        Margin requirements on the margins recomputed from the executed law,
        plus ``default.stable`` (the executed sampled loop of both axes).
    stability : dict
        Per axis ``{"stable", "spectral_radius", "basis"}``
        (:func:`toolbox.analysis.executed.loop_stability`).
    notice : str or None
        :data:`NO_REQUIREMENTS` when the spec has no ``[requirements]``.
    warnings : list of str
        Stored numbers that disagree with the recomputed ones, informational
        margin checks, and the like.
    informational : dict
        Checks shown but not deciding (fcs_mpc's baseline PI margins).
    envelope : dict or None
        The torque-speed grid (:func:`toolbox.verify.torque_speed_grid` as
        JSON, verify.json's ``envelope``): a reachable point that fails fails
        the verdict, unreachable points do not; ``{"skipped": reason}`` when
        the motor has no envelope (no current limit).
    header : dict or None
        ``cct verify`` only, when a controller.h lies next to controller.json:
        ``{"file", "law_sha256", "text_matches", "first_difference_line",
        "matches"}`` (the header's law digest against
        :meth:`~toolbox.artifact.ControllerArtifact.law_sha256`, its whole text
        against the header regenerated from the artifact,
        ``toolbox.pipeline.header_agreement``); a header exported from another
        controller.json or edited by hand fails the verdict.
    """

    method: str
    scenarios: list[ScenarioOutcome] = field(default_factory=list)
    margin_checks: dict = field(default_factory=dict)
    stability: dict = field(default_factory=dict)
    notice: str | None = None
    warnings: list[str] = field(default_factory=list)
    informational: dict = field(default_factory=dict)
    header: dict | None = None
    envelope: dict | None = None

    @property
    def robustness(self) -> dict | None:
        """The drift-box verdict (:class:`toolbox.analysis.DriftVerdict` as JSON) of
        the ``default.robustness`` or ``parameter_drift`` check, None when absent."""
        for checks in (self.margin_checks, self.informational):
            for key in ROBUSTNESS_CHECKS:
                if key in checks:
                    return checks[key].get("robustness")
        return None

    @property
    def passed(self) -> bool:
        return (all(s.passed for s in self.scenarios)
                and all(c["pass"] for c in self.margin_checks.values())
                and (self.header is None or self.header["matches"])
                and (self.envelope is None or self.envelope.get("passed", True)))

    def to_json(self) -> dict:
        out = {"schema": VERIFY_SCHEMA, "method": self.method, "passed": self.passed,
               "notice": self.notice, "warnings": list(self.warnings),
               "stability": self.stability, "robustness": self.robustness,
               "margin_requirements": {k: finalise_check(c)
                                       for k, c in self.margin_checks.items()},
               "scenarios": [s.to_json() for s in self.scenarios]}
        if self.informational:
            out["informational_margin_requirements"] = {
                k: finalise_check(c) for k, c in self.informational.items()}
        if self.header is not None:
            out["header"] = dict(self.header)
        if self.envelope is not None:
            out["envelope"] = dict(self.envelope)
        return out


#: Longest run (controller periods) whose traces verification keeps for the
#: default checks when the scenario does not ask for them: 10 values of 8 bytes
#: a row, 16 MB. Longer runs fall back on the simulator's (stricter) 5 % time.
MAX_CHECK_TRACE_ROWS = 200_000

#: The checks that hold the drift-box verdict: the default drive box, or the spec's box.
ROBUSTNESS_CHECKS = ("default.robustness", "parameter_drift")

#: The notice of a spec without ``[requirements]`` (CLI, verify.json, report).
NO_REQUIREMENTS = "no requirements given; default checks only"


def _finite_or_none(v: float) -> float | None:
    return float(v) if v is not None and math.isfinite(v) else None


def _margin_verdict(artifact, spec, file: str | None) -> tuple[dict, dict, dict, list, dict]:
    """Margin checks, stability, linear figures and warnings from the executed law."""
    margins = compute_margins(artifact, spec.motor)
    warnings = margin_disagreements(artifact.margins, margins, file)
    stability = loop_stability(artifact, spec.motor)
    fresh = {ax: m.to_json(extras=False) for ax, m in margins.items()}
    checks = spec.requirements.check_margins(fresh)
    informational = {}
    if artifact.method in INFORMATIONAL_METHODS:
        informational, checks = checks, {}
        if informational:
            warnings.append(f"margin requirements are informational for {artifact.method}: "
                            f"{INFORMATIONAL_METHODS[artifact.method]}")
    else:
        unstable = [ax for ax, s in stability.items() if s["stable"] is False]
        checks["default.stable"] = finalise_check({
            "quantity": "largest closed-loop pole magnitude (executed sampled loop)",
            "bound": 1.0, "value": max(s["spectral_radius"] for s in stability.values()),
            "unit": "1", "pass": not unstable,
            "reason": (f"the executed sampled loop of the {' and '.join(unstable)} axis is "
                       "unstable (a closed-loop pole on or outside the unit circle)"
                       if unstable else None)})
    # the drift box every design is judged on: the spec's parameter_drift, else the
    # default drive box (toolbox/ARCHITECTURE.md "Robustness verdict")
    drift = _drift_check(artifact, spec)
    key = "parameter_drift" if spec.requirements.parameter_drift else "default.robustness"
    (informational if artifact.method in INFORMATIONAL_METHODS else checks)[key] = drift
    linear = {ax: LinearFigures(m.bandwidth_rad_s, m.response_time_5pct)
              for ax, m in margins.items()}
    return checks, stability, linear, warnings, informational


def _drift_check(artifact, spec) -> dict:
    """The robustness verdict: the executed coupled sampled loop (delay,
    decoupling with the controller's own parameters, speed-sensor errors)
    stays stable for every evaluated set of the drift box at every speed up to
    the maximum (:func:`toolbox.analysis.drift_verdict`: the spec's
    ``[requirements] parameter_drift``, else the default drive box
    :data:`toolbox.analysis.DRIVE_DRIFT`). The record carries the worst
    multiloop disk margin over the box and the box itself (``robustness``).
    """
    v = drift_verdict(artifact, spec.motor, spec.drive, spec.requirements.parameter_drift)
    return finalise_check({
        "quantity": (f"unstable sets of {v.n_sets} ({v.box_text}; corners and samples, "
                     f"electrical speeds up to {v.max_speed_rad_s:.4g} rad/s)"),
        "bound": 0, "value": v.n_unstable, "unit": "sets",
        "pass": v.passed, "reason": v.failure(), "robustness": v.to_json()})


def _fcs_linear_figures(drive) -> dict[str, LinearFigures]:
    """The reach-time yardstick of the predictive law: the default linear loop.

    The axes of an ``fcs_mpc`` artifact hold paper 002's baseline PI, whose
    margins are informational (it is not executed; its sampled loop may even
    be unstable for a high-R/L motor, leaving no bandwidth and no reach
    bound). The switching law is a minimum-time law, so it is held to the
    time the default linear design of this drive reaches its band in
    (bandwidth ``wc`` of :func:`toolbox.design.default_bandwidth`).
    """
    wc = default_bandwidth(drive).value
    return {ax: LinearFigures(wc, math.nan) for ax in ("d", "q")}


def _fcs_ripple(artifact, drive: DriveParams, true_plant: Motor,
                r_hex: float) -> dict[str, float] | None:
    """Per-axis design ripple of the predictive switching law, None for other inverters.

    One vector held for a whole period, and the switching penalty's dead band
    (:func:`toolbox.verify._checks.fcs_ripple`).
    """
    if drive.inverter != "fcs_mpc" or artifact.fcs is None:
        return None
    fcs, L_min = artifact.fcs, min(true_plant.Ld, true_plant.Lq)
    return {"q": fcs_ripple(r_hex, drive.sample_time, L_min, fcs.alpha, fcs.gamma, fcs.beta),
            "d": fcs_ripple(r_hex, drive.sample_time, L_min, fcs.beta, fcs.gamma, fcs.alpha)}


def _fcs_step_times(scenario: Scenario, res: SimResult, true_plant: Motor, artifact,
                    ripple: dict[str, float]) -> dict[str, float]:
    """5 % / 2 % times of a switching-law current step in the band max(b |delta|, ripple).

    See :mod:`toolbox.verify._fcs_metrics`; empty (the kernel's metrics stand)
    without traces or without a current step.
    """
    facts = step_facts(scenario, true_plant, artifact.decoupling.flux_c)
    if facts.axis is None or not facts.has_step or getattr(res, "t", None) is None:
        return {}
    y = res.iq if facts.axis == "q" else res.id
    times, _ = ripple_band_step_times(res.t, y, facts.y0, facts.yf, scenario.step_time or 0.0,
                                      scenario.duration, ripple[facts.axis])
    return times


def verify(artifact, spec, progress: Callable[[int, int], None] | None = None,
           keep_traces: bool = True, file: str | None = None) -> VerifyResult:
    """Simulate ``artifact`` in every scenario of ``spec`` and check it.

    Margins and stability are recomputed from the executed law (the numbers
    stored in the artifact are only compared, see
    :mod:`toolbox.analysis.executed`); every scenario gets the default checks
    of :mod:`toolbox.verify._checks` besides the spec's requirements. In
    verify.json both sit under each scenario's ``requirements`` (the
    ``default.*`` keys), ``default.stable`` under ``margin_requirements``;
    every failing record has a ``reason`` and no value is NaN.

    Parameters
    ----------
    artifact : ControllerArtifact
        The design to verify.
    spec : Spec
        Motor (the simulated plant, before per-scenario overrides), drive,
        scenarios (defaults from :func:`default_scenarios` when none) and
        requirements (the ``sim`` stage bounds).
    progress : callable, optional
        Called as ``progress(done, total)`` after each scenario.
    keep_traces : bool
        Keep the simulated traces (for reports) when the scenario asks.
    file : str, optional
        The controller.json the artifact came from (named in warnings).

    Returns
    -------
    VerifyResult
    """
    scenarios = spec.scenarios or default_scenarios(spec.motor, spec.drive,
                                                    settling_horizon(artifact, spec.motor))
    plant = spec.motor  # the true plant is the spec's Motor (one parameter type)
    margin_checks, stability, linear, warnings, info = _margin_verdict(artifact, spec, file)
    if artifact.fcs is not None:
        linear = _fcs_linear_figures(spec.drive)
    out = VerifyResult(method=artifact.method, margin_checks=margin_checks,
                       stability=stability, warnings=warnings, informational=info,
                       notice=None if spec.requirements.given else NO_REQUIREMENTS)
    for k, sc in enumerate(scenarios):
        law, drive = scenario_setup(artifact, sc, spec.drive)
        # the reach check reads the traces at the controller instants (the kernel's 5 %
        # time also sees the switching ripple inside a period); they are kept when small
        rows = sc.duration / spec.drive.sample_time
        run = (sc if sc.keep_traces or rows > MAX_CHECK_TRACE_ROWS
               else dataclasses.replace(sc, keep_traces=True))
        res = simulate(law, plant, run, drive)  # simulate applies the scenario's overrides
        metrics = dict(res.metrics)
        true_plant = plant.with_overrides(sc.plant_values, sc.plant_scale)
        r_hex, v_max = drive.radii(plant.torque_factor)
        ripple = _fcs_ripple(artifact, drive, true_plant, r_hex)
        if ripple:
            metrics.update(_fcs_step_times(sc, res, true_plant, artifact, ripple))
        error = abs(metrics.get("static_error", float("nan")))
        speed_signal = sc.kind in ("speed_step", "load_step")
        metrics["static_speed_error_abs" if speed_signal else "static_error_abs"] = error
        # a bound on a quantity this kind of scenario does not produce does not apply
        checks = {k: c for k, c in spec.requirements.check(metrics, "sim").items()
                  if c["quantity"] in metrics}
        checks.update(default_checks(
            sc, metrics, res, plant=true_plant, motor=spec.motor, v_max=v_max,
            delay_samples=spec.drive.delay_samples, sample_time=spec.drive.sample_time,
            linear=linear, flux_c=artifact.decoupling.flux_c, ripple=ripple or 0.0))
        checks = {k: finalise_check(c) for k, c in checks.items()}
        kept = res if sc.keep_traces else SimResult(metrics=res.metrics)
        out.scenarios.append(ScenarioOutcome(sc.name or sc.kind, sc.kind, metrics, checks,
                                             kept if keep_traces else None))
        if progress:
            progress(k + 1, len(scenarios))
    out.envelope = envelope_grid(artifact, spec)
    return out


def envelope_grid(artifact, spec) -> dict:
    """The default torque-speed grid (:mod:`toolbox.verify._envelope_grid`)
    as verify.json's ``envelope``: each run ``2 x span``, ``span`` the longest
    span after the step of the default scenarios (so the settling checks of
    the grid see as much of the loop as theirs); speeds above
    ``drive.max_speed`` unreachable. Beside the grid, ``speed_ramp`` (:func:`toolbox.verify._envelope_ramp.speed_ramp`,
    the ramp through base speed; a failing ramp fails ``passed`` and is in
    ``failures``). ``{"skipped": reason}`` when the motor
    has no current limit (the envelope needs one). A saturated motor's
    references come from its magnetic model (:func:`toolbox.plant.envelope_of`)."""
    defaults = default_scenarios(spec.motor, spec.drive, settling_horizon(artifact, spec.motor))
    span = max(sc.duration - (sc.step_time or 0.0) for sc in defaults)
    law, drive = scenario_setup(artifact, defaults[0], spec.drive)
    try:
        env = grid_envelope(spec.motor, drive)
    except SpecError as exc:
        return {"passed": True, "skipped": f"no operating envelope: {exc}"}
    # the predictive law leaves its design ripple band by construction (the
    # scenarios' checks allow it too): the grid's settled error as well
    ripple = _fcs_ripple(artifact, drive, spec.motor, drive.radii(spec.motor.torque_factor)[0])
    band = math.hypot(ripple["d"], ripple["q"]) if ripple else 0.0
    grid = torque_speed_grid(law, spec.motor, drive, env, span=span,
                             max_speed=spec.drive.max_speed, band=band)
    # the linear proof at each point's tangent plant (toolbox/ARCHITECTURE.md
    # "One controller, proved per point")
    grid = with_tangent_loops(grid, artifact, spec.motor, spec.requirements)
    ramp = speed_ramp(law, spec.motor, drive, env, span=span, max_speed=spec.drive.max_speed,
                      tolerance=GRID_TOLERANCE, peak_limit=GRID_PEAK_LIMIT, band=band)
    out = grid.to_json()
    out["speed_ramp"] = ramp.to_json()
    out["passed"] = grid.passed and ramp.passed
    out["failures"] = out["failures"] + ramp.failures()
    return out
