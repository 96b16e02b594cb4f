"""The report draws only what analysis.json and verify.json hold (toolbox/ARCHITECTURE.md
"Layers": report reads the stored results, never re-runs analysis).

* the report package imports neither python-control nor toolbox.analysis;
* changing a number of analysis.json changes the report, figure by figure;
* the step figures of 2-DOF laws (ILQ, total compensation) are the analysis'
  reference-step figures: ILQ overshoot 0.004 % (the old report's rebuilt
  1-DOF loop showed 21.3 %), TC 5 % time finite (it was NaN);
* an analysis.json without ``responses`` is refused with an ArtifactError.
"""

from __future__ import annotations

import ast
import copy
import json
from pathlib import Path

import pytest

import toolbox
from toolbox.errors import ArtifactError
from toolbox.report import ReportData, build_context
from toolbox.report.plots import figures

REPORT_DIR = Path(toolbox.__file__).parent / "report"
DESIGNS = Path(__file__).resolve().parents[2] / "designs"


def _imported_modules(path: Path) -> list[str]:
    """Absolute names of the modules a source file imports (relative ones resolved)."""
    package = "toolbox.report"
    names = []
    for node in ast.walk(ast.parse(path.read_text("utf-8"))):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                mod = f"{base}.{node.module}" if node.module else base
                # "from .. import analysis" imports the sub-package by name
                names += [mod] + [f"{mod}.{a.name}" for a in node.names]
            else:
                names.append(node.module or "")
    return names


def test_report_imports_no_control_nor_analysis():
    """Every module of toolbox/report, at any nesting (function-level imports too)."""
    files = sorted(REPORT_DIR.rglob("*.py"))
    assert len(files) >= 4  # __init__, html, pdf, plots: the walk found the package
    for path in files:
        for name in _imported_modules(path):
            assert name != "control" and not name.startswith("control."), (path.name, name)
            assert not name.startswith("toolbox.analysis"), (path.name, name)


def test_import_check_can_fail(tmp_path):
    """The AST walk sees function-level and relative imports (the check is not vacuous)."""
    src = tmp_path / "bad.py"
    src.write_text("def f():\n    import control\n    from ..analysis import margins\n")
    names = _imported_modules(src)
    assert "control" in names and "toolbox.analysis.margins" in names


def _svgs(context: dict) -> dict[str, str]:
    return {f["id"]: f["svg"] for f in context["figures"]}


def test_figures_follow_analysis_json(full_data, full_context):
    """A number changed in analysis.json changes exactly the figure that draws it."""
    analysis = copy.deepcopy(full_data.analysis)
    step = analysis["responses"]["q"]["step"]
    k = len(step["y"]) // 2
    step["y"][k] = float(step["y"][k]) + 0.5  # a spike in the stored q step
    analysis["responses"]["d"]["S_db"][10] = 30.0  # and in the stored d-axis |S|
    before = _svgs(full_context)
    after = _svgs({"figures": figures(analysis["responses"], analysis["margins"]["discrete"])})
    assert after["step"] != before["step"]
    assert after["sensitivity"] != before["sensitivity"]
    for fid in ("bode", "nyquist", "pzmap"):
        assert after[fid] == before[fid], fid


def test_step_figures_and_markers_follow_analysis_margins(full_data, full_context):
    """The step caption and the Bode markers quote analysis.json's margins."""
    analysis = copy.deepcopy(full_data.analysis)
    analysis["margins"]["discrete"]["q"]["overshoot_pct"] = 12.5
    analysis["margins"]["discrete"]["q"]["phase_margin_deg"] = 33.0
    figs = {f["id"]: f for f in figures(analysis["responses"], analysis["margins"]["discrete"])}
    assert "q axis: overshoot 12.5 %" in figs["step"]["caption"]
    before = _svgs(full_context)
    assert figs["bode"]["svg"] != before["bode"]


def test_weight_bounds_come_from_analysis(full_data, full_context):
    """The dashed gamma/|W_i| curves are analysis.json's: dropping them from the
    stored responses removes them from the figure and the caption says so."""
    assert "bounds gamma/|W_i|" in full_context["figures"][2]["caption"]
    analysis = copy.deepcopy(full_data.analysis)
    for ax in ("d", "q"):
        analysis["responses"][ax]["weight_bounds"] = None
    figs = {f["id"]: f for f in figures(analysis["responses"], analysis["margins"]["discrete"])}
    assert figs["sensitivity"]["caption"].startswith("Weight bounds: not computed")
    assert figs["sensitivity"]["svg"] != _svgs(full_context)["sensitivity"]


def _design_data(name: str) -> tuple[ReportData, dict]:
    """ReportData of a gallery design with the analysis' margins and responses only
    (the full analysis adds sweeps the step figures do not depend on)."""
    from toolbox.analysis import compute_margins, json_ready
    from toolbox.analysis._responses import loop_responses

    spec = toolbox.load_spec(DESIGNS / name)
    art = toolbox.design_spec(spec)
    analysis = json.loads(json.dumps({
        "margins": {"discrete": json_ready({ax: m.to_json() for ax, m in
                                            compute_margins(art, spec.motor).items()})},
        "responses": loop_responses(art, spec.motor)}))
    return ReportData(title=name, spec=spec, artifact=art, analysis=analysis), analysis


def test_ilq_step_overshoot_equals_analysis():
    """ILQ (paper 001, a 2-DOF law): the report's step figures are the analysis'.

    The overshoot is the analysis' number itself (equality); the stored curve's
    peak agrees with it to 5e-4 %-points: y ~ 1 is rounded to 6 significant
    digits (half a unit of 1e-5, i.e. 5e-4 %) and the decimation keeps the peak
    sample.
    The old report's 1-DOF rebuild feedback(K G, 1) showed 21.3 % here.
    """
    data, analysis = _design_data("001_takami2004_ilq.toml")
    ctx = build_context(data)
    for ax in ("d", "q"):
        expected = analysis["margins"]["discrete"][ax]["overshoot_pct"]
        assert ctx["step"][ax]["overshoot_pct"] == expected
        assert expected < 0.01  # percent
        y = analysis["responses"][ax]["step"]["y"]
        assert (max(y) - 1.0) * 100 == pytest.approx(expected, abs=5e-4 + 1e-12)
    step = next(f for f in ctx["figures"] if f["id"] == "step")
    assert f"q axis: overshoot {expected:.3g} %" in step["caption"]


def test_tc_step_time_is_finite():
    """Total compensation (paper 000 eq (11)): the 5 % time shown is finite and the analysis'."""
    data, analysis = _design_data("000_lepioufle1992_tc.toml")
    ctx = build_context(data)
    step = next(f for f in ctx["figures"] if f["id"] == "step")
    for ax in ("d", "q"):
        t5 = ctx["step"][ax]["response_time_5pct"]
        assert t5 == analysis["margins"]["discrete"][ax]["response_time_5pct"]
        assert isinstance(t5, float) and 0 < t5 < 0.01  # s: a few ms (000: ~2.5-3.6 ms)
        assert f"{ax} axis: overshoot" in step["caption"]
        assert f"5 % time {t5 * 1e3:.3g} ms" in step["caption"]
    assert "n/a" not in step["caption"]


def test_load_analysis_without_responses_is_refused(tmp_path, full_data):
    """An analysis.json of an older toolbox (no responses) cannot feed the report:
    ArtifactError naming the file and the key, telling to re-run cct design."""
    from toolbox.pipeline import load_analysis

    art = full_data.artifact
    old = {k: v for k, v in full_data.analysis.items() if k != "responses"}
    (tmp_path / "analysis.json").write_text(json.dumps(old))
    with pytest.raises(ArtifactError) as err:
        load_analysis(tmp_path, art)
    text = str(err.value)
    assert str(tmp_path / "analysis.json") in text and "responses" in text
    assert "re-run `cct design" in text
    (tmp_path / "analysis.json").write_text(json.dumps(full_data.analysis))
    assert load_analysis(tmp_path, art)["responses"] == full_data.analysis["responses"]


def test_cct_report_refuses_old_analysis(tmp_path, full_data):
    """`cct report` on a directory whose analysis.json predates `responses`: exit 2,
    the message says to re-run cct design, and no report is written."""
    from click.testing import CliRunner

    from toolbox.cli import main

    (tmp_path / "controller.json").write_text(full_data.artifact.dumps())
    old = {k: v for k, v in full_data.analysis.items() if k != "responses"}
    (tmp_path / "analysis.json").write_text(json.dumps(old))
    result = CliRunner().invoke(main, ["report", str(tmp_path)])
    assert result.exit_code == 2, result.output
    assert "responses" in result.output and "re-run `cct design" in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["analysis.json", "controller.json"]
