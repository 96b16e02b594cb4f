"""Linear dq models in closed form: the one place the toolbox writes them.

The symbolic derivation (:mod:`._symbolic`, fed to :class:`ElectricalPlant`)
gives the dq electrical model

``L_d di_d/dt = -R i_d + omega L_q i_q + v_d``,
``L_q di_q/dt = -R i_q - omega L_d i_d - omega psi + v_q``

(paper 003 eq (3)-(4); paper 001 eq (1) per axis). The analyses need it
vectorised over thousands of parameter sets and as scalars per axis; these
closed forms are checked against the sympy-derived :class:`ElectricalPlant`
in ``tests/plant/test_linear.py``, so the model is written once.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["axis_coefficients", "zoh_first_order", "dq_matrices", "steady_state_voltage",
           "voltage_limited_speed"]


def axis_coefficients(R, L):
    """Per-axis model ``di/dt = a i + b v`` without cross-coupling.

    Parameters
    ----------
    R : float or array_like
        Stator resistance (ohm).
    L : float or array_like
        Axis inductance ``Ld`` or ``Lq`` (H).

    Returns
    -------
    a, b : float or ndarray
        ``a = -R/L`` (1/s) and ``b = 1/L`` (1/H): the plant ``1/(R + s L)``
        (paper 001 eq (1)).
    """
    return -R / L, 1.0 / L


def zoh_first_order(R, L, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation of ``1/(R + s L)``: ``i+ = a i + b v``.

    Parameters
    ----------
    R, L : float or array_like
        Resistance (ohm) and inductance (H); broadcast.
    Ts : float
        Sample time (s).

    Returns
    -------
    a, b : ndarray
        ``a = exp(-R Ts/L)``, ``b = (1 - a)/R`` (computed with ``expm1`` so
        that small ``R Ts/L`` keeps full precision).
    """
    R = np.asarray(R, float)
    L = np.asarray(L, float)
    a = np.exp(-R * Ts / L)
    b = -np.expm1(-R * Ts / L) / R
    return a, b


def dq_matrices(R, Ld, Lq, omega) -> tuple[np.ndarray, np.ndarray]:
    """Stacked ``A(omega)`` and ``B`` of the dq current dynamics.

    Parameters
    ----------
    R, Ld, Lq : float or array_like
        Resistance (ohm) and inductances (H).
    omega : float or array_like
        Electrical speed (rad/s); everything broadcasts to N sets.

    Returns
    -------
    A, B : ndarray
        (N, 2, 2) each: ``A = [[-R/Ld, omega Lq/Ld], [-omega Ld/Lq, -R/Lq]]``,
        ``B = diag(1/Ld, 1/Lq)``; equal to :meth:`ElectricalPlant.A` and
        :meth:`ElectricalPlant.B` (the back-EMF ``-omega psi/Lq`` is the
        separate input :meth:`ElectricalPlant.emf`).
    """
    R, Ld, Lq, omega = np.broadcast_arrays(*(np.asarray(v, float) for v in (R, Ld, Lq, omega)))
    R, Ld, Lq, omega = (v.reshape(-1) for v in (R, Ld, Lq, omega))
    N = R.size
    A = np.empty((N, 2, 2))
    A[:, 0, 0] = -R / Ld
    A[:, 0, 1] = omega * Lq / Ld
    A[:, 1, 0] = -omega * Ld / Lq
    A[:, 1, 1] = -R / Lq
    B = np.zeros((N, 2, 2))
    B[:, 0, 0] = 1 / Ld
    B[:, 1, 1] = 1 / Lq
    return A, B


def steady_state_voltage(R, Ld, Lq, flux, omega, i_d, i_q):
    """dq voltage that holds constant currents at a constant speed.

    The model with ``di/dt = 0``: ``v_d = R i_d - omega L_q i_q``,
    ``v_q = R i_q + omega (L_d i_d + psi)`` (paper 003 eq (3)-(4)).

    Parameters
    ----------
    R, Ld, Lq, flux : float or array_like
        Resistance (ohm), inductances (H), magnet flux linkage (Wb).
    omega : float or array_like
        Electrical speed (rad/s).
    i_d, i_q : float or array_like
        The held currents (A).

    Returns
    -------
    v_d, v_q : float or ndarray
        Voltages (V); everything broadcasts.
    """
    return R * i_d - omega * Lq * i_q, R * i_q + omega * (Ld * i_d + flux)


def voltage_limited_speed(motor, v_max: float, iq: float) -> float:
    """Mechanical speed at which ``i_q = iq, i_d = 0`` uses the whole voltage (rad/s).

    The steady state of :func:`steady_state_voltage`, ``v_d = -w Lq iq``,
    ``v_q = R iq + w psi`` (``w`` the electrical speed, ``psi`` the flux in
    the motor's convention, ``v_max`` in the same convention) meets
    ``|v| = v_max`` at the positive root of
    ``(Lq^2 iq^2 + psi^2) w^2 + 2 R iq psi w + R^2 iq^2 - v_max^2 = 0``;
    ``0`` when ``R iq`` alone exceeds ``v_max``, ``inf`` without flux and
    inductance (nothing grows with speed).
    """
    a = (motor.Lq * iq) ** 2 + motor.flux ** 2
    b = motor.R * iq * motor.flux
    c = (motor.R * iq) ** 2 - v_max ** 2
    if c >= 0:
        return 0.0
    if a == 0:
        return math.inf
    w_e = (-b + math.sqrt(b * b - a * c)) / a
    return w_e / motor.pole_pairs
