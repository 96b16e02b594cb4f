"""Structured robust tuner (``method = "tune"``): systune-class tuning of the dq PI.

The controller structure is the one of :mod:`toolbox.design.pi` (Tustin PI
per axis plus the cross-coupling and back-EMF feedforward), so the artifact
is executed unchanged by every later stage (simulator, analysis, header).
What is tuned, in the spirit of MATLAB's ``systune`` with ``TuningGoal``
objects:

Tunable blocks
    The four PI gains ``Kp_d``, ``Ki_d``, ``Kp_q``, ``Ki_q``, independently
    and log-parametrised, and (``tune_decoupling``, default true) the scale
    ``k`` of the cross-coupling feedforward: the decoupling's controller-side
    inductances are ``Ld_c = k Ld``, ``Lq_c = k Lq`` (``v_d += -k w_m Lq i_q``,
    ``v_q += k w_m Ld i_d``; the back-EMF term keeps the nominal flux). The
    artifact records the scaled ``Ld_c``, ``Lq_c``, which is what the header
    and the simulator execute.

Hard goals (on every model of the active set)
    The balanced multiloop input disk margin of the coupled sampled loop as
    executed (:class:`toolbox.analysis.margins.MultiModelLoops`: ZOH plant,
    the decoupling and the voltage placement ``theta_k + t_c w_meas`` from the
    measured speed ``g w + p o``) is at least ``disk_margin`` - with the
    drive's computation delay ``d`` and, with ``extra_delay`` (default true),
    with one period more (a second ``MultiModelLoops`` with ``d + 1``; the
    placement stays the header's ``t_c``: an unmodelled period of delay);
    the margin is 0 where the coupled closed loop is unstable, so stability
    is part of the goal.

Soft goal
    The slowest tracking: minimise ``max(t5_d, t5_q)``, the 5 % response
    times of the nominal discrete closed loops (standstill, the executed law,
    ZOH plant and delay, intersample current reconstructed; the figures
    ``analysis.json``'s ``margins.discrete`` reports).

Optimiser
    Nelder-Mead (bounded) on the exact penalty
    ``max(t5_d, t5_q)/1 ms + RHO max(0, alpha (1 + BUFFER) - margin)`` from
    several starts (the robust PI's solution of :mod:`toolbox.design.robust_pi`
    - its 1-D search on the same model set, delay ``d`` only - and scaled
    variants with a weaker decoupling), the best polished by a second run.
    The active model set starts as the robust PI's grid (nominal, corners and
    Latin-hypercube sets of R, Ld, Lq x0.5..x2 and the speed sensor, at
    ``n_speeds`` speeds). After each optimisation a worst-case search
    (bounded Nelder-Mead of the margin over the continuous box of ``(R, Ld,
    Lq, w, g, o)``, started from the worst grid models of each delay) and a
    dense check (``check_samples`` Latin-hypercube points of that 6-D box plus
    its 64 corners and the nominal point, each delay) add every model that
    violates the hard goal to the active set, and the optimisation repeats
    (at most ``max_rounds`` rounds) until none does.

Spec: ``[controller.tune]`` with the model-set keys of
``[controller.robust_pi]`` (``disk_margin``, ``parameter_box``,
``max_speed``, ``n_speeds``, ``speed_gain``, ``speed_offset``, ``samples``,
``seed``, ``decoupling``) and ``extra_delay`` (true), ``tune_decoupling``
(true), ``starts`` (4), ``evaluations`` (per start, 200), ``check_samples``
(2000), ``max_rounds`` (4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import DesignInfeasible
from ..spec import Table
from . import _defaults
from . import robust_pi as RP
from ._common import decoupling_from_motor, make_artifact
from .pi import design_pi, closed_loop_poles
from ..analysis.margins import make_axis_loop, step_figures, compute_margins, MultiModelLoops
from scipy.optimize import minimize
from ..analysis.robustness import sample_parameters

__all__ = ["TuneCfg", "read_cfg", "design", "tune", "dense_check", "nominal_response_times"]

_OWN_KEYS = ("extra_delay", "tune_decoupling", "starts", "evaluations", "check_samples",
             "max_rounds")
_SET_KEYS = tuple(k for k in RP._KEYS if k != "zero_ratios")
N_SEARCH = 150        # frequency points of the optimisation (log grid to Nyquist)
N_WORST = 300         # ... of the worst-case search
N_CHECK = 1200        # ... of the final checks (the robust PI's verification grid)
RHO = 100.0           # penalty: 0.01 of margin short weighs as 1 ms of response time
BUFFER = 0.01         # the search aims at alpha (1 + BUFFER): the coarse grid's peak error
BINDING = 0.02        # a hard goal within 2 % of its bound binds
K_BOUNDS = (0.02, 2.0)  # decoupling scale


@dataclass(frozen=True)
class TuneCfg:
    """Validated ``[controller.tune]``.

    Attributes
    ----------
    models : RobustPiCfg
        The model set (the robust PI's keys; :func:`toolbox.design.robust_pi.model_set`).
    extra_delay : bool
        The hard goal also holds with one period of delay more than designed.
    tune_decoupling : bool
        Tune the cross-coupling feedforward's scale ``k``.
    starts : int
        Starts of the optimisation (1..8).
    evaluations : int
        Nelder-Mead evaluations per start.
    check_samples : int
        Latin-hypercube points of the dense check (besides corners and nominal).
    max_rounds : int
        Rounds of optimisation + worst-case search + dense check.
    details : dict
        Defaults applied (reported in design_parameters).
    """

    models: Any
    extra_delay: bool = True
    tune_decoupling: bool = True
    starts: int = 4
    evaluations: int = 200
    check_samples: int = 2000
    max_rounds: int = 4
    details: dict = None

    @property
    def disk_margin(self) -> float:
        return self.models.disk_margin

    def to_spec(self, spec=None) -> dict[str, Any]:
        """``[controller.tune]`` keys that read back to the same configuration."""
        out = {k: v for k, v in self.models.to_spec(spec).items() if k in _SET_KEYS}
        out.update(extra_delay=self.extra_delay, tune_decoupling=self.tune_decoupling,
                   starts=self.starts, evaluations=self.evaluations,
                   check_samples=self.check_samples, max_rounds=self.max_rounds)
        return out


def read_cfg(method: str, table: Table, motor, drive) -> TuneCfg:
    """Validate ``[controller.tune]`` (the model-set keys as ``[controller.robust_pi]``).

    Raises
    ------
    SpecError
        Unknown key (did-you-mean), or a value out of range; key path
        ``controller.tune.<key>``.
    """
    t = Table(table.data, table.prefix, _SET_KEYS + _OWN_KEYS)
    sub = Table({k: v for k, v in t.data.items() if k in _SET_KEYS}, t.prefix)
    models = RP.read_cfg(method, sub, motor, drive)
    details = dict(models.details)
    return TuneCfg(models=models, extra_delay=t.boolean("extra_delay", True),
                   tune_decoupling=t.boolean("tune_decoupling", True),
                   starts=t.integer("starts", 4, minimum=1, maximum=8),
                   evaluations=t.integer("evaluations", 200, minimum=20, maximum=5000),
                   check_samples=t.integer("check_samples", 2000, minimum=0, maximum=100000),
                   max_rounds=t.integer("max_rounds", 4, minimum=1, maximum=16),
                   details=details)


# ------------------------------------------------------------------ candidates
def _unpack(x, tune_k: bool) -> tuple[tuple, tuple, float]:
    Kp = (math.exp(x[0]), math.exp(x[1]))
    Ki = (math.exp(x[2]), math.exp(x[3]))
    k = math.exp(x[4]) if tune_k else 1.0
    return Kp, Ki, k


def _candidate(spec, cfg: TuneCfg, Kp, Ki, k: float, params=None, equations=()):
    axes = design_pi(tuple(Kp), tuple(Ki), spec.drive.sample_time, structure="pi",
                     method="tustin")
    on = cfg.models.decoupling
    dec = decoupling_from_motor(spec.motor, cross=on, emf=on)
    dec = replace(dec, Ld_c=dec.Ld_c * k, Lq_c=dec.Lq_c * k)
    return make_artifact(spec, axes, dec, params or {}, list(equations))


def nominal_response_times(artifact, motor) -> tuple[float, float]:
    """5 % response times (s) of the nominal discrete d and q loops at standstill.

    The executed law, ZOH plant, the artifact's delay, the intersample current
    reconstructed (:func:`toolbox.analysis.margins.step_figures`); ``inf`` for
    a loop that does not settle.
    """
    out = []
    for name, L in (("d", motor.Ld), ("q", motor.Lq)):
        loop = make_axis_loop(artifact.axes[name], motor.R, L, artifact.sample_time,
                              artifact.delay_samples)
        try:
            t5 = step_figures(loop, loop.reference_loop())["response_time_5pct"]
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            t5 = math.inf
        out.append(float(t5) if np.isfinite(t5) else math.inf)
    return out[0], out[1]


# ------------------------------------------------------------------ model boxes
def _box_ranges(spec, cfg: TuneCfg) -> dict:
    """The continuous box of the worst-case search and the dense check:
    ``name -> (lo, hi, kind)``, the speed in electrical rad/s (0..p max_speed)
    and the sensor offset in mechanical rad/s."""
    m = cfg.models
    ranges = {k: (lo, hi, "scale") for k, (lo, hi) in m.parameter_box.items()}
    p = spec.motor.pole_pairs
    wmax = m.max_speed * p
    lo, hi = m.speed_offset
    ranges["speed"] = ((0.0 if lo == -hi else -wmax), wmax, "offset")
    ranges["speed_gain"] = (m.speed_gain[0], m.speed_gain[1], "scale")
    ranges["speed_offset"] = (lo, hi, "offset")
    return ranges


class _Paired:
    """Margins of artifacts on paired (model, speed) points, per delay."""

    def __init__(self, spec, points: list[dict], delays, n_grid: int):
        self.points = list(points)
        motor = spec.motor
        p = motor.pole_pairs
        self.loops = []
        if not self.points:
            return
        motors = [motor.with_overrides(None, {k: q[k] for k in ("R", "Ld", "Lq")})
                  for q in self.points]
        speeds = np.array([q["speed"] for q in self.points])
        gain = np.array([q["speed_gain"] for q in self.points])
        offset = np.array([q["speed_offset"] * p for q in self.points])
        for d in delays:
            self.loops.append((d, MultiModelLoops(motors, speeds, spec.drive.sample_time, d,
                                                  n_grid, speed_gain=gain,
                                                  speed_offset=offset, paired=True)))

    def margins(self, art) -> dict[int, np.ndarray]:
        return {d: L.disk_margins(art)[:, 0] for d, L in self.loops}


def _point(ranges: dict, u: np.ndarray) -> dict:
    """Box point from unit coordinates ``u`` (log for scale factors)."""
    out = {}
    for (name, (lo, hi, kind)), x in zip(ranges.items(), u):
        x = min(max(float(x), 0.0), 1.0)
        out[name] = (math.exp(math.log(lo) + x * (math.log(hi) - math.log(lo)))
                     if kind == "scale" else lo + x * (hi - lo))
    return out


def _unit(ranges: dict, point: dict) -> np.ndarray:
    u = []
    for name, (lo, hi, kind) in ranges.items():
        v = point[name]
        if hi <= lo:
            u.append(0.0)
        elif kind == "scale":
            u.append((math.log(v) - math.log(lo)) / (math.log(hi) - math.log(lo)))
        else:
            u.append((v - lo) / (hi - lo))
    return np.clip(np.array(u), 0.0, 1.0)


def _grid_point(models, i: int, j: int) -> dict:
    q = models.params[i]
    return {"R": q["R"], "Ld": q["Ld"], "Lq": q["Lq"], "speed": float(models.speeds[j]),
            "speed_gain": q["speed_gain"], "speed_offset": q["speed_offset"]}


def worst_case_search(spec, cfg: TuneCfg, art, starts: list[dict], delay: int,
                      evaluations: int = 80) -> list[tuple[float, dict]]:
    """Minimise the margin of ``art`` over the continuous box from each start
    (bounded Nelder-Mead in unit coordinates); ``(margin, point)`` per start."""
    ranges = _box_ranges(spec, cfg)

    def margin(u):
        P = _Paired(spec, [_point(ranges, u)], (delay,), N_WORST)
        return float(P.margins(art)[delay][0])

    found = []
    for s in starts:
        u0 = _unit(ranges, s)
        r = minimize(margin, u0, method="Nelder-Mead", bounds=[(0.0, 1.0)] * len(u0),
                     options={"maxfev": evaluations, "xatol": 1e-3, "fatol": 1e-4,
                              "initial_simplex": _simplex(u0, 0.15)})
        found.append((float(r.fun), _point(ranges, r.x)))
    return found


def _simplex(u0: np.ndarray, step: float) -> np.ndarray:
    """Initial simplex inside the unit box: each vertex moves one coordinate by
    ``step`` towards the box's interior."""
    S = [u0.copy()]
    for i in range(u0.size):
        v = u0.copy()
        v[i] = v[i] - step if v[i] + step > 1.0 else v[i] + step
        S.append(v)
    return np.array(S)


def dense_points(spec, cfg: TuneCfg) -> list[dict]:
    """Nominal point, the corners and ``check_samples`` Latin-hypercube points of
    the box of ``(R, Ld, Lq, speed, speed_gain, speed_offset)``."""
    ranges = _box_ranges(spec, cfg)
    kept = {k: v for k, v in ranges.items() if v[1] > v[0]}
    P = sample_parameters(kept, cfg.check_samples, cfg.models.seed + 1)
    n = len(next(iter(P.values())))
    fixed = {k: float(v[0]) for k, v in ranges.items() if not v[1] > v[0]}
    return [dict({k: float(P[k][i]) for k in kept}, **fixed) for i in range(n)]


def dense_check(spec, cfg: TuneCfg, art, points: list[dict] | None = None,
                n_grid: int = N_CHECK, chunk: int = 400) -> dict[int, np.ndarray]:
    """Margins of ``art`` on the dense sample (:func:`dense_points`) per delay."""
    points = dense_points(spec, cfg) if points is None else points
    out: dict[int, list] = {d: [] for d in _delays(spec, cfg)}
    for s in range(0, len(points), chunk):
        M = _Paired(spec, points[s:s + chunk], _delays(spec, cfg), n_grid).margins(art)
        for d, v in M.items():
            out[d].append(v)
    return {d: np.concatenate(v) if v else np.zeros(0) for d, v in out.items()}


def _delays(spec, cfg: TuneCfg) -> tuple[int, ...]:
    d = spec.drive.delay_samples
    return (d, d + 1) if cfg.extra_delay else (d,)


# ------------------------------------------------------------------ the tuner
def _starts(spec, cfg: TuneCfg) -> tuple[list[np.ndarray], dict]:
    """Starting points: the robust PI's solution (k = 1) and scaled variants."""
    m = spec.motor
    info: dict[str, Any] = {}
    try:
        rp = RP.tune(spec, cfg.models)
        Kp, Ki = rp["Kp"], rp["Ki"]
        info = {"Kp": {"d": Kp[0], "q": Kp[1]}, "Ki": {"d": Ki[0], "q": Ki[1]},
                "bandwidth_rad_s": rp["bandwidth_rad_s"], "zero": rp["zero"],
                "worst_disk_margin": rp["worst_disk_margin"]}
        wc = rp["bandwidth_rad_s"]
    except DesignInfeasible as err:
        wc = 0.4 * _defaults.largest_stable_pi_bandwidth(spec.drive)
        Kp, Ki = (m.Ld * wc, m.Lq * wc), (m.Ld * wc * wc / 10, m.Lq * wc * wc / 10)
        info = {"infeasible": str(err)}
    variants = [(1.0, None, 1.0), (1.0, 10.0, 0.4), (0.7, 4.0, 0.3), (0.9, 4.0, 0.3),
                (0.6, 10.0, 0.6), (1.2, 10.0, 0.3), (0.8, 30.0, 0.5), (1.0, 4.0, 0.2)]
    xs = []
    for f, zr, k in variants[:cfg.starts]:
        if zr is None:
            kp, ki = Kp, Ki
        else:
            w = wc * f
            kp = (m.Ld * w, m.Lq * w)
            ki = (kp[0] * w / zr, kp[1] * w / zr)
        x = np.log([kp[0], kp[1], ki[0], ki[1]] + ([k] if cfg.tune_decoupling else []))
        xs.append(x)
    return xs, info


def _bounds(spec, cfg: TuneCfg) -> list[tuple[float, float]]:
    m = spec.motor
    wmax = _defaults.largest_stable_pi_bandwidth(spec.drive)
    b = []
    for L in (m.Ld, m.Lq):
        b.append((math.log(L * wmax / 1000.0), math.log(L * wmax * 2.0)))
    for L in (m.Ld, m.Lq):
        b.append((math.log(L * wmax / 1000.0), math.log(L * (2.0 * wmax) ** 2)))
    if cfg.tune_decoupling:
        b.append(tuple(math.log(v) for v in K_BOUNDS))
    return b


def tune(spec, cfg: TuneCfg | None = None) -> dict[str, Any]:
    """Run the tuner (module docstring); returns the winner and its record.

    Raises
    ------
    DesignInfeasible
        No candidate meets the hard goal on the dense check after
        ``max_rounds`` rounds; the message gives the best margin reached and
        where.
    """
    cfg = cfg or spec.controller.cfg
    motor = spec.motor
    alpha = cfg.disk_margin
    target = alpha * (1.0 + BUFFER)
    Ts = spec.drive.sample_time
    delays = _delays(spec, cfg)
    models = RP.model_set(motor, cfg.models)
    grid = {d: models.loops(Ts, d, N_SEARCH) for d in delays}
    active: list[dict] = []          # models added by the worst-case search / dense check
    extra = _Paired(spec, active, delays, N_SEARCH)
    bounds = _bounds(spec, cfg)
    starts, rp_info = _starts(spec, cfg)
    n_eval = [0]

    def evaluate(x):
        Kp, Ki, k = _unpack(x, cfg.tune_decoupling)
        art = _candidate(spec, cfg, Kp, Ki, k)
        t5 = nominal_response_times(art, motor)
        worst = min(float(np.min(L.disk_margins(art))) for L in grid.values())
        if extra.loops:
            worst = min(worst, min(float(np.min(v)) for v in extra.margins(art).values()))
        n_eval[0] += 1
        return art, t5, worst

    def penalty(x):
        _, t5, worst = evaluate(x)
        soft = max(t5) / 1e-3 if all(map(math.isfinite, t5)) else 1e3
        return soft + RHO * max(0.0, target - worst)

    def optimise(x0s, fev):
        best = None
        for x0 in x0s:
            x0 = np.clip(x0, [b[0] for b in bounds], [b[1] for b in bounds])
            r = minimize(penalty, x0, method="Nelder-Mead", bounds=bounds,
                         options={"maxfev": fev, "xatol": 1e-3, "fatol": 1e-3,
                                  "adaptive": False})
            if best is None or r.fun < best.fun:
                best = r
        r = minimize(penalty, best.x, method="Nelder-Mead", bounds=bounds,
                     options={"maxfev": fev, "xatol": 1e-4, "fatol": 1e-4})
        return r if r.fun <= best.fun else best

    rounds = []
    x_best = None
    dense = None
    for rnd in range(cfg.max_rounds):
        r = optimise(starts if x_best is None else [x_best], cfg.evaluations)
        x_best = r.x
        art, t5, worst = evaluate(x_best)
        if worst < alpha:
            # infeasible on the active set itself: more models cannot help
            rounds.append({"round": rnd + 1, "objective": float(r.fun),
                           "response_time_5pct_s": {"d": t5[0], "q": t5[1]},
                           "worst_margin_search": worst, "evaluations": int(r.nfev),
                           "violations_added": []})
            break
        # worst-case search from the worst grid models of each delay
        added = []
        for d in delays:
            M = models.loops(Ts, d, N_WORST).disk_margins(art)
            order = np.argsort(M, axis=None)[:2]
            pts = [_grid_point(models, *np.unravel_index(int(o), M.shape)) for o in order]
            for m_found, p in worst_case_search(spec, cfg, art, pts, d):
                if m_found < alpha:
                    added.append(dict(p, delay=d, margin=m_found, source="worst-case search"))
        if not added:
            dense = dense_check(spec, cfg, art)
            pts = dense_points(spec, cfg)
            for d, v in dense.items():
                bad = np.argsort(v)[:4]
                for b in bad:
                    if v[b] < alpha:
                        added.append(dict(pts[b], delay=d, margin=float(v[b]),
                                          source="dense check"))
        rounds.append({"round": rnd + 1, "objective": float(r.fun),
                       "response_time_5pct_s": {"d": t5[0], "q": t5[1]},
                       "worst_margin_search": worst, "evaluations": int(r.nfev),
                       "violations_added": [_json_point(p) for p in added]})
        if not added:
            break
        active.extend({k: p[k] for k in ("R", "Ld", "Lq", "speed", "speed_gain",
                                          "speed_offset")} for p in added)
        extra = _Paired(spec, active, delays, N_SEARCH)
        dense = None
    Kp, Ki, k = _unpack(x_best, cfg.tune_decoupling)
    art = _candidate(spec, cfg, Kp, Ki, k)
    if dense is None:
        dense = dense_check(spec, cfg, art)
    fine = {d: models.loops(Ts, d, N_CHECK).disk_margins(art) for d in delays}
    act = _Paired(spec, active, delays, N_CHECK).margins(art) if active else {}
    pts = dense_points(spec, cfg)
    per_delay = {}
    for d in delays:
        Mg = fine[d]
        i, j = np.unravel_index(int(np.argmin(Mg)), Mg.shape)
        cand = [(float(Mg[i, j]), _grid_point(models, i, j), "grid")]
        if d in act and act[d].size:
            a = int(np.argmin(act[d]))
            cand.append((float(act[d][a]), active[a], "active (worst-case search)"))
        b = int(np.argmin(dense[d]))
        cand.append((float(dense[d][b]), pts[b], "dense check"))
        m_w, p_w, src = min(cand, key=lambda c: c[0])
        per_delay[d] = {"worst_disk_margin": m_w, "worst_model": dict(_json_point(p_w),
                                                                       found_by=src),
                        "grid_worst": float(Mg[i, j]),
                        "dense_worst": float(dense[d][b]), "dense_points": int(dense[d].size)}
    worst = min(v["worst_disk_margin"] for v in per_delay.values())
    if worst < alpha:
        d_w = min(per_delay, key=lambda d: per_delay[d]["worst_disk_margin"])
        raise DesignInfeasible(
            "controller.tune.disk_margin",
            f"a disk margin the model box allows (the best candidate keeps {worst:.3g} "
            f"with delay {d_w}, after {len(rounds)} rounds)", alpha,
            hint=f"worst model {per_delay[d_w]['worst_model']}; "
                 + ("" if cfg.tune_decoupling else "tune_decoupling = true (the scale of the "
                    "cross-coupling feedforward) may open the window; ")
                 + "lower disk_margin, set extra_delay = false or narrow parameter_box")
    t5 = nominal_response_times(art, motor)
    binding = _binding(per_delay, alpha, t5, x_best, bounds, cfg, spec)
    return {"Kp": Kp, "Ki": Ki, "decoupling_scale": k, "artifact": art,
            "response_time_5pct": t5, "per_delay": per_delay, "worst_disk_margin": worst,
            "binding": binding, "rounds": rounds, "active_models": len(active),
            "grid_models": len(models.params), "speeds": models.speeds,
            "evaluations": n_eval[0], "robust_pi_start": rp_info}


def _json_point(p: dict) -> dict:
    keys = ("R", "Ld", "Lq", "speed", "speed_gain", "speed_offset", "delay", "margin", "source")
    out = {k: (float(p[k]) if isinstance(p[k], (int, float, np.floating)) else p[k])
           for k in keys if k in p}
    if "speed" in out:
        out["speed_rad_s"] = out.pop("speed")
    if "speed_offset" in out:
        out["speed_offset_rad_s_mechanical"] = out.pop("speed_offset")
    return out


def _binding(per_delay, alpha, t5, x, bounds, cfg, spec) -> dict:
    """Which goal binds at the optimum: hard goals within ``BINDING`` of their
    bound, the slowest axis of the soft goal, parameters at their bounds."""
    d0 = spec.drive.delay_samples
    hard = []
    for d, v in per_delay.items():
        name = "disk margin, design delay" if d == d0 else "disk margin, one extra period of delay"
        if v["worst_disk_margin"] <= alpha * (1.0 + BINDING):
            hard.append(f"{name} ({v['worst_disk_margin']:.3f} >= {alpha:g})")
    names = ["Kp_d", "Kp_q", "Ki_d", "Ki_q"] + (["decoupling_scale"] if cfg.tune_decoupling
                                                else [])
    at_bound = [n for n, xi, (lo, hi) in zip(names, x, bounds)
                if xi <= lo + 1e-3 or xi >= hi - 1e-3]
    return {"hard": hard, "soft": f"{'d' if t5[0] >= t5[1] else 'q'}-axis 5 % response time "
                                  f"({max(t5) * 1e3:.3g} ms, the slower axis)",
            "parameters_at_bounds": at_bound}


def design(spec):
    """Design the tuned PI a spec asks for (``method = "tune"``).

    Returns
    -------
    ControllerArtifact
        The artifact of the ``pi`` method (Tustin PI per axis, decoupling with
        the cross-coupling inductances scaled by the tuned ``k``) with
        ``method = "tune"``; the tuning record is in ``design_parameters``.
    """
    cfg: TuneCfg = spec.controller.cfg
    res = tune(spec, cfg)
    Kp, Ki, k = res["Kp"], res["Ki"], res["decoupling_scale"]
    Ts = spec.drive.sample_time
    m = spec.motor
    ax = lambda pair: {"d": float(pair[0]), "q": float(pair[1])}  # noqa: E731
    mr = compute_margins(res["artifact"], m, n_grid=2000)
    mc = cfg.models
    t5 = res["response_time_5pct"]
    params = {
        "rule": "tune", "structure": "pi", "discretisation": "tustin",
        "Kp": ax(Kp), "Ki": ax(Ki), "Ti": ax((Kp[0] / Ki[0], Kp[1] / Ki[1])),
        "Ki_per_sample": ax((Ki[0] * Ts, Ki[1] * Ts)),
        "decoupling": mc.decoupling, "decoupling_scale": float(k),
        "bandwidth_rad_s": ax((Kp[0] / m.Ld, Kp[1] / m.Lq)),
        "gain_crossover_rad_s": ax((mr["d"].gain_crossover_rad_s,
                                    mr["q"].gain_crossover_rad_s)),
        "integral_zero_rad_s": ax((Ki[0] / Kp[0], Ki[1] / Kp[1])),
        "response_time_5pct_s": ax(t5),
        "poles": {name: [[float(p.real), float(p.imag)] for p in
                         closed_loop_poles(L, m.R, Kp[i], Ki[i])]
                  for i, (name, L) in enumerate((("d", m.Ld), ("q", m.Lq)))},
        "tune": {
            "goals": {
                "hard": f"multiloop input disk margin >= {mc.disk_margin:g} on every model, "
                        "delay " + " and ".join(str(d) for d in _delays(spec, cfg))
                        + " periods (0 where unstable)",
                "soft": "minimise max(t5_d, t5_q), nominal discrete loops at standstill"},
            "binding": res["binding"],
            "disk_margin_required": mc.disk_margin,
            "worst_disk_margin": res["worst_disk_margin"],
            "per_delay": {str(d): v for d, v in res["per_delay"].items()},
            "grid_models": res["grid_models"], "active_models_added": res["active_models"],
            "speeds_rad_s": [float(s) for s in res["speeds"]],
            "parameter_box": {kk: list(v) for kk, v in mc.parameter_box.items()},
            "speed_gain": list(mc.speed_gain),
            "speed_offset_rad_s_mechanical": list(mc.speed_offset),
            "dense_check": f"{cfg.check_samples} Latin-hypercube points + corners + nominal of "
                           "(R, Ld, Lq, speed, speed_gain, speed_offset), each delay, "
                           f"{N_CHECK}-point grid",
            "rounds": res["rounds"], "evaluations": res["evaluations"],
            "robust_pi_start": res["robust_pi_start"],
        },
    }
    if cfg.details:
        params["defaults"] = dict(cfg.details)
    equations = ["structured tuning of Kp_d, Ki_d, Kp_q, Ki_q and the cross-coupling "
                 "feedforward scale: min max(t5_d, t5_q) s.t. multiloop disk margin >= alpha "
                 "on every model (delay d and d + 1), worst-case search over the box"]
    return _candidate(spec, cfg, Kp, Ki, k, params, equations)
