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
Tustin-discretised PI - is at least ``disk_margin``, and the coupled closed
loop is stable (:func:`toolbox.analysis.margins.multimodel_disk_margins`,
the same loop as ``mimo_at_speed`` and the robustness sweep). Models: the
nominal motor, the ``2^3`` corners of the box of ``R``, ``Ld``, ``Lq`` scale
factors and ``samples`` Latin-hypercube sets inside it (log-uniform,
:func:`toolbox.analysis.robustness.sample_parameters`), each at
``n_speeds`` electrical speeds ``linspace(0, p max_speed)`` (the margin is
even in the speed).

Search: for each zero choice, a log grid of ``wc`` from
``wc_max/100`` to the largest stable bandwidth of the sampled PI
(``toolbox.design.largest_stable_pi_bandwidth``), then a bisection between
the largest feasible grid point and the next infeasible one (the feasible
set need not be an interval: at low bandwidth the residual coupling of a
mismatched decoupling at speed is what breaks the margin, at high bandwidth
the delay); the largest feasible ``wc`` over the zero choices wins. The
winner is re-checked on a 4x finer frequency grid and backed off by 2 % at a
time until it passes (``design_parameters["verification"]``).

Spec: ``[controller.robust_pi]`` with ``disk_margin`` (default 0.5: gain
factors 0.6..1.67, +/-28 deg simultaneously in both channels),
``parameter_box`` (``{R = [lo, hi], Ld = [..], Lq = [..]}``, scale factors,
default 0.5..2 each: the robustness sweep's default box), ``max_speed``
(mechanical rad/s, default ``drive.max_speed``, the motor's rated speed or the
back-EMF limit, :func:`toolbox.plant.max_electrical_speed`), ``n_speeds``
(default 4), ``samples`` (default 8), ``seed`` (0), ``zero_ratios``
(default ``[4, 10]``), ``decoupling`` (true).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..analysis.robustness import DEFAULT_BOX, sample_parameters
from ..errors import DesignInfeasible, SpecError
from ..spec import Table
from . import _defaults
from ._common import decoupling_from_motor, make_artifact

__all__ = ["RobustPiCfg", "read_cfg", "design", "model_set", "tune"]

_KEYS = ("disk_margin", "parameter_box", "max_speed", "n_speeds", "samples", "seed",
         "zero_ratios", "decoupling")
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
                "samples": self.samples, "seed": self.seed,
                "zero_ratios": list(self.zero_ratios), "decoupling": self.decoupling}


def read_cfg(method: str, table: Table, motor, drive) -> RobustPiCfg:
    """Validate ``[controller.robust_pi]``.

    Raises
    ------
    SpecError
        Unknown key, a disk margin outside (0, 2), a box bound <= 0 or
        lo > hi, a non-positive speed; key path ``controller.robust_pi.<key>``.
    """
    from ..plant import max_electrical_speed

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
    ratios = t.numbers("zero_ratios", (4.0, 10.0), min_length=0, max_length=8)
    for r in ratios:
        if not r > 1.0:
            raise SpecError(t.key("zero_ratios"), "numbers > 1 (wc / integral zero)", list(ratios))
    return RobustPiCfg(disk_margin=alpha, parameter_box=box, max_speed=float(speed),
                       n_speeds=t.integer("n_speeds", 4, minimum=1, maximum=32),
                       samples=t.integer("samples", 8, minimum=0, maximum=256),
                       seed=t.integer("seed", 0, minimum=0),
                       zero_ratios=tuple(ratios), decoupling=t.boolean("decoupling", True),
                       details=details)


def model_set(motor, cfg: RobustPiCfg) -> tuple[list, list[dict], np.ndarray]:
    """The tuner's models: nominal, box corners and Latin-hypercube samples.

    Returns
    -------
    motors : list of Motor
    params : list of dict
        Scale factors ``{R, Ld, Lq}`` of each motor.
    speeds : ndarray
        Electrical speeds (rad/s), ``linspace(0, p max_speed, n_speeds)``.
    """
    ranges = {k: (lo, hi, "scale") for k, (lo, hi) in cfg.parameter_box.items()}
    P = sample_parameters(ranges, cfg.samples, cfg.seed)
    n = len(P["R"])
    params = [{k: float(P[k][i]) for k in _BOX_KEYS} for i in range(n)]
    motors = [motor.with_overrides(None, p) for p in params]
    wmax = cfg.max_speed * motor.pole_pairs
    speeds = np.linspace(0.0, wmax, cfg.n_speeds) if wmax > 0 else np.zeros(1)
    return motors, params, speeds


def _gains(motor, wc: float, ratio: float | None) -> tuple[tuple, tuple]:
    L = (motor.Ld, motor.Lq)
    Kp = tuple(Lx * wc for Lx in L)
    if ratio is None:          # cancellation zero R/L
        Ki = tuple(motor.R * wc for _ in L)
    else:
        Ki = tuple(k * wc / ratio for k in Kp)
    return Kp, Ki


def _candidate(spec, cfg: RobustPiCfg, Kp, Ki):
    from .pi import design_pi

    axes = design_pi(Kp, Ki, spec.drive.sample_time, structure="pi", method="tustin")
    dec = decoupling_from_motor(spec.motor, cross=cfg.decoupling, emf=cfg.decoupling)
    return make_artifact(spec, axes, dec, {}, [])


def tune(spec, cfg: RobustPiCfg | None = None) -> dict[str, Any]:
    """Search the gains (module docstring); returns the winner and the search record.

    Returns
    -------
    dict
        ``Kp``, ``Ki`` (d, q), ``bandwidth_rad_s`` (``wc``), ``zero`` (the
        choice: ``"cancellation"`` or ``wc/<ratio>``), ``worst_disk_margin``,
        ``worst_model`` (scale factors and electrical speed), ``margins``
        (the ``(models, speeds)`` array of the winner), ``candidates``
        (best feasible ``wc`` per zero choice).

    Raises
    ------
    DesignInfeasible
        No bandwidth meets the disk margin on every model; the message gives
        the best margin found and where.
    """
    from ..analysis.margins import MultiModelLoops

    cfg = cfg or spec.controller.cfg
    motor = spec.motor
    motors, params, speeds = model_set(motor, cfg)
    wc_max = _defaults.largest_stable_pi_bandwidth(spec.drive)
    alpha = cfg.disk_margin
    Ts, d = spec.drive.sample_time, spec.drive.delay_samples
    coarse = MultiModelLoops(motors, speeds, Ts, d, N_GRID)
    fine = MultiModelLoops(motors, speeds, Ts, d, 4 * N_GRID)

    def margins(wc, ratio, loops=coarse):
        art = _candidate(spec, cfg, *_gains(motor, wc, ratio))
        return loops.disk_margins(art)

    grid = np.geomspace(wc_max / 100.0, wc_max * 0.999, N_WC)
    best_seen = (-1.0, None, None)
    results = {}
    for ratio in (None,) + tuple(cfg.zero_ratios):
        k = None
        for i in range(len(grid) - 1, -1, -1):    # from the top: the largest feasible point
            m = float(np.min(margins(grid[i], ratio)))
            if m > best_seen[0]:
                best_seen = (m, float(grid[i]), ratio)
            if m >= alpha:
                k = i
                break
        if k is None:
            results[ratio] = None
            continue
        lo = float(grid[k])
        hi = float(grid[k + 1]) if k + 1 < len(grid) else None
        if hi is not None:
            for _ in range(N_BISECT):
                mid = math.sqrt(lo * hi)
                if float(np.min(margins(mid, ratio))) >= alpha:
                    lo = mid
                else:
                    hi = mid
        results[ratio] = lo
    feasible = {r: wc for r, wc in results.items() if wc is not None}
    if not feasible:
        m, wc, ratio = best_seen
        raise DesignInfeasible(
            "controller.robust_pi.disk_margin",
            f"a disk margin the model set allows (best found {m:.3g} at wc = {wc:.4g} rad/s, "
            f"zero {_zero_name(ratio)})", alpha,
            hint="lower disk_margin, shrink parameter_box or max_speed")
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
                               hint="lower disk_margin slightly")
    i, j = np.unravel_index(int(np.argmin(M)), M.shape)
    Kp, Ki = _gains(motor, wc, ratio)
    return {"Kp": Kp, "Ki": Ki, "bandwidth_rad_s": wc, "zero": _zero_name(ratio),
            "worst_disk_margin": float(M[i, j]),
            "worst_model": dict(params[i], speed_rad_s=float(speeds[j])),
            "margins": M, "params": params, "speeds": speeds,
            "candidates": {_zero_name(r): v for r, v in results.items()},
            "backoffs": backoffs, "largest_stable_pi_bandwidth": wc_max}


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
    from .pi import closed_loop_poles, design_pi

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
            "candidates_rad_s": res["candidates"],
            "largest_stable_pi_bandwidth_rad_s": res["largest_stable_pi_bandwidth"],
            "verification": f"{4 * N_GRID}-point grid, {res['backoffs']} back-off(s) of 2 %",
        },
    }
    if cfg.details:
        params["defaults"] = dict(cfg.details)
    equations = ["Kp = L wc, Ki = Kp w_z (robust PI: max wc s.t. multiloop disk margin "
                 ">= alpha on every model of the set, sampled coupled loop with delay)"]
    return make_artifact(spec, axes, dec, params, equations)
