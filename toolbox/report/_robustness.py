"""The robustness section of the content model: the parameter sweep's ranges,
worst cases and figure (``analysis.sweep``)."""

from __future__ import annotations

from typing import Mapping, Sequence

from . import plots
from ._format import _as_float, fmt, fmt_q


#: Sweep parameters (``analysis.sweep.ranges``): name -> (label, unit text).
_SWEEP_LABELS = {"R": "R", "Ld": "Ld", "Lq": "Lq", "flux": "flux", "speed_gain": "speed gain",
                 "speed_offset": "speed offset", "delay_samples": "delay"}

#: Quantities of the sweep's worst cases: key -> (words, unit).
_WORST_WORDS = {"gain_margin_db": ("smallest gain margin", "dB"),
                "phase_margin_deg": ("smallest phase margin", "deg"),
                "stability_margin": ("smallest stability margin 1/max|S|", "1"),
                "disk_margin": ("smallest disk margin", "1"),
                "spectral_radius": ("largest closed-loop pole modulus", "1")}


def _range_text(name: str, entry: Sequence) -> str:
    """``R x0.5..2``, ``speed offset -10..10 rad/s (mechanical)``, ``delay +0..1 periods``."""
    lo, hi = entry[0], entry[1]
    kind = entry[2] if len(entry) > 2 else "scale"
    label = _SWEEP_LABELS.get(name, name)
    if kind == "offset":
        return f"{label} {fmt(lo)}..{fmt(hi)} rad/s (mechanical)"
    if kind == "int":
        return f"{label} {fmt(lo)}..{fmt(hi)} periods"
    return f"{label} x{fmt(lo)}..{fmt(hi)}"


def _params_text(params: Mapping) -> str:
    """One sweep set: ``R x0.5, Ld x0.5, ..., speed offset -10 rad/s, delay 1 period(s)``."""
    parts = []
    for k, v in params.items():
        label = _SWEEP_LABELS.get(k, k)
        if k == "speed_offset":
            parts.append(f"{label} {fmt(_as_float(v))} rad/s")
        elif k == "delay_samples":
            parts.append(f"{label} {fmt(v)} period(s)")
        else:
            parts.append(f"{label} x{fmt(_as_float(v))}")
    return ", ".join(parts)


def _robustness_of(analysis: Mapping | None) -> dict | None:
    """The stress sweep of ``analysis.sweep``, counted as the sweep counts
    (unstable sets / sets), its worst cases and its first unstable sets."""
    sweep = (analysis or {}).get("sweep") or {}
    if not sweep:
        return None
    cases = []
    for axis, worst in sorted(sweep.get("worst", {}).items()):
        for quantity, entry in worst.items():
            words, unit = _WORST_WORDS.get(quantity, (quantity, ""))
            cases.append({"label": f"{axis} axis: {words}",
                          "params": entry.get("params", {}),
                          "metrics": {quantity: entry.get("value")}, "pass": True,
                          "value": f"{fmt_q(entry.get('value'), unit)} {unit}".strip()})
    cases += [{"label": f"unstable set {k + 1}", "params": {
        n: v for n, v in ex.items() if n not in ("spectral_radius", "speed_rad_s")},
        "metrics": {"spectral_radius": ex.get("spectral_radius")}, "pass": False,
        "value": (f"largest closed-loop pole modulus {fmt(_as_float(ex.get('spectral_radius')))}"
                  + (f" at {fmt(_as_float(ex.get('speed_rad_s')))} rad/s electrical"
                     if ex.get("speed_rad_s") is not None else ""))}
        for k, ex in enumerate(sweep.get("unstable_examples", []))]
    worst_rho = _as_float(sweep.get("worst_spectral_radius"))
    speeds = [_as_float(s) for s in sweep.get("speeds_rad_s") or []]
    speeds = [s for s in speeds if s is not None]
    ranges = ", ".join(_range_text(k, v) for k, v in (sweep.get("ranges") or {}).items())
    n_sets, n_unstable = sweep.get("n_sets"), sweep.get("n_unstable")
    speed_text = (f"electrical speeds {fmt(min(speeds))}..{fmt(max(speeds))} rad/s "
                  f"({len(speeds)} speeds)" if speeds else "zero speed")
    notes = (f"Stress sweep (wider than the drift box of the robustness verdict): "
             f"{ranges}; {speed_text}. Largest closed-loop pole modulus over the sweep "
             f"{fmt(worst_rho)} (stable below 1).")
    return {"cases": cases, "worst": [c["label"] for c in cases],
            "notes": notes, "n_sets": n_sets, "n_unstable": n_unstable,
            "examples_shown": len(sweep.get("unstable_examples", []))}


def _robustness(rob: Mapping | None) -> dict | None:
    if not rob:
        return None
    cases = list(rob.get("cases", []))
    worst = [str(w.get("label") if isinstance(w, Mapping) else w) for w in rob.get("worst", [])]
    worst_rows = []
    for c in cases:
        if str(c.get("label")) in worst:
            worst_rows.append({"label": str(c.get("label")),
                               "params": _params_text(c.get("params") or {}),
                               "metrics": str(c.get("value") or fmt(c.get("metrics", {}))),
                               "status": "pass" if c.get("pass") else "fail"})
    n_sets, n_unstable = rob.get("n_sets"), rob.get("n_unstable")
    n_unstable_i = int(n_unstable) if isinstance(n_unstable, (int, float)) else None
    count = (f"{n_unstable} / {n_sets} sets unstable" if n_sets is not None
             else f"{sum(1 for c in cases if c.get('pass') is False)} failing cases")
    return {"count": count, "status": ("pass" if n_unstable_i == 0 else "fail"
                                       if n_unstable_i else ""),
            "notes": str(rob.get("notes", "")),
            "shown": (f"The first {rob.get('examples_shown')} unstable sets are listed."
                      if rob.get("examples_shown") else ""),
            "worst": worst_rows,
            "svg": (plots.robustness_svg(cases, [str(c.get("label")) for c in cases if c.get("pass")])
                    if cases else None)}
