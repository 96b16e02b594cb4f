"""The STM32 MCSDK (``<P>MCSDK``) and TI IQmath (``<P>IQMATH``) integer variants
of a PI law in the header (``templates/vendor.c.j2``), or an ``#error`` saying
why not; the plan is :mod:`toolbox.export._vendor`'s (:func:`vendor_plan`)."""

from __future__ import annotations

from ..errors import ExportRefused
from . import _vendor
from ._check import AXES, _D_PRIORITY_FLOAT_ONLY, ExportCheck, _dec_coeffs, _law_key, _ranges, minimal_laws
from ._format import C_INT32_MAX, _c_error, _f, _int, _Text
from ._placement import _integer_placement


def vendor_plan(artifact, motor, drive, check: ExportCheck):
    """The MCSDK/IQmath plan of a PI law (:mod:`toolbox.export._vendor`), or (None, why)."""
    i_max, w_max = _ranges(artifact, motor, drive, check.v_max)
    dec_coeffs = _dec_coeffs(artifact.decoupling)
    if check.limit == "hexagon":
        return None, ('voltage_limit = "hexagon" is implemented in the float path only; '
                      'the MCSDK/IQmath variants need voltage_limit = "circle"')
    if check.priority != "radial":
        return None, _D_PRIORITY_FLOAT_ONLY.format(variant="the MCSDK/IQmath variants")
    # an ExportCheck built by hand may lack the minimal laws check_exportable keeps
    minimal = check.minimal or minimal_laws(artifact)
    return _vendor.plan_vendor(minimal, i_max, w_max, check.v_max, dec_coeffs)


def _vendor_section(t: _Text, artifact, motor, drive, check: ExportCheck, N: str,
                    P: str) -> None:
    """MCSDK (``<P>MCSDK``) and IQmath (``<P>IQMATH``) variants, or an #error saying why not."""
    plan, why = vendor_plan(artifact, motor, drive, check)
    key = _law_key(artifact)
    if plan is not None:
        try:
            mc = _vendor.mcsdk_constants(plan)
            iq = _vendor.iq_constants(plan)
        except OverflowError as err:
            plan, why = None, str(err)
    if plan is not None:
        body = _Text()
        try:
            mc_comp = _integer_placement(artifact, plan.mc_W_FS, plan.W_FS)
            iq_comp = _integer_placement(artifact, plan.W_FS)
            comp = None if mc_comp is None else {
                "mc_K": mc_comp["K"], "mc_angle": mc_comp["angle"],
                "iq_K": iq_comp["K"], "iq_angle": iq_comp["angle"]}
            _vendor_body(body, plan, mc, iq, N, P, key, comp)
        except ExportRefused as err:          # a constant out of range: no variant
            why = str(err)
        else:
            t.lines.extend(body.lines)
            return
    t(f"#if defined({P}MCSDK) || defined({P}IQMATH)")
    t(_c_error("MCSDK/IQmath variants not available", why))
    t("#endif")


def _vendor_body(t: _Text, plan, mc: dict, iq: dict, N: str, P: str, key: str,
                 comp: dict | None) -> None:
    """The MCSDK/IQmath section (``templates/vendor.c.j2``); numbers formatted
    and range-checked here, in line order."""
    # the header's one template environment; in-function: c_header imports this module
    from .c_header import _render
    gains = [(ax, f"{plan.kp[ax]:.9g}", f"{plan.ki[ax]:.9g}", f"{plan.kaw[ax]:.9g}")
             for ax in AXES]
    d = {"MCSDK_I_FS": _f(plan.mc_I_FS, 'motor.max_current', 'MCSDK_I_FS'),
         "MCSDK_V_FS": _f(plan.V_FS, 'drive.vdc', 'MCSDK_V_FS'),
         "MCSDK_W_FS": _f(plan.mc_W_FS, 'drive.max_speed', 'MCSDK_W_FS'),
         "MCSDK_V_MAX": _int(round(plan.V_MAX / plan.V_FS * 32768), 'drive.vdc', 'MCSDK_V_MAX',
                             0, 32767),
         "IQ_I_BASE": _f(plan.I_FS, 'motor.max_current', 'IQ_I_BASE'),
         "IQ_V_BASE": _f(plan.V_MAX, 'drive.vdc', 'IQ_V_BASE'),
         "IQ_W_BASE": _f(plan.W_FS, 'drive.max_speed', 'IQ_W_BASE')}
    mc_ctx = {k: (_int(g, key, f"MCSDK {k} gain", -32767, 32767), _int(sh, key, f"MCSDK {k} divisor", 0, 15))
              for k, (g, sh) in mc.items()}
    iq_ctx = {k: _int(v, key, f"IQ24 {k}", -C_INT32_MAX, C_INT32_MAX) for k, v in iq.items()}
    t.lines.extend(_render("vendor.c.j2", N=N, P=P, U=N.upper(), gains=gains, d=d, mc=mc_ctx,
                           iq=iq_ctx, comp=comp))
