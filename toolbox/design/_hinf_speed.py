"""``[controller.hinf.at_speed]``: H-infinity against the coupled dq plant at speed.

The synthesis itself is :mod:`._hinf_coupled` (2x2 generalised plant with the
dq coupling, the delayed decoupling and the loop delay; R, Ld, Lq as a
multi-model set; one structured controller for the polytope of speeds). This
module reads the table and turns the result into the artifact's parts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..analysis.robustness import DEFAULT_BOX, DEFAULT_RANGES
from ..errors import SpecError, DesignInfeasible
from ..spec import Table
from ..plant import max_electrical_speed
from ._defaults import default_bandwidth
from ._hinf_coupled import (PADE_ORDER, SPEED_FRACTIONS, axis_controller, coupled_plant,
                            full_order_gamma, model_set, synthesise_structured)

__all__ = ["AtSpeedCfg", "read_at_speed", "design_at_speed"]

KEYS = ("max_speed", "inductance_box", "resistance_box", "speed_gain", "speed_offset",
        "extra_delay")


@dataclass(frozen=True)
class AtSpeedCfg:
    """Validated ``[controller.hinf.at_speed]``.

    Attributes
    ----------
    max_speed : float
        Mechanical speed range ``|Omega| <= max_speed`` (rad/s).
    inductance_box : tuple
        Scale factors ``(lo, hi)`` of the true ``Ld`` and ``Lq``.
    speed_gain : tuple
        Speed-sensor gain range.
    speed_offset : tuple
        Speed-sensor offset range (mechanical rad/s).
    resistance_box : tuple
        Scale factors ``(lo, hi)`` of the true ``R``.
    extra_delay : int
        Periods of delay beyond the design's that the maximum speed's models
        also carry (default 1, the robustness sweep's range).
    """

    max_speed: float
    inductance_box: tuple = DEFAULT_BOX["Ld"]
    speed_gain: tuple = DEFAULT_RANGES["speed_gain"][:2]
    speed_offset: tuple = DEFAULT_RANGES["speed_offset"][:2]
    resistance_box: tuple = DEFAULT_BOX["R"]
    extra_delay: int = 1

    def to_spec(self) -> dict[str, Any]:
        """The table that reads back to this configuration."""
        return {"max_speed": self.max_speed, "inductance_box": list(self.inductance_box),
                "resistance_box": list(self.resistance_box), "extra_delay": self.extra_delay,
                "speed_gain": list(self.speed_gain), "speed_offset": list(self.speed_offset)}


def _range(t: Table, name: str, default: tuple, *, around: float | None) -> tuple:
    if not t.has(name):
        return tuple(default)
    lo, hi = t.numbers(name, length=2)
    if not lo <= hi or (around is not None and not (0 < lo <= around <= hi)):
        cond = f"0 < lo <= {around:g} <= hi" if around is not None else "lo <= hi"
        raise SpecError(t.key(name), f"[lo, hi] with {cond}", [lo, hi])
    return (lo, hi)


def read_at_speed(table: Table, motor, drive) -> AtSpeedCfg | None:
    """``[controller.hinf.at_speed]`` (None when absent).

    Keys: ``max_speed`` (mechanical rad/s, default the drive's maximum speed,
    the motor's rated speed or the back-EMF limit), ``inductance_box``
    (scale factors of the true Ld and Lq, default the sweep's ``[0.5, 2]``),
    ``resistance_box`` (of the true R, default the sweep's ``[0.5, 2]``),
    ``extra_delay`` (periods of delay beyond the design's carried by the
    models at the maximum speed, 0..4, default 1: the sweep's range),
    ``speed_gain`` (default ``[0.9, 1.1]``) and ``speed_offset`` (mechanical
    rad/s, default ``[-10, 10]``).

    Raises
    ------
    SpecError
        Unknown key, a negative speed, a range that is not ``[lo, hi]`` around
        the nominal value; key path ``controller.hinf.at_speed.<key>``.
    """
    if not table.has("at_speed"):
        return None
    t = table.table("at_speed", KEYS)
    default_speed = max_electrical_speed(motor, drive) / motor.pole_pairs
    speed = t.number("max_speed", default_speed, nonnegative=True, unit="rad/s mechanical")
    return AtSpeedCfg(float(speed),
                      _range(t, "inductance_box", DEFAULT_BOX["Ld"], around=1.0),
                      _range(t, "speed_gain", DEFAULT_RANGES["speed_gain"][:2], around=1.0),
                      _range(t, "speed_offset", DEFAULT_RANGES["speed_offset"][:2],
                             around=None),
                      _range(t, "resistance_box", DEFAULT_BOX["R"], around=1.0),
                      t.integer("extra_delay", 1, minimum=0, maximum=4))


def design_at_speed(weights: dict, motor, drive, decoupling, cfg: AtSpeedCfg) -> dict:
    """The structured controller of :mod:`._hinf_coupled` for this box.

    Parameters
    ----------
    weights : dict
        ``{"d": {"w1", "w2", "w3"}, "q": ...}`` (validated, defaults filled).
    motor, drive : Motor, Drive
    decoupling : Decoupling
        The executed decoupling (its ``Ld_c``, ``Lq_c``).
    cfg : AtSpeedCfg

    Returns
    -------
    dict
        ``controllers`` (per axis the continuous ``K_x``), ``gamma`` (the worst
        level over the model set) and ``record`` (for
        ``design_parameters["at_speed"]``).

    Raises
    ------
    DesignInfeasible
        No structured controller stabilises every model (key
        ``controller.hinf.at_speed``).
    """
    p = motor.pole_pairs
    ts = drive.sample_time
    delay = (drive.delay_samples + 0.5) * ts
    wmax = cfg.max_speed * p
    box = {"R": cfg.resistance_box, "Ld": cfg.inductance_box, "Lq": cfg.inductance_box,
           "speed_gain": cfg.speed_gain,
           "speed_offset": tuple(o * p for o in cfg.speed_offset)}
    models = model_set(motor, decoupling.Ld_c, decoupling.Lq_c, wmax, box,
                       cfg.extra_delay * ts)
    plants = [coupled_plant(m, weights, decoupling.Ld_c, decoupling.Lq_c, delay) for m in models]
    nominal = [i for i, m in enumerate(models)
               if (m.R, m.Ld, m.Lq) == (motor.R, motor.Ld, motor.Lq) and m.w_m == m.w
               and m.extra_delay == 0]
    # start: the cancellation PI at the default crossover (integral zero counted)
    wc = default_bandwidth(drive, zero=True).value
    tau_min = ts / math.pi
    start = np.array([motor.Ld * wc, motor.R * wc, 0.1 / wc, motor.Lq * wc, motor.R * wc,
                      0.1 / wc])
    slow = [i for i, m in enumerate(models) if m.extra_delay > 0]
    res = synthesise_structured(plants, start, tau_min, nominal + slow[:1])
    worst = float(res.gammas[res.worst])
    if not math.isfinite(worst):
        raise DesignInfeasible("controller.hinf.at_speed", "a box and speed range over which "
                               "one structured controller stabilises every model",
                               cfg.to_spec(), hint="narrow the boxes or lower max_speed")
    lower = [full_order_gamma(plants[i]) for i in nominal]
    kp_d, ki_d, tau_d, kp_q, ki_q, tau_q = (float(x) for x in res.params)
    record = {
        "max_speed_rad_s": cfg.max_speed, "max_electrical_speed_rad_s": wmax,
        "box": cfg.to_spec(), "models": len(models),
        "speeds_rad_s": [f * wmax for f in SPEED_FRACTIONS],
        "structure": "per axis K(s) = (kp s + ki)/(s (tau s + 1)), tau >= Ts/pi, "
                     "nominal decoupling",
        "controller": {"d": {"kp": kp_d, "ki": ki_d, "tau": tau_d},
                       "q": {"kp": kp_q, "ki": ki_q, "tau": tau_q}},
        "worst_gamma": worst, "worst_model": models[res.worst].to_json(),
        "nominal_gamma": [float(res.gammas[i]) for i in nominal],
        "full_order_gamma_nominal": lower,
        "rounds": res.rounds,
        "basis": f"continuous 2x2 coupled loop, loop delay (d + 1/2) Ts by Pade order "
                 f"{PADE_ORDER} (plus {cfg.extra_delay} period(s) on the maximum speed's "
                 "models); H-infinity norms by SLICOT ab13dd; lower bound: full-order "
                 "2x2 optimum (Theorem 1) of each nominal speed model",
    }
    return {"controllers": {ax: axis_controller(res.params, ax) for ax in ("d", "q")},
            "gamma": worst, "record": record}
