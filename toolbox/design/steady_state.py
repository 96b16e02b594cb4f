"""Symbolic steady-state analysis of dq current controllers (paper 000).

Le Pioufle, Georgiou, Louis, J. Phys. III 2 (1992). Each controller is
closed on the dq plant ``di/dt = f(i, v, omega)`` derived by
:func:`toolbox.plant.derive_dq_model` (not retyped here), with
``omega = p Omega``; sympy then derives the steady state.

(a) PI (or 000's IP) in dq under constant acceleration ``gamma = dOmega/dt``,
    eq (3)-(7). ``Omega = gamma t`` grows, so the currents cannot be found
    from ``di/dt = 0`` alone (the integrators must keep ramping to follow the
    back-EMF). The paper's method: differentiate the closed loop (3) in time,
    which gives eq (4) (the integral states differentiate into the errors,
    Omega into gamma), then set ``d^2 i/dt^2 = di/dt = 0``: a linear system
    in the currents whose solution is eq (6)-(7).
(b) Total compensation (eq (11)) with a speed-measurement error
    ``Omega_m != Omega`` at constant speed, eq (14)-(17): ``di/dt = 0``.
(c) Total compensation with integrators (eq (20)) under constant
    acceleration and a speed sensor ``Omega_m = (1 + lambda) Omega + Omega_0``
    (eq (28)), eq (25)-(31): the method of (a).

Functions return sympy expressions; ``*_values`` functions evaluate them for
a :class:`~toolbox.spec.Motor` (A).
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

import sympy as sp

from .._cache import cached
from ..plant import SYMBOLS as S
from ..plant import derive_dq_model

__all__ = ["SS_SYMBOLS", "pi_law_voltages", "tc_law_voltages", "pi_acceleration_derivative",
           "pi_acceleration_steady_state", "tc_speed_error_steady_state",
           "tc_closed_loop_matrices", "tci_acceleration_steady_state",
           "pi_acceleration_values", "tc_speed_error_values", "tci_acceleration_values"]

E, k_i, K_p, K_I = sp.symbols("E k_i K_p K_I", positive=True)
K_1, K_2, K_11, K_12, K_21, K_22 = sp.symbols("K_1 K_2 K_11 K_12 K_21 K_22", positive=True)
gamma, lam, Omega_0, Omega_m, sigma = sp.symbols("gamma lambda Omega_0 Omega_m sigma", real=True)
i_dref, i_qref, z_d, z_q = sp.symbols("i_dref i_qref z_d z_q", real=True)
di_d, di_q = sp.symbols("di_d di_q", real=True)
R_c, L_dc, L_qc, psi_fc = sp.symbols("R_c L_dc L_qc psi_fc", positive=True)

#: Symbols used in the returned expressions (besides :data:`toolbox.plant.SYMBOLS`).
SS_SYMBOLS = dict(E=E, k_i=k_i, K_p=K_p, K_I=K_I, K_1=K_1, K_2=K_2, K_11=K_11, K_12=K_12,
                  K_21=K_21, K_22=K_22, gamma=gamma, lam=lam, Omega_0=Omega_0,
                  Omega_m=Omega_m, sigma=sigma, i_dref=i_dref, i_qref=i_qref, z_d=z_d,
                  z_q=z_q, di_d=di_d, di_q=di_q, R_c=R_c, L_dc=L_dc, L_qc=L_qc,
                  psi_fc=psi_fc)

_i = (S["i_d"], S["i_q"])
_ref = (i_dref, i_qref)
_z = (z_d, z_q)


def _closed_loop(convention: str, v: tuple[sp.Expr, sp.Expr]) -> sp.Matrix:
    """``di/dt`` of the derived plant with ``v`` applied and ``omega = p Omega``."""
    f = derive_dq_model(convention).di_dt
    return f.subs({S["v_d"]: v[0], S["v_q"]: v[1]}, simultaneous=True).subs(
        S["omega"], S["p"] * S["Omega"])


def pi_law_voltages(structure: str = "pi") -> tuple[sp.Expr, sp.Expr]:
    """000 Fig. 2: dq voltages of the PI (or IP) with integral states ``z``.

    Parameters
    ----------
    structure : {"pi", "ip"}
        ``pi``: ``v = E k_i (K_p e + K_I z)``; ``ip`` (000's IP, "P.I.
        without zero"): ``v = E k_i K_p (K_I z - i)``; ``z' = e = i_ref - i``.

    Returns
    -------
    tuple of sympy.Expr
        ``(v_d, v_q)`` (V).
    """
    if structure == "pi":
        return tuple(E * k_i * (K_p * (_ref[k] - _i[k]) + K_I * _z[k]) for k in (0, 1))
    if structure == "ip":
        return tuple(E * k_i * K_p * (K_I * _z[k] - _i[k]) for k in (0, 1))
    raise ValueError(f"structure: expected 'pi' or 'ip', got {structure!r}")


def _time_derivative(f: sp.Matrix, rates: dict) -> sp.Matrix:
    """Chain rule ``df/dt = sum_x df/dx * x'`` over the given state rates."""
    return sp.Matrix([sum(sp.diff(fk, x) * r for x, r in rates.items()) for fk in f])


def _solve_currents(eqs: sp.Matrix) -> dict:
    """``{i_d: expr, i_q: expr}`` solving ``eqs = 0``, simplified. Cached on disk
    like the dq model the equations start from (``toolbox/_cache.py``): keyed by
    the equations (their ``srepr``), this module's source and sympy's version."""
    digest = hashlib.sha256(sp.srepr(eqs).encode()).hexdigest()[:16]
    return cached(f"steady_state-{digest}", __file__, lambda: _solve(eqs),
                  lambda v: isinstance(v, dict) and set(v) == set(_i))


def _solve(eqs: sp.Matrix) -> dict:
    sol = sp.solve(list(eqs), list(_i), dict=True)
    if len(sol) != 1:
        raise ArithmeticError("steady state: expected one solution for (i_d, i_q)")
    return {k: sp.simplify(sol[0][k]) for k in _i}


@lru_cache(maxsize=None)
def pi_acceleration_derivative(convention: str = "amplitude",
                               structure: str = "pi") -> sp.Matrix:
    """000 eq (4): time derivative of the closed loop (3) at constant acceleration.

    Returns ``[d^2 i_d/dt^2, d^2 i_q/dt^2]`` in ``di_d, di_q`` (the current
    derivatives), the currents, ``Omega`` and ``gamma`` (A/s^2).
    """
    f = _closed_loop(convention, pi_law_voltages(structure))
    rates = {_i[0]: di_d, _i[1]: di_q, z_d: i_dref - _i[0], z_q: i_qref - _i[1],
             S["Omega"]: gamma}
    return _time_derivative(f, rates).applyfunc(sp.expand)


@lru_cache(maxsize=None)
def pi_acceleration_steady_state(convention: str = "amplitude",
                                 structure: str = "pi") -> dict:
    """000 eq (6)-(7): PI (or IP) steady currents at constant acceleration.

    Eq (4) with ``d^2 i/dt^2 = di/dt = 0`` solved for the currents.

    Returns
    -------
    dict
        ``{i_d: expr, i_q: expr}`` in ``E, k_i, K_p, K_I, gamma, i_dref,
        i_qref, p, L_d, L_q, psi_f`` (A). For ``ip``, ``K_I`` is replaced
        by ``K_p K_I`` (000 sect. 2, note on the IP controller).
    """
    eq4 = pi_acceleration_derivative(convention, structure).subs({di_d: 0, di_q: 0})
    return _solve_currents(eq4)


def tc_law_voltages(mismatch: bool = False, integrators: bool = False) -> tuple:
    """000 eq (11) (or (20) with integrators) with the measured speed ``Omega_m`` (V).

    With ``mismatch`` the controller-side parameters ``R_c, L_dc, L_qc,
    psi_fc`` (eq (12)) replace the plant's.
    """
    R, Ld, Lq, psi = ((R_c, L_dc, L_qc, psi_fc) if mismatch
                      else (S["R"], S["L_d"], S["L_q"], S["psi_f"]))
    p = S["p"]
    e = (i_dref - _i[0], i_qref - _i[1])
    lin = ((K_11 * e[0] + K_12 * z_d) * Ld, (K_21 * e[1] + K_22 * z_q) * Lq) if integrators \
        else (K_1 * Ld * e[0], K_2 * Lq * e[1])
    return (R * _i[0] - p * Lq * Omega_m * _i[1] + lin[0],
            R * _i[1] + p * Ld * Omega_m * _i[0] + lin[1] + p * psi * Omega_m)


@lru_cache(maxsize=None)
def tc_closed_loop_matrices(convention: str = "amplitude") -> tuple[sp.Matrix, sp.Matrix]:
    """000 eq (14)-(15): ``di/dt = A_bf i + B_bf`` with speed error, ``i_dref = 0``."""
    f = _closed_loop(convention, tc_law_voltages()).subs(i_dref, 0)
    A_bf = f.jacobian(sp.Matrix(_i)).applyfunc(sp.simplify)
    B_bf = (f - A_bf * sp.Matrix(_i)).applyfunc(sp.simplify)
    return A_bf, B_bf


@lru_cache(maxsize=None)
def tc_speed_error_steady_state(convention: str = "amplitude", mismatch: bool = False) -> dict:
    """000 eq (16)-(17): total compensation steady currents with ``Omega_m != Omega``.

    Constant speed, ``di/dt = 0`` of the plant closed by eq (11) using
    ``Omega_m``; general ``i_dref`` (the paper's (14) takes ``i_dref = 0``).

    Returns
    -------
    dict
        ``{i_d: expr, i_q: expr}`` (A) in ``K_1, K_2, Omega, Omega_m, i_dref,
        i_qref`` and the motor symbols (plus ``R_c, L_dc, L_qc, psi_fc``
        with ``mismatch``).
    """
    f = _closed_loop(convention, tc_law_voltages(mismatch))
    return _solve_currents(f)


@lru_cache(maxsize=None)
def tci_acceleration_steady_state(convention: str = "amplitude") -> dict:
    """000 eq (25)-(31): total compensation with integrators, accelerating.

    Speed sensor ``Omega_m = (1 + lambda) Omega + Omega_0`` (eq (28)),
    ``dOmega/dt = gamma``. Method of (a): differentiate the closed loop
    (plant (1) + law (20)), set ``d^2 i/dt^2 = di/dt = 0``, solve.

    Returns
    -------
    dict
        ``{i_d: expr, i_q: expr}`` (A) in ``K_12, K_22, lambda, gamma``,
        references and motor symbols. It equals the printed (25) with
        ``sigma = -lambda gamma`` (eq (30)) only when ``K_12 L_d = K_22 L_q``
        (= the printed ``E k_i K_I``); ``Omega_0`` drops out.
    """
    v = tc_law_voltages(integrators=True)
    f = _closed_loop(convention, v).subs(Omega_m, (1 + lam) * S["Omega"] + Omega_0)
    rates = {_i[0]: di_d, _i[1]: di_q, z_d: i_dref - _i[0], z_q: i_qref - _i[1],
             S["Omega"]: gamma}
    eqs = _time_derivative(f, rates).subs({di_d: 0, di_q: 0})
    return _solve_currents(eqs)


# ------------------------------------------------------------------ numeric
def _motor_subs(motor) -> dict:
    return {S["R"]: motor.R, S["L_d"]: motor.Ld, S["L_q"]: motor.Lq,
            S["psi_f"]: motor.flux, S["p"]: motor.pole_pairs}


def _evaluate(sol: dict, subs: dict) -> tuple[float, float]:
    return tuple(float(sol[k].subs(subs)) for k in _i)


def pi_acceleration_values(motor, Kp: float, Ki: float, acceleration: float, id_ref: float,
                           iq_ref: float, structure: str = "pi") -> tuple[float, float]:
    """Numeric 000 eq (6)-(7): steady currents of the PI in dq while accelerating.

    Parameters
    ----------
    motor : Motor
        Plant parameters (R, Ld, Lq, flux, pole_pairs, convention).
    Kp : float
        Effective proportional gain ``E k_i Kp_n`` (V/A).
    Ki : float
        Effective integral gain ``E k_i KI_n`` (V/(A s)); for ``ip`` 000's
        ``KI_n`` (1/s), the law being ``v = Kp (Ki int e - i)``.
    acceleration : float
        ``gamma = dOmega/dt`` (rad/s^2, mechanical).
    id_ref, iq_ref : float
        Current references (A).
    structure : {"pi", "ip"}
        Controller structure (000 Fig. 2a / 2b).

    Returns
    -------
    tuple of float
        ``(i_d, i_q)`` (A).
    """
    sol = pi_acceleration_steady_state(motor.convention, structure)
    subs = {**_motor_subs(motor), E: 1, k_i: 1, K_p: Kp, K_I: Ki, gamma: acceleration,
            i_dref: id_ref, i_qref: iq_ref}
    return _evaluate(sol, subs)


def tc_speed_error_values(motor, K1: float, K2: float, speed: float, measured_speed: float,
                          id_ref: float, iq_ref: float) -> tuple[float, float]:
    """Numeric 000 eq (16)-(17): total compensation steady currents with a speed error.

    Parameters
    ----------
    motor : Motor
        Plant parameters (the controller uses the same, nominal, values).
    K1, K2 : float
        Error-dynamics gains of eq (8) (1/s).
    speed : float
        True mechanical speed ``Omega`` (rad/s).
    measured_speed : float
        Speed the controller uses, ``Omega_m`` (rad/s).
    id_ref, iq_ref : float
        Current references (A).

    Returns
    -------
    tuple of float
        ``(i_d, i_q)`` (A).
    """
    sol = tc_speed_error_steady_state(motor.convention)
    subs = {**_motor_subs(motor), K_1: K1, K_2: K2, S["Omega"]: speed,
            Omega_m: measured_speed, i_dref: id_ref, i_qref: iq_ref}
    return _evaluate(sol, subs)


def tci_acceleration_values(motor, K12: float, K22: float, acceleration: float,
                            gain_error: float, id_ref: float, iq_ref: float) -> tuple[float, float]:
    """Numeric 000 eq (25)-(31), derived form: total compensation with integrators.

    Parameters
    ----------
    motor : Motor
        Plant parameters (the controller uses the same, nominal, values).
    K12, K22 : float
        Integral error gains of eq (18) (1/s^2), d and q.
    acceleration : float
        ``gamma`` (rad/s^2, mechanical).
    gain_error : float
        lambda of eq (28), ``Omega_m = (1 + lambda) Omega + Omega_0``
        (dimensionless; the offset ``Omega_0`` does not matter).
    id_ref, iq_ref : float
        Current references (A).

    Returns
    -------
    tuple of float
        ``(i_d, i_q)`` (A).
    """
    sol = tci_acceleration_steady_state(motor.convention)
    subs = {**_motor_subs(motor), K_12: K12, K_22: K22, gamma: acceleration,
            lam: gain_error, i_dref: id_ref, i_qref: iq_ref}
    return _evaluate(sol, subs)
