"""The campaign report (HTML, the design report's style, inline SVG figures).

Figures (matplotlib, serialised by :func:`toolbox.report.plots.svg_from_figure`
so that ids are unique and the bytes deterministic):

* failure regions: scatter over the two strongest drivers (the parameters
  with the largest rank correlation with any failure mode), one seeded
  subset of all rows shared by the scatter and the parallel coordinates (so
  the pass/fail proportions are the table's), parallel coordinates of the
  failing samples over the passing ones (each parameter scaled to its drawn
  range);
* sensitivity ranking (bar chart of the rank correlations);
* histograms of the per-sample loop margins (gain, phase; d and q axes), of
  the response metrics bounded by ``[requirements]`` in each scenario (the
  bound drawn), and of ``worst_ratio``.

Every user string (title, scenario names, failure reasons) is escaped by
jinja2's autoescape.
"""

from __future__ import annotations

import math
from importlib import resources

import numpy as np

from .._version import toolbox_version
from ..spec import REQUIREMENT_KEYS
from ._summary import parameter_columns, stratified_subset, strongest_drivers

__all__ = ["campaign_html", "report_columns"]

PASS_COLOR, FAIL_COLOR = "#9aa3ad", "#b3261e"
#: Points drawn per figure at most (a random but seeded subset beyond).
MAX_POINTS = 4000
MAX_LINES = 300
#: Failure modes drawn in the drivers figure (the most frequent).
MAX_MODES = 3


def _col(table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False))


def _fmt(v, digits: int = 4) -> str:
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return f"{v:.{digits}g}" if math.isfinite(v) else str(v)


def _svg(fig, prefix: str) -> str:
    import matplotlib.pyplot as plt

    from ..report.plots import svg_from_figure

    try:
        return svg_from_figure(fig, prefix)
    finally:
        plt.close(fig)


def _step(v: np.ndarray) -> float:
    """Smallest spacing of the distinct values of a grid axis."""
    u = np.unique(v[np.isfinite(v)])
    return float(np.diff(u).min()) if u.size > 1 else 0.0


def _region_figures(table, summary) -> list[dict]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs = []
    failed = ~_col(table, "passed").astype(bool)
    ranked = strongest_drivers(summary)
    params = parameter_columns(table)
    shared = stratified_subset(failed, MAX_POINTS)  # one subset: the failing share kept
    if len(ranked) >= 2:
        a, b = ranked[0], ranked[1]
        x, y = _col(table, a).astype(float), _col(table, b).astype(float)
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        counts = {"pass": summary["passed"], "fail": summary["failed"]}
        rng = np.random.default_rng(1)  # jitter of grid axes (few distinct values)
        jit = {v: (rng.uniform(-0.3, 0.3, len(x)) * _step(_col(table, v).astype(float))
                   if v in summary.get("grid_axes", []) else 0.0) for v in (a, b)}
        for mask, color, label in ((~failed, PASS_COLOR, "pass"), (failed, FAIL_COLOR, "fail")):
            idx = shared[mask[shared]]
            ax.scatter((x + jit[a])[idx], (y + jit[b])[idx], s=6, c=color,
                       label=f"{label} ({counts[label]})", alpha=0.7, linewidths=0)
        ax.set_xlabel(a)
        ax.set_ylabel(b)
        ax.legend(loc="best")
        ax.set_title("Samples over the two strongest drivers of failure")
        fig.tight_layout()
        total = summary["samples"]
        shown = (f"; {shared.size} of {total} rows drawn (one seeded subset, "
                 f"{100 * failed[shared].mean():.1f} % failing as in the table, "
                 f"{100 * summary['failed'] / total:.1f} %)" if shared.size < total else "")
        figs.append({"id": "scatter", "svg": _svg(fig, "cs"),
                     "caption": f"Failing samples (red) over {a} and {b}, the strongest "
                                f"drivers of the failure modes (rank correlation with each "
                                f"mode, weighted by its failures); grid axes jittered within "
                                f"their spacing{shown}."})
    if len(params) >= 2 and failed.any():
        X = np.column_stack([_col(table, p).astype(float) for p in params])
        lo, hi = X.min(axis=0), X.max(axis=0)
        Xn = (X - lo) / np.where(hi > lo, hi - lo, 1.0)
        fig, ax = plt.subplots(figsize=(6.4, 3.8))
        pos = np.arange(len(params))
        lines = shared[stratified_subset(failed[shared], MAX_LINES)]
        for mask, color, alpha in ((~failed, PASS_COLOR, 0.15), (failed, FAIL_COLOR, 0.35)):
            for i in lines[mask[lines]]:
                ax.plot(pos, Xn[i], color=color, alpha=alpha, linewidth=0.7)
        ax.set_xticks(pos, params)
        ax.set_ylabel("scaled to the drawn range")
        ax.set_title("Parallel coordinates: failing (red) over passing (grey)")
        ax.tick_params(axis="x", labelsize=7)
        fig.tight_layout()
        figs.append({"id": "parallel", "svg": _svg(fig, "cp"),
                     "caption": "Each line is a sample; each parameter is scaled from its "
                                "smallest (0) to its largest (1) drawn value."})
    modes = [m for m, e in summary["sensitivity_by_mode"].items()
             if any(x["rank_correlation"] is not None for x in e)][:MAX_MODES]
    if summary["sensitivity"]:
        names = ranked[::-1]  # the strongest driver on top
        series = [(m, {e["parameter"]: e["rank_correlation"] or 0.0
                       for e in summary["sensitivity_by_mode"][m]}) for m in modes] or [
            ("any failure (pooled)", {e["parameter"]: e["rank_correlation"] or 0.0
                                      for e in summary["sensitivity"]})]
        fig, ax = plt.subplots(figsize=(6.4, 0.8 + 0.3 * len(names) * len(series)))
        h = 0.8 / len(series)
        colors = (FAIL_COLOR, "#1f5fa8", "#e08a00")
        for k, (mode, rho) in enumerate(series):
            ax.barh(np.arange(len(names)) + (k - (len(series) - 1) / 2) * h,
                    [rho.get(n, 0.0) for n in names], height=h, color=colors[k % 3],
                    label=mode)
        ax.set_yticks(np.arange(len(names)), names)
        ax.axvline(0.0, color="#444444", linewidth=0.6)
        ax.set_xlabel("rank correlation with the mode failing (> 0: larger values fail more)")
        ax.set_xlim(-1, 1)
        ax.legend(loc="lower right", fontsize=7)
        fig.tight_layout()
        figs.append({"id": "sensitivity", "svg": _svg(fig, "cr"),
                     "caption": "Drivers of each failure mode: Spearman correlation of each "
                                "parameter with that mode failing (not the pooled pass/fail, "
                                "where modes driven in opposite directions cancel); "
                                "parameters ordered by their weight over the modes."})
    return figs


def _hist(ax, v: np.ndarray, title: str, bound=None, unit: str = "") -> None:
    v = v[np.isfinite(v)]
    if v.size:
        ax.hist(v, bins=40, color="#1f5fa8", alpha=0.8)
    if bound is not None:
        ax.axvline(bound, color=FAIL_COLOR, linestyle="--", label="bound")
    ax.set_title(title + (f" ({unit})" if unit else ""), fontsize=9)
    ax.tick_params(labelsize=7)


#: Metrics shown for a scenario without a bounded one.
_DEFAULT_SHOWN = (("rise_time_10_90", "s"), ("overshoot_pct", "%"))


def _shown(names, spec, slug: str) -> list[tuple]:
    """``(requirement key or None, quantity, unit)`` histogrammed for scenario ``slug``."""
    bounds = spec.requirements.bounds
    shown = [(key, q, u) for key, (stage, _d, q, u) in REQUIREMENT_KEYS.items()
             if stage == "sim" and key in bounds and f"{slug}.{q}" in names]
    return shown or [(None, q, u) for q, u in _DEFAULT_SHOWN]


def report_columns(names, spec, artifact) -> list[str]:
    """The columns of results.parquet the summary and the report read: all but
    the scenario metrics that are not shown."""
    from ._evaluate import make_plan

    slugs = [slug for slug, *_ in make_plan(spec, artifact).runs]
    keep = {f"{slug}.{q}" for slug in slugs for _k, q, _u in _shown(names, spec, slug)}
    return [c for c in names
            if not any(c.startswith(f"{slug}.") for slug in slugs) or c in keep]


def _dist_figures(table, spec, runs: list[str]) -> list[dict]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs = []
    keys = [("gain_margin_db", "gain margin", "dB", "min_gain_margin_db"),
            ("phase_margin_deg", "phase margin", "deg", "min_phase_margin_deg")]
    fig, axes = plt.subplots(2, 2, figsize=(6.4, 4.6))
    for r, (key, label, unit, req) in enumerate(keys):
        for c, axis in enumerate(("d", "q")):
            _hist(axes[r, c], _col(table, f"margin.{axis}.{key}").astype(float),
                  f"{axis} axis {label}", spec.requirements.bounds.get(req), unit)
    fig.tight_layout()
    figs.append({"id": "margins", "svg": _svg(fig, "cm"),
                 "caption": "Loop margins of each sample (sampled loop with the drawn R, L "
                            "and delay, zero speed); dashed: the requirement."})
    bounds = spec.requirements.bounds
    for k, slug in enumerate(runs):
        shown = _shown(table.column_names, spec, slug)
        fig, axes = plt.subplots(1, len(shown), figsize=(6.4, 2.6), squeeze=False)
        for ax, (key, q, unit) in zip(axes[0], shown):
            _hist(ax, _col(table, f"{slug}.{q}").astype(float), q,
                  bounds.get(key) if key else None, unit)
        fig.tight_layout()
        figs.append({"id": f"metrics-{k}", "svg": _svg(fig, f"cq{k}"),
                     "caption": f"Response metrics of scenario {slug} over the samples; "
                                "dashed: the requirement."})
    fig, ax = plt.subplots(figsize=(6.4, 2.6))
    ratio = _col(table, "worst_ratio").astype(float)
    _hist(ax, np.minimum(ratio, 5.0), "worst_ratio (clipped at 5)", 1.0)
    fig.tight_layout()
    figs.append({"id": "ratio", "svg": _svg(fig, "cw"),
                 "caption": "Distance to the closest bound: worst_ratio <= 1 passes."})
    return figs


def _attempts() -> int:
    from ._run import CHUNK_ATTEMPTS

    return CHUNK_ATTEMPTS


def _cells(summary) -> dict | None:
    c = summary.get("cells")
    if not c:
        return None
    a, b = c["axes"]
    return {"axes": [a, b], "rows": [
        {"a": _fmt(r[a]), "b": _fmt(r[b]), "n": r["n"], "rate": f"{100 * r['fail_rate']:.1f} %",
         "modes": "; ".join(f"{m}: {k}" for m, k in r["failures"].items()) or "-"}
        for r in c["cells"]]}


def campaign_html(table, summary: dict, spec, artifact) -> str:
    """The campaign report of a results table and its summary."""
    import jinja2

    from ._evaluate import make_plan

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(resources.files("toolbox.campaign") / "templates")),
        autoescape=True, undefined=jinja2.StrictUndefined)
    css = (resources.files("toolbox.report") / "templates" / "report.css").read_text()
    cfg = spec.campaign
    runs = [slug for slug, *_ in make_plan(spec, artifact).runs]
    n = summary["samples"]
    params = []
    for p in cfg.parameters:
        if p.distribution == "uniform":
            d = f"uniform [{p.low:g}, {p.high:g}]"
        elif p.distribution == "normal":
            d = f"normal (mean {p.mean:g}, std {p.std:g})"
        else:
            d = f"normal (mean {p.mean:g}, std {p.std:g}) truncated to [{p.low:g}, {p.high:g}]"
        params.append({"name": p.name, "dist": d, "mode": p.mode,
                       "nominal": _fmt(getattr(spec.motor, p.name))})
    ys = summary["yields"]

    def pct(y):
        return {"yield": f"{100 * y['yield']:.2f} %",
                "ci": " - ".join(f"{100 * v:.2f} %" for v in y["yield_95"])}

    axes = [k for k, _v in cfg.operating_points]
    yields = [{"key": "per_sample", "label": "Per sample", "n": f"{ys['per_sample']['n']} rows",
               **pct(ys["per_sample"])},
              {"key": "per_motor", "label": "Per motor (every point)",
               "n": f"{ys['per_motor']['n']} motors", **pct(ys["per_motor"])},
              {"key": "per_point", "label": "Per point (worst point)",
               "n": f"{ys['per_point']['n']} points", **pct(ys["per_point"])}]
    grid = [{"point": e["point"], "values": [_fmt(e[k]) for k in axes], "n": e["n"],
             "fail_rate": f"{100 * (1 - e['yield']):.2f} %", **pct(e),
             "modes": "; ".join(f"{m}: {c}" for m, c in e["failures"].items()) or "-"}
            for e in ys["per_point"]["points"]]
    by_mode = [{"mode": m, "count": summary["failure_reasons"].get(m, 0),
                "top": ", ".join([f"{e['parameter']} ({e['rank_correlation']:+.2f})"
                                  for e in entries if e["rank_correlation"] is not None][:3])
                or "-"} for m, entries in summary["sensitivity_by_mode"].items()]
    worst_head = ["sample"] + summary["parameters"] + ["worst check", "worst_ratio", "failure"]
    worst_rows = [[_fmt(w.get(h if h != "worst check" else "worst_check"))
                   for h in worst_head] for w in summary["worst_cases"]]
    context = dict(
        css=css, title=spec.title or "Robustness campaign", method=artifact.method,
        samples=n, seed=cfg.seed, scenarios=runs, passed=summary["passed"],
        failed=summary["failed"], yield_pct=f"{100 * summary['yield']:.2f} %",
        yield_ci=" - ".join(f"{100 * v:.2f} %" for v in summary["yield_95"]),
        min_yield=cfg.min_yield, meets=summary["meets_min_yield"], parameters=params,
        yields=yields, gate=summary["gate"], gate_lower=f"{100 * summary['gate_lower_95']:.2f} %",
        grid=grid, axes=axes, by_mode=by_mode, motors=summary["motors"],
        n_points=summary["operating_points"],
        worst_specs=summary.get("worst_specs", []),
        error_rows=summary.get("error_rows", 0), attempts=_attempts(),
        cells=_cells(summary),
        sensitivity_note=(f"Rank correlations over a seeded subsample of "
                          f"{summary['sensitivity_rows']} of the {n} rows, stratified so that "
                          "its failing share is the table's (counts and yields are exact)."
                          if summary.get("sensitivity_rows", n) < n else ""),
        correlation=(", ".join(cfg.correlation[0]) + " with matrix "
                     + str([list(r) for r in cfg.correlation[1]])) if cfg.correlation else "",
        measured=(f"{len(cfg.measured_rows)} rows of {', '.join(cfg.measured_columns)}"
                  if cfg.measured_rows else ""),
        points=[(k, ", ".join(f"{v:g}" for v in values)) for k, values in cfg.operating_points],
        requirements=[(k, _fmt(b), REQUIREMENT_KEYS[k][3])
                      for k, b in spec.requirements.bounds.items()],
        reasons=[(k, c, f"{100 * c / n:.2f} %") for k, c in summary["failure_reasons"].items()],
        sensitivity=[{"parameter": s["parameter"], "corr": _fmt(s["rank_correlation"], 3),
                      "low": _fmt(s["fail_rate_low_quartile"], 3),
                      "high": _fmt(s["fail_rate_high_quartile"], 3)}
                     for s in summary["sensitivity"]],
        region_figures=_region_figures(table, summary),
        worst_head=worst_head, worst_rows=worst_rows,
        dist_figures=_dist_figures(table, spec, runs), version=toolbox_version())
    return env.get_template("campaign.html.j2").render(**context)
