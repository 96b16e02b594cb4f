"""Campaign results -> summary.json, results.parquet, controller.json, report.html.

The summary answers the questions of a qualification:

* three yields, each with its 95 % Wilson interval: per sample (the share
  of passing rows, motor x operating point), per motor (the share of drawn
  motors that pass at every point of the grid: the worst case a shipped
  motor meets) and per point (the yield at each grid point; the figure is
  the worst point's). ``campaign.gate`` says which one ``min_yield`` is held
  against, and it is the 95 % lower bound that must reach it;
* which checks fail and how often, overall and at each grid point;
* which parameters drive the failures: the Spearman rank correlation of
  each drawn parameter with the failure indicator and the failure rate in
  its lowest and highest quartile, pooled and for each failure mode (each
  failed check on its own);
* the worst samples with their parameters (largest ``worst_ratio``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
import dataclasses

import numpy as np

from .._io import write_atomic
from ._sampling import point_values
from ..spec import spec_to_toml
from ._evaluate import _NOT_MOTOR

__all__ = ["summarize", "write_outputs", "parameter_columns", "wilson_interval"]

#: Worst cases listed in the summary and the report.
N_WORST = 10
_NOT_PARAMETERS = ("sample", "motor", "point", "measured_row", "passed", "failure",
                   "worst_check", "worst_ratio")


def parameter_columns(table) -> list[str]:
    """The drawn columns (motor parameters, operating point) of a results table."""
    return [c for c in table.column_names
            if "." not in c and c not in _NOT_PARAMETERS]


def wilson_interval(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """95 % Wilson score interval of a proportion ``k / n``.

    Examples
    --------
    >>> [round(x, 4) for x in wilson_interval(95, 100)]
    [0.8882, 0.9785]
    """
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return (max(0.0, mid - half), min(1.0, mid + half))


def _sensitivity(table, failed: np.ndarray) -> list[dict]:
    from scipy.stats import rankdata  # lazy: scipy.stats, 622 modules

    out = []
    for name in parameter_columns(table):
        x = np.asarray(table.column(name).to_numpy(zero_copy_only=False), float)
        entry = {"parameter": name, "rank_correlation": None,
                 "fail_rate_low_quartile": None, "fail_rate_high_quartile": None}
        if np.ptp(x) > 0:
            lo, hi = np.quantile(x, [0.25, 0.75])
            entry["fail_rate_low_quartile"] = float(failed[x <= lo].mean())
            entry["fail_rate_high_quartile"] = float(failed[x >= hi].mean())
            if 0 < failed.sum() < failed.size:
                rx, rf = rankdata(x), rankdata(failed)
                entry["rank_correlation"] = float(np.corrcoef(rx, rf)[0, 1])
        out.append(entry)
    out.sort(key=lambda e: -abs(e["rank_correlation"] or 0.0))
    return out


def failure_modes(failure) -> dict[str, np.ndarray]:
    """One boolean mask per failed check (failure mode), from the ``failure``
    column ("a = 1 (bound 2); b"): row ``i`` failed check ``a``."""
    import pyarrow.compute as pc  # lazy: pyarrow.compute, 30 modules

    split = pc.split_pattern(failure, "; ")
    parents = np.asarray(pc.list_parent_indices(split).to_numpy())
    parts = pc.list_flatten(split)
    names = np.asarray(pc.list_element(pc.split_pattern(parts, " = ", max_splits=1), 0)
                       .to_numpy(zero_copy_only=False), dtype=object)
    out = {}
    for mode in sorted(set(names) - {"", None}):
        mask = np.zeros(len(failure), bool)
        mask[parents[names == mode]] = True
        out[mode] = mask
    return out


def _yield(k: int, n: int) -> dict:
    return {"n": int(n), "passed": int(k), "yield": k / n if n else 0.0,
            "yield_95": list(wilson_interval(k, n))}


def yields(table, cfg, passed: np.ndarray, modes: dict) -> dict:
    """``per_sample``, ``per_motor`` and ``per_point`` yields (module docstring)."""
    n = len(passed)
    motor = np.asarray(table.column("motor").to_numpy(), np.int64)
    point = np.asarray(table.column("point").to_numpy(), np.int64)
    complete = cfg.complete_motors
    fails = np.bincount(motor, weights=(~passed).astype(float), minlength=cfg.n_motors) > 0
    per_motor = _yield(int(complete - fails[:complete].sum()), complete)
    per_motor["incomplete_motors"] = cfg.n_motors - complete
    P = cfg.n_operating_points
    rows = np.bincount(point, minlength=P)
    ok = np.bincount(point, weights=passed.astype(float), minlength=P).round().astype(int)
    points = []
    for p in range(P):
        entry = {"point": p, **point_values(cfg, p), **_yield(int(ok[p]), int(rows[p]))}
        entry["failures"] = {m: int(mask[point == p].sum()) for m, mask in modes.items()
                             if mask[point == p].any()}
        points.append(entry)
    worst = min(points, key=lambda e: (e["yield_95"][0], e["point"]))
    per_point = {"n": P, "worst_point": worst["point"], "yield": worst["yield"],
                 "yield_95": worst["yield_95"], "points": points}
    return {"per_sample": _yield(int(passed.sum()), n), "per_motor": per_motor,
            "per_point": per_point}


def _reasons(failure) -> dict[str, int]:
    """Samples per failed check, from the ``failure`` column ("a = 1 (bound 2); b")."""
    import pyarrow.compute as pc  # lazy: pyarrow.compute, 30 modules

    parts = pc.list_flatten(pc.split_pattern(failure, "; "))
    names = pc.list_element(pc.split_pattern(parts, " = ", max_splits=1), 0)
    counts = pc.value_counts(names).to_pylist()
    return {c["values"]: int(c["counts"]) for c in counts if c["values"]}


def _finite(v):
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else str(float(v))
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def summarize(table, spec, artifact) -> dict:
    """The summary of a results table (module docstring); JSON-ready."""
    cfg = spec.campaign
    n = table.num_rows
    passed = np.asarray(table.column("passed").to_numpy(zero_copy_only=False), bool)
    failed = ~passed
    k = int(passed.sum())
    reasons = _reasons(table.column("failure"))
    ratio = np.asarray(table.column("worst_ratio").to_numpy(), float)
    key = -np.where(np.isnan(ratio), np.inf, ratio)
    top = np.argpartition(key, N_WORST)[:N_WORST] if n > N_WORST else np.arange(n)
    order = top[np.lexsort((top, key[top]))]  # largest ratio first, then by sample
    params = parameter_columns(table)
    worst = []
    for i in order:
        row = {c: _finite(table.column(c)[int(i)].as_py()) for c in
               ["sample"] + params + ["worst_check", "worst_ratio", "failure"]}
        worst.append(row)
    yield_ = k / n if n else 0.0
    modes = failure_modes(table.column("failure"))
    ys = yields(table, cfg, passed, modes)
    gated = ys[cfg.gate]
    lower = gated["yield_95"][0]
    by_mode = {m: _sensitivity(table, mask)
               for m, mask in sorted(modes.items(), key=lambda kv: -kv[1].sum())}
    return {
        "schema": "cct.campaign-summary/2",
        "title": spec.title,
        "method": artifact.method,
        "samples": n, "passed": k, "failed": n - k,
        "motors": cfg.n_motors, "operating_points": cfg.n_operating_points,
        "yield": yield_, "yield_95": list(wilson_interval(k, n)),
        "yields": ys,
        "gate": cfg.gate, "gate_yield": gated["yield"], "gate_lower_95": lower,
        "min_yield": cfg.min_yield,
        "meets_min_yield": cfg.min_yield is None or lower >= cfg.min_yield,
        "seed": cfg.seed, "chunk_size": cfg.chunk_size, "chunks": cfg.n_chunks,
        "parameters": params,
        "failure_reasons": dict(sorted(reasons.items(), key=lambda kv: -kv[1])),
        "sensitivity": _sensitivity(table, failed),
        "sensitivity_by_mode": by_mode,
        "worst_cases": worst,
    }


#: Worst failing samples written as ready-to-run spec files.
N_WORST_SPECS = 5


def worst_spec(spec, row: dict, source: str = "campaign") -> str:
    """A spec (TOML) that runs one campaign sample on its own: the campaign's
    spec without ``[campaign]``, whose scenarios (those the campaign runs)
    carry the sample's drawn motor as their true plant (``plant_values``, SI)
    and its operating point (initial speed, speed-sensor gain error and
    offset; the DC link voltage in ``[drive]``). ``cct design FILE --out DIR``
    designs the same controller (the nominal motor is kept) and simulates the
    sample. A computation delay other than the design's cannot be expressed in
    a spec (the design would follow it): such a file says so in its header."""
    from ..verify import default_scenarios  # lazy: numba, scipy.optimize, ~720 modules

    cfg = spec.campaign
    scenarios = spec.scenarios or default_scenarios(spec.motor, spec.drive)
    if cfg.scenarios:
        scenarios = tuple(s for s in scenarios if (s.name or s.kind) in cfg.scenarios)
    plant = {k: float(v) for k, v in row.items()
             if k in parameter_columns_of(row) and k not in _NOT_MOTOR}
    point = {k: row[k] for k in ("speed", "speed_gain_error", "speed_offset",
                                 "delay_samples", "vdc") if k in row}
    new = tuple(dataclasses.replace(
        sc, plant_values={**sc.plant_values, **plant},
        **{("initial_speed" if k == "speed" else k): float(v) for k, v in point.items()
           if k in ("speed", "speed_gain_error", "speed_offset")}) for sc in scenarios)
    drive = spec.drive
    if "vdc" in point:
        drive = dataclasses.replace(drive, vdc=float(point["vdc"]))
    raw = {k: v for k, v in spec.raw.items() if k != "campaign"}
    one = dataclasses.replace(spec, scenarios=new, drive=drive, campaign=None, raw=raw,
                              title=f"{spec.title or 'campaign'}: sample {row['sample']}")
    head = [f"# Sample {row['sample']} of the campaign {source} (motor {row.get('motor')}, "
            f"operating point {row.get('point')}): {row.get('failure') or 'passes'}",
            "# Reproduce: cct design THIS_FILE --out DIR (the controller is designed from "
            "the nominal [motor]; the scenario's plant_values is the drawn motor)."]
    if "delay_samples" in point and int(point["delay_samples"]) != spec.drive.delay_samples:
        head.append(f"# NOTE: the campaign ran this sample with delay_samples = "
                    f"{int(point['delay_samples'])} (the design keeps "
                    f"{spec.drive.delay_samples}); a spec cannot say so without redesigning: "
                    "cct design simulates the design's delay.")
    return "\n".join(head) + "\n" + spec_to_toml(one, source=f"sample {row['sample']}")


def parameter_columns_of(row: dict) -> list[str]:
    """The drawn columns of one worst-case row (as :func:`parameter_columns`)."""
    return [c for c in row if "." not in c and c not in _NOT_PARAMETERS]


def write_outputs(out_dir: Path, table, summary: dict, spec, artifact, *,
                  report: bool = True) -> list[Path]:
    """Write summary.json, controller.json, the worst failing samples as spec
    files (``worst/sample-NNNNNN.toml``) and report.html (atomically);
    ``table`` holds the columns of :func:`toolbox.campaign._report.report_columns`."""
    worst_files = []
    for row in [w for w in summary["worst_cases"] if w.get("failure")][:N_WORST_SPECS]:
        path = out_dir / "worst" / f"sample-{int(row['sample']):06d}.toml"
        full = dict(row)
        full["motor"] = int(table.column("motor")[int(row["sample"])].as_py())
        full["point"] = int(table.column("point")[int(row["sample"])].as_py())
        worst_files.append(write_atomic(path, worst_spec(spec, full, source=str(out_dir))))
    summary["worst_specs"] = [str(p.relative_to(out_dir)) for p in worst_files]
    if (out_dir / "worst").is_dir():  # those of an earlier run of other rows
        for old in (out_dir / "worst").glob("sample-*.toml"):
            if old not in worst_files:
                old.unlink()
    files = worst_files + [write_atomic(out_dir / "summary.json",
                          json.dumps(summary, indent=1, default=_finite) + "\n"),
             write_atomic(out_dir / "controller.json", artifact.dumps())]
    if report:
        from ._report import campaign_html  # cycle: _report imports _summary

        files.append(write_atomic(out_dir / "report.html",
                                  campaign_html(table, summary, spec, artifact)))
    return files
