"""Margin reports: one self-contained HTML file and a PDF with the same content.

The report stage reads plain data only: a :class:`ReportData` bundle of what
earlier stages produced (the validated spec, the controller artifact,
``analysis.json`` and ``verify.json`` as dicts, and the simulated traces).
It re-designs nothing and computes no loop, margin or response: every figure
draws numbers stored in ``analysis.json`` (``responses``, written by
:mod:`toolbox.analysis._responses`), so a 2-DOF law's step is its executed
reference response and the H-infinity weight bounds are those of the weights
the design recorded. The package imports neither python-control nor
``toolbox.analysis`` (a test checks it). What is not given is shown as "not
computed".

Entry points
------------
:func:`write_html` (``ReportData -> str``) and :func:`write_pdf`
(``ReportData -> bytes``, optionally written to a path). Both render the same
content model, :func:`build_context`, made of plain strings, tables and inline
SVG figures (:mod:`toolbox.report.plots`); both also accept that content
model, so the figures are drawn once for the two documents.

Every string coming from a user (title, scenario names, free-text labels) is
escaped for the output language: jinja2 autoescaping for HTML, typst string
literals for the PDF. Figures never contain user strings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from . import plots

__all__ = ["ReportData", "build_context", "write_html", "write_pdf", "zpk_text", "fmt", "fmt_q", "NOT_COMPUTED",
           "METHOD_NAMES", "MARGIN_ROWS", "BASELINE_LABEL", "RESOLUTION", "sim_metric_unit"]

NOT_COMPUTED = "not computed"

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
}

#: MARGINS keys (toolbox/ARCHITECTURE.md "controller.json") -> (label, unit).
MARGIN_ROWS = {
    "gain_margin_db": ("Gain margin", "dB"),
    "gain_crossover_rad_s": ("Gain crossover frequency (|L| = 1)", "rad/s"),
    "phase_margin_deg": ("Phase margin", "deg"),
    "phase_crossover_rad_s": ("Phase crossover frequency (-180 deg)", "rad/s"),
    "disk_margin": ("Disk margin", "1"),
    "stability_margin": ("Stability margin (1/max|S|)", "1"),
    "sensitivity_peak": ("Sensitivity peak max|S|", "1"),
    "bandwidth_rad_s": ("Closed-loop bandwidth", "rad/s"),
    "static_error": ("Static error", "1"),
}

MOTOR_ROWS = (  # field, symbol, quantity, unit
    ("R", "R", "Stator resistance", "ohm"),
    ("Ld", "L_d", "d-axis inductance", "H"),
    ("Lq", "L_q", "q-axis inductance", "H"),
    ("flux", "psi_f", "PM flux linkage", "Wb"),
    ("pole_pairs", "p", "Pole pairs", "1"),
    ("J", "J", "Inertia", "kg m^2"),
    ("friction", "F", "Viscous friction", "N m s/rad"),
    ("convention", "", "dq convention", ""),
    ("rated_current", "", "Rated current", "A"),
    ("max_current", "", "Maximum current", "A"),
    ("rated_speed", "", "Rated speed", "rad/s"),
    ("catalog", "", "Catalog entry", ""),
)

DRIVE_ROWS = (
    ("vdc", "DC-link voltage", "V"),
    ("sample_time", "Controller period", "s"),
    ("delay_samples", "Computation delay", "periods"),
    ("switching_frequency", "Switching frequency", "Hz"),
    ("voltage_limit", "Voltage limit", ""),
    ("max_speed", "Maximum speed", "rad/s"),
)


@dataclass
class ReportData:
    """Everything a report shows (plain data; only the first three are required).

    The report draws and tabulates what these hold and computes no loop,
    margin or response itself: ``analysis`` is ``analysis.json`` and
    ``verification`` is ``verify.json``, as written by ``cct design``.

    Attributes
    ----------
    title : str
        Report title (free user text; escaped in every output).
    spec : toolbox.spec.Spec
        The validated spec (motor, drive, requirements).
    artifact : toolbox.artifact.ControllerArtifact
        The designed controller (axes, typed fields, design parameters, provenance).
    analysis : dict or None
        ``analysis.json``: ``margins.discrete`` (the MARGINS table, margin
        markers and step figures), ``responses`` (every loop figure, see
        :mod:`toolbox.analysis._responses`), ``requirements`` (margin checks),
        ``sweep``, ``mimo_at_speed`` and ``certificate``. ``None``: margins
        from ``artifact.margins`` when non-empty, everything else "not
        computed".
    verification : dict or None
        ``verify.json``: per scenario ``name``, ``kind``, ``passed``,
        ``metrics`` and ``requirements``; ``margin_requirements`` are used
        when ``analysis`` is absent.
    traces : list or None
        Simulated traces per scenario of ``verification``, in its order
        (``{"t": s, "id", "iq", "id_ref", "iq_ref": A, "vd", "vq": V, ...}``,
        a :class:`toolbox.sim.SimResult`, or ``None``); they are not part of
        verify.json, so a report without them shows no trace figure.
    equations : list or None
        The derived dq model as ``{"label", "latex", "text"}`` rows;
        ``None`` derives it from ``spec.motor.convention`` (paper 000 eq
        (1)-(2), 003 eq (3)-(7)).
    generated : str or None
        Report time stamp to print (ISO 8601); ``None`` prints none, which keeps
        the output byte-identical for identical inputs.
    notice : str or None
        One line shown above the checks, e.g. "no requirements given; default
        checks only".
    warnings : list of str or None
        Lines shown with the notice (stored numbers that disagree with the
        recomputed ones, a refused header).
    """

    title: str
    spec: Any
    artifact: Any
    analysis: Mapping | None = None
    verification: Mapping | None = None
    traces: Sequence | None = None
    equations: list | None = None
    generated: str | None = None
    notice: str | None = None
    warnings: list | None = None


# ----------------------------------------------------------------- formatting

def fmt(value: Any, digits: int = 4) -> str:
    """Format a value for a table: numbers to ``digits`` significant digits.

    ``None`` and NaN (a quantity that has no value, e.g. the bandwidth of an
    unstable loop) become "not computed"; infinities "inf"; booleans "yes"/"no".
    """
    if value is None:
        return NOT_COMPUTED
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return NOT_COMPUTED
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return f"{v:.{digits}g}"
    if isinstance(value, complex):
        return f"{value.real:.{digits}g}{value.imag:+.{digits}g}j"
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value, dtype=object)
        if arr.ndim <= 1:
            return "[" + ", ".join(fmt(v, digits) for v in arr.tolist()) + "]"
        return "[" + "; ".join(", ".join(fmt(v, digits) for v in row) for row in arr.tolist()) + "]"
    if isinstance(value, Mapping):
        return ", ".join(f"{k}: {fmt(v, digits)}" for k, v in value.items())
    return str(value)


#: Display resolution of each unit: a value whose magnitude is below it is
#: round-off (e.g. a static error of 4.4e-14) and is shown as 0 (stated in the
#: report under the tables, :data:`RESOLUTION_NOTE`).
RESOLUTION = {"s": 1e-7, "A": 1e-6, "V": 1e-6, "%": 1e-3, "dB": 1e-3, "deg": 1e-3,
              "rad/s": 1e-3, "rad": 1e-6, "Hz": 1e-3, "1/s": 1e-3, "1": 1e-9,
              "A^2": 1e-12, "(N m)^2": 1e-12}
RESOLUTION_NOTE = ("Numbers to 4 significant digits; values below the resolution of their "
                   "unit are shown as 0 (s: 0.1 us, A and V: 1 uA and 1 uV, %, dB, deg, "
                   "rad/s and 1/s: 0.001, dimensionless: 1e-9, A^2 and (N m)^2: 1e-12).")


def fmt_q(value: Any, unit: str, digits: int = 4) -> str:
    """:func:`fmt` of a quantity in ``unit``: below :data:`RESOLUTION` it is 0.

    Parameters
    ----------
    value : float, int, str or None
        The quantity (a string is shown as it is).
    unit : str
        Its unit, a key of :data:`RESOLUTION` (others: no resolution).
    digits : int
        Significant digits.
    """
    v = _as_float(value) if not isinstance(value, str) else None
    res = RESOLUTION.get(unit)
    if v is not None and res is not None and math.isfinite(v) and abs(v) < res:
        return "0"
    return fmt(value if not isinstance(value, (int, float, np.number)) or v is None else v,
               digits)


#: Units of the simulated metrics (:mod:`toolbox.sim._metrics`); ``signal``:
#: the stepped signal's unit (A, or rad/s for a speed scenario).
SIM_METRIC_UNITS = {
    "response_time_5pct": "s", "rise_time_10_90": "s", "settling_time_2pct": "s",
    "overshoot_pct": "%", "static_error": "signal", "final_value": "signal",
    "static_error_abs": "A", "static_speed_error_abs": "rad/s",
    "mse_torque": "(N m)^2", "mse_id": "A^2", "mse_iq": "A^2",
    "commutations_per_s": "1/s", "cell_transitions_per_s": "1/s",
    "saturation_time": "s", "final_speed": "rad/s",
    "E_torque": "(N m)^2", "E_id": "A^2",
}

SPEED_KINDS = ("speed_step", "load_step")


def sim_metric_unit(name: str, kind: str = "") -> str:
    """Unit of a simulated metric of a scenario of ``kind`` ("" when unknown).

    Parameters
    ----------
    name : str
        Metric name (:mod:`toolbox.sim._metrics`).
    kind : str
        Scenario kind: the static error and final value of a speed scenario are rad/s.
    """
    unit = SIM_METRIC_UNITS.get(name, "")
    if unit == "signal":
        return "rad/s" if kind in SPEED_KINDS else "A"
    return unit


def _poly_factors(roots: np.ndarray, var: str = "s") -> str:
    """``(s + a)(s^2 + b s + c)`` text for real / complex-pair roots (rad/s)."""
    parts: list[str] = []
    scale = max(1.0, float(np.max(np.abs(roots)))) if len(roots) else 1.0
    # a root within round-off of the origin is an integrator (e.g. 003 eq (71)-(72))
    roots = np.where(np.abs(roots) < 1e-12 * scale, 0.0, roots)
    done = np.zeros(len(roots), bool)
    for k, r in enumerate(roots):
        if done[k]:
            continue
        done[k] = True
        if abs(r.imag) <= 1e-9 * max(1.0, abs(r)):
            a = -r.real
            parts.append(var if a == 0 else f"({var} {'+' if a > 0 else '-'} {abs(a):.4g})")
        else:
            for j in range(k + 1, len(roots)):  # its conjugate
                if not done[j] and abs(roots[j] - np.conj(r)) <= 1e-6 * abs(r):
                    done[j] = True
                    break
            b, c = -2 * r.real, abs(r) ** 2
            parts.append(f"({var}^2 {'+' if b >= 0 else '-'} {abs(b):.4g} {var} + {c:.4g})")
    return "".join(parts) if parts else "1"


def zpk_text(zpk, var: str = "s") -> str:
    """``k (s + z1)... / ((s + p1)...)`` of a :class:`toolbox.artifact.Zpk`.

    Parameters
    ----------
    zpk : Zpk
        Zeros and poles (rad/s, or z-plane for a discrete-only design), gain.
    var : str
        ``"s"`` or ``"z"``.
    """
    num = _poly_factors(np.asarray(zpk.zeros, complex), var)
    den = _poly_factors(np.asarray(zpk.poles, complex), var)
    head = f"{zpk.gain:.4g}" if num == "1" else f"{zpk.gain:.4g} {num}"
    return head if den == "1" else f"{head} / {den}"


def _flatten(prefix: str, value: Any, out: list) -> None:
    if isinstance(value, Mapping):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    else:
        out.append((prefix, fmt(value)))


# -------------------------------------------------------------- content model

def _margins_of(data: ReportData) -> dict | None:
    """MARGINS per axis: ``analysis.margins.discrete``, else the artifact's."""
    disc = ((data.analysis or {}).get("margins") or {}).get("discrete")
    if disc:
        return dict(disc)
    art = getattr(data.artifact, "margins", None)
    return dict(art) if art else None


def _checks_of(data: ReportData) -> list | None:
    """Requirement checks: the analysis' margin checks and each scenario's.

    verify.json repeats the margin checks (``margin_requirements``); they are
    taken from there only when no analysis is given, so none is listed twice.
    """
    if data.analysis is None and data.verification is None:
        return None
    checks: list[dict] = []
    margin_checks = ((data.analysis or {}).get("requirements")
                     if data.analysis is not None
                     else (data.verification or {}).get("margin_requirements")) or {}
    checks += [{"key": k, **c} for k, c in margin_checks.items()]
    if data.analysis is not None:  # verification's own verdicts (default.stable, parameter_drift)
        checks += [{"key": k, **c} for k, c in
                   ((data.verification or {}).get("margin_requirements") or {}).items()
                   if k not in margin_checks]
    for sc in (data.verification or {}).get("scenarios", []):
        checks += [{"key": k, "scenario": sc.get("name"), **c}
                   for k, c in (sc.get("requirements") or {}).items()]
    return checks


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


def _verdict_card(verification: Mapping | None, baseline: bool = False) -> dict | None:
    """The robustness card: verify.json's drift-box verdict (``robustness``),
    pass (green) or fail (red), with the worst multiloop disk margin, the
    unstable sets and the box; None without verification."""
    rob = (verification or {}).get("robustness")
    if not rob:
        return None
    passed = int(rob.get("n_unstable") or 0) == 0
    first = rob.get("first_unstable") or {}
    # the baseline PI of fcs_mpc does not run: its verdict decides nothing (neutral)
    return {"status": "info" if baseline else "pass" if passed else "fail",
            "disk_margin": fmt(_as_float(rob.get("worst_disk_margin"))),
            "unstable": f"{rob.get('n_unstable')} / {rob.get('n_sets')}",
            "box": str(rob.get("box_text", "")),
            "first": (", ".join(f"{k} {fmt(v)}" for k, v in first.items()) if first else None),
            "informational": BASELINE_LABEL if baseline else None}


#: How the loop figures of a method whose axes do not run are labelled (fcs_mpc:
#: the axes hold paper 002's baseline PI, the switching law runs instead).
BASELINE_LABEL = "baseline PI, informational, not executed"


def _first_failure(check: Mapping) -> str:
    """One sentence saying why ``check`` (a failing requirement check) fails."""
    key = str(check.get("key", ""))
    quantity = str(check.get("quantity", ""))
    unit = str(check.get("unit", ""))
    if quantity in MARGIN_ROWS and check.get("value") is not None:
        label, _ = MARGIN_ROWS[quantity]
        side = "below" if key.startswith("min") else "above"
        where = f" ({check['axis']} axis)" if check.get("axis") else ""
        text = (f"{label}{where} {fmt_q(check.get('value'), unit)} {unit} is {side} the "
                f"required {fmt_q(check.get('bound'), unit)} {unit} ({key})")
    else:
        reason = str(check.get("reason") or "").strip() or (
            f"{quantity} = {fmt_q(_as_float(check.get('value')), unit)} {unit} against the "
            f"bound {_bound_text(check)} {unit}")
        where = check.get("scenario")
        text = (f"scenario \u201c{where}\u201d, {key}: {reason}" if where
                else f"{key}: {reason}")
    text = " ".join(text.split()).rstrip(".")
    return text[:1].upper() + text[1:] + "."


def _banner(data: ReportData, checks: list | None) -> dict:
    """The verdict banner: PASS (green) / FAIL (red) / NOT VERIFIED (grey),
    the failing count and the first failing reason in one sentence.

    A design passes when every requirement and default check holds
    (verify.json ``passed`` when given) and no executed axis is unstable.
    """
    failing = [c for c in checks or [] if not c.get("pass")]
    unstable = [ax for ax, s in sorted(((data.analysis or {}).get("stability") or {}).items())
                if isinstance(s, Mapping) and s.get("stable") is False]
    verified = (data.verification or {}).get("passed")
    if checks is None and verified is None:
        return {"status": "none", "headline": "NOT VERIFIED", "count": "",
                "reason": "No analysis or verification was run: nothing was checked."}
    passed = not failing and not unstable and verified is not False
    n = len(checks or [])
    if passed:
        return {"status": "pass", "headline": "PASS",
                "count": f"{n} / {n} checks pass",
                "reason": "Every requirement and default check holds."}
    if failing:
        reason = _first_failure(failing[0])
    elif unstable:
        reason = (f"The executed sampled loop of the {' and '.join(unstable)} axis is unstable "
                  "(a closed-loop pole on or outside the unit circle).")
    else:
        reason = next((f"{w.rstrip('.')}." for w in data.warnings or []
                       if "controller.h" in str(w) or "header" in str(w)),
                      "The verification failed (see the requirement checks).")
    return {"status": "fail", "headline": "FAIL",
            "count": f"{len(failing)} / {n} checks fail" if n else "",
            "reason": reason}


def _certificate_of(analysis: Mapping | None) -> dict | None:
    """Named facts of ``analysis.certificate``, ``analysis.sampled_certificate``,
    ``analysis.mimo_at_speed`` and ``analysis.mimo_over_box``."""
    facts: dict[str, Any] = {}
    cert = (analysis or {}).get("certificate")
    if cert:
        facts["quadratic stability (continuous loop, no delay)"] = (
            "certified" if cert.get("certified") else "not certified")
        facts["largest certified box scale"] = cert.get("scale")
        for name, (lo, hi) in (cert.get("box") or {}).items():
            facts[f"box {name}"] = f"{lo:.4g} .. {hi:.4g}"
    facts.update(_sampled_certificate_of((analysis or {}).get("sampled_certificate")))
    mimo = (analysis or {}).get("mimo_at_speed") or {}
    if mimo:
        facts["MIMO disk margin, worst electrical speed (rad/s)"] = mimo.get("worst_speed_rad_s")
        facts["MIMO disk margin, worst value"] = mimo.get("worst_disk_margin")
    box = (analysis or {}).get("mimo_over_box") or {}
    if box:
        facts["MIMO disk margin over the parameter box and speeds, worst value"] = (
            box.get("worst_disk_margin"))
        facts["MIMO disk margin over the box, worst electrical speed (rad/s)"] = (
            box.get("worst_speed_rad_s"))
        facts["MIMO disk margin over the box, worst parameters (scale factors)"] = ", ".join(
            f"{k} x{v:g}" for k, v in (box.get("worst_params") or {}).items())
        facts["MIMO over the box: unstable (plant, speed) pairs"] = (
            f"{box.get('n_unstable')} of {box.get('n_models')} plants x "
            f"{len(box.get('speeds_rad_s') or [])} speeds")
    return facts or None


#: units of the sampled certificate's box entries other than the speeds
_SAMPLED_BOX_UNITS = {"R": " ohm", "Ld": " H", "Lq": " H"}
#: labels of its speed entries (electrical rad/s in the JSON)
_SAMPLED_BOX_SPEEDS = {"omega": "speed", "speed_offset": "speed-sensor offset"}
#: labels of the other box entries
_SAMPLED_BOX_LABELS = {"speed_gain": "speed-sensor gain"}


def _speed_text(lo: Any, hi: Any, pole_pairs: Any) -> str:
    """An electrical speed range (rad/s) as mechanical rad/s with electrical in
    brackets (the spec's ``max_speed`` is mechanical); electrical alone when
    the pole pairs are unknown (an analysis.json written before they were)."""
    elec = f"{fmt(lo)} .. {fmt(hi)} rad/s electrical"
    lo, hi, pp = _as_float(lo), _as_float(hi), _as_float(pole_pairs)
    if lo is None or hi is None or not pp:
        return elec
    return f"{fmt(lo / pp)} .. {fmt(hi / pp)} rad/s mechanical ({elec})"


def _sampled_certificate_of(cert: Mapping | None) -> dict[str, Any]:
    """Named facts of ``analysis.sampled_certificate`` (empty when absent); its
    speeds (electrical in the JSON) are stated in mechanical rad/s with
    electrical in brackets."""
    if not isinstance(cert, Mapping):
        return {}
    where = "sampled coupled loop as executed (ZOH, delay, decoupling, voltage placement)"
    pp = cert.get("pole_pairs")
    facts: dict[str, Any] = {
        f"stability certificate, {where}": "certified" if cert.get("certified")
        else "not certified, not even the nominal point",
        "sampled loop: largest certified box scale": cert.get("scale"),
        "sampled loop: what the scale means": "scale k shrinks every range of the "
        "sweep's box towards the nominal point by the factor k, the speed range "
        "included (k = 1: the whole box and speeds up to the maximum); the box "
        "certified is listed below in the spec's units"}
    speed = cert.get("speed_range_rad_s")
    if isinstance(speed, (list, tuple)) and len(speed) == 2:
        facts["sampled loop: speed range covered"] = _speed_text(*speed, pp)
    for name, (lo, hi) in (cert.get("box") or {}).items():
        if name == "omega" and "sampled loop: speed range covered" in facts:
            continue            # the same range
        if name in _SAMPLED_BOX_SPEEDS:
            facts[f"sampled loop: box {_SAMPLED_BOX_SPEEDS[name]}"] = _speed_text(lo, hi, pp)
        else:
            unit = _SAMPLED_BOX_UNITS.get(name, "")
            label = _SAMPLED_BOX_LABELS.get(name, name)
            facts[f"sampled loop: box {label}"] = f"{lo:.4g} .. {hi:.4g}{unit}"
    first = cert.get("first_uncertified")
    if isinstance(first, Mapping):
        c = first.get("corner") or {}
        state = ("unstable" if c.get("unstable") else "stable there, not proven on its cell")

        def speed_at(v):
            w, p = _as_float(v), _as_float(pp)
            if w is None or not p:
                return f"{fmt(v)} rad/s electrical"
            return f"{fmt(w / p)} rad/s mechanical ({fmt(w)} rad/s electrical)"

        facts["sampled loop: first uncertified corner"] = (
            f"scale {fmt(first.get('scale'))}: R x{fmt(c.get('R'))}, Ld x{fmt(c.get('Ld'))}, "
            f"Lq x{fmt(c.get('Lq'))}, w {speed_at(c.get('omega_rad_s'))}, speed gain "
            f"{fmt(c.get('speed_gain'))}, offset {speed_at(c.get('speed_offset_rad_s'))}; "
            f"spectral radius {fmt(c.get('spectral_radius'))} ({state}); {first.get('reason')}")
    return facts


def _step_of(analysis: Mapping | None) -> dict | None:
    """Linear step figures per axis from ``analysis.margins.discrete`` (s and %)."""
    disc = ((analysis or {}).get("margins") or {}).get("discrete") or {}
    out = {ax: {k: disc[ax].get(k) for k in plots.STEP_FIGURES} for ax in ("d", "q")
           if isinstance(disc.get(ax), Mapping)}
    return out or None


def _as_float(v: Any) -> float | None:
    if v is None or isinstance(v, bool):
        return None
    if isinstance(v, str):  # artifact JSON writes "inf"
        try:
            return float(v)
        except ValueError:
            return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def _margin_table(margins: dict | None, checks: list | None) -> list[dict]:
    """Rows: label, unit, d value, q value, requirement text, pass text."""
    by_quantity: dict[str, list[dict]] = {}
    for c in checks or []:
        by_quantity.setdefault(c.get("quantity", ""), []).append(c)
    rows = []
    for key, (label, unit) in MARGIN_ROWS.items():
        vals = {ax: (_as_float((margins or {}).get(ax, {}).get(key)) if margins else None)
                for ax in ("d", "q")}
        req = by_quantity.get(key, [])
        bound = "; ".join(dict.fromkeys(_bound_text(c) for c in req)) if req else ""
        status = ("pass" if all(c.get("pass") for c in req) else "fail") if req else ""
        rows.append({"key": key, "label": label, "unit": unit,
                     "d": fmt_q(vals["d"], unit), "q": fmt_q(vals["q"], unit),
                     "requirement": bound, "status": status})
    return rows


def _bound_text(check: Mapping) -> str:
    key = str(check.get("key", ""))
    op = ">=" if key.startswith("min") else "<=" if key.startswith("max") else "vs"
    return f"{op} {fmt_q(check.get('bound'), str(check.get('unit', '')))}"


def _check_rows(checks: list | None) -> list[dict]:
    rows = []
    for c in checks or []:
        where = c.get("axis") or c.get("scenario") or ""
        # a failing check says why (a verdict the user can follow)
        why = f" ({c['reason']})" if not c.get("pass") and c.get("reason") else ""
        rows.append({"key": str(c.get("key", "")), "quantity": str(c.get("quantity", "")) + why,
                     "where": str(where), "bound": _bound_text(c),
                     "value": fmt_q(_as_float(c.get("value")) if c.get("value") is not None
                                    else None, str(c.get("unit", ""))),
                     "unit": str(c.get("unit", "")),
                     "status": "pass" if c.get("pass") else "fail"})
    return rows


def _equations(spec, given: list | None = None) -> list[dict]:
    """Derived dq model as LaTeX, plain text and SVG (paper 000 eq (1)-(2), 003 eq (3)-(7)).

    ``given`` rows (``{"label", "latex", "text"}``) are rendered as they are;
    otherwise the model is derived for the spec's dq convention. The derived
    rows depend only on the convention and on source code, so they are cached
    on disk (:mod:`toolbox._cache`, keyed by the derivation's, this module's
    and the plotting module's sources and the sympy and matplotlib versions):
    a cache hit imports neither sympy nor matplotlib.
    """
    if given is not None:
        return [{"label": str(e["label"]), "latex": str(e["latex"]), "text": str(e["text"]),
                 "svg": plots.equation_svg(str(e["latex"]).replace(r"\frac", r"\dfrac"))}
                for e in given]
    from .._cache import cached

    convention = spec.motor.convention
    sources = (Path(__file__).parents[1] / "plant" / "_symbolic.py", Path(__file__),
               Path(plots.__file__))
    return cached(f"report_equations-{convention}", sources,
                  lambda: _derived_equations(convention),
                  lambda rows: isinstance(rows, list) and all(
                      isinstance(r, dict) and set(r) == {"label", "latex", "text", "svg"}
                      for r in rows),
                  packages=("sympy", "matplotlib"))


def _derived_equations(convention: str) -> list[dict]:
    """The rows of :func:`_equations` for a dq convention, derived and typeset."""
    import sympy as sp

    from ..plant import derive_dq_model

    model = derive_dq_model(convention)
    di_d, di_q = sp.symbols("di_d di_q", real=True)
    names = {di_d: r"\dot{i}_{d}", di_q: r"\dot{i}_{q}"}
    items = [
        ("Stator voltage, d axis", "v_{d}", model.voltage[0]),
        ("Stator voltage, q axis", "v_{q}", model.voltage[1]),
        ("Current dynamics, d axis", r"\frac{d i_{d}}{dt}", model.di_dt[0]),
        ("Current dynamics, q axis", r"\frac{d i_{q}}{dt}", model.di_dt[1]),
        ("Electromagnetic torque", "T_{e}", model.torque),
        ("Mechanics", r"\frac{d \Omega}{dt}", model.dOmega_dt),
    ]
    out = []
    for label, lhs, expr in items:
        tex = f"{lhs} = {sp.latex(expr, symbol_names=names)}"
        text = f"{sp.sstr(expr)}".replace("di_d", "d(i_d)/dt").replace("di_q", "d(i_q)/dt")
        lhs_text = {"v_{d}": "v_d", "v_{q}": "v_q", "T_{e}": "T_e"}.get(
            lhs, lhs.replace(r"\frac{d i_{d}}{dt}", "d(i_d)/dt")
            .replace(r"\frac{d i_{q}}{dt}", "d(i_q)/dt").replace(r"\frac{d \Omega}{dt}", "d(Omega)/dt"))
        shown = tex.replace(r"\frac", r"\dfrac")  # display-style fractions read better
        out.append({"label": label, "latex": tex, "text": f"{lhs_text} = {text}",
                    "svg": plots.equation_svg(shown)})
    return out


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


def _provenance(data: ReportData) -> list[tuple[str, str]]:
    from .._version import toolbox_version

    prov = dict(data.artifact.provenance or {})
    rows = [(str(k), fmt(v)) for k, v in prov.items() if k != "equations"]
    rows.append(("spec source", str(getattr(data.spec, "source", None) or "(in memory)")))
    rows.append(("report toolbox version", toolbox_version()))
    if data.generated:
        rows.append(("report generated", str(data.generated)))
    return rows


def build_context(data: ReportData) -> dict:
    """The report's content model (plain strings, row lists and SVG strings).

    Parameters
    ----------
    data : ReportData

    Returns
    -------
    dict
        Keys ``title, motor, drive, requirements, equations, controller,
        margins, checks, figures, step, robustness, verdict_card (the
        robustness card: drift-box verdict), banner (the verdict banner:
        ``status`` pass/fail/none, ``headline``, ``count``, ``reason``),
        baseline (the label of informational margins, or None), certificate,
        scenarios, provenance, margins_given, resolution_note``; the HTML and typst templates render it.
        ``step`` holds the analysis' linear step figures per axis (numbers,
        s and %). SVG strings are generated here (trusted); every other
        string is user or derived text that the templates escape.
    """
    spec, art = data.spec, data.artifact
    motor = spec.motor
    motor_rows = [(q, s, fmt(getattr(motor, f)), u) for f, s, q, u in MOTOR_ROWS
                  if getattr(motor, f) is not None]
    drive_rows = [(q, fmt(getattr(spec.drive, f)), u) for f, q, u in DRIVE_ROWS
                  if getattr(spec.drive, f) is not None]
    drive_rows.append(("Max dq voltage (linear modulation)",
                       fmt(spec.drive.max_voltage(motor.convention)), "V"))
    from ..spec import REQUIREMENT_KEYS

    req_rows = []
    for k, v in getattr(spec.requirements, "bounds", {}).items():
        direction, quantity, unit = REQUIREMENT_KEYS[k][-3:]  # (.., direction, quantity, unit)
        req_rows.append((k, quantity, (">=" if direction == "min" else "<=") + " " + fmt(v), unit))
    margins = _margins_of(data)
    checks = _checks_of(data)
    traces = _scenario_traces(data)
    responses = (data.analysis or {}).get("responses")
    certificate = _certificate_of(data.analysis)
    # fcs_mpc: the axes (margins, loop figures, sweeps) are the baseline PI, which does not run
    baseline = getattr(art, "fcs", None) is not None or art.method == "fcs_mpc"
    return {
        "title": str(data.title),
        "motor": motor_rows, "drive": drive_rows, "requirements": req_rows,
        "equations": _equations(spec, data.equations),
        "controller": _controller(art),
        "margins_given": margins is not None,
        "margins": _margin_table(margins, checks),
        "checks": _check_rows(checks),
        "checks_given": checks is not None,
        "figures": plots.figures(responses, margins, traces),
        "figures_given": bool(responses),
        "step": _step_of(data.analysis),
        "robustness": _robustness(_robustness_of(data.analysis)),
        "verdict_card": _verdict_card(data.verification, baseline),
        "banner": _banner(data, checks),
        "baseline": BASELINE_LABEL if baseline else None,
        "resolution_note": RESOLUTION_NOTE,
        "certificate": ([(str(k), fmt(v)) for k, v in certificate.items()]
                        if certificate else None),
        "scenarios": (_scenarios(data.verification, traces)
                      if data.verification is not None else None),
        "provenance": _provenance(data),
        "not_computed": NOT_COMPUTED,
        "notice": [str(x) for x in ([data.notice] if data.notice else []) + list(data.warnings or [])],
    }


from .html import write_html  # noqa: E402  (the renderers use the model above)
from .pdf import write_pdf  # noqa: E402
