"""Symbolic derivation of the PMSM dq model from the three-phase equations.

Starting point (phase quantities, electrical rotor angle ``theta`` of the d
axis from phase a)::

    v_abc = R i_abc + d/dt psi_abc
    psi_abc = L_abc(theta) i_abc + psi_f [cos theta, cos(theta - 2pi/3), cos(theta + 2pi/3)]
    L_xy(theta) = L_s delta_xy + L_0 cos(phi_x - phi_y) + L_2 cos(2 theta - phi_x - phi_y)

(salient rotor: the ``L_2`` terms vary at twice the electrical angle). The
Park transform (amplitude-invariant 2/3, or power-invariant sqrt(2/3)) turns
this into the rotor-frame model; the torque follows from the co-energy
``W = 1/2 i^T L i + i^T psi_f`` as ``T = p dW/dtheta`` at constant currents.

The results are checked against paper 000 eq (1)-(2) (Le Pioufle 1992),
paper 003 eq (3)-(7) (Azaiz 2007) and paper 002 eq (4)-(8) (Cormerais 2002)
in ``tests/plant/test_symbolic.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from .._cache import cached

__all__ = ["SYMBOLS", "DqModel", "park_matrix", "derive_dq_model"]

CONVENTIONS = ("amplitude", "power")

R, L_s, L_0, L_2, psi_pm = sp.symbols("R L_sigma L_0 L_2 psi_pm", positive=True)
L_d, L_q, psi_f, p, J, F = sp.symbols("L_d L_q psi_f p J F", positive=True)
i_d, i_q, v_d, v_q, omega, Omega, theta, T_L = sp.symbols(
    "i_d i_q v_d v_q omega Omega theta T_L", real=True)
di_d, di_q = sp.symbols("di_d di_q", real=True)  # current derivatives in ``voltage``

#: Public symbols of the derived model (names as in the docstrings).
SYMBOLS = dict(R=R, L_d=L_d, L_q=L_q, psi_f=psi_f, p=p, J=J, F=F, i_d=i_d, i_q=i_q,
               v_d=v_d, v_q=v_q, omega=omega, Omega=Omega, theta=theta, T_L=T_L,
               di_d=di_d, di_q=di_q)

_PHASES = (0, 2 * sp.pi / 3, -2 * sp.pi / 3)  # phase axes a, b, c (electrical rad)


def park_matrix(th: sp.Expr, convention: str = "amplitude") -> sp.Matrix:
    """Park transform dq0 <- abc at electrical angle ``th``.

    Parameters
    ----------
    th : sympy.Expr
        Electrical angle of the d axis from phase a (rad).
    convention : {"amplitude", "power"}
        Scaling of the transform (see below).

    ``amplitude``: k = 2/3, zero row 1/2 (amplitude-invariant, used by papers
    000 and 003 and most drives). ``power``: k = sqrt(2/3), zero row
    1/sqrt(2) (power-invariant, paper 002 eq (2)-(3); the q row is
    ``-sin`` so that q leads d, see the test note on paper 002's printed
    ``+sin``).
    """
    if convention not in CONVENTIONS:
        raise ValueError(f"convention: expected one of {CONVENTIONS}, got {convention!r}")
    k, z = ((sp.Rational(2, 3), sp.Rational(1, 2)) if convention == "amplitude"
            else (sp.sqrt(sp.Rational(2, 3)), 1 / sp.sqrt(2)))
    return k * sp.Matrix([[sp.cos(th - ph) for ph in _PHASES],
                          [-sp.sin(th - ph) for ph in _PHASES],
                          [z / k for _ in _PHASES]])


def _phase_inductance(th: sp.Expr) -> sp.Matrix:
    return sp.Matrix(3, 3, lambda x, y: (L_s if x == y else 0)
                     + L_0 * sp.cos(_PHASES[x] - _PHASES[y])
                     + L_2 * sp.cos(2 * th - _PHASES[x] - _PHASES[y]))


def _pm_flux(th: sp.Expr) -> sp.Matrix:
    return sp.Matrix([psi_pm * sp.cos(th - ph) for ph in _PHASES])


_c, _s = sp.symbols("c s", real=True)
#: Groebner basis of the relation between c = cos(theta) and s = sin(theta).
_UNIT_CIRCLE = [_c**2 + _s**2 - 1]


def _to_cs(expr: sp.Expr) -> sp.Expr:
    """``expr`` with every angle expanded into ``cos(theta)``, ``sin(theta)``,
    written as the polynomial variables ``c, s``."""
    e = sp.expand_trig(sp.expand(sp.sympify(expr)))
    return e.subs({sp.sin(theta): _s, sp.cos(theta): _c})


def _reduce(poly: sp.Expr) -> sp.Expr:
    """Normal form of a polynomial in ``c, s`` modulo ``c^2 + s^2 - 1``."""
    return sp.reduced(sp.expand(poly), _UNIT_CIRCLE, _s, _c)[1]


def _simplify(expr: sp.Expr) -> sp.Expr:
    """Exact simplification of trigonometric polynomials in ``theta``.

    Expands every angle into ``cos(theta)``, ``sin(theta)``, replaces them by
    ``c, s`` and reduces numerator and denominator modulo ``c^2 + s^2 - 1``
    (a Groebner-basis normal form, so identities are decided exactly).
    """
    return _simplify_cs(_to_cs(expr))


def _simplify_cs(e: sp.Expr) -> sp.Expr:
    """:func:`_simplify` of an expression already written in ``c, s``."""
    num, den = sp.fraction(sp.cancel(sp.together(e)))
    out = sp.cancel(_reduce(num) / _reduce(den)).subs({_s: sp.sin(theta), _c: sp.cos(theta)})
    return sp.simplify(out) if out.has(theta) else sp.factor_terms(sp.expand(out))


def _simplified_product(*factors: sp.Matrix) -> sp.Matrix:
    """:func:`_simplify` of each entry of the product of ``factors``, multiplied as
    polynomials in ``c, s``: the same expanded polynomials as expanding the
    trigonometric product, without ``expand_trig`` on the long product
    terms (four times faster on ``T L_abc T^-1``)."""
    prod = factors[0].applyfunc(_to_cs)
    for f in factors[1:]:
        prod = prod * f.applyfunc(_to_cs)
    return prod.applyfunc(lambda e: _simplify_cs(sp.expand(e)))


def _trig_inverse(m: sp.Matrix) -> sp.Matrix:
    """Exact inverse of a matrix of trigonometric polynomials in ``theta``
    (the Park transform), simplified as :func:`_simplify`.

    The adjugate over the polynomials in ``c, s`` divided by the determinant
    reduced modulo ``c^2 + s^2 - 1`` (a constant for a Park matrix): equal
    to ``m.inv()`` (Gaussian elimination on the trigonometric entries, whose
    results :func:`_simplify` did not always bring to their simplest form),
    in a sixth of the time (0.6-0.8 s of the 2 s derivation).
    """
    cs = m.applyfunc(_to_cs)
    det = _reduce(cs.det(method="berkowitz"))
    return (cs.adjugate(method="berkowitz") / det).applyfunc(_simplify_cs)


@dataclass(frozen=True)
class DqModel:
    """The derived rotor-frame model (sympy expressions).

    Attributes
    ----------
    convention : str
        ``amplitude`` or ``power`` (Park transform used).
    di_dt : sympy.Matrix
        ``[di_d/dt, di_q/dt]`` in ``i_d, i_q, v_d, v_q, omega`` (electrical
        speed, rad/s) and ``R, L_d, L_q, psi_f`` (A/s).
    voltage : sympy.Matrix
        ``[v_d, v_q]`` as the stator voltage equations (V), with the current
        derivatives as symbols ``Derivative(i_d(t), t)`` replaced by
        ``di_d, di_q``.
    torque : sympy.Expr
        Electromagnetic torque (N m) in ``p, psi_f, L_d, L_q, i_d, i_q``.
    dOmega_dt : sympy.Expr
        Mechanical equation ``(T - F Omega - T_L)/J`` (rad/s^2).
    inductance_map : dict
        ``L_d``, ``L_q`` and ``psi_f`` in terms of the phase quantities
        ``L_sigma, L_0, L_2, psi_pm`` (how the dq parameters arise).
    """

    convention: str
    di_dt: sp.Matrix
    voltage: sp.Matrix
    torque: sp.Expr
    dOmega_dt: sp.Expr
    inductance_map: dict

    def state_equations(self) -> sp.Matrix:
        """``d/dt [i_d, i_q, Omega]`` with ``omega = p Omega`` (full model)."""
        return sp.Matrix([*self.di_dt.subs(omega, p * Omega), self.dOmega_dt])


@lru_cache(maxsize=None)
def derive_dq_model(convention: str = "amplitude") -> DqModel:
    """Derive the dq model of a salient PMSM from its phase equations.

    The result is cached in memory and on disk, keyed by a hash of this
    module's source and the sympy version (:mod:`toolbox._cache`);
    ``_derive_dq_model`` always derives.

    Parameters
    ----------
    convention : {"amplitude", "power"}
        Park transform: amplitude-invariant (2/3; torque carries 3/2) or
        power-invariant (sqrt(2/3); torque factor 1).

    Returns
    -------
    DqModel
        Voltage equations (paper 003 eq (3)-(4)), state equations (paper 000
        eq (1)), torque (paper 003 eq (5) / paper 000 eq (2)) and mechanics
        (paper 003 eq (6)-(7)).

    Notes
    -----
    With ``i_abc = T^{-1}(theta) i_dq0`` and ``theta' = omega``::

        v_dq0 = R i_dq0 + d/dt psi_dq0 + omega T dT^{-1}/dtheta psi_dq0,
        psi_dq0 = T L_abc T^{-1} i_dq0 + T psi_f,abc,

    and ``T dT^{-1}/dtheta = [[0, -1, 0], [1, 0, 0], [0, 0, 0]]``.
    """
    if convention not in CONVENTIONS:
        raise ValueError(f"convention: expected one of {CONVENTIONS}, got {convention!r}")
    return cached(f"dq_model-{convention}", __file__, lambda: _derive_dq_model(convention),
                  lambda m: isinstance(m, DqModel) and m.convention == convention)


def _derive_dq_model(convention: str) -> DqModel:
    """The derivation behind :func:`derive_dq_model` (no cache)."""
    th = theta
    T = park_matrix(th, convention)
    Tinv = _trig_inverse(T)
    L_dq = _simplified_product(T, _phase_inductance(th), Tinv)
    psi_dq_pm = _simplified_product(T, _pm_flux(th))
    rot = _simplified_product(T, Tinv.diff(th))

    i_vec = sp.Matrix([i_d, i_q, 0])
    psi = L_dq * i_vec + psi_dq_pm
    v = R * i_vec + L_dq * sp.Matrix([di_d, di_q, 0]) + omega * rot * psi
    v = v.applyfunc(_simplify)

    # dq parameters in terms of the phase ones (read off the derivation)
    Ld_expr, Lq_expr, pm_expr = L_dq[0, 0], L_dq[1, 1], psi_dq_pm[0]
    to_dq = {L_0: sp.solve([sp.Eq(L_d, Ld_expr), sp.Eq(L_q, Lq_expr)], [L_0, L_2])[L_0]}
    to_dq[L_2] = sp.solve([sp.Eq(L_d, Ld_expr), sp.Eq(L_q, Lq_expr)], [L_0, L_2])[L_2]
    to_dq[psi_pm] = sp.solve(sp.Eq(psi_f, pm_expr), psi_pm)[0]

    v_dq = sp.Matrix([v[0], v[1]]).subs(to_dq).applyfunc(sp.simplify)
    sol = sp.solve([sp.Eq(v_d, v_dq[0]), sp.Eq(v_q, v_dq[1])], [di_d, di_q])
    di_dt = sp.Matrix([sp.simplify(sol[di_d]), sp.simplify(sol[di_q])])

    # torque from co-energy at constant phase currents, then back to dq
    ia, ib, ic = sp.symbols("i_a i_b i_c", real=True)
    i_abc = sp.Matrix([ia, ib, ic])
    W = (i_abc.T * _phase_inductance(th) * i_abc)[0] / 2 + (i_abc.T * _pm_flux(th))[0]
    dW = sp.diff(W, th)
    i_abc_dq = Tinv * sp.Matrix([i_d, i_q, 0])
    torque = p * dW.subs({ia: i_abc_dq[0], ib: i_abc_dq[1], ic: i_abc_dq[2]},
                         simultaneous=True)
    torque = sp.factor(_simplify(torque).subs(to_dq))

    return DqModel(convention=convention, di_dt=di_dt, voltage=v_dq, torque=torque,
                   dOmega_dt=(torque - F * Omega - T_L) / J,
                   inductance_map={L_d: Ld_expr, L_q: Lq_expr, psi_f: pm_expr})
