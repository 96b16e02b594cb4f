"""Verification: run a controller artifact through the spec's scenarios.

Reads only the artifact (the executed discrete laws, decoupling and model
parameters) and the spec's motor, drive, scenarios and requirements; nothing
is re-designed here.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Callable

from toolbox.plant import voltage_limited_speed
from toolbox.spec import Motor

from ._checks import LinearFigures, default_checks, fcs_ripple, finalise_check, step_facts
from ._fcs_metrics import ripple_band_step_times
from ._scenario import Scenario
from ._simulate import (AxisLaw, ControlLaw, DriveParams, SimResult, SpeedLoop,
                        simulate)

__all__ = ["VERIFY_SCHEMA", "control_law", "drive_params",
           "default_scenarios", "verify", "VerifyResult", "ScenarioOutcome", "NO_REQUIREMENTS"]

VERIFY_SCHEMA = "cct.verify/1"


def drive_params(drive, inverter: str = "average") -> DriveParams:
    """Simulator drive settings.

    Parameters
    ----------
    drive : Drive
        Validated drive.
    inverter : {"average", "svm", "fcs_mpc"}
        Inverter model.
    """
    return DriveParams(vdc=drive.vdc, sample_time=drive.sample_time,
                       delay_samples=drive.delay_samples, v_limit=drive.voltage_limit,
                       inverter=inverter, switching_frequency=drive.switching_frequency,
                       hold_frame=drive.hold_frame,
                       voltage_priority=drive.voltage_priority)


def _axis_law(axis) -> AxisLaw:
    aw = None if axis.antiwindup is None else axis.antiwindup.reshape(-1)
    law = axis.law
    return AxisLaw(law.A, law.B, law.C, law.D, aw)


def control_law(artifact, speed_loop: SpeedLoop | None = None) -> ControlLaw:
    """The simulator's :class:`ControlLaw` executing ``artifact``.

    The executed law of each axis is the artifact's ``axes.<axis>.law``; the
    predictive law of ``fcs_mpc`` reads the typed ``artifact.fcs`` weights, and
    method ``cv`` executes its complex-vector law ``artifact.cv``.

    Parameters
    ----------
    artifact : ControllerArtifact
        The design.
    speed_loop : SpeedLoop, optional
        Outer speed loop of the scenario.
    """
    return ControlLaw(d=_axis_law(artifact.axes["d"]), q=_axis_law(artifact.axes["q"]),
                      sample_time=artifact.sample_time, decoupling=artifact.decoupling,
                      speed_loop=speed_loop, fcs=artifact.fcs, cv=artifact.cv)


def default_scenarios(motor, drive=None, horizon: float | None = None) -> tuple[Scenario, ...]:
    """Scenarios used when a spec has no ``[[scenario]]``, scaled to the motor.

    A q-current step to half the current scale at standstill, the same step
    during free acceleration (unloaded start), and the same step at half the
    speed scale (speed held), capped at half the speed the voltage allows at
    that current (:func:`toolbox.plant.voltage_limited_speed`: the speed scale alone ignores
    the ``R i`` and ``w L i`` drops). The scales
    (:func:`toolbox.design._defaults.current_scale`, ``speed_scale``) are
    the rated (else maximum) current and speed, else what the voltage
    allows; each scenario's ``name`` states its numbers.

    Durations: at least 20 ms and 30 time constants of the slowest default
    crossover (``3/wc`` is the 5 % time of a first-order loop: ten of them
    leave room for the slower second-order defaults), and at least
    ``horizon`` when given: :func:`toolbox.analysis.executed.settling_horizon`,
    10 time constants of the executed loop's slowest closed-loop pole that
    shows in the step (so that the settling time the checks require is
    reached within the span). The unloaded start
    must not pass the speed scale nor 80 % of the voltage-limited speed
    (beyond, the back-EMF would saturate the voltage: a field-weakening
    question, not the loop's): a rotor light enough to pass that sooner gets
    a smaller step, sized to arrive there at the end of the span.

    Parameters
    ----------
    motor : Motor
        Rated/max current and speed, torque constant and inertia.
    drive : Drive, optional
        Sample time, delay and voltage; without it the step is half the
        rated current (10 A when unknown) and the speed scenario is left out.
    horizon : float, optional
        Shortest span after the step (s), from the designed loop.
    """
    if drive is None:
        i_step = 0.5 * (motor.rated_current or motor.max_current or 10.0)
        return (Scenario(name="q step at standstill", kind="current_step", duration=0.02,
                         iq_ref=i_step, step_time=0.001, keep_traces=True),
                Scenario(name="q step, unloaded start", kind="unloaded_start", duration=0.02,
                         iq_ref=i_step, step_time=0.001, keep_traces=True))
    # lazy: toolbox.design imports the spec and plant stages, not needed without a drive
    from ..design import current_scale, default_bandwidth, speed_scale
    i_scale, _ = current_scale(motor, drive)
    w_scale, _ = speed_scale(motor, drive)
    i_step = 0.5 * i_scale
    w_reach = voltage_limited_speed(motor, drive.max_voltage(motor.convention), i_step)
    w_held = 0.5 * min(w_scale, w_reach)
    wc = default_bandwidth(drive, zero=True).value
    step_time = 0.001
    span = max(0.02, 30.0 / wc, horizon or 0.0)
    # free acceleration may end at the speed scale or at 80 % of the voltage-limited speed
    # (20 % of the voltage left for the loop); a rotor light enough to pass that within the
    # span steps less current, sized to arrive there at the end (the same span as the
    # other scenarios: the EMF ramp is a disturbance the slower 2-DOF laws reject over
    # several integral time constants, and a shorter span cut them off: the corpus's
    # gimbal motors with ip and lq)
    w_end = min(w_scale, 0.8 * w_reach)
    torque_per_amp = motor.torque_factor * motor.pole_pairs * motor.flux
    i_start = i_step
    if torque_per_amp > 0 and math.isfinite(w_end):
        i_start = min(i_step, w_end * motor.J / (torque_per_amp * span))
    start_txt = (f"{i_start:.4g} A, unloaded start" if i_start == i_step else
                 f"{i_start:.4g} A, unloaded start (reaches {w_end:.4g} rad/s at the end)")
    out = [Scenario(name=f"q step to {i_step:.4g} A (0.5 x current scale) at standstill",
                    kind="current_step", duration=step_time + span, iq_ref=i_step,
                    step_time=step_time, keep_traces=True),
           Scenario(name=f"q step to {start_txt}",
                    kind="unloaded_start", duration=step_time + span, iq_ref=i_start,
                    step_time=step_time, keep_traces=True)]
    if math.isfinite(w_held):
        held_txt = ("0.5 x speed scale" if w_held == 0.5 * w_scale else
                    "0.5 x the speed the voltage allows at this current")
        out.append(Scenario(name=f"q step to {i_step:.4g} A at {w_held:.4g} rad/s ({held_txt})",
                            kind="current_step", duration=step_time + span, iq_ref=i_step,
                            initial_speed=w_held, step_time=step_time, keep_traces=True))
    return tuple(out)


def _speed_loop(scenario: Scenario, sample_time: float) -> SpeedLoop | None:
    sl = dict(scenario.speed_loop)
    if not sl:
        return None
    ts = sl.get("sample_time", sample_time)  # a whole multiple of Ts (checked at spec load)
    return SpeedLoop(kp=sl["kp"], ki=sl.get("ki", 0.0), kd=sl.get("kd", 0.0),
                     sample_time=ts, iq_limit=sl.get("iq_limit", math.inf))


def scenario_setup(artifact, scenario: Scenario, drive) -> tuple[ControlLaw, DriveParams]:
    """The simulator's law and drive for one scenario of ``artifact``.

    The law executes the artifact (:func:`control_law`) under the scenario's
    speed loop, if any; the inverter is the scenario's, else the predictive
    switching law for ``fcs_mpc`` and the ideal average inverter otherwise.
    Verification and the campaign (``toolbox.campaign``) both set up their
    runs through it.

    Parameters
    ----------
    artifact : ControllerArtifact
    scenario : Scenario
    drive : Drive
        The spec's validated drive.
    """
    inverter = scenario.inverter or ("fcs_mpc" if artifact.method == "fcs_mpc" else "average")
    return (control_law(artifact, _speed_loop(scenario, artifact.sample_time)),
            drive_params(drive, inverter))


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
                and (self.header is None or self.header["matches"]))

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
    from ..analysis import compute_margins
    from ..analysis.executed import INFORMATIONAL_METHODS, loop_stability, margin_disagreements

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


def _horizon(artifact, motor) -> float | None:
    """The default scenarios' shortest span (toolbox.analysis.executed.settling_horizon)."""
    from ..analysis.executed import settling_horizon

    return settling_horizon(artifact, motor)


def _drift_check(artifact, spec) -> dict:
    """The robustness verdict: the executed coupled sampled loop (delay,
    decoupling with the controller's own parameters, speed-sensor errors)
    stays stable for every evaluated set of the drift box at every speed up to
    the maximum (:func:`toolbox.analysis.drift_verdict`: the spec's
    ``[requirements] parameter_drift``, else the default drive box
    :data:`toolbox.analysis.DRIVE_DRIFT`). The record carries the worst
    multiloop disk margin over the box and the box itself (``robustness``).
    """
    from ..analysis import drift_verdict

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
    from ..design import default_bandwidth  # lazy: the design stage is heavier

    wc = default_bandwidth(drive).value
    return {ax: LinearFigures(wc, math.nan) for ax in ("d", "q")}


def _fcs_ripple(artifact, drive: DriveParams, true_plant: Motor,
                r_hex: float) -> dict[str, float] | None:
    """Per-axis design ripple of the predictive switching law, None for other inverters.

    One vector held for a whole period, and the switching penalty's dead band
    (:func:`toolbox.sim._checks.fcs_ripple`).
    """
    if drive.inverter != "fcs_mpc" or artifact.fcs is None:
        return None
    fcs, L_min = artifact.fcs, min(true_plant.Ld, true_plant.Lq)
    return {"q": fcs_ripple(r_hex, drive.sample_time, L_min, fcs.alpha, fcs.gamma, fcs.beta),
            "d": fcs_ripple(r_hex, drive.sample_time, L_min, fcs.beta, fcs.gamma, fcs.alpha)}


def _fcs_step_times(scenario: Scenario, res: SimResult, true_plant: Motor, artifact,
                    ripple: dict[str, float]) -> dict[str, float]:
    """5 % / 2 % times of a switching-law current step in the band max(b |delta|, ripple).

    See :mod:`toolbox.sim._fcs_metrics`; empty (the kernel's metrics stand)
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
    of :mod:`toolbox.sim._checks` besides the spec's requirements. In
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
                                                    _horizon(artifact, spec.motor))
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
    return out
