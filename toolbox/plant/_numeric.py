"""Numeric plants generated from the symbolic derivation (not typed again).

The sympy expressions of :func:`~toolbox.plant.derive_dq_model` are turned
into numpy functions with ``lambdify``; the state matrix, input matrix and
back-EMF disturbance are read off them by differentiation, so any change in
the derivation flows through.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
import inspect

import numpy as np

from toolbox.spec import Motor

from .._cache import cached
from ..lti import StateSpace

__all__ = ["ElectricalPlant", "numeric_plant", "axis_plant_models", "axis_plants", "linearise"]

#: The modules the lambdified code is made from (its cache key).
_SOURCES = (Path(__file__).with_name("_symbolic.py"), Path(__file__))


def _electrical_sources(convention: str) -> tuple[str, str, str]:
    """Source of the lambdified A(omega), B, e(omega) with di/dt = A i + B v + e.

    Raises RuntimeError if the generated code names anything that is not a
    numpy attribute (it could not be re-created from its text alone).
    """
    import sympy as sp  # lazy: sympy, ~480 modules (cold cache only)

    from ._symbolic import SYMBOLS as S  # lazy: sympy, ~490 modules
    from ._symbolic import derive_dq_model  # lazy: sympy, ~490 modules

    model = derive_dq_model(convention)
    x = sp.Matrix([S["i_d"], S["i_q"]])
    u = sp.Matrix([S["v_d"], S["v_q"]])
    A = model.di_dt.jacobian(x)
    B = model.di_dt.jacobian(u)
    e = sp.simplify(model.di_dt - A * x - B * u)
    args = (S["R"], S["L_d"], S["L_q"], S["psi_f"], S["omega"])
    out = []
    for m in (A, B, e):
        f = sp.lambdify(args, m, "numpy")
        for name in f.__code__.co_names:
            if getattr(np, name, None) is not f.__globals__.get(name):
                raise RuntimeError(f"lambdified code uses {name!r}, not a numpy name")
        out.append(inspect.getsource(f))
    return tuple(out)


def _compiled(source: str):
    """The function defined by lambdify's generated ``source``, over numpy's
    namespace (the namespace lambdify gave it: its names are numpy's)."""
    namespace = dict(vars(np))
    exec(compile(source, "<lambdified dq model>", "exec"), namespace)  # noqa: S102
    return namespace["_lambdifygenerated"]


@lru_cache(maxsize=None)
def _electrical_matrices(convention: str):
    """Lambdified A(omega), B, e(omega) with di/dt = A i + B v + e.

    The generated code is cached on disk with the derivation
    (:mod:`toolbox._cache`, keyed by this module's and the derivation's
    sources): a cache hit needs neither sympy nor the derivation.
    """
    sources = cached(f"dq_numeric-{convention}", _SOURCES,
                     lambda: _electrical_sources(convention),
                     lambda v: isinstance(v, tuple) and len(v) == 3
                     and all(isinstance(x, str) for x in v))
    return tuple(_compiled(src) for src in sources)


@dataclass(frozen=True)
class ElectricalPlant:
    """The linear dq electrical model ``di/dt = A(omega) i + B v + e(omega)``
    derived for a motor: a model, not a parameter holder.

    The parameters live in the one parameter type, :class:`toolbox.spec.Motor`
    (``motor``); this object evaluates the sympy derivation
    (:func:`~toolbox.plant.derive_dq_model`, lambdified) for them.
    ``omega`` is the electrical speed ``p * Omega`` (rad/s); currents in A,
    voltages in V. Built by :func:`numeric_plant`. The vectorised closed
    forms of :mod:`._linear` are tested equal to it.

    Parameters
    ----------
    motor : toolbox.spec.Motor
        The motor (``R``, ``Ld``, ``Lq``, ``flux`` and its dq ``convention``
        are read).
    """

    motor: Motor

    def _args(self, omega: float) -> tuple:
        m = self.motor
        return (m.R, m.Ld, m.Lq, m.flux, float(omega))

    def _matrices(self):
        return _electrical_matrices(self.motor.convention)

    def A(self, omega: float = 0.0) -> np.ndarray:
        """State matrix at electrical speed ``omega`` (1/s)."""
        return np.array(self._matrices()[0](*self._args(omega)), float)

    def B(self) -> np.ndarray:
        """Input matrix diag(1/Ld, 1/Lq) (1/H)."""
        return np.array(self._matrices()[1](*self._args(0.0)), float)

    def emf(self, omega: float) -> np.ndarray:
        """Back-EMF disturbance term of di/dt (A/s), ``[0, -omega flux/Lq]``."""
        return np.array(self._matrices()[2](*self._args(omega)), float).reshape(2)

    def statespace(self, omega: float = 0.0) -> StateSpace:
        """Two-input two-output system v -> i at fixed electrical speed
        (:class:`toolbox.lti.StateSpace`)."""
        return StateSpace(self.A(omega), self.B(), np.eye(2), np.zeros((2, 2)))


def numeric_plant(motor: Motor) -> ElectricalPlant:
    """The linear dq model derived for a motor.

    Parameters
    ----------
    motor : toolbox.spec.Motor
        Parameters (R, Ld, Lq, flux, convention).
    """
    return ElectricalPlant(motor)


def axis_plant_models(motor) -> dict[str, StateSpace]:
    """Decoupled per-axis plants ``1/(R + s L)`` (A/V), paper 003 eq (33)-(34).

    Read off the diagonal of the derived model at standstill, where the axes
    decouple (``A(0)`` and ``B`` diagonal): one state each, ``x = i``,
    ``A = -R/L``, ``B = 1/L``, ``C = 1``, ``D = 0``.

    Parameters
    ----------
    motor : Motor
        Parameters of the plant.

    Returns
    -------
    dict
        ``{"d": StateSpace, "q": StateSpace}`` (:class:`toolbox.lti.StateSpace`).
    """
    plant = numeric_plant(motor)
    A, B = plant.A(0.0), plant.B()
    if A[0, 1] != 0.0 or A[1, 0] != 0.0 or B[0, 1] != 0.0 or B[1, 0] != 0.0:
        raise RuntimeError(f"the derived dq model is coupled at standstill: A(0) = {A}, B = {B}")
    return {ax: StateSpace(A[k:k + 1, k:k + 1], B[k:k + 1, k:k + 1], [[1.0]], [[0.0]])
            for k, ax in enumerate(("d", "q"))}


def axis_plants(motor) -> dict:
    """The plants of :func:`axis_plant_models` as python-control transfer functions.

    Imports python-control (about 1 s with the scipy.signal and
    matplotlib.pyplot it pulls in): for users and for the H-infinity design
    until it reads :func:`axis_plant_models`. The transfer
    functions are SLICOT's (``tb04ad``) of the two-state model's diagonal
    entries, as before that function existed.

    Parameters
    ----------
    motor : Motor
        Parameters of the plant.

    Returns
    -------
    dict
        ``{"d": control.TransferFunction, "q": control.TransferFunction}``.
    """
    import control  # lazy: python-control, 687 modules

    sys = numeric_plant(motor).statespace(0.0).to_control()
    return {"d": control.ss2tf(sys[0, 0]), "q": control.ss2tf(sys[1, 1])}


@lru_cache(maxsize=None)
def _full_jacobians(convention: str):
    import sympy as sp  # lazy: sympy, ~480 modules (cold cache only)

    from ._symbolic import SYMBOLS as S  # lazy: sympy, ~490 modules
    from ._symbolic import derive_dq_model  # lazy: sympy, ~490 modules

    model = derive_dq_model(convention)
    f = model.state_equations()
    x = sp.Matrix([S["i_d"], S["i_q"], S["Omega"]])
    u = sp.Matrix([S["v_d"], S["v_q"], S["T_L"]])
    args = (S["R"], S["L_d"], S["L_q"], S["psi_f"], S["p"], S["J"], S["F"],
            *x, *u)
    return (sp.lambdify(args, f.jacobian(x), "numpy"),
            sp.lambdify(args, f.jacobian(u), "numpy"))


def linearise(motor, i_d0: float, i_q0: float, Omega0: float) -> tuple[StateSpace, np.ndarray]:
    """Linearise the electromechanical model at an operating point.

    States ``[i_d, i_q, Omega]`` (A, A, rad/s mechanical), inputs
    ``[v_d, v_q, T_L]`` (V, V, N m), outputs the states. The operating-point
    voltages are those that hold the currents constant; the load torque is
    the one that holds the speed constant.

    Parameters
    ----------
    motor : Motor
        Motor parameters (SI).
    i_d0, i_q0 : float
        Operating-point currents (A).
    Omega0 : float
        Operating-point mechanical speed (rad/s).

    Returns
    -------
    sys : toolbox.lti.StateSpace
        The small-signal model.
    u0 : ndarray
        Operating-point inputs ``[v_d0, v_q0, T_L0]``.
    """
    from ._symbolic import SYMBOLS as S  # lazy: sympy, ~490 modules
    from ._symbolic import derive_dq_model  # lazy: sympy, ~490 modules

    jx, ju = _full_jacobians(motor.convention)
    model = derive_dq_model(motor.convention)
    w = motor.pole_pairs * Omega0
    subs = {S["R"]: motor.R, S["L_d"]: motor.Ld, S["L_q"]: motor.Lq,
            S["psi_f"]: motor.flux, S["omega"]: w, S["i_d"]: i_d0, S["i_q"]: i_q0,
            S["p"]: motor.pole_pairs, S["F"]: motor.friction, S["Omega"]: Omega0,
            S["di_d"]: 0, S["di_q"]: 0}
    v0 = [float(model.voltage[k].subs(subs)) for k in range(2)]
    T_L0 = float((model.torque - S["F"] * S["Omega"]).subs(subs))
    point = (motor.R, motor.Ld, motor.Lq, motor.flux, motor.pole_pairs, motor.J,
             motor.friction, i_d0, i_q0, Omega0, v0[0], v0[1], T_L0)
    A = np.array(jx(*point), float)
    B = np.array(ju(*point), float)
    return StateSpace(A, B, np.eye(3), np.zeros((3, 3))), np.array([*v0, T_L0])
