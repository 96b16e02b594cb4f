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
  its lowest and highest quartile, for each failure mode (each failed check
  on its own: pooled into one pass/fail indicator, modes driven in opposite
  directions cancel) and pooled; and the failure rate by the cells of the
  two grid axes that drive the modes most (:func:`cells`);
* the worst samples with their parameters (largest ``worst_ratio``).

Counts (yields, failures per point and mode, worst cases) are exact and
streamed (:class:`Accumulator`); the rank correlations use every row up to
:data:`SUBSAMPLE` rows, a seeded stratified subsample beyond
(``sensitivity_rows`` says how many).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .._io import write_atomic
from ._sampling import point_values

__all__ = ["summarize", "write_outputs", "parameter_columns", "wilson_interval", "Accumulator",
           "stratified_subset", "strongest_drivers", "cells", "SUBSAMPLE"]

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
    from scipy.stats import rankdata

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
    import pyarrow.compute as pc

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


def _finite(v):
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else str(float(v))
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def strongest_drivers(summary) -> list[str]:
    """Parameters ranked as drivers of the failures: by the mean over the
    failure modes of |rank correlation with that mode failing|, each mode
    weighted by its failing samples (a parameter that drives the modes
    holding most failures first; a mode's correlation is never pooled with
    another's, whose sign may be opposite). Parameters no mode ranks follow
    in the pooled order."""
    score: dict[str, float] = {}
    counts = summary.get("failure_reasons", {})
    for mode, entries in summary.get("sensitivity_by_mode", {}).items():
        w = counts.get(mode, 0)
        for e in entries:
            if e["rank_correlation"] is not None:
                score[e["parameter"]] = score.get(e["parameter"], 0.0) + w * abs(
                    e["rank_correlation"])
    ranked = sorted(score, key=lambda k: -score[k])
    return ranked + [s["parameter"] for s in summary["sensitivity"]
                     if s["parameter"] not in score]


def stratified_subset(failed: np.ndarray, k: int, seed: int = 0) -> np.ndarray:
    """Sorted indices of at most ``k`` rows: ``round(k f)`` of the failing
    rows and the rest passing ones (``f`` the failing share), each drawn
    uniformly (seeded), so that the subset's failing share is the table's to
    within ``1 / (2 k)``."""
    n = len(failed)
    if n <= k:
        return np.arange(n)
    fail_idx, pass_idx = np.nonzero(failed)[0], np.nonzero(~failed)[0]
    kf = int(round(k * fail_idx.size / n))
    rng = np.random.default_rng(seed)
    pick = np.concatenate([fail_idx[rng.choice(fail_idx.size, kf, replace=False)],
                           pass_idx[rng.choice(pass_idx.size, k - kf, replace=False)]])
    return np.sort(pick)


#: Rows of the seeded subsample the rank correlations and the report's
#: figures use when a campaign is larger (the counts are exact): the
#: standard error of a rank correlation is then about 1 / sqrt(SUBSAMPLE).
SUBSAMPLE = 100_000


class Accumulator:
    """Exact streaming counts of a results table, fed one piece (a pyarrow
    Table of judged rows, in sample order) at a time by :meth:`add`; memory
    does not grow with the rows (one byte per motor aside). :meth:`subsample`
    then draws the seeded stratified subsample from ``results.parquet`` and
    :meth:`summarize` makes the summary (module docstring)."""

    def __init__(self, spec, artifact):
        cfg = spec.campaign
        self.cfg, self.spec, self.artifact = cfg, spec, artifact
        self.n = 0
        self.passed = 0
        self.error_rows = 0
        self.motor_failed = np.zeros(cfg.n_motors, bool)
        P = cfg.n_operating_points
        self.point_rows = np.zeros(P, np.int64)
        self.point_passed = np.zeros(P, np.int64)
        self.mode_count: dict[str, int] = {}
        self.mode_point: dict[str, np.ndarray] = {}
        self.worst: list[dict] = []
        self.params: list[str] | None = None

    def add(self, piece, error: bool = False) -> None:
        """Count the judged rows of ``piece`` (``error``: rows of a chunk
        that could not be evaluated)."""
        n = piece.num_rows
        if self.params is None:
            self.params = parameter_columns(piece)
        passed = np.asarray(piece.column("passed").to_numpy(zero_copy_only=False), bool)
        motor = np.asarray(piece.column("motor").to_numpy(), np.int64)
        point = np.asarray(piece.column("point").to_numpy(), np.int64)
        P = len(self.point_rows)
        self.n += n
        self.passed += int(passed.sum())
        self.error_rows += n if error else 0
        self.motor_failed[motor[~passed]] = True
        self.point_rows += np.bincount(point, minlength=P)
        self.point_passed += np.bincount(point[passed], minlength=P)
        for mode, mask in failure_modes(piece.column("failure")).items():
            self.mode_count[mode] = self.mode_count.get(mode, 0) + int(mask.sum())
            self.mode_point.setdefault(mode, np.zeros(P, np.int64))
            self.mode_point[mode] += np.bincount(point[mask], minlength=P)
        ratio = np.asarray(piece.column("worst_ratio").to_numpy(), float)
        key = -np.where(np.isnan(ratio), np.inf, ratio)
        top = np.argpartition(key, N_WORST)[:N_WORST] if n > N_WORST else np.arange(n)
        for i in top:
            row = {c: _finite(piece.column(c)[int(i)].as_py()) for c in
                   ["sample"] + self.params + ["worst_check", "worst_ratio", "failure",
                                               "motor", "point"]}
            row["_key"] = (float(key[i]), int(row["sample"]))
            self.worst.append(row)
        self.worst.sort(key=lambda r: r["_key"])  # largest ratio first, then by sample
        del self.worst[N_WORST:]

    def subsample(self, results: Path):
        """The report columns of ``results.parquet`` for every row, or for
        :func:`stratified_subset` of :data:`SUBSAMPLE` rows (read by row
        group: one at a time in memory)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        from ._report import report_columns

        f = pq.ParquetFile(results)
        cols = report_columns(f.schema_arrow.names, self.spec, self.artifact)
        if self.n <= SUBSAMPLE:
            return pq.read_table(results, columns=cols)
        failed = np.zeros(self.n, bool)  # 1 byte per row, read one column at a time
        at = 0
        for batch in f.iter_batches(columns=["passed"]):
            v = np.asarray(batch.column(0).to_numpy(zero_copy_only=False), bool)
            failed[at:at + len(v)] = ~v
            at += len(v)
        pick = stratified_subset(failed, SUBSAMPLE)
        del failed
        parts, at = [], 0
        for g in range(f.num_row_groups):
            rows = f.metadata.row_group(g).num_rows
            lo, hi = np.searchsorted(pick, [at, at + rows])
            if hi > lo:
                parts.append(f.read_row_group(g, columns=cols).take(pick[lo:hi] - at))
            at += rows
        return pa.concat_tables(parts)

    def summarize(self, sub, spec, artifact) -> dict:
        """The summary (module docstring) from the counts and ``sub`` (the
        rows :meth:`subsample` returned: the rank correlations)."""
        cfg = self.cfg
        n, k = self.n, self.passed
        complete = cfg.complete_motors
        per_motor = _yield(int(complete - self.motor_failed[:complete].sum()), complete)
        per_motor["incomplete_motors"] = cfg.n_motors - complete
        points = []
        for p in range(cfg.n_operating_points):
            entry = {"point": p, **point_values(cfg, p),
                     **_yield(int(self.point_passed[p]), int(self.point_rows[p]))}
            entry["failures"] = {m: int(c[p]) for m, c in sorted(self.mode_point.items())
                                 if c[p]}
            points.append(entry)
        worst_point = min(points, key=lambda e: (e["yield_95"][0], e["point"]))
        ys = {"per_sample": _yield(k, n), "per_motor": per_motor,
              "per_point": {"n": len(points), "worst_point": worst_point["point"],
                            "yield": worst_point["yield"],
                            "yield_95": worst_point["yield_95"], "points": points}}
        gated = ys[cfg.gate]
        lower = gated["yield_95"][0]
        failed = ~np.asarray(sub.column("passed").to_numpy(zero_copy_only=False), bool)
        modes = failure_modes(sub.column("failure"))
        by_mode = {m: _sensitivity(sub, modes[m]) if m in modes else []
                   for m in sorted(self.mode_count, key=lambda m: -self.mode_count[m])}
        summary = {
            "schema": "cct.campaign-summary/3",
            "title": spec.title,
            "method": artifact.method,
            "samples": n, "passed": k, "failed": n - k, "error_rows": self.error_rows,
            "motors": cfg.n_motors, "operating_points": cfg.n_operating_points,
            "yield": k / n if n else 0.0, "yield_95": list(wilson_interval(k, n)),
            "yields": ys,
            "gate": cfg.gate, "gate_yield": gated["yield"], "gate_lower_95": lower,
            "min_yield": cfg.min_yield,
            "meets_min_yield": cfg.min_yield is None or lower >= cfg.min_yield,
            "seed": cfg.seed,
            "parameters": self.params or [],
            "grid_axes": [a for a, values in cfg.operating_points if len(values) > 1],
            "failure_reasons": dict(sorted(self.mode_count.items(), key=lambda kv: -kv[1])),
            "sensitivity_rows": sub.num_rows,
            "sensitivity": _sensitivity(sub, failed),
            "sensitivity_by_mode": by_mode,
            "worst_cases": [{k: v for k, v in w.items() if k != "_key"} for w in self.worst],
        }
        summary["drivers"] = strongest_drivers(summary)
        summary["cells"] = cells(summary, cfg)
        return summary


def cells(summary: dict, cfg) -> dict | None:
    """Failure rate (and failures per mode) by the cells of the two grid axes
    that drive the failure modes most (:func:`strongest_drivers`), the other
    axes pooled: exact, from the per-point counts. None with fewer than two
    grid axes."""
    axes = [k for k, values in cfg.operating_points if len(values) > 1]
    if len(axes) < 2:
        return None
    ranked = [p for p in strongest_drivers(summary) if p in axes]
    a, b = (ranked + [x for x in axes if x not in ranked])[:2]
    table: dict[tuple, dict] = {}
    for e in summary["yields"]["per_point"]["points"]:
        cell = table.setdefault((e[a], e[b]), {a: e[a], b: e[b], "n": 0, "failed": 0,
                                               "failures": {}})
        cell["n"] += e["n"]
        cell["failed"] += e["n"] - e["passed"]
        for m, c in e["failures"].items():
            cell["failures"][m] = cell["failures"].get(m, 0) + c
    rows = [dict(v, fail_rate=v["failed"] / v["n"] if v["n"] else 0.0)
            for _k, v in sorted(table.items())]
    return {"axes": [a, b], "cells": rows}


def summarize(table, spec, artifact) -> dict:
    """The summary of a judged results table held in memory (module
    docstring; the campaign itself streams through :class:`Accumulator`)."""
    acc = Accumulator(spec, artifact)
    acc.add(table)
    return acc.summarize(table, spec, artifact)


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
    import dataclasses

    from ..verify import default_scenarios  # lazy: numba, scipy.optimize, ~720 modules
    from ..spec import spec_to_toml
    from ._evaluate import _NOT_MOTOR

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
    ``table`` holds the columns of :func:`toolbox.campaign._report.report_columns`
    (every row, or the subsample the summary's rank correlations used)."""
    worst_files = []
    for row in [w for w in summary["worst_cases"] if w.get("failure")][:N_WORST_SPECS]:
        path = out_dir / "worst" / f"sample-{int(row['sample']):06d}.toml"
        worst_files.append(write_atomic(path, worst_spec(spec, row, source=str(out_dir))))
    summary["worst_specs"] = [str(p.relative_to(out_dir)) for p in worst_files]
    if (out_dir / "worst").is_dir():  # those of an earlier run of other rows
        for old in (out_dir / "worst").glob("sample-*.toml"):
            if old not in worst_files:
                old.unlink()
    files = worst_files + [write_atomic(out_dir / "summary.json",
                          json.dumps(summary, indent=1, default=_finite) + "\n"),
             write_atomic(out_dir / "controller.json", artifact.dumps())]
    if report:
        from ._report import campaign_html

        files.append(write_atomic(out_dir / "report.html",
                                  campaign_html(table, summary, spec, artifact)))
    return files
