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

Modules
-------
The content model is gathered section by section in private modules:
:mod:`toolbox.report._format` (numbers and units), :mod:`toolbox.report._data`
(:class:`ReportData`), :mod:`toolbox.report._checks` (margins, checks,
verdict), :mod:`toolbox.report._robustness`, :mod:`toolbox.report._certificate`
and :mod:`toolbox.report._sections` (controller, step, scenarios,
provenance); this module assembles them (:func:`build_context`, with the
typeset model equations) and re-exports the public names.
"""

from __future__ import annotations

from pathlib import Path

from . import plots
from ._certificate import _certificate_of, _sampled_certificate_of  # noqa: F401
from ._firmware import _firmware_card
from ._checks import (BASELINE_LABEL, MARGIN_ROWS, _banner, _check_rows, _checks_of,
                      _margin_table, _margins_of, _verdict_card)
from ._data import ReportData
from ._format import (NOT_COMPUTED, RESOLUTION, RESOLUTION_NOTE, SIM_METRIC_UNITS,  # noqa: F401
                      SPEED_KINDS, fmt, fmt_q, sim_metric_unit, zpk_text)
from ._robustness import _robustness, _robustness_of
from ._sections import (METHOD_NAMES, _controller, _envelope, _provenance,  # noqa: F401
                        _scenario_traces, _scenarios, _step_of)

__all__ = ["ReportData", "build_context", "write_html", "write_pdf", "zpk_text", "fmt", "fmt_q", "NOT_COMPUTED",
           "METHOD_NAMES", "MARGIN_ROWS", "BASELINE_LABEL", "RESOLUTION", "sim_metric_unit"]

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
    import sympy as sp  # lazy: sympy, ~490 modules (cold cache only)

    from ..plant import derive_dq_model  # lazy: scipy.linalg + plant, ~230 modules

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
        robustness card: drift-box verdict), firmware (the firmware card:
        firmware.json's target figures or why not measured), banner (the verdict banner:
        ``status`` pass/fail/none, ``headline``, ``count``, ``reason``),
        baseline (the label of informational margins, or None), certificate,
        scenarios, envelope (the torque-speed grid: ``summary``, ``status``,
        ``svg``, ``rows``; None without one), provenance, margins_given, resolution_note``; the HTML and typst templates render it.
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
        "firmware": _firmware_card(data.firmware),
        "banner": _banner(data, checks),
        "baseline": BASELINE_LABEL if baseline else None,
        "resolution_note": RESOLUTION_NOTE,
        "certificate": ([(str(k), fmt(v)) for k, v in certificate.items()]
                        if certificate else None),
        "scenarios": (_scenarios(data.verification, traces)
                      if data.verification is not None else None),
        "envelope": _envelope(data.verification),
        "provenance": _provenance(data),
        "not_computed": NOT_COMPUTED,
        "notice": [str(x) for x in ([data.notice] if data.notice else []) + list(data.warnings or [])],
    }


from .html import write_html  # noqa: E402  (the renderers use the model above)
from .pdf import write_pdf  # noqa: E402
from .._cache import cached
from ..spec import REQUIREMENT_KEYS
