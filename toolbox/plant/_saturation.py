"""Small-signal models of a saturated motor at an operating point
(toolbox/ARCHITECTURE.md "Saturated motors"): the incremental dq matrices
with the cross inductance, and the tangent constant-parameter motor. The
magnetics themselves are :class:`toolbox.spec.MagneticModel`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["incremental_dq_matrices", "at_operating_point"]


def incremental_dq_matrices(motor, i_d: float, i_q: float,
                            omega: float) -> tuple[np.ndarray, np.ndarray]:
    """Small-signal dq current dynamics of a motor at an operating point.

    Linearising ``d psi/dt = v - R i - omega J psi(i)`` (``derive_flux_linkage_model``) in the current at ``(i_d, i_q)`` and a
    constant electrical speed ``omega`` (rad/s), with ``L = L_inc(i)``
    (``MagneticModel.incremental_inductance``, cross term included)::

        L di/dt = dv - R di - omega J L di,   J = [[0, -1], [1, 0]]
        A = -L^{-1} (R I + omega J L),   B = L^{-1}.

    A constant-parameter motor (``motor.magnetics is None``) has ``L =
    diag(Ld, Lq)`` and gives :func:`toolbox.plant.dq_matrices` exactly.

    Returns
    -------
    A, B : ndarray (2, 2)
    """
    if motor.magnetics is None:
        L = np.diag([motor.Ld, motor.Lq]).astype(float)
    else:
        L = motor.magnetics.incremental_inductance(i_d, i_q)
    Li = np.linalg.inv(L)
    Jm = np.array([[0.0, -1.0], [1.0, 0.0]])
    return -Li @ (motor.R * np.eye(2) + omega * Jm @ L), Li


def at_operating_point(motor, i_d: float, i_q: float):
    """The constant-parameter motor tangent to a saturated one at ``(i_d, i_q)``:
    ``Ld``, ``Lq`` the diagonal incremental inductances there, ``flux`` the
    intercept ``psi_d(i) - Ld i_d``, no magnetics. The per-axis plants
    ``1/(R + s L_inc)`` of :func:`toolbox.plant.axis_plants` of the result are
    the axis plants at that point (the cross term ``L_dq`` is in
    :func:`incremental_dq_matrices`). A constant-parameter motor is returned
    unchanged."""
    if motor.magnetics is None:
        return motor
    L = motor.magnetics.incremental_inductance(i_d, i_q)
    psd, _ = motor.magnetics.flux(i_d, i_q)
    return replace(motor, Ld=float(L[0, 0]), Lq=float(L[1, 1]),
                   flux=float(psd) - float(L[0, 0]) * i_d, magnetics=None)
