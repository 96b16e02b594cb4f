"""H-infinity synthesis against the coupled dq plant at speed.

Paper 003 designs each axis on its decoupled plant ``G_x = 1/(R + s L_x)``
(eq (33)-(34)); the cross-coupling is cancelled by the decoupling with the
controller's parameters. With mismatched inductances or a speed-sensor error
the cancellation leaves, at electrical speed ``w`` and measured speed
``w_m = g w + o``, the residual coupling

``v_d gets k_d i_q``, ``k_d = w Lq - w_m Lq_c``;
``v_q gets -k_q i_d``, ``k_q = w Ld - w_m Ld_c``

(paper 003 eq (3)-(4) minus the compensation). With each axis's loop closed
(``u_x = -K_x i_x``), ``i_d = S_d G_d k_d i_q`` and ``i_q = -S_q G_q k_q i_d``:
the coupled loop is the nominal axis loops closed through the SISO loop
``k_d k_q S_d G_d S_q G_q``. By the small-gain theorem it is stable for every
real ``k_d``, ``k_q`` of the box when

``c_d c_q |S_d G_d(jv)| |S_q G_q(jv)| < 1`` at every frequency ``v``,

with ``c_d = max |k_d|``, ``c_q = max |k_q|`` over the true inductances, the
speed-sensor gain and offset and ``|w| <= w_max`` (:func:`coupling_gains`).

Synthesis: the S weight of each axis becomes ``w1 + k sqrt(c_d c_q) G_x``
(``|w1 S| < gamma`` and ``|k c G S| = |k c S G| < gamma`` together when the
two weights' phases lie within 90 degrees of each other, as for 003's
first-order lags); ``k`` is raised through :data:`WEIGHT_GAINS` until the
executed controllers meet the small-gain condition on a frequency grid
(:func:`small_gain_peak`). The guarantee is for the continuous loop without
the sampling delay; the analysis stage's sweep and sampled certificate judge
the executed loop.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._lti import TransferFunction, feedback

from ..analysis.robustness import DEFAULT_BOX, DEFAULT_RANGES
from ..errors import SpecError
from ..spec import Table
from ..plant import max_electrical_speed

__all__ = ["AtSpeedCfg", "read_at_speed", "coupling_gains", "coupled_weight",
           "small_gain_peak", "WEIGHT_GAINS"]

KEYS = ("max_speed", "inductance_box", "speed_gain", "speed_offset")
#: gains ``k`` of the coupling weight tried in turn (the first that meets the
#: small-gain condition is kept)
WEIGHT_GAINS = (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0)
#: frequency grid of the small-gain check (rad/s), beyond both loops' dynamics
_GRID = np.logspace(-2, 6, 4001)


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
    """

    max_speed: float
    inductance_box: tuple = DEFAULT_BOX["Ld"]
    speed_gain: tuple = DEFAULT_RANGES["speed_gain"][:2]
    speed_offset: tuple = DEFAULT_RANGES["speed_offset"][:2]

    def to_spec(self) -> dict[str, Any]:
        """The table that reads back to this configuration."""
        return {"max_speed": self.max_speed, "inductance_box": list(self.inductance_box),
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
                             around=None))


def coupling_gains(motor, decoupling, cfg: AtSpeedCfg) -> tuple[float, float]:
    """``(c_d, c_q)`` (ohm): the largest residual coupling gains over the box.

    ``|w Lq - (g w + o) Lq_c|`` is convex in each of ``(w, Lq, g, o)`` (it is
    the modulus of a multi-affine function), so its maximum over the box is at
    a corner; the decoupling off (``cross`` false) leaves ``|w Lq|``.
    """
    p = motor.pole_pairs
    cross = 1.0 if decoupling.cross else 0.0
    best = [0.0, 0.0]
    for w, s, g, o in itertools.product((-cfg.max_speed * p, cfg.max_speed * p),
                                        cfg.inductance_box, cfg.speed_gain, cfg.speed_offset):
        wm = cross * (g * w + o * p)
        best[0] = max(best[0], abs(w * s * motor.Lq - wm * decoupling.Lq_c))
        best[1] = max(best[1], abs(w * s * motor.Ld - wm * decoupling.Ld_c))
    return best[0], best[1]


def coupled_weight(w1: Any, G: Any, gain: float) -> TransferFunction:
    """The S weight ``w1 + gain G`` of the synthesis at speed (common poles
    and zeros cancelled)."""
    w = TransferFunction.from_system(w1) + gain * TransferFunction.from_system(G)
    return w.minreal()


def small_gain_peak(plants: dict, controllers: dict, c_d: float,
                    c_q: float) -> tuple[float, float]:
    """``max_v c_d c_q |S_d G_d S_q G_q|`` on the grid and its frequency (rad/s).

    ``S_x G_x = G_x / (1 + G_x K_x)`` with the continuous controllers the laws
    run; below 1 the coupled loop is stable over the box (module docstring).
    """
    def sg(ax):
        return np.abs(feedback(plants[ax], controllers[ax]).freqresp(_GRID)[0, 0])

    prod = c_d * c_q * sg("d") * sg("q")
    i = int(np.argmax(prod))
    return float(prod[i]), float(_GRID[i])
