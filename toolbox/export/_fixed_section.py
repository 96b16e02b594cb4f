"""The Q31 fixed-point variant of a linear law's header, under
``#ifdef <PREFIX>FIXED_POINT`` (``templates/fixed.c.j2``), or an ``#error``
saying why it is not available; the scaling rules are :mod:`toolbox.export._fixed`'s."""

from __future__ import annotations

import numpy as np

from ..errors import ExportRefused
from . import _fixed
from ._check import AXES, HORIZON, ExportCheck, _law_key
from ._format import _c_error, _f, _int, _q31, _shift, _Text
from ._informational import _informational_pi_gains
from ._placement import _integer_placement
from ._plausible import PLAUSIBLE_MARGIN


def _word(value: float, base: float) -> int:
    """``value`` as a Q31 word of ``base`` (truncated as ``to_q31``), at most INT32_MAX."""
    return min(int(value / base * 2.0 ** 31), 2 ** 31 - 1)


def _fixed_section(t: _Text, check: ExportCheck, N: str, P: str, artifact, drive) -> None:
    """The Q31 variant under ``#ifdef <PREFIX>FIXED_POINT``, or an ``#error`` saying why not.

    A constant of the Q31 variant out of its range (e.g. a current base beyond
    float32) makes the variant unavailable, not the float header.
    """
    t("")
    t(f"#ifdef {P}FIXED_POINT")
    reason = check.fixed_reason
    if check.fixed is not None:
        body = _Text()
        try:
            _fixed_body(body, check, N, P, artifact, drive)
        except ExportRefused as err:
            reason = str(err)
        else:
            t.lines.extend(body.lines)
            t(f"#endif /* {P}FIXED_POINT */")
            return
    t(_c_error("fixed-point variant not available", reason))
    t(f"#endif /* {P}FIXED_POINT */")


def _fixed_body(t: _Text, check: ExportCheck, N: str, P: str, artifact, drive) -> None:
    """The Q31 section (``templates/fixed.c.j2``); numbers formatted and
    range-checked here, in line order."""
    # the header's one template environment; in-function: c_header imports this module
    from .c_header import _render
    plan = check.fixed
    key = _law_key(artifact)
    head = {"I_MAX": f"{plan.I_MAX:.6g}", "W_MAX": f"{plan.W_MAX:.6g}",
            "V_MAX": f"{plan.V_MAX:.6g}",
            "bounds": [(ax, f"{check.fixed_error_bound[ax]:.3g}", f"{HORIZON * 1e3:g}")
                       for ax in AXES if ax in check.fixed_error_bound]}
    d = {"I_BASE": _f(plan.I_BASE, 'motor.max_current', 'Q31_I_BASE'),
         "V_BASE": _f(plan.V_BASE, 'drive.vdc', 'Q31_V_BASE'),
         "W_BASE": _f(plan.W_BASE, 'drive.max_speed', 'Q31_W_BASE'),
         "I_MAX": _f(plan.I_MAX, 'motor.max_current', 'Q31_I_MAX'),
         "W_MAX": _f(plan.W_MAX, 'drive.max_speed', 'Q31_W_MAX'),
         "I_PL": _f(PLAUSIBLE_MARGIN * plan.I_MAX, 'motor.max_current', 'Q31_I_PLAUSIBLE'),
         "W_PL": _f(PLAUSIBLE_MARGIN * plan.W_MAX, 'drive.max_speed', 'Q31_W_PLAUSIBLE'),
         "I_MAX_W": _q31(_word(plan.I_MAX, plan.I_BASE), 'motor.max_current', 'Q31_I_MAX_W'),
         "W_MAX_W": _q31(_word(plan.W_MAX, plan.W_BASE), 'drive.max_speed', 'Q31_W_MAX_W'),
         "I_PL_W": _q31(_word(PLAUSIBLE_MARGIN * plan.I_MAX, plan.I_BASE), 'motor.max_current',
                        'Q31_I_PLAUSIBLE_W'),
         "W_PL_W": _q31(_word(PLAUSIBLE_MARGIN * plan.W_MAX, plan.W_BASE), 'drive.max_speed',
                        'Q31_W_PLAUSIBLE_W'),
         "V_MAX": _q31(plan.vmax_q31, 'drive.vdc', 'Q31_V_MAX'),
         "VDC_BASE": (_f(plan.V_BASE * drive.vdc / check.v_max, 'drive.vdc', 'Q31_VDC_BASE')
                      if drive is not None and drive.vdc > 0 else None)}
    state_bases = [(ax.upper(), i, _f(s, key, f'Q31 {ax}-axis state base'))
                   for ax in AXES for i, s in enumerate(plan.axes[ax].S)]
    dec = [(name.upper(), _q31(m, 'motor', f'Q31 decoupling {name}'), f"{val:.6g}",
            _shift(F, 'motor', f'Q31 decoupling {name} shift'))
           for name, (m, F, val) in plan.dec.items()]
    pi = []
    for ax, kp, ki in _informational_pi_gains(artifact):
        rows = []
        for label, val in (("Kp", kp * plan.I_BASE / plan.V_BASE),
                           ("Ki Ts", ki * artifact.sample_time * plan.I_BASE / plan.V_BASE)):
            q = _fixed._quantise_row(np.array([val]), 1)
            if q is not None:
                rows.append((label, _q31(q[0][0], key, f'Q31 {ax}-axis {label}'),
                             _int(q[1], key, f'Q31 {ax}-axis {label} divisor', 0, 62),
                             f"{val:.6g}"))
        pi.append((ax, rows))
    axes = []
    for ax in AXES:
        fa = plan.axes[ax]
        n = fa.S.size
        shifts = ", ".join(_shift(F, key, f"Q31 {ax}-axis shift") for _, F in fa.rows)
        has_aw = bool(n) and any(m[n + 2] != 0 for m, _ in fa.rows)
        axes.append({
            "ax": ax, "n": n, "fa": shifts,
            "co": ", ".join(_q31(v, key, f"Q31 {ax}-axis output row") for v in fa.out[0]),
            "Fo": _shift(fa.out[1], key, f"Q31 {ax}-axis output shift"),
            "rows": [", ".join(_q31(v, key, f"Q31 {ax}-axis state row") for v in m)
                     for m, _ in fa.rows],
            "aw": ", ".join(_q31(m[n + 2], key, f"Q31 {ax}-axis anti-windup")
                            for m, _ in fa.rows) if has_aw else ""})
    t.lines.extend(_render("fixed.c.j2", N=N, P=P, U=N.upper(), p=P.lower(), head=head, d=d,
                           state_bases=state_bases, dec=dec, pi=pi, axes=axes,
                           comp=_integer_placement(artifact, plan.W_BASE, plan.W_MAX),
                           nd=max(plan.axes["d"].S.size, 1), nq=max(plan.axes["q"].S.size, 1)))
