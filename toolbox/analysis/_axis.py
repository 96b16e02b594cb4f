"""Margins and step figures of the d and q current loops, one axis at a time.

Per axis, the loop is broken at the plant input: ``L = K G`` with the
error controller ``K`` and ``G = 1/(R + s L)`` (:func:`toolbox.plant.axis_plant_models`,
paper 003 eq (33)-(34)).

* **discrete** (default, what users run): ``K`` is the executed discrete law's
  measurement channel (``K = -K_m``, the law is ``v = K_r i_ref + K_m i_meas``),
  the plant is the zero-order-hold discretisation ``b/(z - a)``,
  ``a = exp(-R Ts/L)``, ``b = (1 - a)/R``, times ``z^-d`` for the computation
  delay ``d = artifact.delay_samples``; frequencies run up to Nyquist ``pi/Ts``.
* **continuous**: the continuous error controller with ``1/(R + s L)``,
  optionally with the sampling-plus-computation delay
  ``tau = (d + 1/2) Ts`` as ``exp(-j w tau)`` (``delay="exact"``, frequency
  response route; stability and step figures then use a Pade approximant)
  or as a Pade approximant (``delay="pade"``).

The margins themselves come from :func:`toolbox.analysis._siso.frequency_margins`
(the one margins API); this module assembles the loop and adds the
closed-loop figures (stability, bandwidth, static error, steps).
"""

from __future__ import annotations

import cmath
import math
import weakref
from dataclasses import dataclass, field, fields
from functools import cached_property

import numpy as np

from ..plant import axis_coefficients
from ..artifact import AxisController, json_ready
from ._laws import Law, axis_law
from ._scalar import brentq
from ._siso import MARGIN_KEYS, frequency_margins, log_grid
from ._statespace import (FreqResponse, closed_loop, is_stable, pade, plant_chain, series,
                          zoh_axis)
from ._steps import step_figures

__all__ = ["AxisLoop", "make_axis_loop", "MarginsResult", "axis_margins", "compute_margins"]


@dataclass(frozen=True)
class AxisLoop:
    """One current loop ready for evaluation.

    Attributes
    ----------
    law : Law
        Executed law (discrete) or one-degree-of-freedom continuous law.
    plant : tuple
        ``(A, B, C, D)`` of voltage -> current including the delay (state
        space; a Pade approximant in continuous time).
    discrete : bool
    sample_time : float
        Controller period (s).
    R, L : float
        Plant resistance (ohm) and inductance (H).
    delay_samples : int
    tau : float
        Continuous delay (s) included in ``loop`` (0 if none).
    w_max : float
        Upper end of the frequency grid (rad/s): Nyquist in discrete time.
    exact_delay : bool
        Continuous loop with ``exp(-j w tau)`` in its frequency response
        (``plant`` then holds the Pade twin used for poles and steps).
    """

    law: Law
    plant: tuple
    discrete: bool
    sample_time: float
    R: float
    L: float
    delay_samples: int
    tau: float
    w_max: float
    exact_delay: bool

    # The controllers' and the plant's responses are built once per loop: the
    # margins, the bandwidth, the responses and the sweep's exact recomputations
    # evaluate one loop thousands of times. cached_property writes
    # the instance __dict__ directly, which a frozen dataclass allows.
    @cached_property
    def _controller(self) -> FreqResponse:
        return FreqResponse(*self.law.error_controller())

    @cached_property
    def _reference_controller(self) -> FreqResponse:
        law = self.law
        return FreqResponse(law.A, law.B[:, 0:1], law.C, law.D[:, 0:1])

    @cached_property
    def _plant_fr(self) -> FreqResponse:
        return FreqResponse(*self.plant)

    @cached_property
    def _first_order(self) -> tuple[float, float]:
        """``(a, b)`` of ``b/(x - a)``: the ZOH plant (discrete) or ``1/(R + s L)``."""
        if self.discrete:
            a, b = zoh_axis(self.R, self.L, self.sample_time)
        else:
            a, b = axis_coefficients(self.R, self.L)
        return float(a), float(b)

    def _x(self, w: np.ndarray) -> np.ndarray:
        w = np.atleast_1d(np.asarray(w, float))
        return np.exp(1j * w * self.sample_time) if self.discrete else 1j * w

    def _x_at(self, w: float) -> complex:
        return cmath.exp(1j * w * self.sample_time) if self.discrete else 1j * w

    def plant_response(self, w: np.ndarray) -> np.ndarray:
        """Plant with delay, voltage -> current (A/V), at ``w`` (rad/s)."""
        w = np.atleast_1d(np.asarray(w, float))
        x = self._x(w)
        a, b = self._first_order
        if self.discrete:
            return b / (x - a) * x ** (-self.delay_samples)
        if self.exact_delay or self.tau == 0:
            return np.exp(-1j * w * self.tau) * b / (1j * w - a)
        return self._plant_fr(x)[:, 0, 0]

    def _plant_at(self, w: float, x: complex) -> complex:
        """:meth:`plant_response` at one frequency, in Python arithmetic."""
        a, b = self._first_order
        if self.discrete:
            return b / (x - a) * x ** (-self.delay_samples)
        if self.exact_delay or self.tau == 0:
            return cmath.exp(-1j * w * self.tau) * b / (x - a)
        return self._plant_fr.at(x)

    def loop(self, w: np.ndarray) -> np.ndarray:
        """``L(j w)`` (dimensionless) at the frequencies ``w`` (rad/s)."""
        return self._controller(self._x(w))[:, 0, 0] * self.plant_response(w)

    def loop_at(self, w: float) -> complex:
        """:meth:`loop` at one frequency ``w`` (rad/s)."""
        x = self._x_at(w)
        return self._controller.at(x) * self._plant_at(w, x)

    def reference(self, w: np.ndarray) -> np.ndarray:
        """Reference -> current response ``G K_r/(1 + L)`` at ``w`` (rad/s)."""
        x = self._x(w)
        G = self.plant_response(w)
        Kr = self._reference_controller(x)[:, 0, 0]
        return G * Kr / (1.0 + self._controller(x)[:, 0, 0] * G)

    def reference_at(self, w: float) -> complex:
        """:meth:`reference` at one frequency ``w`` (rad/s)."""
        x = self._x_at(w)
        G = self._plant_at(w, x)
        return G * self._reference_controller.at(x) / (1.0 + self._controller.at(x) * G)

    def reference_loop(self) -> tuple[np.ndarray, ...]:
        """Reference -> current closed loop (state space)."""
        return closed_loop(self.law, self.plant)


def make_axis_loop(axis, R: float, L: float, sample_time: float, delay_samples: int, *,
                   discrete: bool = True, delay: str | None = None,
                   pade_order: int = 3) -> AxisLoop:
    """Assemble the loop of one axis (see the module docstring).

    Parameters
    ----------
    axis : AxisController
    R, L : float
        Plant resistance (ohm) and inductance (H).
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay (periods).
    discrete : bool
        Sampled loop (executed law, ZOH plant, ``z^-d``) or continuous loop.
    delay : {None, "exact", "pade"}
        Continuous mode only: include ``tau = (d + 1/2) Ts`` as ``exp(-s tau)``
        in the frequency response (``"exact"``) or as a Pade approximant of
        order ``pade_order`` everywhere (``"pade"``).
    """
    if delay not in (None, "exact", "pade"):
        raise ValueError(f"delay: expected None, 'exact' or 'pade', got {delay!r}")
    law = axis_law(axis, discrete)
    if discrete:
        a, b = zoh_axis(R, L, sample_time)
        plant = plant_chain(float(a), float(b), int(delay_samples), sample_time)
        return AxisLoop(law, plant, True, sample_time, R, L, int(delay_samples), 0.0,
                        math.pi / sample_time, False)
    a_c, b_c = axis_coefficients(R, L)
    plant = (np.array([[a_c]]), np.array([[b_c]]), np.eye(1), np.zeros((1, 1)))
    tau = 0.0
    if delay is not None:
        tau = (delay_samples + 0.5) * sample_time
        plant = series(pade(tau, pade_order), plant)
    w_max = 1e9 if delay != "exact" else min(1e9, 200.0 / tau)
    return AxisLoop(law, plant, False, sample_time, R, L, int(delay_samples), tau, w_max,
                    delay == "exact")


@dataclass(frozen=True)
class MarginsResult:
    """Margins and linear step figures of one current loop.

    The first nine attributes are the MARGINS keys (toolbox/ARCHITECTURE.md).

    Attributes
    ----------
    gain_margin_db : float
        Gain margin (dB) at the phase crossover; inf if the phase never
        crosses -180 deg.
    gain_crossover_rad_s : float
        Frequency where ``|L| = 1`` (rad/s), where the phase margin is read.
    phase_margin_deg : float
        Phase margin (deg) at the gain crossover; inf without crossover.
    phase_crossover_rad_s : float
        Frequency where ``angle L = -180 deg`` (rad/s), where the gain margin
        is read.
    disk_margin : float
        Balanced (skew 0) disk margin ``alpha = 1/||(S - T)/2||_inf``.
    stability_margin : float
        ``M_m = min_w |1 + L| = 1/||S||_inf`` (paper 003 sect. 3.3).
    sensitivity_peak : float
        ``||S||_inf`` (= 1/M_m).
    bandwidth_rad_s : float
        Closed-loop -3 dB bandwidth of the reference -> current response
        (rad/s), relative to its DC gain.
    static_error : float
        Relative static error of the reference response ``|1 - T_ref(0)|``;
        equals ``|1/(1 + L(0))|`` for one-degree-of-freedom laws, 0 with an
        integrator.
    stable : bool
        Closed loop stable (if not, the margins are not guarantees).
    domain : str
        ``discrete`` or ``continuous`` (with ``delay`` mode).
    delay_margin_s : float
        Extra loop delay tolerated, ``min PM/w_gc`` over gain crossovers (s).
    disk_gain_margin : tuple
        Gain factors ``(low, high)`` guaranteed by the balanced disk margin.
    disk_phase_margin_deg : float
        Phase variation (deg) guaranteed by the balanced disk margin.
    skewed_disk_margins : list of dict
        ``{skew, alpha, gain_low, gain_high, phase_deg}`` for skews -1..1.
    complementary_peak : float
        ``||T||_inf`` of ``T = L/(1 + L)``.
    gain_margins_db, phase_margins_deg : list
        Crossings ``[value (dB or deg), frequency (rad/s)]`` found, the
        eight lowest in frequency.
    response_time_5pct, rise_time_10_90, settling_time_2pct : float
        Linear step response figures (s), the definitions of
        :mod:`toolbox.metrics` (the simulator's and verification's).
    overshoot_pct : float
        Step overshoot (%).
    """

    gain_margin_db: float
    gain_crossover_rad_s: float
    phase_margin_deg: float
    phase_crossover_rad_s: float
    disk_margin: float
    stability_margin: float
    sensitivity_peak: float
    bandwidth_rad_s: float
    static_error: float
    stable: bool = True
    domain: str = "discrete"
    delay_margin_s: float = math.inf
    disk_gain_margin: tuple = (0.0, math.inf)
    disk_phase_margin_deg: float = 90.0
    skewed_disk_margins: list = field(default_factory=list)
    complementary_peak: float = math.nan
    gain_margins_db: list = field(default_factory=list)
    phase_margins_deg: list = field(default_factory=list)
    response_time_5pct: float = math.nan
    rise_time_10_90: float = math.nan
    settling_time_2pct: float = math.nan
    overshoot_pct: float = math.nan

    def to_json(self, extras: bool = True) -> dict:
        """JSON-ready dict: the MARGINS keys first, then (``extras``) the rest."""
        # json_ready copies every list and dict: asdict's deep copy first was a
        # third of the cost
        data = {f.name: getattr(self, f.name) for f in fields(self)}
        out = {k: data[k] for k in MARGIN_KEYS}
        if extras:
            out.update({k: v for k, v in data.items() if k not in MARGIN_KEYS})
        return json_ready(out)


def axis_margins(loop: AxisLoop, *, n_grid: int = 6000, w_min: float = 1e-3,
                 step: bool = True) -> MarginsResult:
    """Margins of one assembled loop (see :func:`compute_margins`).

    Parameters
    ----------
    loop : AxisLoop
        From :func:`make_axis_loop`.
    n_grid : int
        Points of the logarithmic grid from ``w_min`` to ``loop.w_max``.
    w_min : float
        Lowest frequency (rad/s).
    step : bool
        Also compute the linear step figures.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        return _axis_margins(loop, n_grid, w_min, step)


def _axis_margins(loop: AxisLoop, n_grid: int, w_min: float, step: bool) -> MarginsResult:
    w = log_grid(w_min, loop.w_max, n_grid, loop.discrete)
    fm = frequency_margins(loop.loop, w, nyquist=loop.discrete, loop_at=loop.loop_at)
    cl = loop.reference_loop()
    if loop.discrete or loop.tau == 0 or not loop.exact_delay:
        stable = is_stable(cl[0], loop.discrete)
    else:  # exact delay: Pade route for the closed-loop poles
        stable = is_stable(_pade_twin(loop).reference_loop()[0], False)
    figs = {}
    if step and stable:
        cl_step = cl if not loop.exact_delay else _pade_twin(loop).reference_loop()
        figs = step_figures(loop, cl_step)
    balanced = next(d for d in fm.skewed_disk_margins if d["skew"] == 0.0)
    return MarginsResult(
        gain_margin_db=fm.gain_margin_db, gain_crossover_rad_s=fm.gain_crossover_rad_s,
        phase_margin_deg=fm.phase_margin_deg, phase_crossover_rad_s=fm.phase_crossover_rad_s,
        disk_margin=fm.disk_margin, stability_margin=fm.stability_margin,
        sensitivity_peak=fm.sensitivity_peak, bandwidth_rad_s=_bandwidth(loop, w, cl, stable),
        static_error=_static_error(loop, cl, stable), stable=stable,
        domain="discrete" if loop.discrete else (
            "continuous" + ("" if loop.tau == 0 else
                            "+exact_delay" if loop.exact_delay else "+pade_delay")),
        delay_margin_s=fm.delay_margin_s,
        disk_gain_margin=(balanced["gain_low"], balanced["gain_high"]),
        disk_phase_margin_deg=balanced["phase_deg"],
        skewed_disk_margins=fm.skewed_disk_margins, complementary_peak=fm.complementary_peak,
        gain_margins_db=fm.gain_margins_db, phase_margins_deg=fm.phase_margins_deg, **figs)


def _bandwidth(loop: AxisLoop, w: np.ndarray, cl: tuple, stable: bool) -> float:
    """-3 dB bandwidth of the reference response relative to its DC gain (rad/s)."""
    if not stable:
        return math.nan
    dc = abs(_dc_gain(*cl, loop.discrete))
    if not dc > 0:
        return math.nan
    Tref = np.abs(loop.reference(w))
    below = np.nonzero(Tref < dc / math.sqrt(2))[0]
    if not below.size:
        return math.inf
    i = below[0]
    if i == 0:
        return float(w[0])
    f = lambda v: abs(loop.reference_at(v)) - dc / math.sqrt(2)  # noqa: E731
    return math.exp(brentq(lambda lw: f(math.exp(lw)), math.log(w[i - 1]), math.log(w[i])))


def _static_error(loop: AxisLoop, cl: tuple, stable: bool) -> float:
    """``|1 - T_ref(0)|``; 0 with an integrator in the law, nan if unstable."""
    if not stable:
        return math.nan
    if _has_integrator(loop.law, loop.discrete):
        return 0.0
    ess = abs(1.0 - _dc_gain(*cl, loop.discrete))
    return 0.0 if ess < 1e-12 else ess   # rounding of an exact unit DC gain


def _dc_gain(A, B, C, D, discrete: bool) -> float:
    n = A.shape[0]
    M = (np.eye(n) - A) if discrete else -A
    return float((C @ np.linalg.solve(M, B) + D)[0, 0])


def _has_integrator(law: Law, discrete: bool, tol: float = 1e-9) -> bool:
    if law.n == 0:
        return False
    ev = np.linalg.eigvals(law.A)
    return bool(np.any(np.abs(ev - 1) < tol) if discrete else np.any(np.abs(ev) < tol))


def _pade_twin(loop: AxisLoop) -> AxisLoop:
    """The Pade twin of a continuous loop with an exact delay."""
    return AxisLoop(loop.law, loop.plant, False, loop.sample_time, loop.R, loop.L,
                    loop.delay_samples, loop.tau, loop.w_max, False)


def compute_margins(artifact, motor, *, discrete: bool = True, delay: str | None = None,
                    step: bool = True, n_grid: int = 6000) -> dict[str, MarginsResult]:
    """Margins of the d and q current loops of an artifact on a motor.

    Parameters
    ----------
    artifact : ControllerArtifact
        The controller (its executed laws, sample time and delay).
    motor : Motor
        The plant (R in ohm, Ld/Lq in H); :func:`toolbox.plant.axis_plant_models`
        gives the same ``1/(R + s L)``.
    discrete : bool
        True (default): sampled loop as executed (law measurement channel,
        ZOH plant, ``z^-delay_samples``). False: continuous controller and
        plant.
    delay : {None, "exact", "pade"}
        Continuous mode only; see :func:`make_axis_loop`.
    step : bool
        Compute the step figures (s, %) too.
    n_grid : int
        Frequency grid size.

    Returns
    -------
    dict
        ``{"d": MarginsResult, "q": MarginsResult}``.

    Examples
    --------
    >>> m = compute_margins(artifact, motor)               # doctest: +SKIP
    >>> m["q"].phase_margin_deg, m["q"].to_json()          # doctest: +SKIP

    Each axis's result is kept while its :class:`AxisController` lives (frozen,
    hashed by identity) and returned again for the same loop: ``cct design``'s
    verification recomputes the sampled margins the analysis just computed
   .
    """
    out = {}
    for name, L in (("d", motor.Ld), ("q", motor.Lq)):
        axis = artifact.axes[name]
        key = (float(motor.R), float(L), float(artifact.sample_time),
               int(artifact.delay_samples), discrete, None if discrete else delay, step, n_grid)
        known = _MARGINS.setdefault(axis, {}) if isinstance(axis, AxisController) else {}
        if key not in known:
            loop = make_axis_loop(axis, motor.R, L, artifact.sample_time,
                                  artifact.delay_samples, discrete=discrete,
                                  delay=None if discrete else delay)
            known[key] = axis_margins(loop, n_grid=n_grid, step=step)
        out[name] = known[key]
    return out


#: Margins of live controllers by loop (:func:`compute_margins`).
_MARGINS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
