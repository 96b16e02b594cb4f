"""LQ servo (LQI) current control via Riccati equations.

Per axis (after decoupling) the plant is ``di/dt = a i + b u`` with
``a = -R/L`` (1/s), ``b = 1/L`` (1/H) (paper 001 eq (1); paper 003 eq (33)-(34)).
Integral action enters as the servo state ``z`` with ``z' = i_ref - i``.

Continuous design (``domain = "continuous"``): CARE on ``x = [i, z]``,
``u = -K x``; the executed law is discretised with Tustin.

Discrete design (``domain = "discrete"``): at the sample time ``Ts`` with the
computation delay of ``d = drive.delay_samples`` periods modelled as extra
states (the previous inputs): ``x_k = [i_k, z_k, u_{k-1}, ..., u_{k-d}]``,

    i_{k+1} = Phi i_k + Gamma u_{k-d},  z_{k+1} = z_k + Ts (i_ref,k - i_k),

``Phi = exp(a Ts)``, ``Gamma = (Phi - 1) b / a`` (zero-order hold), DARE with
``Q Ts``, ``R Ts`` (the sampled continuous cost; delayed inputs unweighted).
The executed law keeps ``z`` and the input history as its states (native
discrete design).

Default weights (Bryson's rule): ``q_i = 1/i_max^2``, ``r = 1/v_max^2`` and
``q_z = (w_b / i_max)^2`` (an integral error of ``i_max / w_b`` costs as much as
``i_max``), with ``i_max`` = ``current_limit`` (default motor rated or max
current), ``v_max`` = ``voltage_limit`` (default ``drive.max_voltage``) and
``w_b`` = ``bandwidth`` (default ``pi / (10 Ts)``).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla

from ..lti import StateSpace
from ..artifact import AxisController, ControllerArtifact
from ..errors import SpecError
from ..plant import axis_coefficients
from ..spec import Table, check_rate, check_scale
from . import _defaults
from ._common import decoupling_from_motor, make_artifact
from .ilq import first_order_coefficients

__all__ = ["LqCfg", "LqAxis", "bryson_weights", "lqi_continuous", "lqi_discrete",
           "lqi_from_plant", "discrete_model",
           "design_lq", "read_cfg", "design"]

_KEY = "controller.lq"
AXES = ("d", "q")


@dataclass(frozen=True)
class LqCfg:
    """Validated ``[controller.lq]``.

    Attributes
    ----------
    domain : str
        ``"continuous"`` (CARE) or ``"discrete"`` (DARE with the delay).
    Q : dict
        Per axis diagonal ``(q_i, q_z)`` (1/A^2, 1/(A s)^2).
    R : dict
        Per axis input weight (1/V^2).
    bandwidth, current_limit, voltage_limit : float
        What the default weights were derived from (rad/s, A, V).
    """

    domain: str
    Q: dict
    R: dict
    bandwidth: float
    current_limit: float | None
    voltage_limit: float
    defaults: dict | None = None

    def to_spec(self, spec=None) -> dict[str, Any]:
        """``[controller.lq]`` keys that read back to this configuration:
        ``domain`` and the weights ``Q``, ``R`` per axis (Bryson's defaults
        included). ``bandwidth``, ``current_limit`` and ``voltage_limit``
        only shape default weights, so they are left out once Q and R are
        written.

        Parameters
        ----------
        spec : Spec, optional
            Unused (same signature as the other methods' ``to_spec``).

        Returns
        -------
        dict
        """
        return {"domain": self.domain,
                "Q": {ax: [float(v) for v in self.Q[ax]] for ax in ("d", "q")},
                "R": {ax: float(self.R[ax]) for ax in ("d", "q")}}


def bryson_weights(current_limit: float, voltage_limit: float,
                   bandwidth: float) -> tuple[tuple[float, float], float]:
    """Bryson's-rule weights of the LQI servo.

    Parameters
    ----------
    current_limit : float
        Largest acceptable current error (A).
    voltage_limit : float
        Largest voltage (V).
    bandwidth : float
        Target bandwidth (rad/s) tying the integral weight.

    Returns
    -------
    (q_i, q_z) : tuple of float
        ``1/i_max^2`` (1/A^2) and ``(w_b/i_max)^2`` (1/(A s)^2).
    r : float
        ``1/v_max^2`` (1/V^2).
    """
    return (1.0 / current_limit ** 2, (bandwidth / current_limit) ** 2), 1.0 / voltage_limit ** 2


def _check_weights(Q: tuple[float, float], R: float, axis: str) -> None:
    q_i, q_z = Q
    if not (math.isfinite(q_i) and math.isfinite(q_z) and q_i >= 0 and q_z > 0):
        raise SpecError(f"{_KEY}.Q", f"[q_i, q_z] for the {axis} axis with q_i >= 0 and q_z > 0 "
                        "(the integrator must be weighted for the Riccati solution to "
                        "stabilise it)", list(Q))
    if not (math.isfinite(R) and R > 0):
        raise SpecError(f"{_KEY}.R", f"an input weight > 0 (1/V^2) for the {axis} axis "
                        "(R must be positive definite)", R)


@dataclass(frozen=True)
class LqAxis:
    """LQI design of one axis.

    Attributes
    ----------
    K : ndarray (1, n)
        State feedback ``u = -K x`` on ``[i, z, u_{k-1}, .., u_{k-d}]``
        (continuous: ``[i, z]``).
    A, B : ndarray
        Augmented design model (continuous or discrete).
    Q, R : ndarray
        Weights used in the Riccati equation.
    poles : ndarray
        Closed-loop eigenvalues of ``A - B K`` (rad/s or z-plane).
    domain : str
    sample_time : float
    delay_samples : int
    """

    K: np.ndarray
    A: np.ndarray
    B: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    poles: np.ndarray
    domain: str
    sample_time: float
    delay_samples: int

    def law(self) -> StateSpace:
        """Two-input law ``[i_ref, i] -> u`` (continuous for the CARE design,
        discrete at ``sample_time`` for the DARE design)."""
        k = self.K.ravel()
        if self.domain == "continuous":
            # state z, z' = i_ref - i, u = -k_i i - k_z z
            return StateSpace([[0.0]], [[1.0, -1.0]], [[-k[1]]], [[0.0, -k[0]]])
        d, ts = self.delay_samples, self.sample_time
        n = 1 + d                                      # [z, u_{k-1}, ..., u_{k-d}]
        C = -k[1:].reshape(1, n)                       # u = C xi - k_i i
        D = np.array([[0.0, -k[0]]])
        A = np.zeros((n, n))
        B = np.zeros((n, 2))
        A[0, 0] = 1.0
        B[0] = [ts, -ts]
        if d:
            A[1] = C                                   # u_{k-1}^+ = u_k
            B[1] = D
            for j in range(2, n):
                A[j, j - 1] = 1.0                      # shift register
        return StateSpace(A, B, C, D, ts)


def lqi_continuous(a: float, b: float, Q: tuple[float, float], R: float) -> LqAxis:
    """Continuous LQI (CARE) of ``di/dt = a i + b u`` with ``z' = i_ref - i``.

    Parameters
    ----------
    a, b : float
        Plant coefficients (1/s, 1/H).
    Q : (float, float)
        ``(q_i, q_z)`` diagonal state weight.
    R : float
        Input weight (1/V^2).

    Returns
    -------
    LqAxis
    """
    A = np.array([[a, 0.0], [-1.0, 0.0]])
    B = np.array([[b], [0.0]])
    Qm, Rm = np.diag(Q), np.array([[R]])
    P = _riccati(sla.solve_continuous_are, A, B, Qm, Rm)
    K = np.linalg.solve(Rm, B.T @ P)
    poles = np.linalg.eigvals(A - B @ K)
    _check_closed_loop(np.max(poles.real) < 0, poles)
    return LqAxis(K, A, B, Qm, Rm, poles, "continuous", 0.0, 0)


def _riccati(solver, A, B, Q, R, rtol: float = 1e-6) -> np.ndarray:
    """Solve a CARE/DARE and check its residual relative to its largest term:
    with extreme weight ratios the solvers return inaccurate solutions
    silently, and a failure is a consequence of the spec's weights."""
    try:
        # extreme weights make scipy warn (e.g. "invalid value encountered in cast")
        # before it fails or returns: the failure and the residual check below are
        # the message, a library warning is not leaked
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            P = solver(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as err:
        raise SpecError("controller.lq", "weights for which the Riccati equation has a "
                        "stabilising solution", str(err),
                        hint="check Q, R (or the Bryson limits) for extreme ratios") from None
    if solver is sla.solve_continuous_are:
        quad = P @ B @ np.linalg.solve(R, B.T @ P)
        terms = (A.T @ P, P @ A, quad, Q)
        residual = A.T @ P + P @ A - quad + Q
    else:
        quad = A.T @ P @ B @ np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
        terms = (A.T @ P @ A, P, quad, Q)
        residual = A.T @ P @ A - P - quad + Q
    scale = max(np.linalg.norm(t) for t in terms)
    if not np.linalg.norm(residual) <= rtol * scale:
        raise SpecError("controller.lq.R", "weights for which the Riccati equation is solved "
                        f"accurately (relative residual <= {rtol:g})",
                        f"relative residual {np.linalg.norm(residual) / scale:.3g}",
                        hint="bring Q and R closer in scale")
    return P


def _check_closed_loop(stable: bool, poles: np.ndarray) -> None:
    """The Riccati gain must stabilise the model it was computed for; with
    extreme weights the solvers lose accuracy silently, so check."""
    if not stable:
        raise SpecError("controller.lq.R", "weights giving a stabilising LQ gain",
                        f"closed-loop poles {np.round(poles, 4).tolist()}",
                        hint="the Riccati solution is inaccurate for these weights: "
                             "bring Q and R closer in scale")


def discrete_model(a: float, b: float, sample_time: float,
                   delay_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """ZOH servo model with the computation delay as input-history states.

    Returns
    -------
    A, B : ndarray
        On ``[i, z, u_{k-1}, ..., u_{k-d}]``.
    """
    ts, d = sample_time, delay_samples
    phi = math.exp(a * ts)
    gam = (phi - 1.0) / a * b if a != 0 else b * ts
    n = 2 + d
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    A[0, 0] = phi
    A[1, 0], A[1, 1] = -ts, 1.0
    if d == 0:
        B[0, 0] = gam
    else:
        A[0, n - 1] = gam                              # the input applied now is u_{k-d}
        B[2, 0] = 1.0
        for j in range(3, n):
            A[j, j - 1] = 1.0
    return A, B


def lqi_discrete(a: float, b: float, Q: tuple[float, float], R: float,
                 sample_time: float, delay_samples: int = 1) -> LqAxis:
    """Discrete LQI (DARE) at ``sample_time`` with ``delay_samples`` of delay.

    Parameters
    ----------
    a, b : float
        Plant coefficients (1/s, 1/H).
    Q : (float, float)
        ``(q_i, q_z)``; the cost is sampled as ``Q Ts`` (input history unweighted).
    R : float
        Input weight (1/V^2), used as ``R Ts``.
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay (periods), >= 0.

    Returns
    -------
    LqAxis
    """
    A, B = discrete_model(a, b, sample_time, delay_samples)
    n = A.shape[0]
    Qm = np.zeros((n, n))
    Qm[0, 0], Qm[1, 1] = Q
    Qm *= sample_time
    Rm = np.array([[R * sample_time]])
    P = _riccati(sla.solve_discrete_are, A, B, Qm, Rm)
    K = np.linalg.solve(Rm + B.T @ P @ B, B.T @ P @ A)
    poles = np.linalg.eigvals(A - B @ K)
    _check_closed_loop(np.max(np.abs(poles)) < 1, poles)
    return LqAxis(K, A, B, Qm, Rm, poles, "discrete", sample_time, delay_samples)


def lqi_from_plant(G: Any, Q: tuple[float, float], R: float, *, domain: str = "discrete",
                   sample_time: float | None = None, delay_samples: int = 1) -> LqAxis:
    """LQI design of one axis from a plant ``1/(R + s L)``.

    Parameters
    ----------
    G : toolbox.lti.StateSpace or python-control LTI
        First-order plant (A/V).
    Q : (float, float)
        ``(q_i, q_z)``.
    R : float
        Input weight (1/V^2).
    domain : {"continuous", "discrete"}
    sample_time : float, optional
        Controller period (s), required for the discrete design.
    delay_samples : int
        Computation delay (periods), discrete design only.

    Returns
    -------
    LqAxis
    """
    a, b = first_order_coefficients(G)
    _check_weights(Q, R, "plant")
    if domain == "continuous":
        return lqi_continuous(a, b, Q, R)
    if sample_time is None:
        raise ValueError("lqi_from_plant: the discrete design needs sample_time (s)")
    return lqi_discrete(a, b, Q, R, sample_time, delay_samples)


def design_lq(Ld: float, Lq: float, R: float, Q: dict, Rw: dict, sample_time: float, *,
              domain: str = "discrete", delay_samples: int = 1) -> dict[str, LqAxis]:
    """LQI design of both axes.

    Parameters
    ----------
    Ld, Lq, R : float
        Inductances (H) and resistance (ohm).
    Q : dict
        ``{"d": (q_i, q_z), "q": (q_i, q_z)}``.
    Rw : dict
        ``{"d": r, "q": r}`` (1/V^2).
    sample_time : float
        Controller period (s).
    domain : {"continuous", "discrete"}
    delay_samples : int
        Computation delay (periods), discrete design only.

    Returns
    -------
    dict of str to LqAxis

    Examples
    --------
    >>> ax = design_lq(1.4e-3, 2.8e-3, 0.6, {"d": (1e-2, 1e5), "q": (1e-2, 1e5)},
    ...                {"d": 1e-4, "q": 1e-4}, 1e-4)["q"]
    >>> bool(np.all(np.abs(ax.poles) < 1))
    True
    """
    out = {}
    for ax, L in zip(AXES, (Ld, Lq)):
        _check_weights(Q[ax], Rw[ax], ax)
        a, b = axis_coefficients(R, L)
        out[ax] = (lqi_continuous(a, b, Q[ax], Rw[ax]) if domain == "continuous"
                   else lqi_discrete(a, b, Q[ax], Rw[ax], sample_time, delay_samples))
    return out


def read_cfg(method: str, table, motor, drive) -> LqCfg:
    """Validate ``[controller.lq]``.

    Keys: ``domain`` ("continuous" | "discrete", default "discrete"); ``Q``
    (``[q_i, q_z]`` or ``{d = [..], q = [..]}``) and ``R`` (number or
    ``{d =, q =}``) explicit, otherwise Bryson's rule from ``bandwidth``
    (rad/s, default ``wc/4`` with ``wc`` of
    :func:`toolbox.design._defaults.default_bandwidth`), ``current_limit``
    (A, default :func:`toolbox.design._defaults.current_scale`: rated, max or
    voltage-allowed current) and ``voltage_limit`` (V, default per axis
    ``min(drive.max_voltage, wc L i_max)``, the voltage a full-scale error
    asks at crossover; the drive's whole voltage made the loop cross over
    far above what the delay allows).

    Parameters: as :func:`toolbox.design.read_method_cfg`.

    Returns
    -------
    LqCfg
    """
    t = Table(table.data, table.prefix,
              ("domain", "Q", "R", "bandwidth", "current_limit", "voltage_limit"))
    domain = t.string("domain", "discrete", choices=("continuous", "discrete"))
    # Bryson defaults tied to the sample time: crossover wc of
    # _defaults.default_bandwidth (integral zero counted), integral weight at
    # wc/4, and per axis the voltage a full-scale current error may ask at that
    # crossover, wc L i_max (capped by the drive): then Kp ~ sqrt(q_i/r) = wc L
    bw = _defaults.default_bandwidth(drive, zero=True)
    bandwidth = t.number("bandwidth", bw.value / _defaults.ZERO_RATIO, positive=True,
                         unit="rad/s")
    # no current from the motor: the current the voltage allows (_defaults.current_scale)
    i_default, i_source = _defaults.current_scale(motor, drive)
    i_max = t.number("current_limit", i_default, positive=True, unit="A")
    v_drive = drive.max_voltage(motor.convention)
    v_max = t.number("voltage_limit", v_drive, positive=True, unit="V")
    # Bryson's weights are inverse squares of these: one design range for all
    # (toolbox/spec/_bounds.py; 1e-300 A or 1e300 V overflowed here)
    if t.has("bandwidth"):
        check_rate(t.key("bandwidth"), bandwidth, drive)
    if t.has("current_limit"):
        check_scale(t.key("current_limit"), i_max, i_default, "current limit", "A")
    if t.has("voltage_limit"):
        check_scale(t.key("voltage_limit"), v_max, v_drive, "voltage limit", "V")
    v_axis = {ax: (v_max if t.has("voltage_limit") else min(v_drive, bw.value * L * i_max))
              for ax, L in zip(AXES, (motor.Ld, motor.Lq))}
    defaults = None
    if t.has("Q"):
        Q = _read_q(t)
    else:
        Q = {ax: bryson_weights(i_max, v_axis[ax], bandwidth)[0] for ax in AXES}
        defaults = {"weights": {
            **bw.as_dict(),
            "bryson": "q_i = 1/i_max^2, q_z = (w_b/i_max)^2, r = 1/v_max^2",
            "w_b": "bandwidth" if t.has("bandwidth") else f"wc/{_defaults.ZERO_RATIO:g}",
            "i_max": i_max if t.has("current_limit") else f"{i_max:.5g} A from {i_source}",
            "v_max": ("voltage_limit" if t.has("voltage_limit") else
                      "min(V_max drive, wc L i_max) per axis: "
                      + ", ".join(f"{ax} {v:.4g} V" for ax, v in v_axis.items()))}}
    if t.has("R"):
        rd, rq = t.per_axis("R", positive=True, unit="1/V^2")
        Rw = {"d": rd, "q": rq}
    else:
        Rw = {ax: 1.0 / v_axis[ax] ** 2 for ax in AXES}
    for ax in AXES:
        _check_weights(Q[ax], Rw[ax], ax)
    return LqCfg(domain, Q, Rw, bandwidth, i_max, v_max, defaults)


def _read_q(t) -> dict:
    value = t.raw("Q")
    if isinstance(value, dict):
        sub = Table(value, t.key("Q"), AXES)
        return {ax: sub.numbers(ax, length=2) for ax in AXES}
    q = t.numbers("Q", length=2)
    return {"d": q, "q": q}


def design(spec) -> ControllerArtifact:
    """LQI artifact from a validated spec (method ``lq``).

    Continuous domain: the law (integrator state) is discretised with Tustin
    and the axis carries the continuous error controller ``k_i + (-k_z)/s``.
    Discrete domain: the law is the native discrete controller (integrator and
    input-history states); no continuous twin is given.

    Parameters
    ----------
    spec : Spec
        Validated spec with ``controller.method = "lq"``.

    Returns
    -------
    ControllerArtifact
    """
    cfg: LqCfg = spec.controller.cfg
    m, dr = spec.motor, spec.drive
    ts = dr.sample_time
    des = design_lq(m.Ld, m.Lq, m.R, cfg.Q, cfg.R, ts, domain=cfg.domain,
                    delay_samples=dr.delay_samples)
    axes = {}
    for ax in AXES:
        if cfg.domain == "continuous":
            axes[ax] = AxisController.from_law(des[ax].law(), sample_time=ts, method="tustin")
        else:
            axes[ax] = AxisController.from_law(des[ax].law(), sample_time=ts, method="native")
    gains: dict[str, Any] = {
        "domain": cfg.domain,
        "state": ("[i, integral(i_ref - i)]" if cfg.domain == "continuous" else
                  "[i, Ts-sum(i_ref - i), u(k-1), .., u(k-d)]"),
        "K": {ax: des[ax].K for ax in AXES},
        "Q": {ax: list(cfg.Q[ax]) for ax in AXES},
        "R": {ax: cfg.R[ax] for ax in AXES},
        "closed_loop_poles": {ax: [complex(p) for p in des[ax].poles] for ax in AXES},
        "bandwidth": cfg.bandwidth,
        "current_limit": cfg.current_limit,
        "voltage_limit": cfg.voltage_limit,
        "delay_samples": dr.delay_samples if cfg.domain == "discrete" else 0,
    }
    if cfg.defaults:
        gains["defaults"] = cfg.defaults
    eqs = ["001 eq (1)", "003 eq (33)-(34)"]
    return make_artifact(spec, axes, decoupling_from_motor(m), gains, eqs)
