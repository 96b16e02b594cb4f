"""Speed ramp through base speed (toolbox/ARCHITECTURE.md "Operating
envelope"): one run per design beside the torque-speed grid.

The mechanical speed is imposed as a ramp (``kind = "constant_acceleration"``,
the kernel's ``SC_OMEGA0`` / ``SC_ACC`` slots) from 0.5 to 1.5 x base speed
(the top capped by ``drive.max_speed``) while the loop holds the envelope's
reference of the torque limit at the ramp's top speed
(:meth:`~toolbox.plant.OperatingEnvelope.max_torque_point`: the corner of the
current and voltage limits above base speed). Why that reference: the
kernel's current references are two levels (a step), not a schedule over
speed, so the reference is held constant; the top speed's limit point is the
one reference that is feasible over the whole ramp (``|v|^2`` is convex in
the speed at a fixed current, so it stays within the limit between the
ends, both checked) and it crosses base speed at the largest current the
envelope allows there, the voltage margin falling from its low-speed value
to the envelope's headroom at the top: the loop must reject a back-EMF
rising through the speed at which the voltage limit starts to bind.

Timing: the loop first settles for ``span`` (a flying start from zero
current, not judged; the speed ramps from 0.4 x base speed meanwhile), then
the ramp from 0.5 to the top lasts ``10 x span``: the back-EMF sweeps a base
speed's worth of voltage within ten settling spans, faster than a traction or
servo drive's mechanical acceleration (seconds); a loop with integral action
lags a ramp by an error proportional to its rate, so the fast ramp bounds
slower ones. Judged like a grid point over the whole ramp: in every
0.2-span window (the grid's averaging, the last 10 % of its 2-span run) the
mean current stays within ``tolerance`` x the current limit (plus the law's
design band) of the reference, and the peak current within ``peak_limit`` x
the current limit. Where no current fits at the top speed, the ramp's top is
lowered to the highest speed one fits at (bisection; said in ``reason``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from toolbox.errors import SpecError
from toolbox.sim import DriveParams, simulate
from toolbox.spec import Scenario

__all__ = ["SpeedRamp", "speed_ramp", "RAMP_START", "RAMP_END", "RAMP_SPANS"]

#: Ramp start and end, fractions of base speed; its length in settling spans.
RAMP_START = 0.5
RAMP_END = 1.5
RAMP_SPANS = 10.0
#: Averaging window of the ramp's error (spans): the grid's (the last 10 % of 2 spans).
_WINDOW = 0.2


@dataclass(frozen=True)
class SpeedRamp:
    """The speed-ramp run: ``status`` ``"pass"``, ``"fail"`` or
    ``"skipped"`` with ``reason``; speeds (mechanical rad/s) ``speed_start``
    and ``speed_end`` of the judged ramp, ``acceleration`` (rad/s^2),
    ``duration`` (s, settle + ramp); the held reference ``i_d_ref``,
    ``i_q_ref`` (A), its ``torque`` (N m) and ``region``; ``max_error``
    (A, the largest distance of a 0.2-span window's mean current from the
    reference), ``final_error`` (the last window's), ``peak_current`` (A) and the bounds they were
    judged on (``error_bound``, ``peak_bound``, A)."""

    status: str
    reason: str | None
    base_speed: float
    speed_start: float = math.nan
    speed_end: float = math.nan
    acceleration: float = math.nan
    duration: float = math.nan
    i_d_ref: float = math.nan
    i_q_ref: float = math.nan
    torque: float = math.nan
    region: str = ""
    max_error: float = math.nan
    final_error: float = math.nan
    peak_current: float = math.nan
    error_bound: float = math.nan
    peak_bound: float = math.nan

    @property
    def passed(self) -> bool:
        """Not failing (a skipped ramp does not fail the verdict)."""
        return self.status != "fail"

    def summary(self) -> str:
        if self.status == "skipped":
            return f"speed ramp through base speed: skipped ({self.reason})"
        return (f"speed ramp {self.speed_start:.4g} -> {self.speed_end:.4g} rad/s through base "
                f"speed {self.base_speed:.4g} rad/s at {self.torque:.4g} N m ({self.region}): "
                f"{self.status}, max error {self.max_error:.3g} A (bound "
                f"{self.error_bound:.3g} A), peak {self.peak_current:.4g} A (bound "
                f"{self.peak_bound:.4g} A)")

    def failures(self) -> list[str]:
        return [f"speed ramp {self.speed_start:.4g} -> {self.speed_end:.4g} rad/s: "
                f"{self.reason}"] if self.status == "fail" else []

    def to_json(self) -> dict:
        out = {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
               for k, v in asdict(self).items()}
        out.update(passed=self.passed, summary=self.summary())
        return out


def speed_ramp(law, motor, drive: DriveParams, envelope, *, span: float,
               max_speed: float | None = None, tolerance: float, peak_limit: float,
               band: float = 0.0) -> SpeedRamp:
    """The speed ramp through base speed (module docstring) of ``law`` on
    ``motor`` and ``drive`` with the references of ``envelope`` (the grid's,
    :func:`toolbox.verify._envelope_grid.grid_envelope`); ``tolerance`` and
    ``peak_limit`` fractions of the current limit, ``band`` (A) the law's
    design band, as :func:`toolbox.verify.torque_speed_grid`."""
    env = envelope
    base = env.base_speed()
    if not base > 0:
        return SpeedRamp("skipped", "base speed 0: the voltage limit binds at standstill", base)
    w0 = RAMP_START * base
    w1 = RAMP_END * base if max_speed is None else min(RAMP_END * base, max_speed)
    if not w1 > w0:
        return SpeedRamp("skipped", f"drive.max_speed ({max_speed:.4g} rad/s) is below "
                         f"{RAMP_START:g} x base speed ({w0:.4g} rad/s)", base)
    note = None
    if not _fits(env, w1):   # the highest speed a current fits at (bisection, 1e-4)
        lo, hi = base, w1
        while hi - lo > 1e-4 * w1:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _fits(env, mid) else (lo, mid)
        note = f"top speed lowered from {w1:.4g} rad/s: no current fits above {lo:.4g} rad/s"
        w1 = lo
        if not w1 > w0:
            return SpeedRamp("skipped", note, base)
    op = env.max_torque_point(w1)
    ramp_time = RAMP_SPANS * span
    acc = (w1 - w0) / ramp_time
    duration = span + ramp_time
    scen = Scenario(kind="constant_acceleration", duration=duration, step_time=span,
                    id_ref0=op.i_d, iq_ref0=op.i_q, id_ref=op.i_d, iq_ref=op.i_q,
                    initial_speed=w0 - acc * span, acceleration=acc, keep_traces=True,
                    trace_step=drive.sample_time)
    res = simulate(law, motor, scen, drive)
    after = res.t >= span
    # the grid's settled error (mean current of its last 10 %, 0.2 span) in every
    # 0.2-span window of the ramp
    n_win = int(round(RAMP_SPANS / _WINDOW))
    i_d = np.array_split(res.id[after], n_win)
    i_q = np.array_split(res.iq[after], n_win)
    err = np.array([math.hypot(float(np.mean(a)) - op.i_d, float(np.mean(b)) - op.i_q)
                    for a, b in zip(i_d, i_q)])
    max_err, final = float(err.max()), float(err[-1])
    peak = float(np.hypot(res.id[after], res.iq[after]).max())
    e_bound, p_bound = tolerance * env.I + band, peak_limit * env.I
    reasons = []
    if not max_err <= e_bound:
        k = int(np.argmax(err))
        reasons.append(f"{max_err:.3g} A from the reference at "
                       f"{w0 + (w1 - w0) * (k + 0.5) / n_win:.4g} rad/s (bound "
                       f"{e_bound:.3g} A)")
    if not peak <= p_bound:
        reasons.append(f"peak current {peak:.4g} A (bound {p_bound:.4g} A)")
    v_start = float(np.hypot(*env.voltage(op.i_d, op.i_q, w0)))
    if v_start > env.V * (1 + 1e-9):   # not expected (module docstring): say so
        reasons.append(f"the reference needs {v_start:.4g} V at the ramp's start "
                       f"(limit {env.V:.4g} V)")
    status = "fail" if reasons else "pass"
    if note:
        reasons.append(note)
    return SpeedRamp(status, "; ".join(reasons) or None, base, w0, w1,
                     acc, duration, op.i_d, op.i_q, op.torque, op.region, max_err, final, peak,
                     e_bound, p_bound)


def _fits(env, speed: float) -> bool:
    """A current within the limits fits the voltage at ``speed`` (rad/s)."""
    try:
        env.max_torque_point(speed)
    except SpecError:
        return False
    return True
