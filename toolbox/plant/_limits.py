"""Operating limits of a motor on a drive (speed range of the analyses)."""

from __future__ import annotations

__all__ = ["max_electrical_speed"]


def max_electrical_speed(motor, drive=None) -> float:
    """Highest electrical speed the analyses consider (rad/s).

    The mechanical speed is, in this order: ``drive.max_speed``;
    ``motor.rated_speed``; the speed where the back-EMF ``p omega psi``
    reaches the drive's largest voltage ``drive.max_voltage(convention)``
    (no field weakening); 0 without a drive. It is multiplied by the pole
    pairs.

    Parameters
    ----------
    motor : Motor
        ``pole_pairs``, ``flux`` (Wb), ``rated_speed`` (mechanical rad/s,
        optional) and ``convention``.
    drive : Drive, optional
        ``max_speed`` (mechanical rad/s, optional) and ``max_voltage``.

    Returns
    -------
    float
        Electrical speed (rad/s), >= 0.
    """
    if drive is not None and getattr(drive, "max_speed", None):
        mech = drive.max_speed
    elif getattr(motor, "rated_speed", None):
        mech = motor.rated_speed
    elif drive is not None:
        mech = drive.max_voltage(motor.convention) / (motor.pole_pairs * motor.flux)
    else:
        mech = 0.0
    return float(mech) * motor.pole_pairs
