"""Default design parameters derived from the sample time and the delay.

Every method designs a controller from the motor and the drive alone: when
a spec gives no bandwidth (poles, weights, ...), the crossover is the largest
one whose phase margin, for the ideal loop of the method, is
:data:`TARGET_PM_DEG` once the sampling is accounted for.

The rule (stated in every artifact that uses it, ``design_parameters["defaults"]``)
------------------------------------------------------------------------
A sampled current loop loses phase to the computation delay (``delay_samples``
periods) and to the zero-order hold (half a period on average):
``exp(-s T_eq)`` with ``T_eq = (delay_samples + 1/2) Ts`` (e.g. Holmes,
Lipo, McGrath, Kong, "Optimized design of stationary frame three phase AC
current regulators", IEEE TPEL 24 (2009), sect. III; the same ``T_sigma``
as the symmetric-optimum rule in :mod:`toolbox.design.pi`).

* Cancellation PI (pi, pi_lag, tc): the open loop is ``wc/s exp(-s T_eq)``,
  crossover ``wc``, phase margin ``PM = 90 deg - wc T_eq``. For
  ``PM >= PM_target`` the crossover must be ``wc <= (90 deg - PM_target)/T_eq``.
* Loops with an integral zero at ``wc/4`` (ip, tci with damping 1, ilq with
  sigma factor 2): the zero costs ``atan(1/4) = 14.0 deg`` more at crossover,
  so ``wc <= (90 deg - atan(1/4) - PM_target)/T_eq``.

``PM_target`` is 65 deg: 60 deg required plus 5 deg for what the
``exp(-s T_eq)`` approximation neglects (Tustin warping of the PI, the
plant pole ``R/L`` when it is not cancelled); ``tests/design/test_defaults.py``
checks that the *sampled* loops keep >= 60 deg (PI family) on three motors.
For one period of delay the PI rule gives ``wc = 0.291/Ts``, about
``omega_Nyquist/10.8`` (Nyquist ``pi/Ts``).

Default current and speed scales (for Bryson's rule and default scenarios)
are :func:`current_scale` and :func:`speed_scale`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["TARGET_PM_DEG", "ZERO_RATIO", "DefaultBandwidth", "equivalent_delay",
           "default_bandwidth", "largest_stable_pi_bandwidth", "current_scale", "speed_scale"]

#: phase margin the default crossover is designed for (deg): 60 + 5 of allowance
TARGET_PM_DEG = 65.0
#: integral zero of the second-order defaults at crossover / ZERO_RATIO
ZERO_RATIO = 4.0


@dataclass(frozen=True)
class DefaultBandwidth:
    """A default crossover and the rule that produced it.

    Attributes
    ----------
    value : float
        Crossover (rad/s).
    rule : str
        The formula with its numbers, for the artifact and the report.
    """

    value: float
    rule: str

    def as_dict(self) -> dict:
        """Plain data for ``design_parameters["defaults"]``."""
        return {"bandwidth_rad_s": self.value, "rule": self.rule}


def equivalent_delay(sample_time: float, delay_samples: int) -> float:
    """``T_eq = (delay_samples + 1/2) Ts`` (s): computation delay plus the
    zero-order hold's average half period."""
    return (delay_samples + 0.5) * sample_time


def default_bandwidth(drive, *, zero: bool = False, extra_delay: float = 0.0,
                      target_pm_deg: float = TARGET_PM_DEG) -> DefaultBandwidth:
    """Largest crossover with the target phase margin for the sampled loop.

    Parameters
    ----------
    drive : Drive
        Supplies ``sample_time`` and ``delay_samples``.
    zero : bool
        True for loops with an integral zero at ``wc/ZERO_RATIO`` (ip, tci,
        ilq defaults): ``atan(1/ZERO_RATIO)`` more phase is lost at crossover.
    extra_delay : float
        Further small time constant in the loop (s), e.g. a measurement lag
        (its phase ``atan(wc T) <= wc T`` is counted as a delay: conservative).
    target_pm_deg : float
        Phase margin designed for (deg).

    Returns
    -------
    DefaultBandwidth
    """
    t_eq = equivalent_delay(drive.sample_time, drive.delay_samples) + extra_delay
    zero_deg = math.degrees(math.atan(1.0 / ZERO_RATIO)) if zero else 0.0
    theta = math.radians(90.0 - target_pm_deg - zero_deg)
    wc = theta / t_eq
    zero_txt = f" - atan(1/{ZERO_RATIO:g}) = {zero_deg:.1f} deg (integral zero at wc/{ZERO_RATIO:g})" \
        if zero else ""
    lag_txt = f" + lag {extra_delay:.3g} s" if extra_delay else ""
    rule = (f"wc = (90 deg - PM {target_pm_deg:g} deg{zero_txt}) / T_eq, "
            f"T_eq = (delay_samples {drive.delay_samples} + 0.5) Ts{lag_txt} = {t_eq:.4g} s: "
            f"wc = {wc:.5g} rad/s = {wc * drive.sample_time:.3g}/Ts "
            f"(= Nyquist pi/Ts / {math.pi / (wc * drive.sample_time):.3g})")
    return DefaultBandwidth(wc, rule)


def largest_stable_pi_bandwidth(drive) -> float:
    """Bandwidth at which the cancellation PI loop loses stability (rad/s).

    With the plant pole cancelled, the sampled loop is the integrator
    ``K z^-d/(z - 1)``, ``K = wc Ts``, ``d = delay_samples``; its
    characteristic polynomial ``z^(d+1) - z^d + K`` has a root on the unit
    circle at ``K = 2 sin(pi/(2 (2 d + 1)))`` (1 for one period of delay,
    2 without delay). Used to suggest a bandwidth in error messages; the
    default (:func:`default_bandwidth`) is about a third of it.

    Parameters
    ----------
    drive : Drive
        Sample time ``Ts`` and ``delay_samples``.

    Returns
    -------
    float
        ``2 sin(pi/(4 d + 2))/Ts`` (rad/s).
    """
    d = drive.delay_samples
    return 2.0 * math.sin(math.pi / (2.0 * (2 * d + 1))) / drive.sample_time


def current_scale(motor, drive) -> tuple[float, str]:
    """Current that scales default scenarios and Bryson weights (A).

    The motor's ``rated_current``, else its ``max_current``, else the current
    the voltage allows: the largest step the default-bandwidth PI can make
    without leaving linear modulation, ``V_max/(R + wc L_max)`` (a step ``di``
    asks for ``wc L di`` at once, the resistance ``R i`` in steady state).

    Parameters
    ----------
    motor : Motor
        Rated and maximum current, R, Ld, Lq.
    drive : Drive
        Voltage, sample time and delay (for the default crossover).

    Returns
    -------
    value : float
        Current (A).
    source : str
        Where it came from, with the formula and numbers.
    """
    if motor.rated_current:
        return float(motor.rated_current), "motor.rated_current"
    if motor.max_current:
        return float(motor.max_current), "motor.max_current"
    v_max = drive.max_voltage(motor.convention)
    wc = default_bandwidth(drive).value
    L = max(motor.Ld, motor.Lq)
    i = v_max / (motor.R + wc * L)
    return i, (f"voltage-allowed current V_max/(R + wc L_max) = {v_max:.4g}/({motor.R:.4g} + "
               f"{wc:.5g} x {L:.4g}) = {i:.4g} A (no rated_current or max_current given)")


def speed_scale(motor, drive) -> tuple[float, str]:
    """Mechanical speed that scales default scenarios (rad/s).

    The motor's ``rated_speed``, else the drive's ``max_speed``, else the
    base speed ``V_max/(p flux)`` where the back-EMF alone uses the whole
    voltage; capped at that base speed (a scenario above it needs field
    weakening, which the current loops do not do).

    Parameters
    ----------
    motor : Motor
        Rated speed, pole pairs and flux.
    drive : Drive
        Voltage and ``max_speed``.

    Returns
    -------
    value : float
        Speed (rad/s), ``inf`` when the motor has no flux and no speed given.
    source : str
        Where it came from.
    """
    v_max = drive.max_voltage(motor.convention)
    emf = motor.pole_pairs * motor.flux
    base = v_max / emf if emf > 0 else math.inf
    base_txt = f"base speed V_max/(p flux) = {v_max:.4g}/{emf:.4g} = {base:.5g} rad/s"
    for name, value in (("motor.rated_speed", motor.rated_speed),
                        ("drive.max_speed", drive.max_speed)):
        if value:
            if value > base:
                return base, f"{base_txt} (below {name} = {value:.5g} rad/s)"
            return float(value), name
    return base, base_txt
