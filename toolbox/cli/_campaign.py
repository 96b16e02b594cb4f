"""``cct campaign``: the robustness campaign of a spec's [campaign] table
(README.md "Campaigns"), with its exit code for an unusable cluster or disk."""

from __future__ import annotations

import sys

import click

from ..errors import SpecError
from ._conventions import _QUIET, EXIT_OK, EXIT_REQUIREMENT, _spec_errors
from ._failsafe import EXIT_INTERRUPTED, EXIT_TERMINATED, Terminated
from ._progress import CountBar

#: cct campaign: the cluster or the output disk is not usable (the input is
#: sound; retry on a working cluster). README.md "Campaigns".
EXIT_INFRASTRUCTURE = 4


@click.command()
@click.argument("spec", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Campaign directory (chunks, results.parquet, summary.json, report.html); "
                   "an interrupted campaign resumes from it.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="tcp://host:8786 of a running Dask scheduler; default: a LocalCluster "
                   "on this machine; 'serial': this process, no Dask.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="LocalCluster worker processes (default: one per core); with "
                   "--scheduler, wait for this many workers.")
@click.option("--controller", "design_dir", type=click.Path(file_okay=False), default=None,
              help="A design directory (cct design --out): simulate its controller.json "
                   "(a candidate design) instead of designing SPEC's controller.")
@click.option("--no-report", is_flag=True, help="Do not write report.html.")
@_QUIET
@_spec_errors
def campaign(spec: str, out_dir: str, scheduler: str | None, workers: int | None,
             design_dir: str | None, no_report: bool, quiet: bool) -> None:
    """Run the robustness campaign of SPEC's [campaign] table: design once,
    simulate every sample on Dask, write one row per sample to
    OUT/results.parquet, a summary and a report.

    Exit 0 when the gated yield's 95 % lower bound reaches
    campaign.min_yield (or none is given), 1 below it, 2 on bad input, 4 when
    the cluster or the output disk is not usable (scheduler unreachable,
    silent or lost mid-run, no workers, workers without the toolbox or of
    another build, disk full or read-only), or when the gate is missed with
    error rows (chunks that failed on the workers 3 times: they count as
    failing). Run the same command again after an interrupt or an exit 4 to
    resume (rows already written are skipped; error rows are run again).

    \b
    Example:
      cct campaign designs/campaigns/003_azaiz2007_hinf.toml --out out/campaign_003
      cct campaign designs/campaigns/003_azaiz2007_hinf.toml --out out/c --scheduler tcp://scheduler-host:8786
      cct campaign designs/campaigns/003_azaiz2007_hinf.toml --out out/c_pi --controller out/003_pi
    """
    from ..campaign import CHUNK_ATTEMPTS, parse_address, run_campaign
    from ..errors import InfrastructureError
    from ..spec import load_spec

    s = load_spec(spec)
    if s.campaign is None:
        raise SpecError("campaign", "a [campaign] table (missing)", file=spec,
                        hint="README.md \"Campaigns\"")
    if scheduler is not None and scheduler not in ("local", "serial"):
        parse_address(scheduler)  # http://, no port: exit 2 before anything runs
    artifact = None
    if design_dir is not None:
        from ..pipeline import load_artifact

        artifact = load_artifact(design_dir)
    try:
        with CountBar(quiet=quiet, desc="campaign") as bar:
            run = run_campaign(s, out_dir, scheduler=scheduler, workers=workers,
                               artifact=artifact, progress=bar, report=not no_report)
    except InfrastructureError as err:
        click.echo(f"cct: infrastructure error: {err}", err=True)
        sys.exit(EXIT_INFRASTRUCTURE)
    except (KeyboardInterrupt, Terminated) as err:
        what = "interrupted" if isinstance(err, KeyboardInterrupt) else "terminated"
        click.echo(f"cct: {what}; the chunks written are kept in {out_dir}/chunks: "
                   "run the same command again to resume", err=True)
        sys.exit(EXIT_INTERRUPTED if isinstance(err, KeyboardInterrupt) else EXIT_TERMINATED)
    sm = run.summary
    if not quiet:
        for path in run.files:
            click.echo(f"wrote {path}", err=True)
    ys = sm["yields"]

    def pct(y) -> str:
        return (f"{100 * y['yield']:.2f} % (95 % interval {100 * y['yield_95'][0]:.2f} - "
                f"{100 * y['yield_95'][1]:.2f} %)")

    click.echo(f"campaign: {sm['motors']} motors x {sm['operating_points']} operating points "
               f"= {sm['samples']} samples, {sm['passed']} pass; {run.chunks_run} chunks run"
               + (f" ({run.chunk_size} rows each)" if run.chunk_size else "")
               + f", {run.chunks_resumed} resumed")
    worst = ys["per_point"]["points"][ys["per_point"]["worst_point"]]
    where = ", ".join(f"{k} {v:g}" for k, v in worst.items()
                      if k not in ("point", "n", "passed", "yield", "yield_95", "failures"))
    for gate, label, y in (("per_sample", "per-sample yield", ys["per_sample"]),
                           ("per_motor", f"per-motor yield ({ys['per_motor']['n']} motors at "
                            "every point)", ys["per_motor"]),
                           ("per_point", f"per-point yield (worst of {ys['per_point']['n']} "
                            f"points{': ' + where if where else ''})", ys["per_point"])):
        click.echo(f"  {label}: {pct(y)}" + ("  <- gate" if gate == sm["gate"] else ""))
    for name, count in list(sm["failure_reasons"].items())[:5]:
        click.echo(f"  fails {name}: {count}")
    for mode, entries in sm["sensitivity_by_mode"].items():
        ranked = [e for e in entries if e["rank_correlation"] is not None][:3]
        if ranked and mode != "error":
            click.echo(f"  drivers of {mode}: " + ", ".join(
                f"{e['parameter']} ({e['rank_correlation']:+.2f})" for e in ranked))
    if sm.get("cells"):
        a, b = sm["cells"]["axes"]
        rates = [c["fail_rate"] for c in sm["cells"]["cells"]]
        click.echo(f"  failure rate by {a} x {b}: {100 * min(rates):.1f} % to "
                   f"{100 * max(rates):.1f} %")
    if sm["min_yield"] is not None:
        click.echo(f"  min_yield {sm['min_yield']:g} on the {sm['gate'].replace('_', '-')} "
                   f"yield's 95 % lower bound {100 * sm['gate_lower_95']:.2f} %: "
                   + ("pass" if run.passed else "FAIL"))
    if run.error_rows:
        first = next((w["failure"] for w in sm["worst_cases"] if w["worst_check"] == "error"),
                     "")
        message = (f"{run.error_rows} samples could not be evaluated (chunks failed on the "
                   f"workers {CHUNK_ATTEMPTS} times; counted as failing): {first[:200]}")
        if not run.passed:
            click.echo(f"cct: infrastructure error: {message}; rerun the same command to "
                       "evaluate them again", err=True)
            sys.exit(EXIT_INFRASTRUCTURE)
        click.echo(f"cct: warning: {message}", err=True)
    sys.exit(EXIT_OK if run.passed else EXIT_REQUIREMENT)
