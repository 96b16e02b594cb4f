"""Torque-speed grid verification: torque steps at the operating envelope's
references over the operating range (toolbox/ARCHITECTURE.md "Operating
envelope").

The default grid (:data:`DEFAULT_TORQUES` x :data:`DEFAULT_SPEEDS`): 0, 50 and
100 % of the standstill torque limit at 0, 50, 100, 150 and 200 % of base
speed, the envelope (:class:`toolbox.plant.OperatingEnvelope`) with 5 % of the
drive's voltage kept for the loop's transients. At each point the speed is
imposed (``kind = "current_step"``, mechanical state held) and the current
reference is the envelope's (MTPA below base speed, field weakening above,
MTPV / the torque limit where the request exceeds what the limits allow). Each
point is a torque step at that speed: the loop first settles at the reference
of the step's start (a flying start from zero current, not judged), then the
reference steps to the point's:

* 50 % and 100 % torque: from the zero-torque reference (0 A below base
  speed, the field-weakening d current above) to the point's;
* 0 % torque: down from the 100 % reference at that speed (a load dump).

A point is judged after the step: the current settles within
``tolerance`` x the current limit of the reference (mean of the last 10 % of
the run) and its peak amplitude stays within ``peak_limit`` x the current
limit (the drive's overcurrent margin). Status ``"pass"``, ``"fail"`` (with
the reason), or ``"unreachable"``: a speed above ``drive.max_speed`` or one
at which no current fits (the back-EMF beyond the voltage limit with the
current limit reached); unreachable points are reported, not simulated, and
do not fail the verdict: the drive cannot run there. A torque the limits cut
at that speed runs at the limit, and the point says so.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, fields, replace

import numpy as np

from toolbox.analysis.envelope_points import tangent_loops
from toolbox.errors import SpecError
from toolbox.plant import OperatingEnvelope, envelope_of
from toolbox.sim import DriveParams, simulate
from toolbox.spec import Scenario

__all__ = ["GridPoint", "EnvelopeGrid", "torque_speed_grid", "DEFAULT_TORQUES",
           "DEFAULT_SPEEDS", "GRID_TOLERANCE", "GRID_PEAK_LIMIT", "GRID_HEADROOM"]

#: Default grid: fractions of the standstill torque limit and of base speed.
DEFAULT_TORQUES = (0.0, 0.5, 1.0)
DEFAULT_SPEEDS = (0.0, 0.5, 1.0, 1.5, 2.0)
#: Settled-error bound, fraction of the current limit (0.4 A of 20 A on paper 003's motor).
GRID_TOLERANCE = 0.02
#: Peak current after the step, multiple of the current limit: the overcurrent
#: margin drives keep between the continuous limit and the trip.
GRID_PEAK_LIMIT = 1.2
#: Voltage fraction the envelope leaves to the loop's transients.
GRID_HEADROOM = OperatingEnvelope.HEADROOM
#: Speeds of the limit curves drawn in the report.
CURVE_POINTS = 41


@dataclass(frozen=True)
class GridPoint:
    """One point of :func:`torque_speed_grid`.

    ``speed`` (mechanical rad/s) and ``torque`` (N m, the request clamped to
    the limit at that speed; NaN when unreachable); ``region`` the
    :class:`~toolbox.plant.OperatingPoint` region (``"unreachable"`` when not
    simulated); ``i_d_ref``, ``i_q_ref`` the reference after the step and
    ``i_d0``, ``i_q0`` before it (A); ``i_d``, ``i_q`` the mean simulated
    currents over the last 10 %; ``error`` their distance from the reference
    (A); ``peak_current`` the largest ``|i|`` after the step (A);
    ``status`` ``"pass"``, ``"fail"`` or ``"unreachable"`` and ``reason``
    (None when passing without remark).
    """

    speed_fraction: float
    torque_fraction: float
    speed: float
    torque: float
    region: str
    i_d0: float
    i_q0: float
    i_d_ref: float
    i_q_ref: float
    i_d: float
    i_q: float
    error: float
    peak_current: float
    status: str
    reason: str | None = None
    linear: dict | None = None

    @property
    def ok(self) -> bool:
        return self.status == "pass"

    def to_json(self) -> dict:
        # the fields as they are (``linear`` is JSON data already): asdict's
        # deep copy of it cost more than the rest of the point
        return {f.name: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for f in fields(self) for v in (getattr(self, f.name),)}


@dataclass(frozen=True)
class EnvelopeGrid:
    """The grid's points and the numbers they were judged on.

    ``base_speed`` (rad/s), ``torque_limit`` (N m at standstill), ``v_max``
    (V, the envelope's voltage limit), ``i_max`` (A), ``voltage_priority``,
    ``step_time`` and ``duration`` (s) of each run, ``band`` (A) the settled
    error the law leaves by design, allowed on top of ``tolerance x i_max``.
    """

    points: tuple[GridPoint, ...]
    base_speed: float
    torque_limit: float
    v_max: float
    i_max: float
    voltage_priority: str
    step_time: float
    duration: float
    tolerance: float = GRID_TOLERANCE
    peak_limit: float = GRID_PEAK_LIMIT
    curves: dict | None = None
    band: float = 0.0
    linear_summary: str | None = None

    @property
    def passed(self) -> bool:
        """No reachable point fails (unreachable points are not failures)."""
        return all(p.status != "fail" for p in self.points)

    def counts(self) -> dict[str, int]:
        return {s: sum(p.status == s for p in self.points)
                for s in ("pass", "fail", "unreachable")}

    def summary(self) -> str:
        """One line: the counts, the base speed, torque limit and priority."""
        c = self.counts()
        return (f"torque-speed grid: {c['pass']} pass, {c['fail']} fail, "
                f"{c['unreachable']} unreachable of {len(self.points)} points "
                f"(base speed {self.base_speed:.4g} rad/s, torque limit "
                f"{self.torque_limit:.4g} N m, {self.voltage_priority} voltage priority)"
                + (f"; {self.linear_summary}" if self.linear_summary else ""))

    def failures(self) -> list[str]:
        """Each failing point named with its reason."""
        return [f"{p.torque_fraction:g} x torque limit at {p.speed_fraction:g} x base speed "
                f"({p.speed:.4g} rad/s): {p.reason}" for p in self.points if p.status == "fail"]

    def to_json(self) -> dict:
        return {"passed": self.passed, "counts": self.counts(), "summary": self.summary(),
                "failures": self.failures(),
                "base_speed_rad_s": self.base_speed, "torque_limit_nm": self.torque_limit,
                "v_max": self.v_max, "i_max": self.i_max,
                "voltage_priority": self.voltage_priority,
                "torque_fractions": sorted({p.torque_fraction for p in self.points}),
                "speed_fractions": sorted({p.speed_fraction for p in self.points}),
                "step_time_s": self.step_time, "duration_s": self.duration,
                "tolerance_fraction": self.tolerance, "peak_limit_fraction": self.peak_limit,
                "design_band_a": self.band, "curves": self.curves,
                "points": [p.to_json() for p in self.points]}


def limit_curves(env: OperatingEnvelope, speed_max: float, n: int = CURVE_POINTS) -> dict:
    """The envelope's limit curves for the report, ``n`` speeds from 0 to
    ``speed_max`` (rad/s): ``torque_limit`` (N m, both limits; None where no
    current fits), ``current_limit`` (the standstill torque limit, the
    current circle alone) and ``voltage_limit`` (the MTPV torque, the voltage
    limit alone; None beyond 10 x the standstill limit, near standstill)."""
    speed = np.linspace(0.0, speed_max, n)
    t_cur = env.max_torque_point(0.0).torque
    both, volt = [], []
    for w in speed:
        try:
            both.append(env.max_torque_point(float(w)).torque)
        except SpecError:
            both.append(None)
        t_v = float(env.torque(*env.mtpv(float(w)))) if w > 0 else math.inf
        volt.append(t_v if t_v <= 10.0 * t_cur else None)
    return {"speed_rad_s": [float(w) for w in speed], "torque_limit": both,
            "current_limit": [t_cur] * n, "voltage_limit": volt}


def _simulate_all(law, motor, drive: DriveParams, scenarios):
    """:func:`toolbox.sim.simulate` of each scenario, in order, on one thread
    per core (``numba.config.NUMBA_NUM_THREADS``, as ``simulate_batch``): the
    compiled kernel releases the GIL and the runs are independent, so the
    results are the sequential ones, bit for bit. ``simulate_batch`` itself
    does not apply: it runs one scenario, without traces, over many plants."""
    if len(scenarios) < 2:
        return [simulate(law, motor, sc, drive) for sc in scenarios]
    import numba  # loaded with toolbox.sim
    with ThreadPoolExecutor(min(len(scenarios), numba.config.NUMBA_NUM_THREADS)) as pool:
        return list(pool.map(lambda sc: simulate(law, motor, sc, drive), scenarios))


def grid_envelope(motor, drive: DriveParams, headroom: float = GRID_HEADROOM) -> OperatingEnvelope:
    """The grid's envelope (:func:`toolbox.plant.envelope_of`: the saturated
    one for a saturated motor): ``motor`` with ``(1 - headroom)`` of the
    drive's voltage circle (SpecError when the motor has no current limit)."""
    if not 0.0 <= headroom < 1.0:
        raise SpecError("headroom", "a fraction in [0, 1)", headroom)
    return envelope_of(motor, v_max=(1.0 - headroom) * drive.radii(motor.torque_factor)[1])


def torque_speed_grid(law, motor, drive: DriveParams, envelope=None, *, span: float = 0.02,
                      max_speed: float | None = None, torques=DEFAULT_TORQUES,
                      speeds=DEFAULT_SPEEDS, tolerance: float = GRID_TOLERANCE,
                      peak_limit: float = GRID_PEAK_LIMIT, band: float = 0.0) -> EnvelopeGrid:
    """Torque steps at the envelope's references over a torque-speed grid
    (module docstring).

    Parameters
    ----------
    law : ControlLaw
        The current controller (``toolbox.sim.control_law(artifact)``).
    motor : Motor
        The plant (and the envelope's motor unless ``envelope`` is given).
    drive : DriveParams
        The simulated drive (its ``voltage_priority`` is the firmware's).
    envelope : OperatingEnvelope, optional
        Default :func:`grid_envelope` (5 % voltage headroom).
    span : float
        Time (s) before the step (the flying start settles) and after it.
    max_speed : float, optional
        Highest mechanical speed of the drive (rad/s, ``drive.max_speed``);
        grid speeds above it are unreachable.
    torques, speeds : sequence of float
        Fractions of the standstill torque limit and of base speed.
    tolerance, peak_limit : float
        Settled error and peak current after the step, fractions of the
        current limit.
    band : float
        Settled error (A) the law leaves by design, allowed on top of
        ``tolerance`` (the predictive law's ripple band,
        :func:`toolbox.verify.fcs_ripple`; 0 for linear laws).
    """
    env = envelope if envelope is not None else grid_envelope(motor, drive)
    settle = tolerance * env.I + band
    base = env.base_speed()
    t_max = env.max_torque_point(0.0).torque
    nan = float("nan")
    pts: list = []          # GridPoint, or (sf, tf, speed, op, start, scenario) to simulate
    for sf in speeds:
        speed = sf * base
        for tf in torques:
            def unreachable(reason):
                pts.append(GridPoint(sf, tf, speed, nan, "unreachable", *[nan] * 8,
                                     "unreachable", reason))
            if max_speed is not None and speed > max_speed * (1 + 1e-12):
                unreachable(f"{speed:.4g} rad/s is above drive.max_speed ({max_speed:.4g} rad/s)")
                continue
            try:
                op = env.operating_point(tf * t_max, speed)
                start = env.operating_point(t_max if tf == 0 else 0.0, speed)
            except SpecError:
                unreachable(f"no current fits at {speed:.4g} rad/s: the back-EMF exceeds the "
                            f"voltage limit ({env.V:.4g} V) with the current limit "
                            f"({env.I:.4g} A) reached")
                continue
            scen = Scenario(kind="current_step", duration=2.0 * span, step_time=span,
                            id_ref0=start.i_d, iq_ref0=start.i_q, id_ref=op.i_d, iq_ref=op.i_q,
                            initial_speed=speed, keep_traces=True, trace_step=drive.sample_time)
            pts.append((sf, tf, speed, op, start, scen))
    runs = iter(_simulate_all(law, motor, drive, [p[5] for p in pts if isinstance(p, tuple)]))
    for k, p in enumerate(pts):
        if not isinstance(p, tuple):
            continue
        sf, tf, speed, op, start, _scen = p
        res = next(runs)
        after = res.t >= span
        n = max(1, len(res.t) // 20)
        i_d, i_q = float(np.mean(res.id[-n:])), float(np.mean(res.iq[-n:]))
        err = float(np.hypot(i_d - op.i_d, i_q - op.i_q))
        peak = float(np.hypot(res.id[after], res.iq[after]).max())
        reasons = []
        if not err <= settle:
            reasons.append(f"settled {err:.3g} A from the reference (bound "
                           f"{settle:.3g} A)")
        if not peak <= peak_limit * env.I:
            reasons.append(f"peak current {peak:.4g} A after the step (bound "
                           f"{peak_limit * env.I:.4g} A)")
        if abs(op.torque - tf * t_max) > 1e-9 * max(t_max, 1e-12):
            reasons.append(f"torque limited to {op.torque:.4g} N m ({op.region}) of "
                           f"{tf * t_max:.4g} N m requested")
        status = "pass" if err <= settle and peak <= peak_limit * env.I else "fail"
        pts[k] = GridPoint(sf, tf, speed, op.torque, op.region, start.i_d, start.i_q,
                           op.i_d, op.i_q, i_d, i_q, err, peak, status,
                           "; ".join(reasons) or None)
    top = max(speeds) * base if speeds else base
    return EnvelopeGrid(tuple(pts), base, t_max, env.V, env.I, drive.voltage_priority,
                        span, 2.0 * span, tolerance, peak_limit,
                        limit_curves(env, top if top > 0 else 1.0), band)


# ---------------------------------------------------------------------------
# The linear proof at each point (toolbox/ARCHITECTURE.md "Operating envelope",
# "One controller, proved per point"): the executed loop at the tangent plant of
# each reachable point, :func:`toolbox.analysis.envelope_points.tangent_loops`.
# Kept apart from the simulation above: it reads the artifact, not the ControlLaw.

def with_tangent_loops(grid: EnvelopeGrid, artifact, motor, requirements=None) -> EnvelopeGrid:
    """``grid`` with each reachable point's linear result (``linear``): the
    executed sampled loop at the tangent plant of its speed and reference
    currents (after the step). A point whose tangent loop is unstable or below
    a margin requirement fails, the reason appended to the simulation's."""
    reach = [p for p in grid.points if p.status != "unreachable"]
    loops = iter(tangent_loops(artifact, motor, [(p.speed, p.i_d_ref, p.i_q_ref) for p in reach],
                               requirements=requirements))
    points, n_stable, worst = [], 0, math.inf
    for p in grid.points:
        if p.status == "unreachable":
            points.append(p)
            continue
        lin = next(loops)
        if lin.analysed:
            n_stable += bool(lin.stable)
            worst = min(worst, lin.mimo_disk_margin)
        reason = "; ".join(r for r in (p.reason, lin.reason) if r) or None
        status = "fail" if p.status == "fail" or not lin.passed else p.status
        points.append(replace(p, status=status, reason=reason, linear=lin.to_json()))
    analysed = sum(bool(p.linear and p.linear["analysed"]) for p in points)
    text = (None if not reach else
            "tangent loops: not analysed (the law has no linear loop)" if not analysed else
            f"tangent loops: {n_stable} stable of {analysed}, worst multiloop disk "
            f"margin {worst:.3g}")
    return replace(grid, points=tuple(points), linear_summary=text)
