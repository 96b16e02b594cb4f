"""The verdict of the content model: the stored margins and requirement
checks, their tables, the verdict banner and the robustness card's verdict."""

from __future__ import annotations

from typing import Mapping

from ._data import ReportData
from ._format import _as_float, fmt, fmt_q


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
