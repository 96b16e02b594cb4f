"""controller.h of method ``cv``: the direct discrete-time complex-vector law.

The header computes the law's gains every period at the measured speed, as
the simulator's kernel does (``toolbox/sim/_kernel_cv.py``; formulas in
:mod:`toolbox.design.cv_discrete`, toolbox/ARCHITECTURE.md "Direct
discrete-time complex-vector control"): templates ``cv_top.c.j2`` and
``cv.c.j2``, float only. The integer variants (``<P>FIXED_POINT``,
``<P>MCSDK``, ``<P>IQMATH``) are ``#error``s naming why; the SVM hexagon
limit is refused (the law is exported with the circle limit, radial or
d-axis priority). The usage example is the linear law's
(``templates/example.c.j2``): same input, output and status contract, and
the same restart and handover functions (``<p>reset``, ``<p>preset_at``,
``<p>preset``); the state holds per axis the law's integrator and delayed
voltages (``d[]``, ``q[]``, the coordinates of the standstill axes).
"""

from __future__ import annotations

import numpy as np

from ..errors import ExportRefused
from ._format import _f, _int, _Text, sanitise_comment
from ._placement import _placement_convention
from ._plausible import _plausible_context

__all__ = ["write_cv_header"]


def write_cv_header(artifact, motor, drive, name: str, title: str, *, render,
                    provenance: dict, example) -> str:
    """The header text of a ``cv`` artifact.

    Parameters
    ----------
    artifact : ControllerArtifact
        Method ``cv`` (its ``cv`` field and ``decoupling``).
    motor, drive : Motor, Drive
        For the voltage limit, the plausibility limits and the convention.
    name : str
        The C prefix without its underscore.
    title : str
        Title of the provenance comment (in ``provenance`` already).
    render : callable
        ``render(template, **context) -> lines`` (``c_header._render``).
    provenance : dict
        The provenance strings (``c_header._provenance``).
    example : callable or None
        ``example(t, N, P)`` appends the usage example; None for none.

    Raises
    ------
    ExportRefused
        No drive data, the hexagon limit, or a constant out of float32 range
        (naming the spec key).
    """
    if drive is None:
        raise ExportRefused("drive", "drive data (vdc) for the voltage limit",
                            hint="pass drive= or keep [drive] in the artifact's spec")
    limit = getattr(drive, "voltage_limit", None) or "circle"
    if limit != "circle":
        raise ExportRefused("drive.voltage_limit", '"circle" for method cv (its header '
                            "limits the voltage on the circle)", limit)
    priority = getattr(drive, "voltage_priority", None) or "radial"
    conv = motor.convention if motor is not None else "amplitude"
    v_max = drive.max_voltage(conv)
    N = name.lower()
    P = name.upper() + "_"
    guard = f"{P}CONTROLLER_H"
    cv, dec = artifact.cv, artifact.decoupling
    ts, nd = artifact.sample_time, int(artifact.delay_samples)
    pc, pi, pd = cv.poles(ts, 1)
    t_c = dec.delay_compensation_time
    key = "controller.cv"
    coef = [_f(c, key, f"pole polynomial coefficient a_{k}")
            for k, c in enumerate(np.real(np.poly(cv.poles(ts, nd))))]
    d = {"ts": _f(ts, "drive.sample_time", "SAMPLE_TIME"),
         "nd": _int(nd, "drive.delay_samples", "DELAY_SAMPLES", 0),
         "vmax": _f(v_max, "drive.vdc", "V_MAX"),
         "vmax_per_vdc": _f(v_max / drive.vdc, "drive.vdc", "V_MAX_PER_VDC"),
         "vdc": _f(drive.vdc, "drive.vdc", "DRIVE_VDC"),
         "convention": sanitise_comment(conv),
         "R": _f(dec.R_c, "motor.R", "DEC_R"), "Ld": _f(dec.Ld_c, "motor.Ld", "DEC_LD"),
         "Lq": _f(dec.Lq_c, "motor.Lq", "DEC_LQ"),
         "flux": _f(dec.flux_c, "motor.flux", "DEC_FLUX"), "emf": int(bool(dec.emf)),
         "pole_pairs": _int(dec.pole_pairs, "motor.pole_pairs", "POLE_PAIRS", 1),
         "t_comp": _f(t_c, "drive.angle_compensation", "DELAY_COMP_TIME"),
         "comp_periods": f"{t_c / ts:g}", "comp_convention": _placement_convention(artifact),
         "eps_per_w": _f(t_c - (nd + 0.5) * ts, "drive.angle_compensation", "CV_EPS_PER_W"),
         "pc": _f(pc, key + ".bandwidth", "CV_PC"),
         "pi": _f(pi, key + ".integral_bandwidth", "CV_PI"),
         "pd": _f(pd, key + ".delay_pole", "CV_PD"),
         "alpha_c": f"{cv.bandwidth:.9g}", "alpha_i": f"{cv.integral_bandwidth:.9g}"}
    t = _Text()
    t.lines.extend(render("cv_top.c.j2", prov=provenance, N=N, P=P, U=N.upper(), guard=guard,
                          delay=nd, d_priority=priority == "d_axis", d=d))
    t("")
    t.lines.extend(render("cv.c.j2", N=N, P=P, U=N.upper(), nd=nd, coef=coef,
                          convention=sanitise_comment(conv), d_priority=priority == "d_axis",
                          plausible=_plausible_context(artifact, motor, drive, v_max)))
    if example is not None:
        t("")
        example(t, N, P)
    t("")
    t(f"#endif /* {guard} */")
    return t.text()
