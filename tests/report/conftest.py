"""Fixtures of the report tests: a PI design of the paper 003 motor (azaiz2007).

The report consumes plain data only, so the fixture builds it here: a PI
artifact by pole-zero cancellation (Kp = L wc, Ki = R wc, paper 000 sect. 2)
through ``AxisController.from_error_controller``, carrying paper 003's
H-infinity weights in the typed ``artifact.weights`` so that the weight bounds are drawn;
its ``analysis.json`` from :func:`toolbox.analysis.analysis_report` (small
sweep, no certificate); a synthetic ``verify.json`` with traces from the
linear closed loop. ``python_control_margins`` gives python-control's
``stability_margins`` of the sampled loop, an independent route to check the
margins the figures mark.
"""

from __future__ import annotations

import dataclasses

import control
import numpy as np
import pytest

from toolbox.artifact import AxisController, AxisWeights, TransferFunctionData
from toolbox.design._common import decoupling_from_motor, make_artifact
from toolbox.report import ReportData

HOSTILE = "<script>alert(1)</script> & \"quotes\" ' ; rm -rf / #set $x$ \\ [*a*] {b} <<c>>"
WC = 1500.0  # rad/s, loop crossover asked of the PI


def _spec(title: str):
    from toolbox.spec import spec_from_dict

    data = {"title": title, "motor": {"catalog": "azaiz2007"},
            "drive": {"vdc": 150, "sample_time": 1e-4},
            "controller": {"method": "pi", "pi": {"bandwidth": WC}},
            "requirements": {"min_phase_margin_deg": 60.0, "min_gain_margin_db": 40.0}}
    return spec_from_dict(data)


#: Paper 003's q-axis weights (num/den in s), recorded as an H-infinity design does.
WEIGHTS = {"w1": {"num": [0.66225, 117.4499], "den": [1, 0.0117]},
           "w2": {"num": [25, 25000], "den": [1, 50000]},
           "w3": {"num": [1e4, 1.3568e6], "den": [1, 2.7135e6]}}


def _artifact(spec, weights: bool = False):
    m, ts = spec.motor, spec.drive.sample_time
    typed = None
    if weights:
        w = AxisWeights(gamma=1.0, **{k: TransferFunctionData(np.array(v["num"], float),
                                                               np.array(v["den"], float))
                                      for k, v in WEIGHTS.items()})
        typed = {"d": w, "q": w}
    params: dict = {}
    axes = {}
    for name, L in (("d", m.Ld), ("q", m.Lq)):
        kp, ki = L * WC, m.R * WC
        params[name] = {"Kp": kp, "Ki": ki}
        axes[name] = AxisController.from_error_controller(control.tf([kp, ki], [1, 0]), ts)
    art = make_artifact(spec, axes, decoupling_from_motor(m), params,
                        ["000 sect. 2 (PI by pole-zero cancellation)"], weights=typed)
    prov = {**art.provenance, "created": "2026-01-01T00:00:00+00:00"}
    return dataclasses.replace(art, provenance=prov)


def _margins(art, motor):
    from toolbox.plant import axis_plants

    out = {}
    ts = art.sample_time
    for name, G in axis_plants(motor).items():
        K = art.axes[name].to_statespace(discrete=True).to_control()
        Gd = control.sample_system(control.ss(G), ts, "zoh")
        L = K * Gd * control.tf([1], [1, 0], ts)
        gm, pm, sm, wpc, wgc, _ = control.stability_margins(L)
        out[name] = {"gain_margin_db": 20 * np.log10(gm), "gain_crossover_rad_s": wgc,
                     "phase_margin_deg": pm, "phase_crossover_rad_s": wpc,
                     "stability_margin": sm, "sensitivity_peak": 1 / sm,
                     "disk_margin": None, "bandwidth_rad_s": None, "static_error": 0.0}
    return out, L


def _verification(L) -> tuple[dict, list]:
    """A verify.json with two scenarios (one named by hostile text) and their traces."""
    T = control.feedback(L, 1)
    t = np.arange(300) * 1e-4
    y = np.asarray(control.step_response(T, T=t).outputs).reshape(-1)
    traces = {"t": t, "iq": 10 * y, "iq_ref": np.full_like(t, 10.0), "id": 0.02 * y,
              "id_ref": np.zeros_like(t), "vd": -2 * y, "vq": 20 * y + 3}
    verify = {"schema": "cct.verify/1", "method": "pi", "passed": False,
              "margin_requirements": {},
              "scenarios": [
                  {"name": "q step 10 A", "kind": "step", "passed": True,
                   "metrics": {"response_time_5pct": 1.9e-3, "overshoot_pct": 2.1},
                   "requirements": {}},
                  {"name": HOSTILE, "kind": "step", "passed": False,
                   "metrics": {"overshoot_pct": 40.0},
                   "requirements": {"max_overshoot_pct": {
                       "quantity": "overshoot_pct", "bound": 20.0, "value": 40.0, "unit": "%",
                       "pass": False}}}]}
    return verify, [traces, None]


def _analysis(spec, art) -> dict:
    """analysis.json of ``art`` (a 50-set sweep and no certificate keep it fast)."""
    import json

    from toolbox.analysis import analysis_report

    rep = analysis_report(art, spec.motor, spec.drive, sweep_sets=50, certificate=False)
    rep["requirements"] = spec.requirements.check_margins(
        {ax: rep["margins"]["discrete"][ax] for ax in ("d", "q")})
    return json.loads(json.dumps(rep))  # exactly what the file holds


@pytest.fixture(scope="session")
def python_control_margins():
    """python-control's margins of the full fixture's sampled loops (independent route)."""
    spec = _spec(HOSTILE)
    return _margins(_artifact(spec), spec.motor)[0]


@pytest.fixture(scope="session")
def full_data() -> ReportData:
    spec = _spec(HOSTILE)
    art = _artifact(spec, weights=True)
    analysis = _analysis(spec, art)
    art = art.with_margins(analysis["margins"]["discrete"])
    _, L = _margins(art, spec.motor)
    verify, traces = _verification(L)
    return ReportData(title=HOSTILE, spec=spec, artifact=art, analysis=analysis,
                      verification=verify, traces=traces)


@pytest.fixture(scope="session")
def passing_data(full_data) -> ReportData:
    """``full_data`` with every check passing (a passing design)."""
    import copy

    analysis = copy.deepcopy(full_data.analysis)
    for c in analysis["requirements"].values():
        c["pass"] = True
    verify = copy.deepcopy(full_data.verification)
    verify["passed"] = True
    for sc in verify["scenarios"]:
        sc["passed"] = True
        for c in sc["requirements"].values():
            c["pass"] = True
    return dataclasses.replace(full_data, analysis=analysis, verification=verify)


@pytest.fixture(scope="session")
def minimal_data() -> ReportData:
    spec = _spec("Minimal report")
    return ReportData(title="Minimal report", spec=spec, artifact=_artifact(spec))


@pytest.fixture(scope="session")
def hostile() -> str:
    """A title that is HTML, shell and typst markup/code at once."""
    return HOSTILE


# Rendering takes a second (typst; the plant's sympy derivation and the mathtext
# equations on first use), so each document is rendered once per session.

@pytest.fixture(scope="session")
def full_context(full_data) -> dict:
    from toolbox.report import build_context

    return build_context(full_data)


@pytest.fixture(scope="session")
def full_html(full_context) -> str:
    from toolbox.report.html import render_html

    return render_html(full_context)


@pytest.fixture(scope="session")
def full_pdf(full_context) -> bytes:
    import typst

    from toolbox.report.pdf import render_typst

    source, images = render_typst(full_context)
    return typst.compile(source.encode("utf-8"), format="pdf", sys_inputs=images)
