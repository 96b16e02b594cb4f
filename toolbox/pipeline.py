"""The whole job as plain function calls: spec -> design -> analysis -> verification
-> report and header. The CLI is a thin layer over these functions.

Every stage after design reads the controller artifact; nothing re-runs the
design. Outputs are computed in memory first and written only when every
stage succeeded (bad input writes nothing), each file atomically.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ._io import check_text_depth, read_limited, write_set
from .artifact import ControllerArtifact, spec_sha256
from .errors import ArtifactError, CctError, ExportRefused, SpecError
from .spec import Spec, load_spec, spec_from_dict, SpecErrors
from .design import design
from .export import write_header

__all__ = ["unstable_axes", "refuse_unstable_export", "DesignOutputs", "report_data",
           "design_spec", "analyse", "run_verification", "build_outputs", "write_outputs",
           "load_artifact", "load_analysis", "header_agreement", "spec_of_artifact",
           "OUTPUT_FILES", "check_integrity", "saturated_spectral_radius"]

OUTPUT_FILES = ("controller.json", "analysis.json", "verify.json", "controller.h",
                "firmware.json", "report.html", "report.pdf")

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    pass


def design_spec(spec: Spec | str | Path | dict) -> ControllerArtifact:
    """Design the controller a spec asks for.

    Parameters
    ----------
    spec : Spec, str, Path or dict
        A validated spec, a spec file or the spec as plain data.

    Raises
    ------
    SpecError
        (``DesignInfeasible`` included) naming the spec file when it has one.
    """
    if isinstance(spec, (str, Path)):
        spec = load_spec(spec)
    elif isinstance(spec, dict):
        spec = spec_from_dict(spec)
    try:
        return design(spec)
    except SpecError as err:  # a refusal names the spec file, as load_spec's errors do
        if err.file is None and spec.source:
            raise err.with_file(spec.source) from None
        raise


def analyse(artifact: ControllerArtifact, spec: Spec, *,
            sampled_certificate: bool = False) -> tuple[ControllerArtifact, dict]:
    """Margins (into the artifact) and the full analysis document.

    Parameters
    ----------
    artifact : ControllerArtifact
        The design.
    spec : Spec
        Motor, drive and requirements (the ``margins`` stage bounds).
    sampled_certificate : bool
        Also certify the sampled coupled loop (up to about a second; see
        :func:`toolbox.analysis.analysis_report`).

    Returns
    -------
    artifact : ControllerArtifact
        A copy with ``margins`` filled.
    analysis : dict
        JSON-ready analysis (``analysis.json``), with requirement checks.
    """
    from .analysis import analysis_report  # lazy: scipy.optimize, ~260 modules
    from .analysis.executed import INFORMATIONAL_METHODS, loop_stability  # lazy: ~260 modules

    report = analysis_report(artifact, spec.motor, spec.drive,
                             sampled_certificate=sampled_certificate)
    margins = report["margins"]["discrete"]
    # an unstable loop is a design that exists but fails (exit 1, outputs written,
    # no controller.h), not bad input: the report must show the user why
    report["stability"] = loop_stability(artifact, spec.motor)
    # MARGINS of controller.json: the sampled loop as executed (toolbox/ARCHITECTURE.md "controller.json")
    artifact = artifact.with_margins(margins)
    checks = spec.requirements.check_margins(artifact.margins)
    if artifact.method in INFORMATIONAL_METHODS:
        # the baseline PI does not run: its margins never decide
        report["requirements"] = {}
        report["informational_requirements"] = checks
    else:
        report["requirements"] = checks
    return artifact, report


def unstable_axes(analysis: dict | None) -> list[str]:
    """Axes whose executed sampled loop is unstable, per ``analysis["stability"]``."""
    stability = (analysis or {}).get("stability") or {}
    return [ax for ax, s in sorted(stability.items()) if s.get("stable") is False]


def refuse_unstable_export(artifact: ControllerArtifact, motor, file: str | None = None) -> None:
    """Raise :class:`ExportRefused` when the executed sampled loop is unstable.

    ``fcs_mpc`` is exempt: its axes hold only the baseline PI for comparison,
    and the header exports the predictive switching law instead.

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant the stability is judged on.
    file : str, optional
        The controller.json named in the message.
    """
    if artifact.method == "fcs_mpc":
        return
    from .analysis.executed import loop_stability  # lazy: scipy.optimize, ~260 modules

    stability = loop_stability(artifact, motor)
    unstable = [ax for ax, s in sorted(stability.items()) if s["stable"] is False]
    if unstable:
        rho = ", ".join(f"{ax} {stability[ax]['spectral_radius']:.6g}" for ax in unstable)
        raise ExportRefused(f"axes.{unstable[0]}.law",
                            "a law whose sampled loop (ZOH plant, computation delay) is stable",
                            f"closed-loop spectral radius {rho}", file=file,
                            hint="no firmware header is written for an unstable loop; slow "
                                 "the design down or shorten the sample time")
    for ax in sorted(artifact.axes):
        rho = saturated_spectral_radius(artifact.axes[ax])
        if rho is not None and rho > 1 + 1e-9:
            raise ExportRefused(f"axes.{ax}.antiwindup", "a back-calculation gain aw whose "
                                "saturated recursion x' = (A - aw C) x is stable (spectral "
                                "radius < 1)", f"spectral radius {rho:.6g}", file=file,
                                hint="in voltage saturation the law's state would diverge; "
                                     "re-run cct design (Hanus's gain is stable)")


def saturated_spectral_radius(axis) -> float | None:
    """Spectral radius of the law's recursion with the back-calculation loop
    closed at full saturation (the output held by the limit): ``x' = A x +
    aw (v_sat - C x - D e)``, i.e. ``A - aw C`` (controller.h, toolbox/
    ARCHITECTURE.md "controller.h"). None for a static law or no anti-windup."""
    law, aw = axis.law, axis.antiwindup
    if aw is None or law.A.size == 0:
        return None
    M = law.A - np.asarray(aw, float).reshape(-1, 1) @ np.asarray(law.C, float)[:1, :]
    if not np.all(np.isfinite(M)):
        return math.inf
    return float(np.max(np.abs(np.linalg.eigvals(M))))


def check_integrity(artifact: ControllerArtifact, spec: Spec, file: str | None = None) -> None:
    """A controller.json that agrees with itself: ``provenance.spec_sha256``
    is the digest of the stored spec, and the law's ``sample_time`` and
    ``delay_samples`` are the stored spec's drive (a controller designed for
    another period or delay must not be exported or verified against this one).

    Raises
    ------
    ArtifactError
        Naming the key that disagrees, the value expected and the one found.
    """
    stored = artifact.provenance.get("spec_sha256")
    digest = spec_sha256(artifact.spec)
    if stored != digest:
        raise ArtifactError("provenance.spec_sha256", f"the sha256 of the stored spec ({digest})",
                            stored, file=file,
                            hint="the spec in controller.json was changed after cct design; "
                                 "re-run cct design")
    if not math.isclose(artifact.sample_time, spec.drive.sample_time, rel_tol=1e-9):
        raise ArtifactError("sample_time", "the stored spec's drive.sample_time "
                            f"({spec.drive.sample_time:g} s)", artifact.sample_time, file=file,
                            hint="the law was made for another controller period; re-run "
                                 "cct design")
    if artifact.delay_samples != spec.drive.delay_samples:
        raise ArtifactError("delay_samples", "the stored spec's drive.delay_samples "
                            f"({spec.drive.delay_samples})", artifact.delay_samples, file=file,
                            hint="the law was made for another computation delay; re-run "
                                 "cct design")


def run_verification(artifact: ControllerArtifact, spec: Spec,
                     progress: Callable[[int, int], None] | None = None,
                     file: str | None = None):
    """Closed-loop simulation of every scenario (see :func:`toolbox.verify.verify`).

    Parameters
    ----------
    artifact : ControllerArtifact
        The design to simulate.
    spec : Spec
        Plant, drive, scenarios and requirements.
    progress : callable, optional
        ``progress(done, total)`` after each scenario.
    file : str, optional
        The controller.json the artifact came from (named in warnings).
    """
    from .verify import verify  # lazy: numba + the kernel, ~500 modules

    return verify(artifact, spec, progress=progress, file=file)


@dataclass
class DesignOutputs:
    """Everything ``cct design`` produces, in memory."""

    artifact: ControllerArtifact
    spec: Spec
    analysis: dict | None = None
    verification: object | None = None
    header: str | None = None
    firmware: dict | None = None      # firmware.json: target figures of the header
    html: str | None = None
    pdf: bytes | None = None
    files: dict[str, str | bytes] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    header_refused: str | None = None

    @property
    def notice(self) -> str | None:
        """:data:`toolbox.verify.NO_REQUIREMENTS` when the spec has no requirements."""
        from .verify import NO_REQUIREMENTS  # lazy: numba + the kernel, ~500 modules

        return None if self.spec.requirements.given else NO_REQUIREMENTS

    @property
    def passed(self) -> bool:
        """Every requirement and default check holds (margins, stability, scenarios)."""
        ok = True
        if self.analysis is not None:
            ok &= all(c["pass"] for c in self.analysis.get("requirements", {}).values())
            ok &= not unstable_axes(self.analysis)
        ok &= self.header_refused is None
        if self.verification is not None:
            ok &= self.verification.passed
        return ok


def build_outputs(spec: Spec, *, analysis: bool = True, verification: bool = True,
                  report: bool = True, header: bool = True,
                  sampled_certificate: bool = False,
                  progress: Progress = _quiet) -> DesignOutputs:
    """Run the pipeline in memory (no files written).

    Parameters
    ----------
    spec : Spec
        Validated spec.
    analysis, verification, report, header : bool
        Which stages after design to run (all by default).
    sampled_certificate : bool
        Add the sampled-loop certificate to the analysis (opt-in: up to about a second).
    progress : callable
        Called with the name of each stage as it starts.

    Raises
    ------
    SpecError
        Bad input or a design that cannot be exported; nothing is produced.
    """
    try:
        return _build(spec, analysis, verification, report, header, sampled_certificate,
                      progress)
    except CctError as err:
        raise (err.with_file(spec.source) if spec.source and not err.file else err) from None


def _build(spec: Spec, analysis: bool, verification: bool, report: bool, header: bool,
           sampled_certificate: bool, progress: Progress) -> DesignOutputs:
    progress("design")
    artifact = design_spec(spec)
    out = DesignOutputs(artifact=artifact, spec=spec)
    # design-time advice (e.g. a PI bandwidth past the stability limit, with the value that works)
    out.warnings.extend(str(w) for w in artifact.design_parameters.get("design_warnings", []))
    if analysis:
        progress("analysis")
        out.artifact, out.analysis = analyse(artifact, spec,
                                             sampled_certificate=sampled_certificate)
    if verification:
        progress("verification")
        out.verification = run_verification(out.artifact, spec)
    if header:
        progress("firmware header")

        try:
            refuse_unstable_export(out.artifact, spec.motor)
        except ExportRefused as err:
            # a design that exists but must not reach firmware: everything else is
            # still written so the report shows why (exit 1 through `passed`)
            out.header_refused = str(err)
            out.warnings.append(f"controller.h not written: {err}")
            progress(f"firmware header refused: {err}")
        else:
            out.header = write_header(out.artifact, spec.motor, spec.drive,
                                      prefix=spec.export_prefix)
            from .export.firmware import measure_firmware
            out.firmware = measure_firmware(out.header, spec.export_prefix)
    if report:
        progress("report")
        # lazy: jinja2 + report, 33 modules
        from .report import build_context, write_html, write_pdf

        context = build_context(report_data(out))  # figures drawn once for both
        out.html = write_html(context)
        out.pdf = write_pdf(context)
    out.files = _files(out)
    return out


def report_data(out: DesignOutputs):
    """The :class:`~toolbox.report.ReportData` of a pipeline run (plain data).

    The report gets ``analysis.json`` and ``verify.json`` as the dicts that
    are written, plus the simulated traces (not stored in verify.json).

    Parameters
    ----------
    out : DesignOutputs
        Artifact, spec and whatever analysis and verification produced.
    """
    from .report import ReportData  # lazy: jinja2 + report, 33 modules

    verification = traces = None
    if out.verification is not None:
        verification = out.verification.to_json()
        traces = [sc.result for sc in out.verification.scenarios]
    warnings = list(out.warnings)
    if out.verification is not None:
        warnings += [w for w in out.verification.warnings if w not in warnings]
    return ReportData(title=out.spec.title or (out.spec.source or "untitled"), spec=out.spec,
                      artifact=out.artifact, analysis=out.analysis,
                      verification=verification, traces=traces,
                      notice=out.notice, warnings=warnings, firmware=out.firmware)


def _files(out: DesignOutputs) -> dict[str, str | bytes]:
    files: dict[str, str | bytes] = {"controller.json": out.artifact.dumps()}
    if out.analysis is not None:
        files["analysis.json"] = json.dumps(out.analysis, indent=1, allow_nan=False) + "\n"
    if out.verification is not None:
        files["verify.json"] = json.dumps(out.verification.to_json(), indent=1,
                                          allow_nan=False) + "\n"
    if out.header is not None:
        files["controller.h"] = out.header
    if out.firmware is not None:
        from .export.firmware import FIRMWARE_JSON, firmware_json
        files[FIRMWARE_JSON] = firmware_json(out.firmware)
    if out.html is not None:
        files["report.html"] = out.html
    if out.pdf is not None:
        files["report.pdf"] = out.pdf
    return files


def write_outputs(files: dict[str, str | bytes], out_dir: str | Path) -> list[Path]:
    """Write the outputs into ``out_dir`` as one set (see :func:`toolbox._io.write_set`):
    a crash or Ctrl-C leaves the old set or the new one, never a mix.

    Parameters
    ----------
    files : dict
        File name -> text or bytes.
    out_dir : str or Path
        Directory (created when missing).
    """
    out = Path(out_dir)
    # a new controller.json supersedes every output of the old design: none
    # of them may survive next to it (a stale report contradicting the design)
    drop = OUTPUT_FILES if "controller.json" in files else ()
    try:
        return write_set(files, out, drop=drop)
    except OSError as err:
        raise SpecError("--out", "a writable directory", str(out),
                        hint=err.strerror or str(err)) from None


def load_artifact(out_dir: str | Path) -> ControllerArtifact:
    """Read ``out_dir/controller.json`` (validated)."""
    path = Path(out_dir) / "controller.json"
    if not path.exists() and not path.is_symlink():
        raise ArtifactError("", "a design directory with controller.json",
                            "No such file or directory", file=str(path))
    raw = read_limited(path, ArtifactError, what="controller.json file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ArtifactError("", "a UTF-8 text file", "undecodable bytes",
                            file=str(path)) from None
    return ControllerArtifact.loads(text, file=str(path))


def header_agreement(out_dir: str | Path, artifact: ControllerArtifact,
                     spec: Spec | None = None) -> dict | None:
    """Whether ``out_dir/controller.h`` was exported from ``artifact``: its
    ``law sha256`` line against :meth:`ControllerArtifact.law_sha256` and,
    with ``spec`` (the artifact's stored spec), its whole text against the
    header regenerated from the artifact with the header's own prefix (None
    when there is no controller.h). A header without the line (older toolbox)
    or edited by hand (a coefficient, the decoupling, a limit) does not match.

    Returns
    -------
    dict or None
        ``{"file": "controller.h", "law_sha256": <header's digest or None>,
        "matches": bool}``; with ``spec`` also ``text_matches`` (bool) and
        ``first_difference_line`` (1-based, or None).
    """
    path = Path(out_dir) / "controller.h"
    if not path.is_file():
        return None
    raw = read_limited(path, ArtifactError, what="controller.h file")
    found = re.search(rb"^ \* law sha256:\s+([0-9a-f]{64})\s*$", raw[:4096], re.MULTILINE)
    digest = found.group(1).decode() if found else None
    out = {"file": "controller.h", "law_sha256": digest,
           "matches": digest == artifact.law_sha256()}
    if spec is not None:
        line = _header_difference(raw, artifact, spec)
        out.update(text_matches=line is None, first_difference_line=line)
        out["matches"] = out["matches"] and line is None
    return out


def _header_difference(raw: bytes, artifact: ControllerArtifact, spec: Spec) -> int | None:
    """First line (1-based) where ``raw`` differs from the header regenerated
    from ``artifact`` with the prefix the header uses; None when equal."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        return 1
    named = re.search(r"^static inline void ([A-Za-z][A-Za-z0-9_]{0,30})init\(", text,
                      re.MULTILINE)
    prefix = named.group(1) if named else spec.export_prefix
    try:
        expected = write_header(artifact, spec.motor, spec.drive, prefix=prefix)
    except CctError:  # the artifact cannot be exported: no header can be its own
        return 1
    if text == expected:
        return None
    got, want = text.splitlines(), expected.splitlines()
    for k, (a, b) in enumerate(zip(got, want)):
        if a != b:
            return k + 1
    return min(len(got), len(want)) + 1


def load_analysis(out_dir: str | Path, artifact: ControllerArtifact) -> dict | None:
    """``out_dir/analysis.json`` when it belongs to ``artifact``, else None.

    Parameters
    ----------
    out_dir : str or Path
        Design directory.
    artifact : ControllerArtifact
        The controller the analysis must describe (same method and sample time).

    Raises
    ------
    ArtifactError
        The analysis belongs to ``artifact`` but holds no ``responses`` (the
        figure data the report draws; written by ``cct design`` since schema
        cct.analysis/1 gained it): the report cannot be drawn from it.
    """
    path = Path(out_dir) / "analysis.json"
    if not path.exists():
        return None
    name = str(path)
    raw = read_limited(path, ArtifactError, what="analysis.json file")
    try:
        text = raw.decode("utf-8")
        check_text_depth(text, ArtifactError, file=name)  # json recurses
        data = json.loads(text)
    except (UnicodeDecodeError, json.JSONDecodeError):
        return None  # unreadable: analyse again rather than trust it
    same = (isinstance(data, dict) and data.get("schema") == "cct.analysis/1"
            and data.get("method") == artifact.method
            and data.get("sample_time") == artifact.sample_time)
    if not same:
        return None
    _check_analysis(data, name)
    if not isinstance(data.get("responses"), dict):
        raise ArtifactError("responses", "the response data the report draws "
                            "(Bode, Nyquist, S/T/KS, step, pole-zero per axis)",
                            "no 'responses' key" if "responses" not in data
                            else data["responses"], file=str(path),
                            hint=f"written by an older toolbox; re-run `cct design SPEC "
                                 f"--out {out_dir}` to regenerate it")
    return data


def _check_analysis(data: dict, file: str) -> None:
    """The parts of analysis.json that the report reads have the right shape."""
    for key in ("requirements", "sweep", "certificate", "sampled_certificate",
                "mimo_at_speed", "mimo_over_box", "margins"):
        if data.get(key) is not None and not isinstance(data[key], dict):
            raise ArtifactError(key, "an object", type(data[key]).__name__, file=file)
    for key, check in (data.get("requirements") or {}).items():
        where = f"requirements.{key}"
        if not isinstance(check, dict):
            raise ArtifactError(where, "an object with quantity, bound, value, unit, pass",
                                type(check).__name__, file=file)
        if not isinstance(check.get("pass"), bool):
            raise ArtifactError(f"{where}.pass", "true or false", check.get("pass"), file=file)
        for name in ("bound", "value"):
            v = check.get(name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                raise ArtifactError(f"{where}.{name}", "a number or null", v, file=file)
    _check_shapes(data, file)


def _is_num(v: Any) -> bool:
    return v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))


def _shape(value: Any, key: str, kind: str, file: str) -> Any:
    """``value`` of the ``kind`` the report reads ("object", "list", "number",
    "numbers": a list of numbers, "pair": two numbers), else ArtifactError."""
    ok = {"object": lambda v: isinstance(v, dict),
          "list": lambda v: isinstance(v, list),
          "number": _is_num,
          "real": lambda v: _is_num(v) and v is not None,
          "numbers": lambda v: isinstance(v, list) and all(_is_num(x) for x in v),
          "pair": lambda v: (isinstance(v, list) and len(v) == 2
                             and all(_is_num(x) and x is not None for x in v))}[kind](value)
    if not ok:
        what = {"object": "an object", "list": "a list", "number": "a number or null",
                "real": "a number",
                "numbers": "a list of numbers", "pair": "[low, high] numbers"}[kind]
        raise ArtifactError(key, what, value if not isinstance(value, (dict, list))
                            else type(value).__name__, file=file,
                            hint="analysis.json as cct design writes it; re-run cct design")
    return value


def _check_shapes(data: dict, file: str) -> None:
    """The nested fields the report reads from the sweep, the certificates and
    the MIMO summaries (a wrong shape made ``cct report`` crash)."""
    sweep = data.get("sweep") or {}
    if sweep:
        for axis, worst in _shape(sweep.get("worst", {}), "sweep.worst", "object",
                                  file).items():
            for quantity, entry in _shape(worst, f"sweep.worst.{axis}", "object",
                                          file).items():
                where = f"sweep.worst.{axis}.{quantity}"
                _shape(entry, where, "object", file)
                _shape(entry.get("params", {}), f"{where}.params", "object", file)
                _shape(entry.get("value"), f"{where}.value", "number", file)
        for k, ex in enumerate(_shape(sweep.get("unstable_examples", []),
                                      "sweep.unstable_examples", "list", file)):
            _shape(ex, f"sweep.unstable_examples[{k}]", "object", file)
        for name in ("worst_spectral_radius", "n_sets", "n_unstable"):
            _shape(sweep.get(name), f"sweep.{name}", "number", file)
        if sweep.get("speeds_rad_s") is not None:
            _shape(sweep["speeds_rad_s"], "sweep.speeds_rad_s", "numbers", file)
    cert = data.get("certificate") or {}
    for name, pair in _shape(cert.get("box") or {}, "certificate.box", "object",
                             file).items():
        _shape(pair, f"certificate.box.{name}", "pair", file)
    box = data.get("mimo_over_box") or {}
    for name, v in _shape(box.get("worst_params") or {}, "mimo_over_box.worst_params",
                          "object", file).items():
        _shape(v, f"mimo_over_box.worst_params.{name}", "real", file)
    if box.get("speeds_rad_s") is not None:
        _shape(box["speeds_rad_s"], "mimo_over_box.speeds_rad_s", "list", file)


def spec_of_artifact(artifact: ControllerArtifact, file: str | None = None) -> Spec:
    """The validated spec stored in an artifact (re-validated, not re-designed).

    Raises
    ------
    ArtifactError
        The stored spec is invalid; the key path is the one inside
        controller.json (``spec.motor.R``).
    """
    try:
        return spec_from_dict(artifact.spec, file=file)
    except SpecError as err:
        raise _as_artifact_error(err, file) from None


def _as_artifact_error(err: SpecError, file: str | None) -> ArtifactError:
    if isinstance(err, SpecErrors):
        first = err.errors[0]
        hint = f"and {len(err.errors) - 1} more error(s) in the stored spec"
        return ArtifactError(f"spec.{first.key}" if first.key else "spec", first.expected,
                             first.got if first.has_got else CctError._MISSING,
                             file=file, hint=hint)
    return ArtifactError(f"spec.{err.key}" if err.key else "spec", err.expected,
                         err.got if err.has_got else CctError._MISSING, file=file,
                         hint=err.hint)
