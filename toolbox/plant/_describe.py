"""Readable forms of the derived model for one motor (``cct derive``)."""

from __future__ import annotations

import sympy as sp

from ._symbolic import SYMBOLS as S
from ._symbolic import derive_dq_model

__all__ = ["describe_model"]


def _equations(motor) -> list[tuple[str, sp.Expr, sp.Expr]]:
    model = derive_dq_model(motor.convention)
    values = {S["R"]: motor.R, S["L_d"]: motor.Ld, S["L_q"]: motor.Lq,
              S["psi_f"]: motor.flux, S["p"]: motor.pole_pairs, S["J"]: motor.J,
              S["F"]: motor.friction}
    did, diq, dW = (sp.Symbol(r"\frac{d i_d}{d t}"), sp.Symbol(r"\frac{d i_q}{d t}"),
                    sp.Symbol(r"\frac{d \Omega}{d t}"))
    eqs = model.state_equations()
    out = [("di_d/dt", did, eqs[0]), ("di_q/dt", diq, eqs[1]),
           ("T_e", sp.Symbol("T_e"), model.torque), ("dOmega/dt", dW, eqs[2])]
    return [(name, lhs, rhs.subs(values).evalf(6)) for name, lhs, rhs in out] + [
        (f"{name} (symbolic)", lhs, rhs) for name, lhs, rhs in out]


def describe_model(motor, fmt: str = "text") -> str:
    """The dq model of ``motor`` as text, LaTeX or Markdown.

    Parameters
    ----------
    motor : Motor
    fmt : {"text", "latex", "markdown"}

    Returns
    -------
    str
        Symbolic equations (derived, :func:`~toolbox.plant.derive_dq_model`)
        followed by the same with the motor's numbers.
    """
    eqs = _equations(motor)
    head = (f"dq model, {motor.convention}-invariant Park transform "
            f"(torque factor {motor.torque_factor:g}); omega = p Omega, Omega mechanical (rad/s)")
    ordered = [e for e in eqs if e[0].endswith("(symbolic)")] + [
        e for e in eqs if not e[0].endswith("(symbolic)")]
    if fmt == "latex":
        lines = [f"% {head}", r"\begin{align}"]
        lines += [rf"{sp.latex(lhs)} &= {sp.latex(rhs)} \\" for _, lhs, rhs in ordered]
        lines.append(r"\end{align}")
        return "\n".join(lines) + "\n"
    if fmt == "markdown":
        lines = [f"**{head}**", ""]
        lines += [f"$$ {sp.latex(lhs)} = {sp.latex(rhs)} $$" for _, lhs, rhs in ordered]
        return "\n".join(lines) + "\n"
    lines = [head, ""]
    for name, _, rhs in ordered:
        lines.append(f"{name} = {sp.sstr(rhs)}")
    return "\n".join(lines) + "\n"
