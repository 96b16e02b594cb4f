"""The float path of a linear law's header (``templates/float.c.j2``): per-axis
realisation contexts, anti-windup lines and the state preset
(:func:`preset_coefficients`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._check import AXES
from ._format import _f, _farr, _Text
from ._sos import Realisation


def _axis_context(real: Realisation, ax: str, key: str) -> dict:
    """Template data of one axis linear law (numbers formatted and range-checked)."""
    what = f"{ax}-axis law coefficient"
    n = real.order
    ctx: dict[str, Any] = {"ax": ax, "A": ax.upper(), "form": real.form, "n": n}
    if real.form == "sos":
        co = real.cmsis_coefficients()
        ctx["m"] = co.shape[0]
        ctx["rows"] = [_farr(row, key, what) for row in co]
        if co.shape[0] == 0:
            ctx["gain"] = _f(real.gain, key, what)
        return ctx
    ctx["d0"] = _f(real.D[0, 0], key, what)
    ctx["d1"] = _f(real.D[0, 1], key, what)
    if n:
        ctx.update(a=_farr(real.A.ravel(), key, what), b=_farr(real.B.ravel(), key, what),
                   c=_farr(real.C.ravel(), key, what))
    return ctx


def _aw_lines(real: Realisation, field_: str, dv: str, key: str) -> list[str]:
    out = []
    for i, a in enumerate(real.aw):
        if a != 0.0:
            out.append(f"    s->{field_}[{i}] += {_f(a, key, f'{field_}-axis anti-windup gain')} * {dv};")
    return out


def preset_coefficients(real: Realisation) -> tuple[np.ndarray, np.ndarray]:
    """The bumpless-transfer state of one axis law: ``x = g c + H u``.

    For inputs ``u = [i_ref, i_meas]`` held and a wanted linear-law output
    ``v``, ``c = v - D u``; ``x`` solves ``C x = c`` exactly (the next output is
    ``v``) and, among those states, is the closest to the steady-state manifold
    ``(I - A) x = B u`` in least squares: with an integrator (a pole at z = 1)
    on the manifold exactly, so the output stays ``v`` while the error stays
    0. ``[I - A; C]`` has full column rank for an observable (minimal) law,
    which makes the solution unique. In the executed coordinates of ``real``
    (SOS: the df2T states ``x[2k], x[2k+1]`` of stage ``k``).

    Returns
    -------
    (ndarray, ndarray)
        ``g`` (n,) and ``H`` (n, 2); empty for a static law (n = 0).
    """
    n = real.order
    if n == 0:
        return np.zeros(0), np.zeros((0, 2))
    M = np.eye(n) - real.A
    C = real.C.reshape(1, n)
    K = np.block([[M.T @ M, C.T], [C, np.zeros((1, 1))]])
    # right-hand sides for c (unit) and for each input channel of u
    rhs = np.zeros((n + 1, 3))
    rhs[n, 0] = 1.0
    rhs[:n, 1:] = M.T @ real.B
    sol = np.linalg.solve(K, rhs)
    return sol[:n, 0], sol[:n, 1:]


def _preset_context(real: Realisation, key: str, ax: str) -> dict:
    what = f"{ax}-axis preset coefficient"
    g, H = preset_coefficients(real)
    ctx = {"n": real.order, "d0": _f(real.D[0, 0], key, what), "d1": _f(real.D[0, 1], key, what),
           "one_dof": real.form == "sos"}
    if real.order:
        # coefficients below 1e-30 are round-off of exact zeros
        clean = lambda a: np.where(np.abs(a) < 1e-30, 0.0, a)  # noqa: E731
        ctx.update(g=_farr(clean(g), key, what), h=_farr(clean(H).ravel(), key, what))
    return ctx


def _float_section(t: _Text, reals: dict, N: str, P: str, key: str, hexagon: bool,
                   comp: bool, plausible: dict | None = None, convention: str = "amplitude",
                   d_priority: bool = False) -> None:
    """The float path (templates/float.c.j2)."""
    # the header's one template environment; in-function: c_header imports this module
    from .c_header import _render
    inputs = ["i_d_ref", "i_q_ref", "i_d", "i_q", "omega_m"] + (["theta_e"] if hexagon else [])
    checks = [f"{N}_finite(in->{v})" for v in inputs]
    aw = _aw_lines(reals["d"], "d", "(vds - vd)", key) + \
        _aw_lines(reals["q"], "q", "(vqs - vq)", key)
    t.lines.extend(_render(
        "float.c.j2", N=N, P=P, U=N.upper(), hexagon=hexagon, comp=comp,
        d_priority=d_priority, nd=max(reals["d"].order, 1), nq=max(reals["q"].order, 1),
        form_d=reals["d"].form, order_d=reals["d"].order,
        form_q=reals["q"].form, order_q=reals["q"].order,
        axes=[_axis_context(reals[ax], ax, key) for ax in AXES],
        checks=checks,
        check_pairs=[" && ".join(checks[i:i + 2]) for i in range(2, len(checks), 2)],
        plausible=plausible, convention=convention,
        presets=[_preset_context(reals[ax], key, ax) for ax in AXES],
        aw=[ln.strip().replace("s->", "nx.") for ln in aw]))
