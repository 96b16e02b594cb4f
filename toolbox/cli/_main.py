"""``cct``: one command per pipeline stage.

Exit codes (toolbox/ARCHITECTURE.md "Errors and exit codes"): 0 every
requirement holds, 1 a requirement fails (outputs still written), 2 bad input
(nothing written): :class:`~toolbox.errors.CctError` and its subclasses; 3 an
internal error (a bug: one line naming the command, its stage and the file
holding the traceback, ``_failsafe``); 130 Ctrl-C, 143 ``SIGTERM``. No
traceback reaches the terminal.
"""

from __future__ import annotations

import errno
import json
import sys
from pathlib import Path
from dataclasses import replace
import re

import click

from ..errors import SpecError
from ._campaign import campaign
from ._compare import compare
from ._conventions import (_QUIET, EXIT_OK, EXIT_REQUIREMENT, _spec_errors,
                           _write_file)
from ._echo import (_echo_wrapped, _envelope_failures, _envelope_line, _fmt, _notices,
                    _robustness_line)
from ._failsafe import (EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_TERMINATED, Terminated,
                        internal_error_message, signal_handlers, where)
from ._progress import StepBar, design_stages
from ..spec import load_spec, spec_to_toml, CATALOG, CATALOG_NOTES, Motor


class _Cct(click.Group):
    """The ``cct`` group: every command runs under explicit signal
    dispositions and a top-level handler, so that nothing but a one-line
    message reaches the user (toolbox/ARCHITECTURE.md "Errors and exit
    codes"): Ctrl-C exit 130, ``SIGTERM`` exit 143 (outputs are swapped in as
    a set, so an interrupt leaves the old set or the new one and no staging
    directory), any unexpected exception exit 3 with its traceback in a
    file."""

    def invoke(self, ctx: click.Context):
        where.reset()
        with signal_handlers():
            try:
                return super().invoke(ctx)
            except (click.exceptions.Exit, click.ClickException, click.exceptions.Abort):
                raise
            except KeyboardInterrupt:
                click.echo("cct: interrupted (no output half-written)", err=True)
                sys.exit(EXIT_INTERRUPTED)
            except Terminated:
                click.echo("cct: terminated (no output half-written)", err=True)
                sys.exit(EXIT_TERMINATED)
            except OSError as err:
                if err.errno == errno.EPIPE:  # click's own handling: a closed pipe
                    raise
                click.echo(internal_error_message(err), err=True)
                sys.exit(EXIT_INTERNAL)
            except Exception as err:  # a bug: one line, the traceback in a file
                click.echo(internal_error_message(err), err=True)
                sys.exit(EXIT_INTERNAL)


@click.group(cls=_Cct, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="current-control-toolbox")
def main() -> None:
    """Current Control Toolbox: PMSM current-controller design from spec to
    verified controller, report and C header.

    \b
    Example:
      cct design designs/003_azaiz2007_hinf.toml --out out/003
    """


# the commands with modules of their own
main.add_command(compare)
main.add_command(campaign)


@main.command()
@click.argument("spec", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print the resolved spec as JSON.")
@_spec_errors
def check(spec: str, as_json: bool) -> None:
    """Validate SPEC and print the resolved spec as TOML (catalog and
    defaults applied, datasheet values converted to per-phase dq values,
    each with its formula and the dq convention as comments).

    \b
    Example:
      cct check designs/000_lepioufle1992_tc.toml
    """
    s = load_spec(spec)
    if as_json:
        click.echo(json.dumps(s.raw, indent=1, sort_keys=True))
        return
    click.echo(spec_to_toml(s, spec), nl=False)


@main.command()
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
def motors(as_json: bool) -> None:
    """List the motor catalog with key figures.

    \b
    Example:
      cct motors
    """
    rows = []
    for name, values in CATALOG.items():
        m = Motor(**values)
        rows.append({"name": name, "source": CATALOG_NOTES[name], "R_ohm": m.R,
                     "Ld_H": m.Ld, "Lq_H": m.Lq, "flux_Wb": m.flux,
                     "pole_pairs": m.pole_pairs, "tau_d_ms": 1e3 * m.tau_d,
                     "tau_q_ms": 1e3 * m.tau_q, "rated_current_A": m.rated_current,
                     "torque_constant_Nm_per_A": m.torque_constant,
                     "emf_constant_V_s_per_rad": m.emf_constant,
                     "convention": m.convention})
    if as_json:
        click.echo(json.dumps(rows, indent=1))
        return
    click.echo(f"{'name':<15}{'R':>7}{'Ld':>9}{'Lq':>9}{'flux':>8}{'p':>3}"
               f"{'tau_d':>8}{'tau_q':>8}{'I_rated':>9}{'k_T':>7}{'k_E':>7}  dq")
    click.echo(f"{'':<15}{'ohm':>7}{'mH':>9}{'mH':>9}{'Wb':>8}{'':>3}"
               f"{'ms':>8}{'ms':>8}{'A':>9}{'Nm/A':>7}{'Vs/rad':>7}")
    for r in rows:
        rated = f"{r['rated_current_A']:.1f}" if r["rated_current_A"] else "-"
        click.echo(f"{r['name']:<15}{r['R_ohm']:>7.3g}{1e3 * r['Ld_H']:>9.4g}"
                   f"{1e3 * r['Lq_H']:>9.4g}{r['flux_Wb']:>8.4g}{r['pole_pairs']:>3}"
                   f"{r['tau_d_ms']:>8.3g}{r['tau_q_ms']:>8.3g}{rated:>9}"
                   f"{r['torque_constant_Nm_per_A']:>7.3g}"
                   f"{r['emf_constant_V_s_per_rad']:>7.3g}  {r['convention']}")
    click.echo("")
    for r in rows:
        click.echo(f"{r['name']}: {r['source']}")


@main.command()
@click.argument("spec", type=click.Path(dir_okay=False))
@click.option("--latex", "fmt", flag_value="latex", help="LaTeX align environment.")
@click.option("--markdown", "fmt", flag_value="markdown", help="Markdown with math.")
@_spec_errors
def derive(spec: str, fmt: str | None) -> None:
    """Print the dq model derived for the motor of SPEC.

    \b
    Example:
      cct derive designs/000_lepioufle1992_tc.toml --markdown
    """
    from ..plant import describe_model  # lazy: scipy.linalg, ~320 modules

    click.echo(describe_model(load_spec(spec).motor, fmt or "text"), nl=False)


@main.command()
@click.argument("spec", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Output directory.")
@click.option("--only-controller", is_flag=True,
              help="Write controller.json only (no analysis, verification, report, header).")
@click.option("--sampled-certificate", is_flag=True,
              help="Also certify the sampled coupled dq loop over the parameter box and "
                   "speeds (up to about a second more per design).")
@click.option("--method", "method", default=None, metavar="M",
              help="Design with method M instead of the spec's controller.method "
                   "(pi, ip, pi_lag, tc, tci, ilq, lq, hinf, fcs_mpc, robust_pi, tune, cv).")
@click.option("--set", "sets", multiple=True, metavar="KEY.PATH=VALUE",
              help="Override one spec value before validation (repeatable); VALUE is a "
                   "TOML scalar or array, e.g. --set controller.pi.bandwidth=1500 "
                   "--set 'requirements.parameter_drift.R=[0.8, 1.5]'.")
@_QUIET
@_spec_errors
def design(spec: str, out_dir: str, only_controller: bool, sampled_certificate: bool,
           method: str | None, sets: tuple[str, ...], quiet: bool) -> None:
    """Design the controller of SPEC and write controller.json, analysis.json,
    verify.json, controller.h, report.html and report.pdf into OUT.

    Exit 0 when every requirement holds, 1 when one fails (outputs written),
    2 on bad input (nothing written).

    \b
    Example:
      cct design designs/003_azaiz2007_hinf.toml --out out/003
      cct design designs/003_azaiz2007_hinf.toml --method pi --set controller.pi.bandwidth=1500 --out out/003_pi
    """
    from ..pipeline import build_outputs, write_outputs  # lazy: scipy.linalg, ~320 modules

    overrides = ([("--method", f"controller.method={json.dumps(method)}")] if method else [])
    overrides += [("--set", text) for text in sets]
    s = load_spec(spec, overrides)
    full = not only_controller
    with StepBar(design_stages(full, full, full, full), quiet=quiet, desc="design") as bar:
        out = build_outputs(s, analysis=full, verification=full, report=full, header=full,
                            sampled_certificate=sampled_certificate, progress=bar)
    for path in write_outputs(out.files, out_dir):
        if not quiet:
            click.echo(f"wrote {path}", err=True)
    _summary(out)
    sys.exit(EXIT_OK if out.passed else EXIT_REQUIREMENT)


def _summary(out) -> None:
    warnings = list(out.warnings)
    if out.verification is not None:
        warnings += out.verification.warnings
    # the notice describes what was checked: nothing is checked without verification
    _notices(out.notice if out.verification is not None else None, warnings)
    # the result summary is printed even with -q: -q silences progress only
    # fcs_mpc's axes hold the baseline PI, which does not run: its margins say nothing
    # about the executed loop (toolbox.report.BASELINE_LABEL)
    basis = ("baseline PI, informational, not executed" if out.artifact.method == "fcs_mpc"
             else "sampled loop")
    for axis, m in out.artifact.margins.items():
        click.echo(f"{axis} axis ({basis}): GM {_fmt(m.get('gain_margin_db'))} dB, "
                   f"PM {_fmt(m.get('phase_margin_deg'))} deg, "
                   f"Mm {_fmt(m.get('stability_margin'))}")
    if out.verification is not None:
        _robustness_line(out.verification)
        _envelope_line(out.verification)
    failed = []
    if out.analysis is not None:
        failed += [k for k, c in out.analysis.get("requirements", {}).items() if not c["pass"]]
    if out.verification is not None:
        from ..verify import ROBUSTNESS_CHECKS  # lazy: numba + scipy, ~810 modules

        # the drift-box verdict names its first failing set (factors and speed)
        failed += [k if k not in ROBUSTNESS_CHECKS else f"{k} ({c.get('reason')})"
                   for k, c in out.verification.margin_checks.items() if not c["pass"]]
        for sc in out.verification.scenarios:
            failed += [f"{sc.name}: {k} ({c.get('reason')})" for k, c in sc.checks.items()
                       if not c["pass"]]
        failed += _envelope_failures(out.verification)
    failed = list(dict.fromkeys(failed))
    if out.header_refused:
        failed.append("controller.h refused")
    _echo_failed(failed)


def _echo_failed(failed: list[str]) -> None:
    """``requirements: all pass``, or ``requirements: FAILED n checks:`` and
    one wrapped line per failed check (a reason may run to hundreds of
    characters: no line beyond 100 columns)."""
    if not failed:
        click.echo("requirements: all pass")
        return
    click.echo(f"requirements: FAILED {len(failed)} check{'s' if len(failed) > 1 else ''}:")
    for item in failed:
        _echo_wrapped("  - ", item)


@main.command()
@click.argument("out_dir", type=click.Path(file_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print verify.json to stdout.")
@_QUIET
@_spec_errors
def verify(out_dir: str, as_json: bool, quiet: bool) -> None:
    """Re-run the closed-loop verification of the design in OUT_DIR and write
    OUT_DIR/verify.json (exit 1 if a requirement fails).

    \b
    Example:
      cct verify out/003
    """
    from ..pipeline import (check_integrity, header_agreement, load_artifact,  # lazy: ~320 modules
                            run_verification, spec_of_artifact, write_outputs)

    file = str(Path(out_dir) / "controller.json")
    artifact = load_artifact(out_dir)
    spec = spec_of_artifact(artifact, file=file)
    check_integrity(artifact, spec, file=file)
    # margins and stability are recomputed from the executed law, never read back
    with StepBar(["verification"], quiet=quiet, desc="verify") as bar:
        bar("verification")
        result = run_verification(artifact, spec, file=file)
    result = replace(result, header=header_agreement(out_dir, artifact, spec))
    text = json.dumps(result.to_json(), indent=1, allow_nan=False) + "\n"
    write_outputs({"verify.json": text}, out_dir)
    _notices(result.notice, result.warnings)
    if as_json:
        click.echo(text, nl=False)
    else:
        for axis, s in result.stability.items():
            verdict = {True: "stable", False: "UNSTABLE", None: "not analysed"}[s["stable"]]
            click.echo(f"{axis} axis: {verdict} ({s['basis']})")
        _robustness_line(result)
        _envelope_line(result)
        for f in _envelope_failures(result):
            _echo_wrapped("FAIL  ", f)
        for sc in result.scenarios:
            status = "pass" if sc.passed else "FAIL"
            t5 = _fmt(sc.metrics.get('response_time_5pct'))
            click.echo(f"{status}  {sc.name}: 5% response "
                       f"{t5 + ' s' if t5 != 'not reached' else t5}, static error "
                       f"{_fmt(sc.metrics.get('static_error'))}")
            for key, check in sc.checks.items():
                if not check["pass"]:
                    click.echo(f"      {key}: {check.get('reason')}")
        for key, check in result.margin_checks.items():
            click.echo(f"{'pass' if check['pass'] else 'FAIL'}  {key}: "
                       f"{_fmt(check['value'])} (bound {_fmt(check['bound'])})"
                       + ("" if check["pass"] else f": {check.get('reason')}"))
        header = result.header
        if header is not None and not header["matches"]:
            if header["law_sha256"] != artifact.law_sha256():
                click.echo(f"FAIL  controller.h: exported from another controller.json (law "
                           f"sha256 {header['law_sha256'] or 'missing'}, controller.json "
                           f"{artifact.law_sha256()}): run cct export {out_dir} before "
                           "flashing it")
            else:
                click.echo(f"FAIL  controller.h: differs from the header regenerated from "
                           f"controller.json at line {header['first_difference_line']} (edited "
                           f"after export?): run cct export {out_dir} before flashing it")
    sys.exit(EXIT_OK if result.passed else EXIT_REQUIREMENT)


@main.command()
@click.argument("out_dir", type=click.Path(file_okay=False))
@_QUIET
@_spec_errors
def report(out_dir: str, quiet: bool) -> None:
    """Regenerate report.html and report.pdf from the design in OUT_DIR.

    Reads controller.json and analysis.json (analysing again only when
    analysis.json is missing; one from an older toolbox without the figure
    data is refused: re-run cct design); the scenarios are simulated again because
    their traces are not stored. Nothing is re-designed.

    \b
    Example:
      cct report out/003
    """
    # lazy: ~320 modules
    from ..pipeline import (DesignOutputs, analyse, check_integrity, load_analysis,
                            load_artifact, report_data, run_verification, spec_of_artifact,
                            write_outputs)
    from ..report import build_context, write_html, write_pdf  # lazy: jinja2 + report, 126 modules

    from ..analysis import compute_margins  # lazy: scipy, ~580 modules
    from ..analysis.executed import loop_stability  # lazy: scipy, ~580 modules

    file = str(Path(out_dir) / "controller.json")
    artifact = load_artifact(out_dir)
    spec = spec_of_artifact(artifact, file=file)
    check_integrity(artifact, spec, file=file)
    # read (and validated) before anything is simulated: a malformed file is refused at once
    analysis = load_analysis(out_dir, artifact)
    with StepBar(["verification", "analysis", "report"], quiet=quiet, desc="report") as bar:
        # verified first, on the artifact as stored: its margins are compared, not trusted
        bar("verification")
        verification = run_verification(artifact, spec, file=file)
        files = {}
        bar("analysis")
        if analysis is None:
            artifact, analysis = analyse(artifact, spec)
            files["analysis.json"] = json.dumps(analysis, indent=1, allow_nan=False) + "\n"
        # the report shows margins, margin checks and stability of the executed law,
        # not the stored numbers (the stored response figures are drawn as they are)
        fresh = {ax: m.to_json() for ax, m in compute_margins(artifact, spec.motor).items()}
        artifact = artifact.with_margins(fresh)
        analysis = {**analysis,
                    "margins": {**(analysis.get("margins") or {}), "discrete": fresh},
                    "stability": loop_stability(artifact, spec.motor),
                    "requirements": {k: c for k, c in verification.margin_checks.items()
                                     if not k.startswith("default.")}}
        from ..export.firmware import load_firmware
        out = DesignOutputs(artifact=artifact, spec=spec, analysis=analysis,
                            verification=verification, firmware=load_firmware(out_dir))
        bar("report")
        context = build_context(report_data(out))  # figures drawn once for both
        files.update({"report.html": write_html(context), "report.pdf": write_pdf(context)})
    write_outputs(files, out_dir)
    _notices(out.notice, verification.warnings)
    sys.exit(EXIT_OK if out.passed else EXIT_REQUIREMENT)


@main.command()
@click.argument("out_dir", type=click.Path(file_okay=False))
@click.option("--format", "fmt", type=click.Choice(["c", "json"]), default="c",
              show_default=True, help="C header or controller JSON.")
@click.option("--output", "-o", type=click.Path(dir_okay=False),
              help="File to write (default: OUT_DIR/controller.h or stdout for json).")
@click.option("--prefix", default=None,
              help="Prefix of every C identifier of the header (guard, types, functions, "
                   "macros), e.g. motor1_ (default: the spec's [export] prefix, else cct_).")
@_spec_errors
def export(out_dir: str, fmt: str, output: str | None, prefix: str | None) -> None:
    """Export the controller of OUT_DIR as a C99 header or JSON.

    The header ends with a usage example (init, bus-voltage update,
    per-period call, fault handling) inside #if 0.

    \b
    Example:
      cct export out/003 --format c -o firmware/current_loop.h
      cct export out/m1 --prefix motor1_ -o firmware/motor1.h
    """
    from ..pipeline import load_artifact, spec_of_artifact  # lazy: ~320 modules

    artifact = load_artifact(out_dir)
    if fmt == "json":
        text = artifact.dumps()
        if output:
            _write_file(output, text, "--output")
        else:
            click.echo(text, nl=False)
        return
    from ..export import write_header  # lazy: scipy.linalg + export, ~330 modules
    from ..pipeline import check_integrity, refuse_unstable_export  # lazy: ~320 modules

    file = str(Path(out_dir) / "controller.json")
    spec = spec_of_artifact(artifact, file=file)
    check_integrity(artifact, spec, file=file)
    refuse_unstable_export(artifact, spec.motor, file=file)
    # refusals name the design file the controller came from
    if prefix is not None:
        from ..export import prefix_name  # lazy: ~330 modules
        try:
            prefix_name(prefix, key="--prefix")  # a bad option is bad input (exit 2)
        except SpecError as err:
            raise SpecError(err.key, err.expected, prefix,
                            hint="the rule of the spec's export.prefix") from None
    text = write_header(artifact, spec.motor, spec.drive, source=file,
                        prefix=prefix if prefix is not None else spec.export_prefix)
    _write_file(output or Path(out_dir) / "controller.h", text, "--output")
    if not output:  # the target figures of the header (or why not measured) next to it
        from ..export.firmware import FIRMWARE_JSON, firmware_json, measure_firmware
        _write_file(Path(out_dir) / FIRMWARE_JSON, firmware_json(measure_firmware(
            text, prefix if prefix is not None else spec.export_prefix)), "--output")


@main.command()
@click.option("--designs", "designs_dir", default="designs", show_default=True,
              type=click.Path(file_okay=False), help="Directory of spec files.")
@click.option("--out", "out_dir", default="reports", show_default=True,
              type=click.Path(file_okay=False), help="Gallery directory.")
@click.option("--sampled-certificate", is_flag=True,
              help="Also certify the sampled coupled dq loop over the parameter box and "
                   "speeds (up to about a second more per design).")
@_QUIET
@_spec_errors
def gallery(designs_dir: str, out_dir: str, sampled_certificate: bool, quiet: bool) -> None:
    """Regenerate the report gallery: every spec in DESIGNS into OUT/<name>/.

    Every design's outputs are written; exit 1 when any design fails.

    \b
    Example:
      cct gallery
    """
    from ..pipeline import build_outputs, write_outputs  # lazy: scipy.linalg, ~320 modules

    failed = []
    paths = sorted(Path(designs_dir).glob("*.toml"))
    with StepBar([p.name for p in paths], quiet=quiet, desc="gallery") as bar:
        for path in paths:
            bar(path.name)
            out = build_outputs(load_spec(path), sampled_certificate=sampled_certificate)
            write_outputs({**out.files, **_figures(out.html or "")}, Path(out_dir) / path.stem)
            if not out.passed:
                failed.append(path.name)
    for name in failed:
        click.echo(f"FAIL  {name}", err=True)
    sys.exit(EXIT_REQUIREMENT if failed else EXIT_OK)


def _figures(html: str) -> dict[str, str]:
    """The report's inline SVG figures as files ``fig-<name>.svg`` (for the README)."""
    found = re.findall(r'<figure id="(fig-[a-z0-9-]+)">.*?(<svg.*?</svg>)', html, flags=re.S)
    return {f"{name}.svg": svg + "\n" for name, svg in found}
