"""Robust PI tuner: the fastest PI whose coupled sampled loop keeps a disk margin on a model set.

In the spirit of MATLAB's ``systune``/``looptune`` (structured, multi-model
tuning): the controller structure is fixed (the dq PI with decoupling of
:mod:`toolbox.design.pi`, executed as that method executes it) and its
gains are chosen to maximise the bandwidth subject to a robustness
constraint that must hold on every model of a set.

Structure (both axes, one bandwidth ``wc``):
``Kp_x = L_x wc``, ``Ki_x = Kp_x w_z`` (``L_x`` the nominal ``Ld``/``Lq``),
with the integral zero ``w_z`` one of ``R/L_x`` (the cancellation zero) or
``wc/zr`` for the ``zero_ratios`` ``zr``; the decoupling feedforward uses the
nominal parameters (controller side).

Constraint, on every model: the balanced multiloop (input, diagonal) disk
margin of the coupled dq loop **as executed** - ZOH plant, the drive's
computation delay, the decoupling with the controller's parameters, the
Tustin-discretised PI, the voltage placed at ``theta_k + t_c w_meas``
(``drive.angle_compensation``: ``eps = t_c w_meas - (d + 1/2) Ts w`` below) -
is at least ``disk_margin``, and the coupled closed loop is stable
(:class:`toolbox.analysis.margins.MultiModelLoops`, the same loop as
``mimo_at_speed`` and the robustness sweep).

Models: the box of ``R``, ``Ld``, ``Lq`` scale factors and of the speed
sensor - gain ``g`` and offset ``o`` of the measured speed
``w_meas = g w + p o`` (``o`` mechanical), the sensor errors the robustness
sweep applies (:data:`toolbox.analysis.robustness.DEFAULT_RANGES`:
0.9..1.1 and +/-10 rad/s, paper 000 sect. 3 "robustness to speed error") -
as the nominal point, the corners (``2^5`` by default) and ``samples``
Latin-hypercube sets inside it (log-uniform scale factors, uniform offset,
:func:`toolbox.analysis.robustness.sample_parameters`), each at
``n_speeds`` true electrical speeds ``linspace(0, p max_speed)``. The
measured speed enters what the controller computes from it: the decoupling
``W`` and the placement rotation ``R(eps)``,
``eps = t_c w_meas - (d + 1/2) Ts w``, in the loop response and in the
stability check alike. The margin is even in the speed jointly with the
offset (the loop at ``(-w, o)`` is the loop at ``(w, -o)``), so a symmetric
offset range needs only ``w >= 0``; an asymmetric one is evaluated at
``linspace(-p max_speed, p max_speed, 2 n_speeds - 1)``.

Search: for each zero choice, a log grid of ``wc`` from
``wc_max/100`` to the largest stable bandwidth of the sampled PI
(``toolbox.design.largest_stable_pi_bandwidth``), then a bisection between
the largest feasible grid point and the next infeasible one (the feasible
set need not be an interval: at low bandwidth the residual coupling of a
mismatched decoupling at speed is what breaks the margin, at high bandwidth
the delay); the largest feasible ``wc`` over the zero choices wins. The
winner is re-checked on a 4x finer frequency grid and backed off by 2 % at a
time until it passes (``design_parameters["verification"]``). When no
bandwidth meets the margin, the largest margin over the search (the grid,
refined by a golden-section search around its best point) is reported with
the model that limits it and what the same design keeps without the sensor
errors, at standstill and on the nominal motor (``DesignInfeasible``).

Spec: ``[controller.robust_pi]`` with ``disk_margin`` (default 0.5: gain
factors 0.6..1.67, +/-28 deg simultaneously in both channels),
``parameter_box`` (``{R = [lo, hi], Ld = [..], Lq = [..]}``, scale factors,
default 0.5..2 each: the robustness sweep's default box), ``max_speed``
(mechanical rad/s, default ``drive.max_speed``, the motor's rated speed or the
back-EMF limit, :func:`toolbox.plant.max_electrical_speed`), ``n_speeds``
(default 4), ``speed_gain`` (``[lo, hi]``, default ``[0.9, 1.1]``, ``lo <= 1 <=
hi``), ``speed_offset`` (``[lo, hi]`` mechanical rad/s, default
``[-10, 10]``, ``lo <= 0 <= hi``; ``[1, 1]`` and ``[0, 0]`` model an exact
sensor), ``samples`` (default 8), ``seed`` (0), ``zero_ratios`` (default
``[4, 10]``), ``decoupling`` (true).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..analysis.robustness import DEFAULT_BOX, DEFAULT_RANGES, sample_parameters
from ..errors import DesignInfeasible, SpecError
from ..spec import Table
from . import _defaults
from ._common import decoupling_from_motor, make_artifact
from ..plant import max_electrical_speed
from .pi import design_pi, closed_loop_poles
from ..analysis.margins import MultiModelLoops, multimodel_disk_margins

__all__ = ["RobustPiCfg", "ModelSet", "read_cfg", "design", "model_set", "tune"]

_KEYS = ("disk_margin", "parameter_box", "max_speed", "n_speeds", "speed_gain", "speed_offset",
         "samples", "seed", "zero_ratios", "decoupling")
#: The robustness sweep's speed-sensor ranges (toolbox/analysis/_sampling.py,
#: paper 000 sect. 3): gain 0.9..1.1, offset +/-10 rad/s mechanical.
DEFAULT_SPEED_GAIN = tuple(DEFAULT_RANGES["speed_gain"][:2])
DEFAULT_SPEED_OFFSET = tuple(DEFAULT_RANGES["speed_offset"][:2])
_BOX_KEYS = ("R", "Ld", "Lq")
N_GRID = 300          # frequency points of the search (the check uses 4x more)
N_WC = 16             # log grid of the bandwidth per zero choice (factor 1.36)
N_BISECT = 8          # bisection steps (a factor 1.3 bracket -> 0.1 %)
BACKOFF = 0.98


@dataclass(frozen=True)
class RobustPiCfg:
    """Validated ``[controller.robust_pi]``.

    Attributes
    ----------
    disk_margin : float
        Balanced multiloop disk margin required on every model (0 < alpha < 2).
    parameter_box : dict
        ``{"R": (lo, hi), "Ld": .., "Lq": ..}`` scale factors of the nominal motor.
    max_speed : float
        Mechanical speed range ``|Omega| <= max_speed`` (rad/s).
    n_speeds : int
        Speeds ``linspace(0, p max_speed, n_speeds)`` per model.
    speed_gain : tuple
        ``(lo, hi)`` gain of the speed measurement.
    speed_offset : tuple
        ``(lo, hi)`` offset of the speed measurement (rad/s mechanical).
    samples : int
        Latin-hypercube sets inside the box (besides nominal and corners).
    seed : int
        Seed of the Latin hypercube.
    zero_ratios : tuple of float
        ``wc / w_z`` choices besides the cancellation zero.
    decoupling : bool
        Cross-coupling and back-EMF feedforward (nominal parameters).
    details : dict
        Defaults applied (reported in design_parameters).
    """

    disk_margin: float = 0.5
    parameter_box: dict = field(default_factory=lambda: dict(DEFAULT_BOX))
    max_speed: float = 0.0
    n_speeds: int = 4
    speed_gain: tuple = DEFAULT_SPEED_GAIN
    speed_offset: tuple = DEFAULT_SPEED_OFFSET
    samples: int = 8
    seed: int = 0
    zero_ratios: tuple = (4.0, 10.0)
    decoupling: bool = True
    details: dict = field(default_factory=dict)

    def to_spec(self, spec=None) -> dict[str, Any]:
        """``[controller.robust_pi]`` keys that read back to the same configuration."""
        return {"disk_margin": self.disk_margin,
                "parameter_box": {k: list(v) for k, v in self.parameter_box.items()},
                "max_speed": self.max_speed, "n_speeds": self.n_speeds,
                "speed_gain": list(self.speed_gain), "speed_offset": list(self.speed_offset),
                "samples": self.samples, "seed": self.seed,
                "zero_ratios": list(self.zero_ratios), "decoupling": self.decoupling}


def read_cfg(method: str, table: Table, motor, drive) -> RobustPiCfg:
    """Validate ``[controller.robust_pi]``.

    Raises
    ------
    SpecError
        Unknown key, a disk margin outside (0, 2), a box bound <= 0 or
        lo > hi, a non-positive speed, a sensor range not containing the exact
        sensor; key path ``controller.robust_pi.<key>``.
    """
    t = Table(table.data, table.prefix, _KEYS)
    details: dict[str, Any] = {}
    alpha = t.number("disk_margin", 0.5, positive=True)
    if not alpha < 2.0:
        raise SpecError(t.key("disk_margin"), "a number > 0 and < 2 (balanced disk margin)",
                        alpha)
    box = dict(DEFAULT_BOX)
    if t.has("parameter_box"):
        bt = t.table("parameter_box", _BOX_KEYS)
        for name in _BOX_KEYS:
            if bt.has(name):
                lo, hi = bt.numbers(name, length=2)
                if not (0 < lo <= 1 <= hi):
                    raise SpecError(bt.key(name), "[lo, hi] with 0 < lo <= 1 <= hi (scale factors)",
                                    [lo, hi])
                box[name] = (lo, hi)
    else:
        details["parameter_box"] = "default: R, Ld, Lq x0.5..x2 (the robustness sweep's box)"
    default_speed = max_electrical_speed(motor, drive) / motor.pole_pairs
    speed = t.number("max_speed", default_speed, nonnegative=True, unit="rad/s mechanical")
    if not t.has("max_speed"):
        details["max_speed"] = (f"default {default_speed:.6g} rad/s "
                                "(drive max_speed, rated speed or EMF limit)")
    gain = t.numbers("speed_gain", DEFAULT_SPEED_GAIN, length=2)
    if not 0 < gain[0] <= 1.0 <= gain[1]:
        raise SpecError(t.key("speed_gain"), "[lo, hi] with 0 < lo <= 1 <= hi (gain of the "
                        "measured speed)", list(gain))
    offset = t.numbers("speed_offset", DEFAULT_SPEED_OFFSET, length=2, unit="rad/s mechanical")
    if not offset[0] <= 0.0 <= offset[1]:
        raise SpecError(t.key("speed_offset"), "[lo, hi] with lo <= 0 <= hi (rad/s mechanical)",
                        list(offset))
    if not (t.has("speed_gain") and t.has("speed_offset")):
        details["speed_sensor"] = ("default: the robustness sweep's speed-sensor errors, gain "
                                   f"{DEFAULT_SPEED_GAIN[0]:g}..{DEFAULT_SPEED_GAIN[1]:g}, offset "
                                   f"{DEFAULT_SPEED_OFFSET[0]:g}..{DEFAULT_SPEED_OFFSET[1]:g} "
                                   "rad/s mechanical")
    ratios = t.numbers("zero_ratios", (4.0, 10.0), min_length=0, max_length=8)
    for r in ratios:
        if not r > 1.0:
            raise SpecError(t.key("zero_ratios"), "numbers > 1 (wc / integral zero)", list(ratios))
    return RobustPiCfg(disk_margin=alpha, parameter_box=box, max_speed=float(speed),
                       n_speeds=t.integer("n_speeds", 4, minimum=1, maximum=32),
                       speed_gain=tuple(gain), speed_offset=tuple(offset),
                       samples=t.integer("samples", 8, minimum=0, maximum=256),
                       seed=t.integer("seed", 0, minimum=0),
                       zero_ratios=tuple(ratios), decoupling=t.boolean("decoupling", True),
                       details=details)


@dataclass(frozen=True)
class ModelSet:
    """The tuner's models (:func:`model_set`).

    Attributes
    ----------
    motors : list of Motor
    params : list of dict
        Per model: scale factors ``R``, ``Ld``, ``Lq``, the sensor's
        ``speed_gain`` and ``speed_offset`` (rad/s mechanical).
    speeds : ndarray
        True electrical speeds (rad/s).
    speed_gain : ndarray
        Sensor gain per model.
    speed_offset : ndarray
        Sensor offset per model, electrical rad/s (``p`` times the mechanical).
    """

    motors: list
    params: list
    speeds: np.ndarray
    speed_gain: np.ndarray
    speed_offset: np.ndarray

    def loops(self, sample_time: float, delay_samples: int, n_grid: int):
        """:class:`toolbox.analysis.margins.MultiModelLoops` of the set."""
        return MultiModelLoops(self.motors, self.speeds, sample_time, delay_samples, n_grid,
                               speed_gain=self.speed_gain, speed_offset=self.speed_offset)

    def disk_margins(self, artifact, n_grid: int = N_GRID) -> np.ndarray:
        """``(models, speeds)`` multiloop disk margins of ``artifact`` on the set."""
        return self.loops(artifact.sample_time, artifact.delay_samples,
                          n_grid).disk_margins(artifact)

    def measured_speed(self, i: int, j: int) -> float:
        """Measured electrical speed of model ``i`` at speed ``j`` (rad/s)."""
        return float(self.speed_gain[i] * self.speeds[j] + self.speed_offset[i])


def model_set(motor, cfg: RobustPiCfg) -> ModelSet:
    """The tuner's models: nominal, box corners and Latin-hypercube samples.

    The box spans ``R``, ``Ld``, ``Lq`` and the speed sensor's gain and offset
    (a range of zero width is held at its value rather than doubling the
    corners); module docstring.
    """
    ranges = {k: (lo, hi, "scale") for k, (lo, hi) in cfg.parameter_box.items()}
    fixed = {}
    for name, (lo, hi), kind in (("speed_gain", cfg.speed_gain, "scale"),
                                 ("speed_offset", cfg.speed_offset, "offset")):
        if hi > lo:
            ranges[name] = (lo, hi, kind)
        else:
            fixed[name] = float(lo)
    P = sample_parameters(ranges, cfg.samples, cfg.seed)
    n = len(P["R"])
    params = [dict({k: float(P[k][i]) for k in ranges}, **fixed) for i in range(n)]
    motors = [motor.with_overrides(None, {k: p[k] for k in _BOX_KEYS}) for p in params]
    p = motor.pole_pairs
    wmax = cfg.max_speed * p
    lo, hi = cfg.speed_offset
    if wmax <= 0:
        speeds = np.zeros(1)
    elif lo == -hi:                    # (-w, o) is (w, -o): w >= 0 covers the range
        speeds = np.linspace(0.0, wmax, cfg.n_speeds)
    else:
        speeds = np.linspace(-wmax, wmax, 2 * cfg.n_speeds - 1)
    gain = np.array([q["speed_gain"] for q in params])
    offset = np.array([q["speed_offset"] * p for q in params])
    return ModelSet(motors, params, speeds, gain, offset)


def _gains(motor, wc: float, ratio: float | None) -> tuple[tuple, tuple]:
    L = (motor.Ld, motor.Lq)
    Kp = tuple(Lx * wc for Lx in L)
    if ratio is None:          # cancellation zero R/L
        Ki = tuple(motor.R * wc for _ in L)
    else:
        Ki = tuple(k * wc / ratio for k in Kp)
    return Kp, Ki


def _candidate(spec, cfg: RobustPiCfg, Kp, Ki):
    axes = design_pi(Kp, Ki, spec.drive.sample_time, structure="pi", method="tustin")
    dec = decoupling_from_motor(spec.motor, cross=cfg.decoupling, emf=cfg.decoupling)
    return make_artifact(spec, axes, dec, {}, [])


def tune(spec, cfg: RobustPiCfg | None = None, advise: bool = True) -> dict[str, Any]:
    """Search the gains (module docstring); returns the winner and the search record.

    Returns
    -------
    dict
        ``Kp``, ``Ki`` (d, q), ``bandwidth_rad_s`` (``wc``), ``zero`` (the
        choice: ``"cancellation"`` or ``wc/<ratio>``), ``worst_disk_margin``,
        ``worst_model`` (scale factors, sensor errors, true and measured
        electrical speed), ``margins`` (the ``(models, speeds)`` array of the
        winner), ``models`` (the :class:`ModelSet`), ``candidates`` (best
        feasible ``wc`` per zero choice).

    Raises
    ------
    DesignInfeasible
        No bandwidth meets the disk margin on every model; the message gives
        the largest margin reached, its bandwidth, the model that limits it
        and the margins of the same design without the sensor errors, at
        standstill and on the nominal motor (:func:`_limitation`), and with
        ``advise`` what would pass (:func:`_what_passes`: a disk margin the
        search is re-run with and succeeds, or a smaller maximum speed).
    """
    cfg = cfg or spec.controller.cfg
    motor = spec.motor
    models = model_set(motor, cfg)
    wc_max = _defaults.largest_stable_pi_bandwidth(spec.drive)
    alpha = cfg.disk_margin
    Ts, d = spec.drive.sample_time, spec.drive.delay_samples
    coarse = models.loops(Ts, d, N_GRID)
    fine = models.loops(Ts, d, 4 * N_GRID)

    def margins(wc, ratio, loops=coarse):
        art = _candidate(spec, cfg, *_gains(motor, wc, ratio))
        return loops.disk_margins(art)

    grid = np.geomspace(wc_max / 100.0, wc_max * 0.999, N_WC)
    # candidates are ranked by (worst margin, - unstable pairs): with every
    # bandwidth unstable somewhere the refusal reports the least unstable one
    best_seen = ((-1.0, 0), None, None)           # score, wc, ratio
    results = {}
    for ratio in (None,) + tuple(cfg.zero_ratios):
        def score(x, r=ratio):
            M = margins(x, r)
            return float(np.min(M)), -int(np.count_nonzero(M == 0.0))

        lo, best_i = None, ((-1.0, 0), 0)
        for i in range(len(grid) - 1, -1, -1):    # from the top: the largest feasible point
            sc = score(grid[i])
            best_i = max(best_i, (sc, i))
            if sc[0] >= alpha:
                lo = float(grid[i])
                break
        sc, i = best_i
        x = float(grid[i])
        if lo is None and sc[0] > 0:
            # the feasible window may fall between two grid points (with the
            # sensor errors it spans ~1.2x on paper 003's motor, the grid steps
            # 1.36x): maximise between the best point's neighbours
            m, x = _golden_max(lambda v: score(v)[0], float(grid[max(i - 1, 0)]),
                               float(grid[min(i + 1, len(grid) - 1)]), (sc[0], x))
            sc = (m, 0)
            if m >= alpha:
                lo = x
        if sc > best_seen[0]:
            best_seen = (sc, x if lo is None else lo, ratio)
        if lo is None:
            results[ratio] = None
            continue
        above = grid[grid > lo]                   # infeasible (scanned from the top)
        hi = float(above[0]) if above.size else None
        if hi is not None:
            for _ in range(N_BISECT):
                mid = math.sqrt(lo * hi)
                if score(mid)[0] >= alpha:
                    lo = mid
                else:
                    hi = mid
        results[ratio] = lo
    feasible = {r: wc for r, wc in results.items() if wc is not None}
    if not feasible:
        (m, _), wc, ratio = best_seen
        raise DesignInfeasible(
            "controller.robust_pi.disk_margin",
            f"a disk margin the model set allows (best found {m:.3g} at wc = {wc:.4g} rad/s, "
            f"zero {_zero_name(ratio)})", alpha,
            hint=_what_passes(margins(wc, ratio, fine), models, alpha, wc, spec.motor.pole_pairs,
                              _retry(spec, cfg) if advise else None)
            + "; " + _limitation(spec, cfg, models, wc, ratio, margins))
    ratio = max(feasible, key=lambda r: feasible[r])
    wc = feasible[ratio]
    # re-check on a finer grid; back off until it passes
    backoffs = 0
    while True:
        M = margins(wc, ratio, fine)
        if float(np.min(M)) >= alpha or backoffs >= 20:
            break
        wc *= BACKOFF
        backoffs += 1
    if float(np.min(M)) < alpha:
        raise DesignInfeasible("controller.robust_pi.disk_margin",
                               "a disk margin the fine-grid check confirms", alpha,
                               hint=f"{float(np.min(M)):.3g} after {backoffs} back-offs of 2 % "
                               f"to wc = {wc:.4g} rad/s; "
                               + _what_passes(M, models, alpha, wc, motor.pole_pairs,
                                              _retry(spec, cfg) if advise else None))
    i, j = np.unravel_index(int(np.argmin(M)), M.shape)
    Kp, Ki = _gains(motor, wc, ratio)
    return {"Kp": Kp, "Ki": Ki, "bandwidth_rad_s": wc, "zero": _zero_name(ratio),
            "worst_disk_margin": float(M[i, j]),
            "worst_model": _model_record(models, i, j),
            "margins": M, "params": models.params, "speeds": models.speeds, "models": models,
            "candidates": {_zero_name(r): v for r, v in results.items()},
            "backoffs": backoffs, "largest_stable_pi_bandwidth": wc_max}


def _model_record(models: ModelSet, i: int, j: int) -> dict[str, float]:
    """Scale factors, sensor errors, true and measured electrical speed of a model."""
    return dict(models.params[i], speed_rad_s=float(models.speeds[j]),
                measured_speed_rad_s=models.measured_speed(i, j))


def _golden_max(f, lo: float, hi: float, best: tuple, steps: int = N_BISECT) -> tuple:
    """``(f, x)`` of the largest ``f`` seen by a golden-section search of ``log x``
    on ``[lo, hi]``, starting from ``best``."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = math.log(lo), math.log(hi)
    c, e = b - g * (b - a), a + g * (b - a)
    fc, fe = f(math.exp(c)), f(math.exp(e))
    for _ in range(steps):
        for v, x in ((fc, c), (fe, e)):
            if v > best[0]:
                best = (v, math.exp(x))
        if fc >= fe:
            b, e, fe = e, c, fc
            c = b - g * (b - a)
            fc = f(math.exp(c))
        else:
            a, c, fc = c, e, fe
            e = a + g * (b - a)
            fe = f(math.exp(e))
    for v, x in ((fc, c), (fe, e)):
        if v > best[0]:
            best = (v, math.exp(x))
    return best


def _limitation(spec, cfg: RobustPiCfg, models: ModelSet, wc: float, ratio, margins) -> str:
    """Why the best design misses the margin, from its margins on the set:
    the limiting model, the same design without the speed-sensor errors, at
    standstill and on the nominal motor, and the trend either side of ``wc``."""
    M = margins(wc, ratio)
    unstable = M == 0.0
    if np.any(unstable):          # the unstable pair at the lowest speed
        cols = np.nonzero(unstable.any(axis=0))[0]
        j = int(cols[np.argmin(np.abs(models.speeds[cols]))])
        i = int(np.nonzero(unstable[:, j])[0][0])
    else:
        i, j = np.unravel_index(int(np.argmin(M)), M.shape)
    rec = _model_record(models, i, j)
    where = ", ".join(f"{k} x{rec[k]:.3g}" for k in _BOX_KEYS)
    parts = [f"limited by {where} at {rec['speed_rad_s']:.4g} rad/s electrical, the speed "
             f"measured {rec['measured_speed_rad_s']:.4g} (gain {rec['speed_gain']:.3g}, offset "
             f"{rec['speed_offset']:+.3g} rad/s mechanical)"]
    if np.any(unstable):
        speeds = np.abs(models.speeds[unstable.any(axis=0)])
        parts.append(f"{int(np.count_nonzero(unstable))} of {M.size} (model, speed) pairs "
                     f"unstable, at {speeds.min():.4g}..{speeds.max():.4g} rad/s electrical")
    art = _candidate(spec, cfg, *_gains(spec.motor, wc, ratio))
    if np.any(models.speed_gain != 1.0) or np.any(models.speed_offset != 0.0):
        exact = multimodel_disk_margins(art, models.motors, models.speeds, n_grid=N_GRID)
        parts.append(f"without the speed-sensor errors the same design keeps "
                     f"{float(np.min(exact)):.3g}"
                     + (f" ({int(np.count_nonzero(exact == 0.0))} pairs unstable)"
                        if np.any(exact == 0.0) else ""))
    still = models.speeds == 0.0
    if np.any(still) and not np.all(still):
        parts.append(f"at standstill {float(np.min(M[:, still])):.3g}")
    parts.append(f"on the nominal motor {float(np.min(M[0])):.3g}")
    lower, higher = (float(np.min(margins(wc * f, ratio))) for f in (0.8, 1.25))
    parts.append(f"either side of wc the worst margin falls: {lower:.3g} at 0.8 wc, "
                 f"{higher:.3g} at 1.25 wc")
    return "; ".join(parts)


def _retry(spec, cfg: RobustPiCfg):
    """``ok(alpha)``: does the search succeed with ``disk_margin = alpha``?"""
    import dataclasses

    def ok(alpha: float) -> bool:
        try:
            tune(spec, dataclasses.replace(cfg, disk_margin=alpha), advise=False)
        except DesignInfeasible:
            return False
        return True
    return ok


#: Tries of a suggested disk margin, each 10 % below the last.
ADVICE_TRIES = 3


def _what_passes(M: np.ndarray, models: ModelSet, alpha: float, wc: float, pole_pairs: int,
                 ok=None) -> str:
    """Computed advice for a refusal: what would pass, never a guess.

    ``M`` holds the disk margins (models x speeds) of the best design found,
    on the fine frequency grid. The disk margin it keeps (rounded down) is
    offered only when the search re-run with it succeeds (``ok``; up to
    :data:`ADVICE_TRIES` values, each 10 % lower); otherwise, or without
    ``ok``, the largest ``max_speed`` whose speeds all keep ``alpha`` on
    every model at this bandwidth; when not even the lowest speed does, the
    margin it keeps there (the box or the margin must change: lowering the
    speed range cannot pass)."""
    parts = []
    best = float(M.min())
    if best > 0 and ok is not None:
        cand = math.floor(best * 1000) / 1000
        for _ in range(ADVICE_TRIES):
            if cand > 0 and ok(cand):
                parts.append(f"disk_margin = {cand:.3g} passes (the search re-run with it "
                             "succeeds)")
                break
            cand = math.floor(cand * 900) / 1000
    speeds = np.abs(models.speeds)
    good = M.min(axis=0) >= alpha
    passing, found = 0.0, False
    for j in np.argsort(speeds):
        if not good[j]:
            break
        passing, found = float(speeds[j]), True
    if found and 0 < passing < float(speeds.max()):
        parts.append(f"max_speed = {passing / pole_pairs:.4g} rad/s mechanical "
                     f"({passing:.4g} rad/s electrical) keeps disk_margin = {alpha:g} on "
                     f"every model at wc = {wc:.4g} rad/s")
    elif not found:
        low = speeds == speeds.min()
        parts.append(f"at {speeds.min():.4g} rad/s electrical the worst margin is already "
                     f"{float(M[:, low].min()):.3g} < {alpha:g}: a lower max_speed cannot "
                     "pass; narrow parameter_box or lower disk_margin")
    if not parts and best <= 0:
        parts.append("the best design found has unstable (model, speed) pairs (worst margin "
                     "0): no disk_margin passes with this parameter_box; narrow it")
    return "; ".join(parts) or (f"no disk_margin from {best:.3g} down by "
                                f"{ADVICE_TRIES} steps of 10 % passes; narrow parameter_box")


def _zero_name(ratio) -> str:
    return "cancellation R/L" if ratio is None else f"wc/{ratio:g}"


def design(spec):
    """Design the robust PI a spec asks for (``method = "robust_pi"``).

    Returns
    -------
    ControllerArtifact
        The same artifact as the ``pi`` method (Tustin PI per axis, decoupling
        from the nominal motor) with ``method = "robust_pi"``; the tuning
        record is in ``design_parameters``.
    """
    cfg: RobustPiCfg = spec.controller.cfg
    res = tune(spec, cfg)
    Kp, Ki = res["Kp"], res["Ki"]
    Ts = spec.drive.sample_time
    axes = design_pi(Kp, Ki, Ts, structure="pi", method="tustin")
    dec = decoupling_from_motor(spec.motor, cross=cfg.decoupling, emf=cfg.decoupling)
    ax = lambda pair: {"d": float(pair[0]), "q": float(pair[1])}  # noqa: E731
    params = {
        "rule": "robust", "structure": "pi", "discretisation": "tustin",
        "Kp": ax(Kp), "Ki": ax(Ki), "Ti": ax((Kp[0] / Ki[0], Kp[1] / Ki[1])),
        "Ki_per_sample": ax((Ki[0] * Ts, Ki[1] * Ts)),
        "decoupling": cfg.decoupling,
        "bandwidth_rad_s": ax((res["bandwidth_rad_s"],) * 2),
        "integral_zero": res["zero"],
        "poles": {name: [[float(p.real), float(p.imag)] for p in
                         closed_loop_poles(L, spec.motor.R, Kp[k], Ki[k])]
                  for k, (name, L) in enumerate((("d", spec.motor.Ld), ("q", spec.motor.Lq)))},
        "robust": {
            "disk_margin_required": cfg.disk_margin,
            "worst_disk_margin": res["worst_disk_margin"],
            "worst_model": res["worst_model"],
            "n_models": len(res["params"]), "speeds_rad_s": [float(s) for s in res["speeds"]],
            "parameter_box": {k: list(v) for k, v in cfg.parameter_box.items()},
            "speed_gain": list(cfg.speed_gain),
            "speed_offset_rad_s_mechanical": list(cfg.speed_offset),
            "candidates_rad_s": res["candidates"],
            "largest_stable_pi_bandwidth_rad_s": res["largest_stable_pi_bandwidth"],
            "verification": f"{4 * N_GRID}-point grid, {res['backoffs']} back-off(s) of 2 %",
        },
    }
    if cfg.details:
        params["defaults"] = dict(cfg.details)
    equations = ["Kp = L wc, Ki = Kp w_z (robust PI: max wc s.t. multiloop disk margin "
                 ">= alpha on every model of the set, sampled coupled loop with delay, "
                 "decoupling and voltage placement from the measured speed g w + o)"]
    return make_artifact(spec, axes, dec, params, equations)
