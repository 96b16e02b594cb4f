"""Stability margins of the current loops (per axis and coupled at speed).

Per axis, the loop is broken at the plant input: ``L = K G`` with the
error controller ``K`` and ``G = 1/(R + s L)`` (:func:`toolbox.plant.axis_plants`,
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

Naming (DESIGN.md MARGINS, same as python-control ``stability_margins``):
``gain_margin_db`` is measured at the **phase crossover** (angle L = -180 deg),
whose frequency is ``phase_crossover_rad_s``; ``phase_margin_deg`` is
measured at the **gain crossover** (|L| = 1), ``gain_crossover_rad_s``.

Margins are computed on a dense logarithmic grid (plus the Nyquist point in
discrete time) and each crossing or extremum is refined (Brent root finding
on ``log|L|`` and ``Im L``; bounded scalar minimisation for the peaks). When
several crossings exist, the headline margins are those closest to
instability (python-control's rule: the gain margin with the smallest
``|log GM|``, the phase margin with the smallest ``|PM|``); the others are in
``gain_margins_db``/``phase_margins_deg``.

Disk margins (Seiler, Packard, Gahinet, "An introduction to disk margins",
IEEE Control Systems Magazine 40(5), 2020): for skew ``sigma`` the loop
tolerates every simultaneous gain and phase variation ``f`` in the disk
``D(alpha, sigma) = {(2 + (1 - sigma) delta)/(2 - (1 + sigma) delta) : |delta| < alpha}``
with ``alpha = 1 / max_w |S + (sigma - 1)/2|`` (SISO); ``sigma = 0`` is the
balanced disk margin ``1/||(S - T)/2||_inf`` reported as ``disk_margin``.
For the coupled 2x2 loop at speed, :func:`mimo_disk_margins` uses the
multiloop (input, diagonal uncertainty) version with the upper bound of the
structured singular value obtained by D-scaling:
``mu(M) <= min_{d>0} sigma_max(D M D^-1)``, ``D = diag(d, 1)``,
``M = S_i + (sigma - 1)/2 I``, ``S_i = (I + C P)^-1`` - a guaranteed
(possibly conservative) multiloop disk margin ``alpha = 1/max_w mu_ub``; the
unstructured ``1/max_w sigma_max(M)`` is reported next to it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq, minimize_scalar

__all__ = ["MARGIN_KEYS", "MarginsResult", "MimoMarginsResult", "AxisLoop", "CoupledLoop",
           "compute_margins", "make_axis_loop", "axis_margins", "mimo_disk_margins",
           "mimo_loop_response", "coupled_closed_loop", "coupled_plant", "decoupling_matrix",
           "disk_variations", "law_to_continuous", "mu_upper_2x2", "sigma_max_2x2",
           "zoh_2x2", "json_ready"]

#: The DESIGN.md MARGINS keys (controller.json), in contract order.
MARGIN_KEYS = ("gain_margin_db", "gain_crossover_rad_s", "phase_margin_deg",
               "phase_crossover_rad_s", "disk_margin", "stability_margin",
               "sensitivity_peak", "bandwidth_rad_s", "static_error")


def json_ready(value: Any) -> Any:
    """Plain-JSON copy: arrays to lists, numpy scalars to Python, non-finite
    floats to the strings ``"inf"``, ``"-inf"``, ``"nan"`` (artifact convention)."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else ("inf" if v > 0 else "-inf" if v < 0 else "nan")
    if isinstance(value, (complex, np.complexfloating)):
        return [float(value.real), float(value.imag)]
    return value


# --------------------------------------------------------------------------
# loop assembly (shared with robustness.py and certificate.py)
# --------------------------------------------------------------------------
AXES = ("d", "q")


@dataclass(frozen=True)
class Law:
    """Matrices of one axis' executed law ``[i_ref, i_meas] -> v``.

    ``B[:, 0]``/``D[0, 0]`` act on the reference, ``B[:, 1]``/``D[0, 1]`` on
    the measurement. ``dt`` None means continuous.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float | None

    @property
    def n(self) -> int:
        """Number of states."""
        return self.A.shape[0]

    def error_controller(self) -> tuple[np.ndarray, ...]:
        """``(A, B, C, D)`` of the error controller ``K = -K_m`` (V/A)."""
        return self.A, -self.B[:, 1:2], self.C, -self.D[:, 1:2]


def axis_law(axis, discrete: bool) -> Law:
    """The law of an :class:`AxisController`.

    Discrete: the executed two-input law. Continuous: for a one-degree-of-
    freedom law (reference channel = minus measurement channel) the
    continuous error controller as ``v = K (i_ref - i_meas)``; for a
    two-degree-of-freedom law (IP, total compensation, ILQ) the continuous
    twin of the executed law obtained by :func:`law_to_continuous` (the
    artifact stores no continuous law). Without a continuous error controller
    the discrete law is converted too.
    """
    s = axis.law
    if discrete:
        return Law(s.A, s.B, s.C, s.D, s.dt)
    one_dof = (np.allclose(s.B[:, 0], -s.B[:, 1], rtol=1e-12, atol=0)
               and np.isclose(s.D[0, 0], -s.D[0, 1], rtol=1e-12, atol=0))
    if one_dof and axis.continuous is not None:
        c = axis.continuous
        return Law(c.A, np.hstack([c.B, -c.B]), c.C, np.hstack([c.D, -c.D]), None)
    return law_to_continuous(Law(s.A, s.B, s.C, s.D, s.dt), s.method)


def law_to_continuous(law: Law, method: str | None) -> Law:
    """Continuous twin of a discrete law (inverse of its discretisation).

    ``tustin``: inverse bilinear map, ``A_c = (2/T) E^-1 (A_d - I)``,
    ``B_c = E^-1 B_d``, ``C_c = (4/T) C_d E^-1``, ``D_c = D_d - C_d E^-1 B_d``
    with ``E = I + A_d`` (needs no pole at z = -1). Otherwise (``zoh``,
    ``native``...): the ZOH inverse through the matrix logarithm of
    ``[[A_d, B_d], [0, I]]`` (integrators allowed; needs no pole on the
    negative real axis).
    """
    from scipy.linalg import logm

    T = float(law.dt)
    n, m = law.B.shape
    if n == 0:
        return Law(law.A, law.B, law.C, law.D, None)
    if method == "tustin":
        E = np.eye(n) + law.A
        Ei = np.linalg.inv(E)
        return Law((2 / T) * Ei @ (law.A - np.eye(n)), Ei @ law.B, (4 / T) * law.C @ Ei,
                   law.D - law.C @ Ei @ law.B, None)
    M = np.zeros((n + m, n + m))
    M[:n, :n] = law.A
    M[:n, n:] = law.B
    M[n:, n:] = np.eye(m)
    Lg = np.real(logm(M)) / T
    return Law(Lg[:n, :n], Lg[:n, n:], law.C, law.D, None)


def freqresp(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
             x: np.ndarray) -> np.ndarray:
    """``C (x I - A)^-1 B + D`` at the complex points ``x`` (s or z).

    Returns an array of shape ``(len(x), p, m)``.
    """
    x = np.asarray(x, complex).reshape(-1)
    n = A.shape[0]
    p, m = D.shape
    if n == 0:
        return np.broadcast_to(D.astype(complex), (x.size, p, m)).copy()
    M = x[:, None, None] * np.eye(n) - A
    return C @ np.linalg.solve(M, np.broadcast_to(B.astype(complex), (x.size, n, m))) + D


def zoh_axis(R, L, Ts) -> tuple[np.ndarray, np.ndarray]:
    """ZOH discretisation of ``1/(R + s L)``: ``(a, b)`` (broadcasts)."""
    R = np.asarray(R, float)
    L = np.asarray(L, float)
    a = np.exp(-R * Ts / L)
    b = -np.expm1(-R * Ts / L) / R
    return a, b


def plant_chain(a: float, b: float, d: int, Ts: float) -> tuple[np.ndarray, ...]:
    """State space of ``z^-d b/(z - a)``; the current is the first state."""
    n = 1 + d
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    C = np.zeros((1, n))
    A[0, 0] = a
    C[0, 0] = 1.0
    if d == 0:
        B[0, 0] = b
    else:
        A[0, 1] = b          # i+ = a i + b q1
        for j in range(1, d):
            A[j, j + 1] = 1.0  # q_j+ = q_{j+1}
        B[d, 0] = 1.0        # q_d+ = v
    return A, B, C, np.zeros((1, 1))


def pade(tau: float, order: int) -> tuple[np.ndarray, ...]:
    """State space of the ``order`` Pade approximation of ``exp(-s tau)``."""
    import control

    num, den = control.pade(tau, order)
    sys = control.ss(control.tf(num, den))
    return (np.array(sys.A, float), np.array(sys.B, float), np.array(sys.C, float),
            np.array(sys.D, float))


def series(first: tuple, second: tuple) -> tuple[np.ndarray, ...]:
    """State space of ``second * first`` (signal passes ``first`` then ``second``)."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [B2 @ C1, A2]])
    B = np.vstack([B1, B2 @ D1])
    C = np.hstack([D2 @ C1, C2])
    return A, B, C, D2 @ D1


def closed_loop(law: Law, plant: tuple) -> tuple[np.ndarray, ...]:
    """Reference -> current closed loop of a law and a strictly proper plant.

    ``plant`` is ``(Ap, Bp, Cp, Dp)`` from voltage (V) to current (A) with
    ``Dp = 0``. States ``[x_law, x_plant]``; returns ``(A, B, C, D)``.
    """
    Ap, Bp, Cp, Dp = plant
    if np.any(Dp):
        raise ValueError("plant must be strictly proper")
    Ak, Bk, Ck, Dk = law.A, law.B, law.C, law.D
    A = np.block([[Ak, Bk[:, 1:2] @ Cp],
                  [Bp @ Ck, Ap + Bp @ Dk[:, 1:2] @ Cp]])
    B = np.vstack([Bk[:, 0:1], Bp @ Dk[:, 0:1]])
    C = np.hstack([np.zeros((1, law.n)), Cp])
    return A, B, C, np.zeros((1, 1))


def is_stable(A: np.ndarray, discrete: bool, tol: float = 1e-9) -> bool:
    """Schur (discrete) or Hurwitz (continuous) test of a state matrix."""
    if A.shape[0] == 0:
        return True
    ev = np.linalg.eigvals(A)
    return bool(np.all(np.abs(ev) < 1 - tol) if discrete else np.all(ev.real < -tol))


def zoh_coupled(Ac: np.ndarray, Bc: np.ndarray, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Stacked ZOH discretisation: ``Ac`` (N, n, n), ``Bc`` (N, n, m).

    Returns ``Phi = exp(A Ts)`` and ``Gamma = int_0^Ts exp(A t) dt B``
    through the exponential of the augmented matrix ``[[A, B], [0, 0]] Ts``.
    """
    N, n, _ = Ac.shape
    m = Bc.shape[2]
    M = np.zeros((N, n + m, n + m))
    M[:, :n, :n] = Ac * Ts
    M[:, :n, n:] = Bc * Ts
    E = expm(M)
    return E[:, :n, :n], E[:, :n, n:]


# --------------------------------------------------------------------------
# per-axis loop model
# --------------------------------------------------------------------------
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

    def _x(self, w: np.ndarray) -> np.ndarray:
        w = np.atleast_1d(np.asarray(w, float))
        return np.exp(1j * w * self.sample_time) if self.discrete else 1j * w

    def plant_response(self, w: np.ndarray) -> np.ndarray:
        """Plant with delay, voltage -> current (A/V), at ``w`` (rad/s)."""
        w = np.atleast_1d(np.asarray(w, float))
        x = self._x(w)
        if self.discrete:
            a, b = zoh_axis(self.R, self.L, self.sample_time)
            return b / (x - a) * x ** (-self.delay_samples)
        if self.exact_delay or self.tau == 0:
            return np.exp(-1j * w * self.tau) / (self.R + 1j * w * self.L)
        return freqresp(*self.plant, x)[:, 0, 0]

    def loop(self, w: np.ndarray) -> np.ndarray:
        """``L(j w)`` (dimensionless) at the frequencies ``w`` (rad/s)."""
        K = freqresp(*self.law.error_controller(), self._x(w))[:, 0, 0]
        return K * self.plant_response(w)

    def reference(self, w: np.ndarray) -> np.ndarray:
        """Reference -> current response ``G K_r/(1 + L)`` at ``w`` (rad/s)."""
        x = self._x(w)
        Kr = freqresp(self.law.A, self.law.B[:, 0:1], self.law.C, self.law.D[:, 0:1], x)[:, 0, 0]
        return self.plant_response(w) * Kr / (1.0 + self.loop(w))

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
    plant = (np.array([[-R / L]]), np.array([[1.0 / L]]), np.eye(1), np.zeros((1, 1)))
    tau = 0.0
    if delay is not None:
        tau = (delay_samples + 0.5) * sample_time
        plant = series(pade(tau, pade_order), plant)
    w_max = 1e9 if delay != "exact" else min(1e9, 200.0 / tau)
    return AxisLoop(law, plant, False, sample_time, R, L, int(delay_samples), tau, w_max,
                    delay == "exact")


# --------------------------------------------------------------------------
# result
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class MarginsResult:
    """Margins and linear step figures of one current loop.

    The first nine attributes are the DESIGN.md MARGINS keys.

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
        Linear step response figures (s), same definitions as the simulator
        (:mod:`toolbox.sim`): band around the reference.
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
        data = asdict(self)
        out = {k: data[k] for k in MARGIN_KEYS}
        if extras:
            out.update({k: v for k, v in data.items() if k not in MARGIN_KEYS})
        return json_ready(out)


# --------------------------------------------------------------------------
# margin computation on a frequency grid with refinement
# --------------------------------------------------------------------------
def disk_variations(alpha: float, skew: float = 0.0) -> tuple[float, float, float]:
    """Gain and phase variations guaranteed by a disk margin.

    Parameters
    ----------
    alpha : float
        Disk margin (dimensionless).
    skew : float
        Disk skew ``sigma`` (0 balanced, 1 for S, -1 for T).

    Returns
    -------
    gain_low, gain_high : float
        Real-axis intercepts of ``D(alpha, sigma)`` (gain factors).
    phase_deg : float
        Largest ``theta`` with ``exp(j theta)`` in the disk (deg), from
        ``cos theta = (1 + g_low g_high)/(g_low + g_high)`` (90 deg when the
        disk is a half plane, 180 when it contains the unit circle).
    """
    lo = max((1 - 0.5 * alpha * (1 - skew)) / (1 + 0.5 * alpha * (1 + skew)), 0.0)
    den = 1 - 0.5 * alpha * (1 + skew)
    hi = (1 + 0.5 * alpha * (1 - skew)) / den if den > 0 else math.inf
    if not math.isfinite(hi):
        return lo, hi, 90.0 if den == 0 else 180.0
    c = (1 + lo * hi) / (lo + hi) if lo + hi != 0 else -2.0
    phase = math.degrees(math.acos(c)) if abs(c) <= 1 else (180.0 if c < -1 else 0.0)
    return float(lo), float(hi), phase


def _grid(w_lo: float, w_hi: float, n: int, discrete: bool) -> np.ndarray:
    w = np.logspace(math.log10(w_lo), math.log10(w_hi), n)
    if discrete:
        w[-1] = w_hi  # exact Nyquist point
    return w


def _roots_in_grid(fun, w: np.ndarray, vals: np.ndarray) -> list[float]:
    """Refined zeros of ``fun`` at sign changes of ``vals`` on ``w``."""
    out = []
    idx = np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0]
    for i in idx:
        try:
            u = brentq(lambda lw: fun(math.exp(lw)), math.log(w[i]), math.log(w[i + 1]),
                       xtol=1e-13, rtol=1e-13)
        except ValueError:
            continue
        out.append(math.exp(u))
    out += [float(w[i]) for i in np.nonzero(vals == 0)[0]]
    return sorted(out)


def _peak(fun, w: np.ndarray, vals: np.ndarray) -> tuple[float, float]:
    """Maximum of ``fun`` (scalar of w) refined around the grid maximum."""
    i = int(np.nanargmax(vals))
    lo, hi = math.log(w[max(i - 1, 0)]), math.log(w[min(i + 1, len(w) - 1)])
    best_w, best = float(w[i]), float(vals[i])
    if hi > lo:
        res = minimize_scalar(lambda lw: -fun(math.exp(lw)), bounds=(lo, hi),
                              method="bounded", options={"xatol": 1e-10})
        if -res.fun > best:
            best_w, best = math.exp(res.x), float(-res.fun)
    return best, best_w


def _dc_gain(A, B, C, D, discrete: bool) -> float:
    n = A.shape[0]
    M = (np.eye(n) - A) if discrete else -A
    return float((C @ np.linalg.solve(M, B) + D)[0, 0])


def _has_integrator(law: Law, discrete: bool, tol: float = 1e-9) -> bool:
    if law.n == 0:
        return False
    ev = np.linalg.eigvals(law.A)
    return bool(np.any(np.abs(ev - 1) < tol) if discrete else np.any(np.abs(ev) < tol))


def _step_response(loop: AxisLoop, A, B, C, D):
    """Fine-grid step response of the reference loop: ``(t, y)`` or None."""
    Ts = loop.sample_time
    if loop.discrete:
        n_steps = 2000
        while True:
            x = np.zeros(A.shape[0])
            X = np.empty((n_steps + 1, A.shape[0]))
            Bv = B[:, 0]
            for k in range(n_steps + 1):
                X[k] = x
                x = A @ x + Bv
            # intersample: i(t_k + s) = e^{-R s/L} i_k + (1 - e^{-R s/L})/R u_k
            nl = loop.law.n
            i_k = X[:, nl]
            if loop.delay_samples >= 1:
                u_k = X[:, nl + 1]
            else:
                Ck, Dk = loop.law.C, loop.law.D
                u_k = X[:, :nl] @ Ck[0] + Dk[0, 0] + Dk[0, 1] * i_k
            m = 10
            s = np.arange(m) * Ts / m
            e = np.exp(-loop.R * s / loop.L)
            y = (i_k[:, None] * e + u_k[:, None] * (1 - e) / loop.R).reshape(-1)
            t = (np.arange(n_steps + 1)[:, None] * Ts + s).reshape(-1)
            if _settled(y) or n_steps >= 32000:
                return t, y
            n_steps *= 2
    t_end = 2000 * Ts
    while True:
        t = np.linspace(0.0, t_end, 8001)
        h = t[1]
        n = A.shape[0]
        M = np.zeros((n + 1, n + 1))
        M[:n, :n] = A * h
        M[:n, n:] = B * h
        E = expm(M)
        x = np.zeros(n)
        y = np.empty(t.size)
        for k in range(t.size):
            y[k] = C[0] @ x + D[0, 0]
            x = E[:n, :n] @ x + E[:n, n]
        if _settled(y) or t_end >= 3.2:
            return t, y
        t_end *= 2


def _settled(y: np.ndarray) -> bool:
    """Inside the 2 % band over the last 30 % of the window."""
    tail = y[int(0.7 * y.size):]
    return bool(np.all(np.abs(tail - 1.0) <= 0.02)) and np.all(np.isfinite(y))


def _step_figures(loop: AxisLoop, cl) -> dict:
    from ..sim._metrics import step_metrics

    t, y = _step_response(loop, *cl)
    figs = step_metrics(t, y, 0.0, 1.0, 0.0)
    return {k: float(v) for k, v in figs.items()}


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
    w = _grid(w_min, loop.w_max, n_grid, loop.discrete)
    Lw = loop.loop(w)
    L1 = lambda x: complex(loop.loop(np.array([x]))[0])  # noqa: E731
    cl = loop.reference_loop()
    A_cl = cl[0]
    if loop.discrete or loop.tau == 0 or not loop.exact_delay:
        stable = is_stable(A_cl, loop.discrete)
    else:  # exact delay: Pade route for the closed-loop poles
        stable = is_stable(_pade_twin(loop).reference_loop()[0], False)

    # gain crossovers (|L| = 1) -> phase margins
    wgc = _roots_in_grid(lambda x: math.log(abs(L1(x))), w, np.log(np.abs(Lw)))
    pms = []
    for x in wgc:
        pm = math.degrees(np.angle(-L1(x)))
        pms.append([pm, x])
    # phase crossovers (Im L = 0, Re L < 0) -> gain margins
    wpc = _roots_in_grid(lambda x: L1(x).imag, w, Lw.imag)
    if loop.discrete and abs(Lw[-1].imag) <= 1e-9 * abs(Lw[-1]) and loop.w_max not in wpc:
        wpc.append(float(loop.w_max))
    gms = []
    for x in wpc:
        Lx = L1(x)
        if Lx.real < 0 and abs(Lx.imag) <= 1e-6 * abs(Lx):
            gms.append([-20 * math.log10(abs(Lx)), x])
    if gms:
        gm_db, w_gm = min(gms, key=lambda g: abs(g[0]))
    else:
        gm_db, w_gm = math.inf, math.nan
    if pms:
        pm, w_pm = min(pms, key=lambda p: abs(p[0]))
        delay_margin = min((math.radians(p) / x if p > 0 else 0.0) for p, x in pms)
    else:
        pm, w_pm, delay_margin = math.inf, math.nan, math.inf

    S = lambda x: 1.0 / (1.0 + L1(x))  # noqa: E731
    Sw = 1.0 / (1.0 + Lw)
    Tw = Lw * Sw
    s_peak, _ = _peak(lambda x: abs(S(x)), w, np.abs(Sw))
    t_peak, _ = _peak(lambda x: abs(1 - S(x)), w, np.abs(Tw))
    skewed = []
    for sigma in (-1.0, -0.5, 0.0, 0.5, 1.0):
        peak, _ = _peak(lambda x: abs(S(x) + 0.5 * (sigma - 1)), w,
                        np.abs(Sw + 0.5 * (sigma - 1)))
        alpha = 1.0 / peak
        lo, hi, ph = disk_variations(alpha, sigma)
        skewed.append({"skew": sigma, "alpha": alpha, "gain_low": lo, "gain_high": hi,
                       "phase_deg": ph})
    dm = next(d for d in skewed if d["skew"] == 0.0)

    # bandwidth of the reference response (-3 dB w.r.t. DC)
    Tref = np.abs(loop.reference(w))
    Tref1 = lambda v: float(abs(loop.reference(np.array([v]))[0]))  # noqa: E731
    dc = abs(_dc_gain(*cl, loop.discrete)) if stable else math.nan
    bw = math.nan
    if stable and dc > 0:
        below = np.nonzero(Tref < dc / math.sqrt(2))[0]
        if below.size:
            i = below[0]
            if i == 0:
                bw = float(w[0])
            else:
                f = lambda v: Tref1(v) - dc / math.sqrt(2)  # noqa: E731
                bw = math.exp(brentq(lambda lw: f(math.exp(lw)), math.log(w[i - 1]),
                                     math.log(w[i])))
        else:
            bw = math.inf
    if not stable:
        ess = math.nan
    elif _has_integrator(loop.law, loop.discrete):
        ess = 0.0
    else:
        ess = abs(1.0 - _dc_gain(*cl, loop.discrete))
        ess = 0.0 if ess < 1e-12 else ess   # rounding of an exact unit DC gain

    figs = {}
    if step and stable:
        cl_step = cl if not loop.exact_delay else _pade_twin(loop).reference_loop()
        figs = _step_figures(loop, cl_step)
    return MarginsResult(
        gain_margin_db=float(gm_db), gain_crossover_rad_s=float(w_pm),
        phase_margin_deg=float(pm), phase_crossover_rad_s=float(w_gm),
        disk_margin=float(dm["alpha"]), stability_margin=float(1.0 / s_peak),
        sensitivity_peak=float(s_peak), bandwidth_rad_s=float(bw), static_error=float(ess),
        stable=stable,
        domain="discrete" if loop.discrete else (
            "continuous" + ("" if loop.tau == 0 else
                            "+exact_delay" if loop.exact_delay else "+pade_delay")),
        delay_margin_s=float(delay_margin),
        disk_gain_margin=(dm["gain_low"], dm["gain_high"]),
        disk_phase_margin_deg=dm["phase_deg"], skewed_disk_margins=skewed,
        complementary_peak=float(t_peak), gain_margins_db=sorted(gms, key=lambda g: g[1])[:8],
        phase_margins_deg=sorted(pms, key=lambda p: p[1])[:8],
        **figs)


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
        The plant (R in ohm, Ld/Lq in H); :func:`toolbox.plant.axis_plants`
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
    """
    out = {}
    for name, L in (("d", motor.Ld), ("q", motor.Lq)):
        loop = make_axis_loop(artifact.axes[name], motor.R, L, artifact.sample_time,
                              artifact.delay_samples, discrete=discrete,
                              delay=None if discrete else delay)
        out[name] = axis_margins(loop, n_grid=n_grid, step=step)
    return out


# --------------------------------------------------------------------------
# coupled dq loop at speed (shared with robustness.py)
# --------------------------------------------------------------------------
def coupled_plant(R, Ld, Lq, omega) -> tuple[np.ndarray, np.ndarray]:
    """Stacked ``A(omega)`` (N, 2, 2) and ``B`` (N, 2, 2) of the dq plant.

    ``A = [[-R/Ld, omega Lq/Ld], [-omega Ld/Lq, -R/Lq]]``,
    ``B = diag(1/Ld, 1/Lq)`` (paper 003 eq (3)-(4); equal to
    :meth:`toolbox.plant.ElectricalPlant.A`, checked in the tests).
    """
    R, Ld, Lq, omega = np.broadcast_arrays(*(np.asarray(v, float) for v in (R, Ld, Lq, omega)))
    R, Ld, Lq, omega = (v.reshape(-1) for v in (R, Ld, Lq, omega))
    N = R.size
    A = np.empty((N, 2, 2))
    A[:, 0, 0] = -R / Ld
    A[:, 0, 1] = omega * Lq / Ld
    A[:, 1, 0] = -omega * Ld / Lq
    A[:, 1, 1] = -R / Lq
    B = np.zeros((N, 2, 2))
    B[:, 0, 0] = 1 / Ld
    B[:, 1, 1] = 1 / Lq
    return A, B


def decoupling_matrix(decoupling, omega_meas) -> np.ndarray:
    """``W`` (N, 2, 2) with ``v += W i``: ``W = cross w_m [[0, -Lq_c], [Ld_c, 0]]``."""
    wm = np.atleast_1d(np.asarray(omega_meas, float)).reshape(-1)
    W = np.zeros((wm.size, 2, 2))
    if decoupling.cross:
        W[:, 0, 1] = -wm * decoupling.Lq_c
        W[:, 1, 0] = wm * decoupling.Ld_c
    return W


def zoh_2x2(A: np.ndarray, B: np.ndarray, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form ZOH of stacked 2x2 plants (fast twin of :func:`zoh_coupled`).

    ``exp(A T) = exp(m T) [cosh(D T) I + T sinhc(D T) (A - m I)]`` with
    ``m = tr A / 2``, ``D = sqrt(m^2 - det A)`` (complex) and
    ``sinhc(x) = sinh(x)/x`` (series near 0); ``Gamma = A^-1 (Phi - I) B``,
    valid because ``det A = R^2/(Ld Lq) + omega^2 > 0`` for the dq plant.
    """
    m = 0.5 * (A[:, 0, 0] + A[:, 1, 1])
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    D = np.sqrt((m * m - det).astype(complex))
    x = D * Ts
    small = np.abs(x) < 1e-3
    xs = np.where(small, 1.0, x)
    sinhc = np.where(small, 1 + x * x / 6 + x ** 4 / 120, np.sinh(xs) / xs)
    e = np.exp(m * Ts)
    c0 = np.real(e * np.cosh(x))
    c1 = np.real(e * Ts * sinhc)
    I = np.eye(2)
    Phi = c0[:, None, None] * I + c1[:, None, None] * (A - m[:, None, None] * I)
    Gam = np.linalg.solve(A, (Phi - I) @ B)
    return Phi, Gam


@dataclass(frozen=True)
class CoupledLoop:
    """Stacked discrete closed loops of the coupled dq current control.

    ``x+ = A x + B r + c`` with states ``[i_d, i_q, x_law_d, x_law_q,
    q_1 .. q_d]`` (``q_j``: commanded dq voltages waiting in the delay line,
    ``q_1`` is applied) and the dq current references ``r`` (A); ``c`` holds
    the back-EMF and its (possibly wrong) compensation. ``A`` (N, n, n).
    """

    A: np.ndarray
    B: np.ndarray
    c: np.ndarray

    def spectral_radius(self) -> np.ndarray:
        """Largest pole modulus of each closed loop (N,)."""
        return np.max(np.abs(np.linalg.eigvals(self.A)), axis=-1)

    def steady_currents(self, r) -> np.ndarray:
        """Static dq currents (N, 2) for constant references ``r`` (A)."""
        N, n, _ = self.A.shape
        rhs = self.B @ np.asarray(r, float).reshape(2) + self.c
        x = np.linalg.solve(np.eye(n) - self.A, rhs[..., None])[..., 0]
        return x[:, :2]


def coupled_closed_loop(laws: dict, decoupling, sample_time: float, delay_samples: int, *,
                        R, Ld, Lq, omega, omega_meas=None, flux=0.0) -> CoupledLoop:
    """Vectorised closed loops of the executed dq control at fixed speeds.

    Parameters
    ----------
    laws : dict
        ``{"d": Law, "q": Law}`` discrete executed laws (:func:`axis_law`).
    decoupling : Decoupling
        Compensation terms and the controller's model parameters.
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay (periods).
    R, Ld, Lq : array_like
        True plant parameters (ohm, H, H), broadcast to N sets.
    omega : array_like
        True electrical speed (rad/s).
    omega_meas : array_like, optional
        Measured electrical speed used by the compensation (rad/s); default
        ``omega`` (paper 000 eq (14)-(17) study its errors).
    flux : array_like
        True magnet flux (Wb), for the back-EMF term ``c``.

    Returns
    -------
    CoupledLoop
        The plant is ZOH-discretised at each speed (exact for constant speed).
    """
    Ts, d = sample_time, int(delay_samples)
    omega_meas = omega if omega_meas is None else omega_meas
    R, Ld, Lq, omega, omega_meas, flux = (
        np.atleast_1d(v).astype(float).reshape(-1)
        for v in np.broadcast_arrays(R, Ld, Lq, omega, omega_meas, flux))
    N = R.size
    Ac, Bc = coupled_plant(R, Ld, Lq, omega)
    Phi, Gam = zoh_2x2(Ac, Bc, Ts)
    W = decoupling_matrix(decoupling, omega_meas)
    ld, lq = laws["d"], laws["q"]
    nd, nq = ld.n, lq.n
    nx = 2 + nd + nq
    n = nx + 2 * d
    # commanded voltage v = Kx x + Kr r + k0
    Kx = np.zeros((N, 2, n))
    Kx[:, :, :2] = W
    Kx[:, 0, 0] += ld.D[0, 1]
    Kx[:, 1, 1] += lq.D[0, 1]
    Kx[:, 0, 2:2 + nd] = ld.C[0]
    Kx[:, 1, 2 + nd:nx] = lq.C[0]
    Kr = np.diag([ld.D[0, 0], lq.D[0, 0]])
    k0 = np.zeros((N, 2))
    if decoupling.emf:
        k0[:, 1] = omega_meas * decoupling.flux_c
    emf = np.zeros((N, 2))
    emf[:, 1] = -omega * flux          # back-EMF as a voltage
    A = np.zeros((N, n, n))
    B = np.zeros((N, n, 2))
    c = np.zeros((N, n))
    A[:, :2, :2] = Phi
    c[:, :2] = (Gam @ emf[..., None])[..., 0]
    # law states
    A[:, 2:2 + nd, 0] = ld.B[:, 1]
    A[:, 2:2 + nd, 2:2 + nd] = ld.A
    B[:, 2:2 + nd, 0] = ld.B[:, 0]
    A[:, 2 + nd:nx, 1] = lq.B[:, 1]
    A[:, 2 + nd:nx, 2 + nd:nx] = lq.A
    B[:, 2 + nd:nx, 1] = lq.B[:, 0]
    if d == 0:
        A[:, :2, :] += Gam @ Kx
        B[:, :2, :] += Gam @ Kr
        c[:, :2] += (Gam @ k0[..., None])[..., 0]
    else:
        A[:, :2, nx:nx + 2] = Gam                       # q_1 applied
        for j in range(d - 1):                          # q_j+ = q_{j+1}
            A[:, nx + 2 * j:nx + 2 * j + 2, nx + 2 * j + 2:nx + 2 * j + 4] = np.eye(2)
        last = slice(nx + 2 * (d - 1), nx + 2 * d)      # q_d+ = v
        A[:, last, :] = Kx
        B[:, last, :] = Kr
        c[:, last] = k0
    return CoupledLoop(A, B, c)


@dataclass(frozen=True)
class MimoMarginsResult:
    """Multiloop (input) disk margins of the coupled dq loop over speed.

    Attributes
    ----------
    speeds_rad_s : list
        Electrical speeds analysed (rad/s).
    disk_margin : list
        Multiloop balanced disk margin at each speed (mu upper bound by
        D-scaling; guaranteed), 0 where the closed loop is unstable.
    disk_margin_unstructured : list
        ``1/max_w sigma_max(S_i - I/2)`` at each speed (full-block bound).
    stable : list of bool
        Closed-loop stability at each speed (eigenvalues).
    worst_speed_rad_s : float
        Speed of the smallest multiloop disk margin (rad/s).
    worst_disk_margin : float
    worst_gain_margin : tuple
        Simultaneous gain factors ``(low, high)`` tolerated in both channels
        at the worst speed.
    worst_phase_margin_deg : float
        Simultaneous phase variation tolerated (deg) at the worst speed.
    domain : str
    """

    speeds_rad_s: list
    disk_margin: list
    disk_margin_unstructured: list
    stable: list
    worst_speed_rad_s: float
    worst_disk_margin: float
    worst_gain_margin: tuple
    worst_phase_margin_deg: float
    domain: str = "discrete"

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready(asdict(self))


def sigma_max_2x2(M: np.ndarray) -> np.ndarray:
    """Largest singular value of stacked 2x2 complex matrices (closed form)."""
    fro2 = np.sum(np.abs(M) ** 2, axis=(-2, -1))
    det = M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0]
    disc = np.sqrt(np.maximum(fro2 ** 2 - 4 * np.abs(det) ** 2, 0.0))
    return np.sqrt(0.5 * (fro2 + disc))


def mu_upper_2x2(M: np.ndarray, n_scale: int = 49, n_refine: int = 40) -> np.ndarray:
    """Upper bound of mu for two 1x1 complex blocks: ``min_d sigma_max(D M D^-1)``.

    ``D = diag(d, 1)``; a logarithmic grid of ``d`` (1e-6..1e6) then a
    ternary search in ``log d`` around the best grid point (the scaled norm is
    convex in ``log d``). Every ``d`` gives a valid upper bound, so an
    unconverged search only adds conservatism.
    """
    def scaled(logd):
        dsc = np.exp(logd)
        Ms = np.array(M, complex, copy=True)
        Ms[..., 0, 1] = M[..., 0, 1] * dsc
        Ms[..., 1, 0] = M[..., 1, 0] / dsc
        return sigma_max_2x2(Ms)

    grid = np.linspace(math.log(1e-6), math.log(1e6), n_scale)
    vals = np.stack([scaled(np.full(M.shape[:-2], g)) for g in grid], axis=-1)
    j = np.argmin(vals, axis=-1)
    step = grid[1] - grid[0]
    lo = grid[j] - step
    hi = grid[j] + step
    for _ in range(n_refine):
        m1 = lo + (hi - lo) / 3
        m2 = hi - (hi - lo) / 3
        left = scaled(m1) < scaled(m2)
        hi = np.where(left, m2, hi)
        lo = np.where(left, lo, m1)
    return np.minimum(np.min(vals, axis=-1), scaled(0.5 * (lo + hi)))


def _electrical_max_speed(motor, drive) -> float:
    mech = None
    if drive is not None and getattr(drive, "max_speed", None):
        mech = drive.max_speed
    elif getattr(motor, "rated_speed", None):
        mech = motor.rated_speed
    elif drive is not None:
        mech = drive.max_voltage(motor.convention) / (motor.pole_pairs * motor.flux)
    else:
        mech = 0.0
    return float(mech) * motor.pole_pairs


def mimo_loop_response(artifact, motor, omega: float, w: np.ndarray, *,
                       discrete: bool = True, omega_meas: float | None = None) -> np.ndarray:
    """Input loop ``L_i = (K - W) P`` (Nw, 2, 2) of the coupled dq loop.

    ``P`` is the plant ``v -> i`` at electrical speed ``omega`` (ZOH with
    ``z^-d`` in discrete time; ``exp(-s tau)``, ``tau = (d + 1/2) Ts``, in
    continuous time), ``K = diag(K_d, K_q)`` the error controllers (executed
    laws' measurement channels in discrete time) and ``W`` the decoupling
    with the controller's model parameters and measured speed.
    """
    Ts, d = artifact.sample_time, artifact.delay_samples
    w = np.atleast_1d(np.asarray(w, float))
    Ac, Bc = coupled_plant(motor.R, motor.Ld, motor.Lq, omega)
    if discrete:
        Phi, Gam = zoh_coupled(Ac, Bc, Ts)
        x = np.exp(1j * w * Ts)
        P = np.linalg.solve(x[:, None, None] * np.eye(2) - Phi[0], np.broadcast_to(Gam[0], (w.size, 2, 2)))
        P = P * (x ** (-d))[:, None, None]
    else:
        x = 1j * w
        P = np.linalg.solve(x[:, None, None] * np.eye(2) - Ac[0], np.broadcast_to(Bc[0], (w.size, 2, 2)))
        P = P * np.exp(-1j * w * (d + 0.5) * Ts)[:, None, None]
    C = np.zeros((w.size, 2, 2), complex)
    for k, name in enumerate(AXES):
        law = axis_law(artifact.axes[name], discrete)
        C[:, k, k] = freqresp(*law.error_controller(), x)[:, 0, 0]
    W = decoupling_matrix(artifact.decoupling, omega if omega_meas is None else omega_meas)[0]
    return (C - W) @ P


def mimo_disk_margins(artifact, motor, drive=None, *, n_speeds: int = 9,
                      n_grid: int = 1500, discrete: bool = True,
                      max_speed_rad_s: float | None = None) -> MimoMarginsResult:
    """Balanced multiloop input disk margin of the coupled loop over speed.

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        True plant (equal to the controller's model unless you pass another).
    drive : Drive, optional
        ``max_speed`` (mechanical, rad/s) sets the speed range; else
        ``motor.rated_speed``; else the speed where the back-EMF reaches the
        voltage limit.
    n_speeds : int
        Electrical speeds on ``linspace(-w_max, w_max)`` (odd: includes 0).
    n_grid : int
        Frequency points (log grid 1e-2 rad/s .. Nyquist, or 1e7 rad/s).
    discrete : bool
        Sampled loop (default) or continuous loop with ``exp(-s tau)``.
    max_speed_rad_s : float, optional
        Electrical speed range override (rad/s).

    Returns
    -------
    MimoMarginsResult
        Formula: ``alpha(omega) = 1/max_w mu_ub(S_i(jw) - I/2)`` with
        ``S_i = (I + L_i)^-1`` (module docstring); the residual coupling
        left by the delayed, sampled decoupling is in ``L_i``.
    """
    wmax = max_speed_rad_s if max_speed_rad_s is not None else _electrical_max_speed(motor, drive)
    speeds = np.linspace(-wmax, wmax, n_speeds) if wmax > 0 else np.zeros(1)
    Ts = artifact.sample_time
    w_hi = math.pi / Ts if discrete else 1e7
    w = _grid(1e-2, w_hi, n_grid, discrete)
    if discrete:
        w = w[:-1]  # z = -1 exactly can hit a Tustin controller's pole/zero
    laws = {k: axis_law(artifact.axes[k], True) for k in AXES}
    dm, du, st = [], [], []
    for om in speeds:
        if discrete:
            loop = coupled_closed_loop(laws, artifact.decoupling, Ts, artifact.delay_samples,
                                       R=motor.R, Ld=motor.Ld, Lq=motor.Lq, omega=om)
            stable = bool(loop.spectral_radius()[0] < 1 - 1e-9)
        else:
            stable = _continuous_coupled_stable(artifact, motor, om)
        Li = mimo_loop_response(artifact, motor, om, w, discrete=discrete)
        S = np.linalg.inv(np.eye(2) + Li)
        M = S - 0.5 * np.eye(2)
        a_mu = 1.0 / float(np.max(mu_upper_2x2(M))) if stable else 0.0
        a_u = 1.0 / float(np.max(sigma_max_2x2(M))) if stable else 0.0
        dm.append(a_mu)
        du.append(a_u)
        st.append(stable)
    k = int(np.argmin(dm))
    lo, hi, ph = disk_variations(dm[k], 0.0)
    return MimoMarginsResult([float(x) for x in speeds], dm, du, st, float(speeds[k]), dm[k],
                             (lo, hi), ph, "discrete" if discrete else "continuous+exact_delay")


def _continuous_coupled_stable(artifact, motor, omega: float, pade_order: int = 3) -> bool:
    """Closed-loop stability of the continuous coupled loop (Pade delay)."""
    import control

    Ts, d = artifact.sample_time, artifact.delay_samples
    Ac, Bc = coupled_plant(motor.R, motor.Ld, motor.Lq, omega)
    P = control.ss(Ac[0], Bc[0], np.eye(2), np.zeros((2, 2)))
    num, den = control.pade((d + 0.5) * Ts, pade_order)
    Dl = control.ss(control.tf(num, den))
    P = P * control.append(Dl, Dl)
    Ks = []
    for name in AXES:
        law = axis_law(artifact.axes[name], False)
        Ks.append(control.ss(*law.error_controller()))
    C = control.append(*Ks) - control.ss([], [], [], decoupling_matrix(artifact.decoupling, omega)[0])
    cl = control.feedback(P * C, np.eye(2))
    return bool(np.all(np.real(cl.poles()) < 0))
