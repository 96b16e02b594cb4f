"""The plausible ranges of the measured signals the float header checks
(:func:`plausibility_limits`) and their template context."""

from __future__ import annotations

import math

from ._format import _f


#: the plausible ranges of the measured signals are this many times the
#: ranges the drive is rated for (a transient overshoot never trips them; an
#: ADC or encoder glitch does)
PLAUSIBLE_MARGIN = 2.0
#: set_vdc accepts VDC_MIN_PER_NOMINAL x .. VDC_MAX_PER_NOMINAL x the nominal bus
VDC_MIN_PER_NOMINAL = 1e-3
VDC_MAX_PER_NOMINAL = 2.0


def speed_range(artifact, motor, drive, v_max: float) -> float:
    """The mechanical speed range (rad/s) of the header: ``drive.max_speed``,
    else the larger of ``motor.rated_speed`` and the speed at which the
    back-EMF is twice ``V_MAX`` (a speed the drive cannot exceed under its own
    voltage, so the integer variants never clamp a reachable speed)."""
    w_rng = getattr(drive, "max_speed", None) if drive is not None else None
    if w_rng:
        return float(w_rng)
    dec = artifact.decoupling
    w_emf = 2.0 * v_max / max(dec.pole_pairs * dec.flux_c, 1e-9)
    return float(max(w_emf, (motor.rated_speed or 0.0) if motor is not None else 0.0))


def plausibility_limits(artifact, motor, drive, v_max: float) -> dict[str, float]:
    """The plausible ranges the float header checks its measurements against.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller (its decoupling model supplies the fallbacks).
    motor, drive : Motor, Drive or None
        Ratings: ``motor.max_current`` (else 2 x ``motor.rated_current``),
        ``drive.max_speed``, ``drive.vdc``.
    v_max : float
        Voltage limit at the nominal bus (V).

    Returns
    -------
    dict
        ``i`` (A): ``|i_d|``, ``|i_q|`` measured beyond it are refused;
        ``PLAUSIBLE_MARGIN`` x the current range: ``motor.max_current``, else
        the largest of 2 x rated, the voltage-limited current ``V_MAX / R``
        and the short-circuit current ``flux / min(Ld, Lq)`` (currents the
        drive can produce are never refused without a stated maximum).
        ``w`` (rad/s, mechanical): ``PLAUSIBLE_MARGIN`` x ``drive.max_speed``,
        else x the larger of ``motor.rated_speed`` and the speed at which the
        back-EMF is twice ``V_MAX``. ``vdc_min``, ``vdc_max`` (V): the bus
        readings ``set_vdc`` accepts, ``1e-3`` and ``2`` x ``drive.vdc``.
    """
    dec = artifact.decoupling
    i_rng = motor.max_current if motor is not None else None
    if not i_rng:
        # currents the drive can produce: never refused without a stated maximum
        rated = 2.0 * motor.rated_current if motor is not None and motor.rated_current else 0.0
        i_rng = max(rated, v_max / max(dec.R_c, 1e-9),
                    dec.flux_c / max(min(dec.Ld_c, dec.Lq_c), 1e-12))
    w_rng = speed_range(artifact, motor, drive, v_max)
    vdc = drive.vdc if drive is not None else v_max * math.sqrt(3.0)
    return {"i": PLAUSIBLE_MARGIN * float(i_rng), "w": PLAUSIBLE_MARGIN * float(w_rng),
            "vdc_min": VDC_MIN_PER_NOMINAL * float(vdc), "vdc_max": VDC_MAX_PER_NOMINAL * float(vdc)}


def _plausible_context(artifact, motor, drive, v_max: float) -> dict[str, str]:
    """The plausibility macros' values, formatted and range-checked."""
    lim = plausibility_limits(artifact, motor, drive, v_max)
    return {"i": _f(lim["i"], "motor.max_current", "I_PLAUSIBLE"),
            "w": _f(lim["w"], "drive.max_speed", "W_PLAUSIBLE"),
            "vdc_min": _f(lim["vdc_min"], "drive.vdc", "VDC_MIN"),
            "vdc_max": _f(lim["vdc_max"], "drive.vdc", "VDC_PLAUSIBLE")}
