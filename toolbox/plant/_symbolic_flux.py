"""Symbolic derivation of the flux-linkage form of the dq model (saturated motors).

Starting point: the phase equations with an arbitrary (saturable) flux
linkage, ``v_abc = R i_abc + d/dt psi_abc``, no assumption on how psi_abc
depends on the currents. The Park transform ``T(theta)``
(:func:`toolbox.plant._symbolic.park_matrix`, both conventions) with
``psi_dq0 = T psi_abc``, ``theta' = omega`` gives::

    v_dq0 = R i_dq0 + T d/dt (T^{-1} psi_dq0)
          = R i_dq0 + d psi_dq0/dt + omega T dT^{-1}/dtheta psi_dq0,

that is ``d psi/dt = v - R i - omega J psi`` with ``J = [[0, -1], [1, 0]]``
(the state equation of the simulator for saturated motors,
toolbox/ARCHITECTURE.md "Saturated motors"). The torque follows from the
power balance: the input power ``p_abc = v_abc^T i_abc = k v_dq^T i_dq``
(``k = 3/2`` amplitude-invariant, 1 power-invariant) splits into copper
loss, the magnetic energy rate ``k i^T d psi/dt`` and the part proportional
to the speed, ``k omega (psi_d i_q - psi_q i_d) = T Omega``, hence
``T = k p (psi_d i_q - psi_q i_d)``. With the linear magnetics
``psi_d = L_d i_d + psi_f``, ``psi_q = L_q i_q`` both reduce to
:func:`toolbox.plant._symbolic.derive_dq_model` (``tests/plant``).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ._symbolic import CONVENTIONS, SYMBOLS, _trig_inverse, park_matrix

__all__ = ["FluxLinkageModel", "derive_flux_linkage_model"]

psi_d, psi_q = sp.symbols("psi_d psi_q", real=True)
t = sp.Symbol("t", real=True)


@dataclass(frozen=True)
class FluxLinkageModel:
    """The flux-linkage form (sympy expressions).

    Attributes
    ----------
    convention : str
    dpsi_dt : sympy.Matrix
        ``[d psi_d/dt, d psi_q/dt]`` in ``v_d, v_q, R, i_d, i_q, omega,
        psi_d, psi_q``.
    torque : sympy.Expr
        ``k p (psi_d i_q - psi_q i_d)`` (N m).
    power_factor : sympy.Expr
        ``k`` of ``p_abc = k v_dq^T i_dq``.
    """

    convention: str
    dpsi_dt: sp.Matrix
    torque: sp.Expr
    power_factor: sp.Expr


def derive_flux_linkage_model(convention: str = "amplitude") -> FluxLinkageModel:
    """Derive ``d psi/dt`` and the torque from the phase equations (module docstring).

    Parameters
    ----------
    convention : {"amplitude", "power"}

    Returns
    -------
    FluxLinkageModel
    """
    if convention not in CONVENTIONS:
        raise ValueError(f"convention: expected one of {CONVENTIONS}, got {convention!r}")
    S = SYMBOLS
    th = sp.Function("theta")(t)
    T = park_matrix(th, convention)
    Tinv = _trig_inverse(T)
    pd, pq = sp.Function("psi_d")(t), sp.Function("psi_q")(t)
    psi_dq0 = sp.Matrix([pd, pq, 0])
    # v_dq0 - R i_dq0 = T d/dt (T^{-1} psi_dq0)
    emf = (T * (Tinv * psi_dq0).diff(t)).applyfunc(sp.simplify)
    emf = emf.subs(sp.Derivative(th, t), S["omega"])
    dpd, dpq = sp.symbols("dpsi_d dpsi_q", real=True)
    emf = emf.subs({sp.Derivative(pd, t): dpd, sp.Derivative(pq, t): dpq})
    emf = emf.subs({pd: psi_d, pq: psi_q}).applyfunc(sp.simplify)
    v = sp.Matrix([S["v_d"], S["v_q"]])
    i = sp.Matrix([S["i_d"], S["i_q"]])
    sol = sp.solve([sp.Eq(v[k] - S["R"] * i[k], emf[k]) for k in range(2)], [dpd, dpq])
    dpsi_dt = sp.Matrix([sp.expand(sol[dpd]), sp.expand(sol[dpq])])
    # power balance: k from T^{-T} T^{-1} (the dq block is k times identity)
    G = (Tinv.T * Tinv).applyfunc(sp.simplify)
    k = sp.simplify(G[0, 0])
    # p_in = copper loss + magnetic energy rate + mechanical power (free of v)
    mech = sp.expand(k * (v.T * i)[0] - k * S["R"] * (i.T * i)[0] - k * (i.T * dpsi_dt)[0])
    # mechanical power T Omega = T omega / p
    torque = sp.factor(sp.expand(mech / S["omega"] * S["p"]))
    return FluxLinkageModel(convention=convention, dpsi_dt=dpsi_dt, torque=torque,
                            power_factor=k)
