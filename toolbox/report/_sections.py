"""The controller, step, scenario and provenance sections of the content
model: the controller table (:data:`METHOD_NAMES`), the analysis' linear step
figures, the simulated scenarios and the provenance rows."""

from __future__ import annotations

from typing import Mapping, Sequence

from . import plots
from ._data import ReportData
from ._format import _as_float, _flatten, fmt, fmt_q, sim_metric_unit, zpk_text
from .._version import toolbox_version


#: Long names of the design methods (toolbox/ARCHITECTURE.md "Spec file").
METHOD_NAMES = {
    "pi": "PI in dq (pole-zero cancellation)",
    "ip": "IP in dq (proportional action on the measurement)",
    "pi_lag": "PI with first-order lag",
    "tc": "Total compensation (decoupling + pole placement)",
    "tci": "Total compensation with integrators",
    "ilq": "Inverse LQ (ILQ)",
    "lq": "LQ servo via Riccati",
    "hinf": "H-infinity mixed sensitivity",
    "fcs_mpc": "Finite-control-set predictive control",
    "robust_pi": "Robust PI (multi-model disk-margin tuning at speed)",
    "tune": "Structured robust tuning of the PI (hard disk-margin goals, fastest response)",
    "cv": "Direct discrete-time complex-vector control (poles placed in z at the measured speed)",
}


def _step_of(analysis: Mapping | None) -> dict | None:
    """Linear step figures per axis from ``analysis.margins.discrete`` (s and %)."""
    disc = ((analysis or {}).get("margins") or {}).get("discrete") or {}
    out = {ax: {k: disc[ax].get(k) for k in plots.STEP_FIGURES} for ax in ("d", "q")
           if isinstance(disc.get(ax), Mapping)}
    return out or None


#: Non-executed controllers an axis may carry: attribute -> label in the table.
_NOT_EXECUTED = (("full_order", "full order, not executed"),
                 ("reduced", "reduced, not executed"))


def _controller(artifact) -> dict:
    axes = []
    for name in ("d", "q"):
        ax = artifact.axes[name]
        var = "s" if ax.continuous is not None else "z"
        # the executed law's order and views (discrete is derived from law)
        row = {"axis": name, "order": ax.order, "zpk": f"K({var}) = " + zpk_text(ax.zpk, var),
               "discretisation": ax.law.method or "",
               "continuous": "yes" if ax.continuous is not None else "no (discrete design)",
               "alt": None, "alt_label": None, "alt_order": None}
        for attr, label in _NOT_EXECUTED:
            other = getattr(ax, attr)
            if other is not None:
                ovar = "s" if other.continuous is not None else "z"
                row.update(alt=f"K({ovar}) = " + zpk_text(other.zpk, ovar), alt_label=label,
                           alt_order=other.order)
        axes.append(row)
    params: list = []
    _flatten("", artifact.design_parameters, params)
    dec = artifact.decoupling
    decoupling = [("Cross-coupling compensation", "yes" if dec.cross else "no", ""),
                  ("Back-EMF compensation", "yes" if dec.emf else "no", ""),
                  ("R_c (controller model)", fmt(dec.R_c), "ohm"),
                  ("Ld_c", fmt(dec.Ld_c), "H"), ("Lq_c", fmt(dec.Lq_c), "H"),
                  ("flux_c", fmt(dec.flux_c), "Wb"), ("pole_pairs", str(dec.pole_pairs), "1")]
    if artifact.fcs is None:
        decoupling.append(("Voltage placement: v_dq placed at theta_k + t_c w_e "
                           "(drive.angle_compensation; 0: none)",
                           fmt(dec.delay_compensation_time), "s"))
    if artifact.fcs is not None:
        f = artifact.fcs
        decoupling += [("Criterion (23) weight alpha (i_q error)", fmt(f.alpha), "1"),
                       ("Criterion (23) weight beta (i_d error)", fmt(f.beta), "1"),
                       ("Criterion (23) weight gamma (commutations)", fmt(f.gamma), "1")]
    prov = artifact.provenance or {}
    return {"method": artifact.method,
            "method_name": METHOD_NAMES.get(artifact.method, artifact.method),
            "sample_time": fmt(artifact.sample_time), "delay": artifact.delay_samples,
            "equations": [str(e) for e in prov.get("equations", [])],
            "design_parameters": params, "axes": axes, "decoupling": decoupling}


def _scenario_traces(data: ReportData) -> list[dict | None]:
    """The traces of each verification scenario (``traces_dict`` form), in order."""
    n = len((data.verification or {}).get("scenarios", []))
    given = list(data.traces or [])
    return [plots.traces_dict(given[k]) if k < len(given) else None for k in range(n)]


def _scenarios(verification: Mapping | None, traces: Sequence) -> list[dict]:
    """Scenario rows of verify.json, each with its trace figure when traces are given."""
    out = []
    for k, sc in enumerate((verification or {}).get("scenarios", [])):
        tr = traces[k] if k < len(traces) else None
        metrics = sc.get("metrics") or {}
        passed = sc.get("passed")
        out.append({
            "name": str(sc.get("name", f"scenario {k + 1}")),
            "kind": str(sc.get("kind", "")),
            "status": "" if passed is None else ("pass" if passed else "fail"),
            "metrics": [(str(m), (fmt_q(_as_float(v), sim_metric_unit(str(m), sc.get("kind", "")))
                                  if not isinstance(v, str) else v),
                         sim_metric_unit(str(m), str(sc.get("kind", ""))))
                        for m, v in metrics.items()],
            "svg": plots.scenario_svg(tr, prefix=f"sc{k}") if tr else None,
        })
    return out


def _provenance(data: ReportData) -> list[tuple[str, str]]:
    prov = dict(data.artifact.provenance or {})
    rows = [(str(k), fmt(v)) for k, v in prov.items() if k != "equations"]
    rows.append(("spec source", str(getattr(data.spec, "source", None) or "(in memory)")))
    rows.append(("report toolbox version", toolbox_version()))
    if data.generated:
        rows.append(("report generated", str(data.generated)))
    return rows


def _envelope(verification) -> dict | None:
    """The torque-speed grid section (verify.json ``envelope``): its one-line
    summary, the envelope figure (:func:`toolbox.report.plots.envelope_svg`,
    each point's reason as hover text) and one row per point with its status,
    reason and tangent loop (the executed loop linearised at the point,
    :func:`toolbox.report.plots.envelope_linear_text`; the figure's hover text
    does not print), the speed ramp through base speed (``speed_ramp``) as the
    last row. None without a grid."""
    env = (verification or {}).get("envelope")
    if not env:
        return None
    if env.get("skipped"):
        return {"summary": f"Torque-speed grid: skipped ({env['skipped']}).", "status": "none",
                "svg": None, "rows": [], "key": None}
    rows = [(f"{p['torque_fraction']:g} x at {p['speed_fraction']:g} x base",
             fmt(p["speed"]), fmt(p.get("torque")), str(p.get("region")), str(p["status"]),
             str(p.get("reason") or ""), plots.envelope_linear_text(p.get("linear")))
            for p in env.get("points", [])]
    ramp = env.get("speed_ramp")
    if ramp:   # the speed ramp through base speed: one more row, its line in the summary
        rows.append((f"speed ramp to {fmt(ramp.get('speed_end'))} rad/s",
                     f"{fmt(ramp.get('speed_start'))} .. {fmt(ramp.get('speed_end'))}",
                     fmt(ramp.get("torque")), str(ramp.get("region") or ""),
                     str(ramp["status"]), str(ramp.get("reason") or ramp.get("summary", "")),
                     "-"))
    return {"summary": str(env.get("summary", "")) + (f"; {ramp['summary']}" if ramp else ""),
            "status": "pass" if env.get("passed") else "fail",
            "svg": plots.envelope_svg(env), "rows": rows, "key": None}
