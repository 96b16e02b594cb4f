"""Fixtures of the report tests: a PI design of the paper 003 motor (azaiz2007).

The report consumes plain data only, so the fixture builds it here: a PI
artifact by pole-zero cancellation (Kp = L wc, Ki = R wc, paper 000 sect. 2)
through ``AxisController.from_error_controller``; margins from python-control's
``stability_margins`` on the sampled loop (an independent route from the
report's own curve reading); synthetic verification traces from the linear
closed loop.
"""

from __future__ import annotations

import dataclasses

import control
import numpy as np
import pytest

from toolbox.artifact import AxisController
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
    try:
        return spec_from_dict(data)
    except Exception:  # pi design module not written yet: assemble the spec directly
        from toolbox.spec._catalog import CATALOG
        from toolbox.spec._model import ControllerChoice, Drive, Motor, Requirements, Spec

        return Spec(title=title, motor=Motor(**CATALOG["azaiz2007"], catalog="azaiz2007"),
                    drive=Drive(vdc=150.0, sample_time=1e-4),
                    controller=ControllerChoice("pi", {"bandwidth": WC}),
                    requirements=Requirements(dict(data["requirements"])),
                    raw={**data, "motor": dict(CATALOG["azaiz2007"])})


def _artifact(spec):
    m, ts = spec.motor, spec.drive.sample_time
    gains = {}
    axes = {}
    for name, L in (("d", m.Ld), ("q", m.Lq)):
        kp, ki = L * WC, m.R * WC
        gains[name] = {"Kp": kp, "Ki": ki}
        axes[name] = AxisController.from_error_controller(control.tf([kp, ki], [1, 0]), ts)
    art = make_artifact(spec, axes, decoupling_from_motor(m), gains,
                        ["000 sect. 2 (PI by pole-zero cancellation)"])
    prov = {**art.provenance, "created": "2026-01-01T00:00:00+00:00"}
    return dataclasses.replace(art, provenance=prov)


def _margins(art, motor):
    from toolbox.plant import axis_plants

    out = {}
    ts = art.sample_time
    for name, G in axis_plants(motor).items():
        K = art.axes[name].to_statespace(discrete=True)
        Gd = control.sample_system(control.ss(G), ts, "zoh")
        L = K * Gd * control.tf([1], [1, 0], ts)
        gm, pm, sm, wpc, wgc, _ = control.stability_margins(L)
        out[name] = {"gain_margin_db": 20 * np.log10(gm), "gain_crossover_rad_s": wgc,
                     "phase_margin_deg": pm, "phase_crossover_rad_s": wpc,
                     "stability_margin": sm, "sensitivity_peak": 1 / sm,
                     "disk_margin": None, "bandwidth_rad_s": None, "static_error": 0.0}
    return out, L


def _checks(spec, margins):
    checks = []
    for ax in ("d", "q"):
        try:
            result = spec.requirements.check(margins[ax], "margins")
        except TypeError:  # older signature without the stage
            result = spec.requirements.check(margins[ax])
        for key, c in result.items():
            checks.append({"key": key, **c, "axis": ax})
    return checks


def _scenarios(L):
    T = control.feedback(L, 1)
    t = np.arange(300) * 1e-4
    y = np.asarray(control.step_response(T, T=t).outputs).reshape(-1)
    traces = {"t": t, "iq": 10 * y, "iq_ref": np.full_like(t, 10.0), "id": 0.02 * y,
              "id_ref": np.zeros_like(t), "vd": -2 * y, "vq": 20 * y + 3}
    return [{"name": "q step 10 A", "kind": "step", "pass": True,
             "metrics": {"response_time_5pct": 1.9e-3, "overshoot_pct": 2.1},
             "traces": traces},
            {"name": HOSTILE, "kind": "step", "pass": False, "metrics": {"overshoot_pct": 40.0},
             "traces": None}]


def _robustness():
    cases = []
    for k, (fr, fl) in enumerate([(r, l) for r in (0.5, 1.0, 2.0) for l in (0.5, 1.0, 2.0)]):
        pm = 80 - 25 * abs(np.log2(fl)) - 3 * abs(np.log2(fr))
        cases.append({"label": f"R x{fr}, L x{fl}", "params": {"R": fr, "L": fl},
                      "metrics": {"phase_margin_deg": pm, "gain_margin_db": 20 - 5 * np.log2(fl)},
                      "pass": bool(pm >= 60)})
    return {"cases": cases, "worst": ["R x2.0, L x2.0", "R x0.5, L x0.5"],
            "notes": "Resistance and inductances scaled about nominal."}


@pytest.fixture(scope="session")
def full_data() -> ReportData:
    spec = _spec(HOSTILE)
    art = _artifact(spec)
    margins, L = _margins(art, spec.motor)
    art = art.with_margins(margins)
    weights = {ax: {"w1": {"num": [0.66225, 117.4499], "den": [1, 0.0117]},
                    "w2": control.tf([25, 25000], [1, 50000]),
                    "w3": {"num": [1e4, 1.3568e6], "den": [1, 2.7135e6]}, "gamma": 1.0}
               for ax in ("d", "q")}
    return ReportData(title=HOSTILE, spec=spec, artifact=art, margins=margins,
                      checks=_checks(spec, margins), robustness=_robustness(),
                      certificate={"closed loop stable": True, "gamma": 0.98,
                                   "note": HOSTILE},
                      scenarios=_scenarios(L), weights=weights)


@pytest.fixture(scope="session")
def minimal_data() -> ReportData:
    spec = _spec("Minimal report")
    return ReportData(title="Minimal report", spec=spec, artifact=_artifact(spec))


@pytest.fixture(scope="session")
def hostile() -> str:
    """A title that is HTML, shell and typst markup/code at once."""
    return HOSTILE


# Rendering takes seconds (matplotlib figures; the plant's sympy derivation on
# first use), so each document is rendered once per session.

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
