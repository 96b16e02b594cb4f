"""One chunk of a campaign: draw, simulate, measure, judge (runs on a worker).

A :class:`Plan` is everything a worker needs, made once on the client from
the spec and the designed artifact (the design is never re-run on a worker):
the campaign table, the nominal motor, the executed control law and drive of
each scenario, the requirement bounds, and the artifact for the per-sample
loop margins. :func:`evaluate_chunk` turns ``(plan, start, stop)`` into the
rows ``start .. stop - 1`` as plain numpy columns of measurements; it has no
side effect (the client writes the Parquet file), so a chunk lost with its
worker is simply run again. The rows are judged against the requirements
by :func:`judge_rows`, on the client, from the stored measurements (the
bounds are no part of a chunk: changing them re-judges without simulating).

Columns of a row (one per sample): ``sample``; the drawn parameters (motor
parameters in SI, ``measured_row``, the operating point: ``speed``,
``speed_gain_error``, ``speed_offset``, ``delay_samples``, ``vdc`` as given);
per scenario ``<scenario>.``
every simulator metric (:data:`toolbox.sim.METRIC_NAMES`) and
``static_error_abs`` (A, or rad/s for speed scenarios: ``static_speed_error_abs``);
per axis ``margin.<axis>.`` gain margin (dB), phase margin (deg), stability
margin and disk margin of the sampled loop at zero speed with the drawn
``R``, ``L`` and delay. :func:`judge_rows` adds ``passed``, ``failure`` (the
failed checks, ``""`` when passed), ``worst_check`` and ``worst_ratio`` (the
most violated bound: value/bound for an upper bound, bound/value for a lower
one; > 1 fails).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Any
import os
import socket

import numpy as np

from ..spec import OPERATING_POINT_KEYS, REQUIREMENT_KEYS
from ._sampling import draw_samples
from ._cluster import BuildMismatch, mismatch_message, worker_build

__all__ = ["Plan", "make_plan", "evaluate_chunk", "judge_rows", "judge_error_rows",
           "scenario_slug", "warm_up", "DIVERGED", "ERROR_CHECK", "JUDGE_COLUMNS"]

#: Reason of a sample whose simulation produced non-finite currents.
DIVERGED = "diverged"
#: Reason of a sample whose drawn parameters are not physical (a normal tail).
NON_PHYSICAL = "non-physical draw"
#: ``worst_check`` (and failure mode) of the rows of a chunk that could not
#: be evaluated (its ``failure`` is ``"error = <the exception>"``).
ERROR_CHECK = "error"
#: Columns :func:`judge_rows` adds.
JUDGE_COLUMNS = ("passed", "failure", "worst_check", "worst_ratio")
_POSITIVE = ("R", "Ld", "Lq", "J")
#: Frequency points of the per-sample margin grid (1 rad/s .. Nyquist).
MARGIN_GRID = 600


@dataclass(frozen=True)
class Plan:
    """What a worker needs to evaluate chunks (picklable plain data).

    Attributes
    ----------
    cfg : toolbox.spec.CampaignCfg
    motor : toolbox.spec.Motor
        The nominal motor.
    runs : tuple
        ``(slug, scenario, law, drive_params)`` per scenario.
    bounds : dict
        The ``[requirements]`` bounds.
    artifact : ControllerArtifact
        For the loop margins of each sample.
    threads : int or None
        Threads of each simulation batch (:func:`toolbox.sim.simulate_batch`'s
        ``threads``; None: its default, one per core).
    build : tuple
        ``(toolbox version, source hash)`` of the client; a worker of another
        build refuses the chunk (:class:`toolbox.campaign._cluster.BuildMismatch`).
        Empty: not checked (in-process runs).
    """

    cfg: Any
    motor: Any
    runs: tuple
    bounds: dict
    artifact: Any
    threads: int | None = None
    build: tuple = ()


def scenario_slug(name: str) -> str:
    """A column-friendly scenario name: ``"i_q step 0 -> 10 A"`` -> ``"i_q_step_0_10_A"``."""
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_") or "scenario"


def make_plan(spec, artifact, threads: int | None = None, build: tuple = ()) -> Plan:
    """The :class:`Plan` of ``spec``'s campaign for the designed ``artifact``.

    Scenarios: those named in ``campaign.scenarios``, else every
    ``[[scenario]]``, else :func:`toolbox.verify.default_scenarios`.
    """
    from ..sim import scenario_setup  # lazy: numba + the kernel, ~450 modules
    from ..verify import default_scenarios  # lazy: numba, scipy.optimize, ~720 modules

    cfg = spec.campaign
    scenarios = spec.scenarios or default_scenarios(spec.motor, spec.drive)
    if cfg.scenarios:
        scenarios = tuple(s for s in scenarios if (s.name or s.kind) in cfg.scenarios)
    runs, seen = [], set()
    for k, sc in enumerate(scenarios):
        slug = scenario_slug(sc.name or sc.kind)
        if slug in seen:
            slug = f"{slug}_{k}"
        seen.add(slug)
        law, drive = scenario_setup(artifact, sc, spec.drive)
        runs.append((slug, dataclasses.replace(sc, keep_traces=False), law, drive))
    return Plan(cfg=cfg, motor=spec.motor, runs=tuple(runs),
                bounds=dict(spec.requirements.bounds), artifact=artifact,
                threads=threads, build=tuple(build))


_NOT_MOTOR = ("sample", "motor", "point", "measured_row") + OPERATING_POINT_KEYS


def _physical(cols: dict, n: int) -> np.ndarray:
    ok = np.ones(n, bool)
    for name, v in cols.items():
        if name in _NOT_MOTOR:
            continue
        ok &= np.isfinite(v) & ((v > 0) if name in _POSITIVE else (v >= 0))
    return ok


def _margins(plan: Plan, R: np.ndarray, Ld: np.ndarray, Lq: np.ndarray,
             delay: np.ndarray | None = None) -> dict:
    # lazy: scipy.optimize/signal, ~490 modules
    from ..analysis.robustness import batch_loop_margins

    art = plan.artifact
    d = (np.full(len(R), art.delay_samples, int) if delay is None
         else np.asarray(delay, int))
    return {f"margin.{axis}.{key}": np.asarray(v, float)
            for axis, m in batch_loop_margins(art, R, Ld, Lq, d, MARGIN_GRID).items()
            for key, v in m.items()}


def _judge(checks: list, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``passed``, ``failure``, ``worst_check``, ``worst_ratio`` from
    ``checks``: ``(name, value array, bound, direction)`` or ``(name, fail mask)``."""
    failure = [[] for _ in range(n)]
    worst_ratio = np.zeros(n)
    worst_check = np.array([""] * n, dtype=object)
    for check in checks:
        if len(check) == 2:
            name, bad = check
            ratio = np.where(bad, np.inf, 0.0)
            for i in np.nonzero(bad)[0]:
                failure[i].append(name)
        else:
            name, value, bound, direction = check
            with np.errstate(divide="ignore", invalid="ignore"):
                if direction == "max":
                    bad = ~(value <= bound)
                    ratio = value / bound if bound > 0 else np.where(bad, np.inf, 0.0)
                else:
                    bad = ~(value >= bound)
                    ratio = np.where(value > 0, bound / value, np.where(bad, np.inf, 0.0))
                # ratio > 1 exactly when the bound is violated (NaN: never measured)
                ratio = np.where(bad, np.maximum(np.nan_to_num(ratio, nan=np.inf), 1.0),
                                 np.clip(np.nan_to_num(ratio, nan=0.0), 0.0, 1.0))
            for i in np.nonzero(bad)[0]:
                failure[i].append(f"{name} = {value[i]:.4g} (bound {bound:g})")
        take = ratio > worst_ratio
        worst_ratio = np.where(take, ratio, worst_ratio)
        worst_check[take] = name
    passed = np.array([not f for f in failure], bool)
    return passed, np.array(["; ".join(f) for f in failure], dtype=object), worst_check, worst_ratio


def warm_up(plan: Plan) -> None:
    """Load the compiled kernel and the margin code in this process (one nominal
    sample per scenario), so that the first chunk's time is simulation time."""
    from ..sim import simulate_batch  # lazy: numba + the kernel, ~450 modules

    for _slug, scenario, law, drive in plan.runs:
        simulate_batch(law, [plan.motor], scenario, drive)
    m = plan.motor
    _margins(plan, np.array([m.R]), np.array([m.Ld]), np.array([m.Lq]))


def evaluate_chunk(plan: Plan, start: int, stop: int) -> dict[str, np.ndarray]:
    """The measurements of rows ``start .. stop - 1`` (module docstring), as
    ``{column: array}``; not judged (:func:`judge_rows`).

    Deterministic: a sample's row depends on the plan and its index only.
    """
    from ..sim import METRIC_NAMES, simulate_batch  # lazy: numba + the kernel, ~450 modules

    if plan.build:
        if worker_build() != tuple(plan.build):
            raise BuildMismatch(mismatch_message(f"on {socket.gethostname()} (pid "
                                                 f"{os.getpid()})", worker_build(), plan.build))
    cfg, motor = plan.cfg, plan.motor
    n = stop - start
    cols = draw_samples(cfg, motor, start, stop)
    varied = [k for k in cols if k not in _NOT_MOTOR]
    ok = _physical(cols, n)
    good = np.nonzero(ok)[0]
    motors = [motor.with_overrides({k: float(cols[k][i]) for k in varied}) for i in good]
    op_keys = [k for k in OPERATING_POINT_KEYS if k in cols]
    if op_keys:  # one batch per operating point present in the chunk
        grid = np.column_stack([cols[k][good].astype(float) for k in op_keys])
        points, which = np.unique(grid, axis=0, return_inverse=True)
        groups = [(dict(zip(op_keys, p)), good[which.ravel() == j])
                  for j, p in enumerate(points)]
    else:
        groups = [({}, good)]
    out: dict[str, np.ndarray] = dict(cols)
    for slug, scenario, law, drive in plan.runs:
        table = {m: np.full(n, np.nan) for m in METRIC_NAMES}
        for point, rows in groups:
            if rows.size == 0:
                continue
            sc = dataclasses.replace(scenario, **{
                ("initial_speed" if k == "speed" else k): float(v)
                for k, v in point.items() if k in ("speed", "speed_gain_error", "speed_offset")})
            dr = dataclasses.replace(drive, **{
                k: (int(v) if k == "delay_samples" else float(v))
                for k, v in point.items() if k in ("delay_samples", "vdc")})
            pick = np.searchsorted(good, rows)
            res = simulate_batch(law, [motors[j] for j in pick], sc, dr,
                                 threads=plan.threads)
            for m in METRIC_NAMES:
                table[m][rows] = res.metrics[m]
        speed_signal = scenario.kind in ("speed_step", "load_step")
        err_key = "static_speed_error_abs" if speed_signal else "static_error_abs"
        table[err_key] = np.abs(table["static_error"])
        for m, v in table.items():
            out[f"{slug}.{m}"] = v
    R = np.where(ok, cols.get("R", np.full(n, motor.R)), motor.R)
    Ld = np.where(ok, cols.get("Ld", np.full(n, motor.Ld)), motor.Ld)
    Lq = np.where(ok, cols.get("Lq", np.full(n, motor.Lq)), motor.Lq)
    # a motor's margins depend on (R, Ld, Lq, delay) only: computed once per
    # distinct tuple (elementwise, so the values are those of any batching)
    delay = np.asarray(cols.get("delay_samples", np.full(n, plan.artifact.delay_samples)), float)
    key = np.column_stack([R, Ld, Lq, delay])
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    margins = {k: v[inv] for k, v in _margins(plan, uniq[:, 0], uniq[:, 1], uniq[:, 2],
                                               uniq[:, 3].astype(int)).items()}
    for k, v in margins.items():
        out[k] = np.where(ok, v, np.nan)
    return out


def judge_rows(cols, slugs, bounds: dict) -> dict[str, np.ndarray]:
    """``passed``, ``failure``, ``worst_check`` and ``worst_ratio`` of measured
    rows (``cols``: ``{column: array}`` as :func:`evaluate_chunk` returns or a
    chunk file holds) against ``bounds`` (the ``[requirements]`` bounds), for
    the scenarios ``slugs``. A row fails when its drawn parameters are not
    physical, a scenario diverged (non-finite final value or MSE) or a bound
    is violated (NaN never passes)."""
    n = len(cols["sample"])
    ok = _physical({k: np.asarray(v, float) for k, v in cols.items()
                    if "." not in k and k not in _NOT_MOTOR and k not in JUDGE_COLUMNS}, n)
    checks: list = [(NON_PHYSICAL, ~ok)]
    for slug in slugs:
        final = np.asarray(cols[f"{slug}.final_value"], float)
        mse = np.asarray(cols[f"{slug}.mse_iq"], float)
        checks.append((f"{slug}: {DIVERGED}", ok & ~(np.isfinite(final) & np.isfinite(mse))))
        for key, bound in bounds.items():
            stage, direction, quantity, _unit = REQUIREMENT_KEYS[key]
            if stage != "sim" or f"{slug}.{quantity}" not in cols:
                continue
            value = np.where(ok, np.asarray(cols[f"{slug}.{quantity}"], float), np.nan)
            checks.append((f"{slug}: {key}", value, bound, direction))
    for key, bound in bounds.items():
        stage, direction, quantity, _unit = REQUIREMENT_KEYS[key]
        if stage != "margins" or f"margin.d.{quantity}" not in cols:
            continue
        pick = np.minimum if direction == "min" else np.maximum
        value = np.where(ok, pick(np.asarray(cols[f"margin.d.{quantity}"], float),
                                  np.asarray(cols[f"margin.q.{quantity}"], float)), np.nan)
        checks.append((f"margins: {key}", value, bound, direction))
    passed, failure, worst_check, worst_ratio = _judge(checks, n)
    return {"passed": passed, "failure": failure, "worst_check": worst_check,
            "worst_ratio": worst_ratio}


def judge_error_rows(n: int, message: str) -> dict[str, np.ndarray]:
    """The judgement of ``n`` rows whose chunk could not be evaluated: not
    passed, ``failure`` ``"error = <message>"`` (failure mode ``error``),
    ``worst_check``
    :data:`ERROR_CHECK`, ``worst_ratio`` inf (a sample never shown to pass
    counts as failing)."""
    return {"passed": np.zeros(n, bool),
            "failure": np.array([f"{ERROR_CHECK} = " + message.replace(";", ",")] * n,
                                dtype=object),
            "worst_check": np.array([ERROR_CHECK] * n, dtype=object),
            "worst_ratio": np.full(n, np.inf)}
