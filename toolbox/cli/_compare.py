"""``cct compare``: design several specs for one drive and print their
margins, step figures and robustness side by side, ranked (the table, its
columns and the ranking)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import click

from ..errors import CctError, SpecError
from ._conventions import (_QUIET, EXIT_OK, EXIT_REQUIREMENT, _spec_errors,
                           _write_file)
from ._echo import _echo_wrapped, _fmt
from ._progress import StepBar
from ..spec import load_spec


@click.command()
@click.argument("specs", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--json", "json_path", type=click.Path(dir_okay=False),
              help="Also write the table as JSON to this file.")
@click.option("--method", "methods", multiple=True, metavar="M",
              help="Design each SPEC with method M instead of its own (repeatable; "
                   "\"all\" = every method), as cct design --method.")
@click.option("--sampled-certificate", is_flag=True,
              help="Also certify the sampled coupled dq loop over the parameter box and "
                   "speeds (up to about a second more per design).")
@_QUIET
@_spec_errors
def compare(specs: tuple[str, ...], json_path: str | None, methods: tuple[str, ...],
            sampled_certificate: bool, quiet: bool) -> None:
    """Design every SPEC and print bandwidth, 5 % time, margins and robustness
    side by side, ranked.

    Each design is also verified (margins and stability of the executed law,
    requirements and default checks, the drift-box robustness verdict of cct
    design). A spec that cannot be designed (bad input, infeasible, another
    motor or drive than the first) is listed as refused with its file and
    reason; the others are still compared. Rank: passing designs first, then
    the larger worst multiloop disk margin over the drift box, then the
    shorter 5 % response time (worst axis). Exit 1 when any design fails or
    is refused.

    With ``--method``, each SPEC is designed once per method given (its
    other method tables dropped, as cct design --method): one motor, every
    method side by side.

    \b
    Examples:
      cct compare designs/000_*.toml designs/003_azaiz2007_hinf.toml
      cct compare designs/003_azaiz2007_pi.toml --method all
    """
    from ..analysis import compare_designs  # lazy: scipy, ~580 modules
    from ..pipeline import design_spec, run_verification  # lazy: ~320 modules

    from ..spec import METHODS

    chosen = list(dict.fromkeys(m for name in methods
                                for m in (METHODS if name == "all" else (name,))))
    for m in chosen:
        if m not in METHODS:
            raise SpecError("--method", "one of " + ", ".join(METHODS) + ' or "all"', m)
    jobs = ([(f"{p} --method {m}", p, [("--method", f"controller.method={json.dumps(m)}")])
             for p in specs for m in chosen] if chosen else [(p, p, []) for p in specs])
    refused: list[dict] = []
    loaded: list = []
    for path, file, overrides in jobs:
        try:
            s = load_spec(file, overrides=overrides)
        except CctError as err:
            refused.append({"spec": path, "refused": str(err)})
            continue
        if loaded and (s.motor, s.drive.vdc, s.drive.sample_time) != (
                loaded[0][1].motor, loaded[0][1].drive.vdc, loaded[0][1].drive.sample_time):
            # each artifact carries its own delay; the plant must be common
            refused.append({"spec": path, "refused": str(SpecError(
                "motor", f"the motor, vdc and sample_time of {loaded[0][0]} (compare "
                "designs for one drive)", "a different one", file=s.source))})
            continue
        loaded.append((path, s))
    names = [Path(p).name for p, _ in loaded]  # "x.toml --method pi" with --method
    steps = ([f"design {n}" for n in names] + ["analysis"]
             + [f"verification {n}" for n in names])
    designed = []
    rows: list[dict] = []
    with StepBar(steps, quiet=quiet, desc="compare") as bar:
        for name, (path, s) in zip(names, loaded):
            bar(f"design {name}")
            try:
                designed.append((path, s, design_spec(s)))
            except CctError as err:
                refused.append({"spec": path, "refused": str(err)})
        bar("analysis")
        if designed:
            rows = compare_designs([a for _, _, a in designed], designed[0][1].motor,
                                   designed[0][1].drive,
                                   sampled_certificate=sampled_certificate)
        for (spec_path, s, art), row in zip(designed, rows):
            bar(f"verification {Path(spec_path).name}")
            row["spec"] = spec_path
            result = run_verification(art, s)
            row["passed"] = result.passed
            row["failures"] = _failures(result)
            row["notice"] = result.notice
            # the drift-box verdict cct design prints (one sweep for both commands)
            rob = result.robustness or {}
            row["robustness"] = {k: rob.get(k) for k in (
                "n_unstable", "n_sets", "worst_disk_margin", "box_text")}
            if art.method == "fcs_mpc":
                # its axes hold the baseline PI: margins informational, step figures
                # from what it executes (the switching law, simulated)
                row["margins_basis"] = "baseline PI (informational, not executed)"
                row["response_times"] = _executed_step_figures(result)
    for k, row in enumerate(sorted(rows, key=_rank_key)):
        row["rank"] = k + 1
    if json_path:
        _write_file(json_path, json.dumps(rows + refused, indent=1, allow_nan=False) + "\n",
                    "--json")
    if rows:
        _print_table(sorted(rows, key=_rank_key))
    for row in sorted(rows, key=_rank_key):
        if not row["passed"]:
            _echo_wrapped(f"FAIL  {row['spec']}: ", "; ".join(row["failures"]))
    for entry in refused:
        # the message names the file, the key, what was expected and what was found
        _echo_wrapped("REFUSED  ", entry["refused"], file_key=True)
    failed = bool(refused) or any(not r["passed"] for r in rows)
    sys.exit(EXIT_REQUIREMENT if failed else EXIT_OK)


#: The ranking cct compare states under its table.
RANK_CRITERION = ("rank: passing designs first, then the larger worst multiloop disk margin "
                  "over the drift box, then the shorter 5 % response time (worst axis)")


def _rank_key(row: dict) -> tuple:
    """Sort key of :data:`RANK_CRITERION` (missing numbers rank last)."""
    dm = (row.get("robustness") or {}).get("worst_disk_margin")
    dm = float(dm) if isinstance(dm, (int, float)) and math.isfinite(dm) else -math.inf
    t5 = _worst(row.get("response_times") or {}, "response_time_5pct", max)
    return (not row.get("passed", False), -dm, t5 if math.isfinite(t5) else math.inf)


def _executed_step_figures(result) -> dict:
    """Worst 5 % time and overshoot over the simulated scenarios (one "q" entry)."""
    def worst(key):
        values = [float(sc.metrics[key]) for sc in result.scenarios
                  if sc.metrics.get(key) is not None and math.isfinite(sc.metrics[key])]
        missing = any(sc.metrics.get(key) is None or not math.isfinite(sc.metrics[key])
                      for sc in result.scenarios)
        return None if missing or not values else max(values)
    return {"q": {"response_time_5pct": worst("response_time_5pct"),
                  "overshoot_pct": worst("overshoot_pct"), "basis": "simulated (executed law)"}}


def _failures(result) -> list[str]:
    """``key: reason`` of every failing check of a verification."""
    doc = result.to_json()  # verify.json's checks carry the reason of every failure
    out = [f"{k}: {c.get('reason')}" for k, c in doc["margin_requirements"].items()
           if not c["pass"]]
    for sc in doc["scenarios"]:
        out += [f"{sc['name']}: {k}: {c.get('reason')}"
                for k, c in (sc.get("requirements") or {}).items() if not c["pass"]]
    return out


#: Columns of the compare table: (header, value of a row); worst axis throughout.
_COLUMNS = (
    ("rank", lambda r: r.get("rank", "")),
    ("method", lambda r: r["method"]),
    ("BW rad/s", lambda r: _worst(r["margins"], "bandwidth_rad_s", min)),
    ("GM dB", lambda r: _worst(r["margins"], "gain_margin_db", min)),
    ("PM deg", lambda r: _worst(r["margins"], "phase_margin_deg", min)),
    ("Mm", lambda r: _worst(r["margins"], "stability_margin", min)),
    ("t5% ms", lambda r: 1e3 * _worst(r["response_times"], "response_time_5pct", max)),
    # overshoot to 0.01 %: a simulated 6.7e-14 % is round-off, not an overshoot
    ("OS %", lambda r: _hundredths(_worst(r["response_times"], "overshoot_pct", max))),
    ("worst GM dB", lambda r: _worst(r["worst_case"], "gain_margin_db", min)),
    ("unstable", lambda r: "{}/{}".format(*(
        (r["robustness"]["n_unstable"], r["robustness"]["n_sets"])
        if (r.get("robustness") or {}).get("n_sets") is not None
        else (r["n_unstable"], r["n_sets"])))),
    ("drift disk", lambda r: (r.get("robustness") or {}).get("worst_disk_margin")),
    ("MIMO disk", lambda r: r["mimo_worst_disk_margin"]),
    ("box MIMO", lambda r: r["mimo_box"]["worst_disk_margin"]),
    ("box worst at", lambda r: _box_where(r["mimo_box"])),
    ("cert. scale", lambda r: (r["certificate"] or {}).get("certified_scale")),
    ("sampled cert.", lambda r: (r.get("sampled_certificate") or {}).get("certified_scale")),
    ("verdict", lambda r: "pass" if r.get("passed", True) else "FAIL"),
)


def _hundredths(x: float) -> float:
    """``x`` rounded to 0.01 (NaN kept: "not reached")."""
    return round(x, 2) + 0.0 if math.isfinite(x) else x


def _box_where(box: dict) -> str:
    """``w=<rad/s> R<x>Ld<x>Lq<x>``: speed and scale factors of the worst box model."""
    p = box["worst_params"]
    return f"w={box['worst_speed_rad_s']:.0f} " + "".join(f"{k}x{v:g}" for k, v in p.items())


def _worst(per_axis: dict, key: str, pick) -> float:
    values = [float(v[key]) for v in per_axis.values() if v.get(key) is not None]
    return pick(values) if values else float("nan")


def _print_table(rows: list[dict]) -> None:
    """Sampled-loop margins and step figures, robustness over the sweep."""
    informational = {"BW rad/s", "GM dB", "PM deg", "Mm", "worst GM dB", "unstable",
                     "drift disk", "MIMO disk", "cert. scale", "sampled cert."}
    table = [[h for h, _ in _COLUMNS]] + [
        [_fmt(get(r)) + ("*" if h in informational and r.get("margins_basis") else "")
         for h, get in _COLUMNS] for r in rows]
    widths = [max(len(line[k]) for line in table) for k in range(len(_COLUMNS))]
    for spec, line in zip(["spec"] + [r["spec"] for r in rows], table):
        click.echo("  ".join(c.rjust(w) for c, w in zip(line, widths)) + f"  {spec}")
    _echo_wrapped("", "worst axis throughout; unstable: sets of the drift box (as cct "
                  "design) whose coupled sampled loop is unstable; drift disk: worst "
                  "multiloop disk margin over it; worst GM: over the stress sweep of the "
                  "report")
    _echo_wrapped("", RANK_CRITERION)
    if any(r.get("margins_basis") for r in rows):
        _echo_wrapped("", "* fcs_mpc: margins and robustness of its baseline PI "
                      "(informational, not executed); its t5% and OS are simulated from the "
                      "switching law")
