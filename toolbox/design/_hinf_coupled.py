"""H-infinity synthesis against the coupled dq plant at speed (2x2, multi-model).

Paper 003 (Azaiz 2007) designs each axis on its decoupled plant
``G_x = 1/(R + s L_x)`` (eq (33)-(34)) and relies on the decoupling to cancel
the cross-coupling of eq (3)-(4). At speed, with the true ``R``, ``Ld``,
``Lq`` away from the controller's and the decoupling delayed by the sampling,
the cancellation is not exact and the two loops interact. Here the
generalised plant is the whole 2x2 loop (:func:`coupled_plant`):

* the dq plant of 003 eq (3)-(4) at electrical speed ``w`` with true
  ``R``, ``Ld``, ``Lq`` (``L di/dt = -R i - w J L i + v_applied``, the
  back-EMF a constant disturbance that leaves the loop's dynamics alone);
* the executed decoupling with the controller's ``Ld_c``, ``Lq_c`` and the
  measured speed ``w_m = g w + o`` (``v = u + w_m [[0, -Lq_c], [Ld_c, 0]] i``,
  toolbox/ARCHITECTURE.md "controller.json", ``decoupling``);
* the loop delay of "The digital loop" (``delay_samples`` periods of
  computation plus half a period of zero-order hold, the voltage placement
  compensating the rotation) as a Pade approximation of order
  :data:`PADE_ORDER` on each voltage channel, decoupling included (the
  decoupling is delayed with the rest of the command);
* the mixed-sensitivity outputs of 003 eq (35)-(40) per axis:
  ``z = [W1 e; W2 u]`` (``W3 i`` when a T weight is given), ``y = e = r - i``.

R, Ld and Lq are real parametric uncertainty, handled as a multi-model
problem: the models are the corners of the box (R, Ld, Lq, speed-sensor gain
and offset) at the speeds of :data:`SPEED_FRACTIONS` of the maximum, plus the
nominal plant at each speed, and the maximum speed's models again with
``extra_delay`` more periods of delay (the robustness sweep's delay range,
toolbox/ARCHITECTURE.md "Robustness verdict") (:func:`model_set`). Speeds below zero are the
mirror image (``w, w_m -> -w, -w_m`` flips the q-axis states) of the same set
with the offset negated, which the set holds.

The controller stays in the structure every later stage executes (two SISO
laws plus the decoupling): per axis ``K_x(s) = (kp s + ki) / (s (tau s + 1))``,
a PI with a roll-off, realised with an exact integrator. Its six parameters
minimise the worst closed-loop H-infinity norm ``max_i ||F_l(P_i, K)||_inf``
over the models (one controller for the whole polytope of speeds, the coupling
inside; no scalar small-gain argument, no weight inflation), subject to
internal stability of every model's closed loop; ``tau >= Ts/pi`` keeps the
roll-off pole realisable at the sample time. Optimiser: Nelder-Mead on the
logarithms of the parameters (nonsmooth objective) on an active set of models,
started from the cancellation PI at the default crossover; after each run the
whole set is evaluated and the worst model joins the active set until none
exceeds the active worst (:func:`synthesise_structured`).

The full-order 2x2 optimum of each nominal speed model (no structure
constraint, the Riccati route of Theorem 1, :func:`full_order_gamma`) is a
lower bound of what any controller reaches on that model; the structured
controller's level on it is at least that bound. Norms are SLICOT ab13dd
(:func:`toolbox.lti.linf_norm`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..lti import StateSpace, TransferFunction, append, linf_norm, pade, series, tf2ss
from ._hinf_gamma import gamma_iteration
from ._hinf_plant import PartitionedPlant, closed_loop

__all__ = ["PADE_ORDER", "SPEED_FRACTIONS", "Model", "coupled_plant", "model_set",
           "structured_controller", "StructuredResult", "synthesise_structured",
           "full_order_gamma", "closed_loop_gamma"]

#: order of the Pade approximation of the loop delay on each voltage channel
PADE_ORDER = 2
#: speeds of the model set, as fractions of the maximum electrical speed
SPEED_FRACTIONS = (0.0, 0.5, 1.0)
#: an unstable closed loop costs this much (times 1 + its largest real part)
_UNSTABLE = 1e3
#: Nelder-Mead budget per active-set round and the rounds
_MAXFEV = 500
_ROUNDS = 6


@dataclass(frozen=True)
class Model:
    """One plant of the model set: true ``R`` (ohm), ``Ld``, ``Lq`` (H),
    electrical speed ``w`` and the measured speed ``w_m`` the decoupling uses
    (rad/s electrical), ``extra_delay`` (s) of loop delay beyond the design's."""

    R: float
    Ld: float
    Lq: float
    w: float
    w_m: float
    extra_delay: float = 0.0

    def to_json(self) -> dict:
        return {"R_ohm": self.R, "Ld_H": self.Ld, "Lq_H": self.Lq, "speed_rad_s": self.w,
                "measured_speed_rad_s": self.w_m, "extra_delay_s": self.extra_delay}


def _core(model: Model, Ld_c: float, Lq_c: float, delay: float) -> StateSpace:
    """Inputs ``[r_d, r_q, u_d, u_q]``, outputs ``[e_d, e_q, u_d, u_q, i_d, i_q]``
    (module docstring); states ``[i_d, i_q, Pade(d), Pade(q)]``."""
    num, den = pade(delay + model.extra_delay, PADE_ORDER)
    pd = append(tf2ss(num, den), tf2ss(num, den))
    n = pd.nstates
    R, Ld, Lq, w, wm = model.R, model.Ld, model.Lq, model.w, model.w_m
    Dc = np.array([[0.0, -wm * Lq_c], [wm * Ld_c, 0.0]])
    Ai = np.array([[-R / Ld, w * Lq / Ld], [-w * Ld / Lq, -R / Lq]])
    Li = np.diag([1.0 / Ld, 1.0 / Lq])
    I2, Z = np.eye(2), np.zeros
    A = np.block([[Ai + Li @ pd.D @ Dc, Li @ pd.C], [pd.B @ Dc, pd.A]])
    B = np.block([[Z((2, 2)), Li @ pd.D], [Z((n, 2)), pd.B]])
    C = np.block([[-I2, Z((2, n))], [Z((2, 2 + n))], [I2, Z((2, n))]])
    D = np.block([[I2, Z((2, 2))], [Z((2, 2)), I2], [Z((2, 4))]])
    return StateSpace(A, B, C, D)


def coupled_plant(model: Model, weights: dict, Ld_c: float, Lq_c: float,
                  delay: float) -> PartitionedPlant:
    """The 2x2 generalised plant of one model (module docstring).

    Parameters
    ----------
    model : Model
    weights : dict
        ``{"d": {"w1", "w2", "w3"}, "q": {...}}`` (SISO systems; ``w3`` may be None
        on both axes).
    Ld_c, Lq_c : float
        The decoupling's inductances (H).
    delay : float
        Loop delay of the design (s), ``(delay_samples + 1/2) Ts``; the model's
        ``extra_delay`` adds to it.

    Returns
    -------
    PartitionedPlant
        ``w = r`` (2), ``u`` (2), ``z = [w1 e; w2 u; (w3 i)]``, ``y = e``.
    """
    core = _core(model, Ld_c, Lq_c, delay)
    names = ["w1", "w2"] + (["w3"] if weights["d"].get("w3") is not None else [])
    W = append(*[_ss(weights[ax][nm]) for nm in names for ax in "dq"])
    zc = StateSpace(core.A, core.B, core.C[:2 * len(names)], core.D[:2 * len(names)])
    Zs = series(zc, W)
    Ce = np.hstack([core.C[:2], np.zeros((2, Zs.nstates - core.nstates))])
    return PartitionedPlant(A=Zs.A, B1=Zs.B[:, :2], B2=Zs.B[:, 2:], C1=Zs.C, C2=Ce,
                            D11=Zs.D[:, :2], D12=Zs.D[:, 2:], D21=core.D[:2, :2],
                            D22=core.D[:2, 2:])


def _ss(W) -> StateSpace:
    tf = TransferFunction.from_system(W)
    return tf2ss(tf.num, tf.den)


def model_set(motor, Ld_c: float, Lq_c: float, max_speed: float, box: dict,
              extra_delay: float = 0.0) -> list[Model]:
    """Corners of the box at each speed of :data:`SPEED_FRACTIONS`, plus the
    nominal plant (exact speed sensor) at each speed; with ``extra_delay > 0``
    (s) the maximum speed's models once more with that much more delay.

    ``box``: ``R``, ``Ld``, ``Lq`` (scale factors ``(lo, hi)``),
    ``speed_gain`` ``(lo, hi)`` and ``speed_offset`` ``(lo, hi)`` (electrical
    rad/s). At standstill only the offset acts on the decoupling.
    """
    out = []
    for frac in SPEED_FRACTIONS:
        w = frac * max_speed
        out.append(Model(motor.R, motor.Ld, motor.Lq, w, w))
        sensor = sorted({(g * w + o) for g in box["speed_gain"] for o in box["speed_offset"]})
        for r, ld, lq, wm in itertools.product(box["R"], box["Ld"], box["Lq"], sensor):
            out.append(Model(r * motor.R, ld * motor.Ld, lq * motor.Lq, w, wm))
    if extra_delay > 0:
        out += [Model(m.R, m.Ld, m.Lq, m.w, m.w_m, extra_delay) for m in out
                if m.w == max_speed]
    return out


def structured_controller(params: np.ndarray) -> StateSpace:
    """``diag(K_d, K_q)``, ``K_x = (kp s + ki)/(s (tau s + 1))`` from
    ``params = [kp_d, ki_d, tau_d, kp_q, ki_q, tau_q]`` (states: integral of
    the error, output), strictly proper."""
    blocks = []
    for kp, ki, tau in np.reshape(params, (2, 3)):
        blocks.append(StateSpace(np.array([[0.0, 0.0], [ki / tau, -1.0 / tau]]),
                                 np.array([[1.0], [kp / tau]]), np.array([[0.0, 1.0]]),
                                 np.zeros((1, 1))))
    return append(*blocks)


def axis_controller(params: np.ndarray, axis: str) -> StateSpace:
    """The SISO ``K_x`` of one axis (``"d"`` or ``"q"``)."""
    kp, ki, tau = np.reshape(params, (2, 3))["dq".index(axis)]
    return StateSpace(np.array([[0.0, 0.0], [ki / tau, -1.0 / tau]]),
                      np.array([[1.0], [kp / tau]]), np.array([[0.0, 1.0]]), np.zeros((1, 1)))


def closed_loop_gamma(P: PartitionedPlant, K: StateSpace) -> float:
    """``||F_l(P, K)||_inf``, or ``inf`` when the closed loop is not internally
    stable (largest real part of a pole >= -1e-6 rad/s)."""
    cl = closed_loop(P, K)
    if np.linalg.eigvals(cl.A).real.max() >= -1e-6:
        return math.inf
    return float(linf_norm(cl))


def _cost(theta: np.ndarray, plants: list, tau_min: float) -> float:
    p = _params(theta, tau_min)
    K = structured_controller(p)
    worst = 0.0
    for P in plants:
        cl = closed_loop(P, K)
        a = float(np.linalg.eigvals(cl.A).real.max())
        if a >= -1e-6:
            return _UNSTABLE * (1.0 + a)
        worst = max(worst, float(linf_norm(cl)))
    return worst


def _params(theta: np.ndarray, tau_min: float) -> np.ndarray:
    """Positive parameters from the search variables: ``kp, ki = exp(.)``,
    ``tau = tau_min + exp(.)``."""
    e = np.exp(np.asarray(theta, float)).reshape(2, 3)
    e[:, 2] += tau_min
    return e.ravel()


@dataclass(frozen=True)
class StructuredResult:
    """Outcome of :func:`synthesise_structured`.

    Attributes
    ----------
    params : ndarray
        ``[kp_d, ki_d, tau_d, kp_q, ki_q, tau_q]`` (V/A, V/(A s), s).
    gammas : ndarray
        ``||F_l(P_i, K)||_inf`` on every model (inf when unstable).
    worst : int
        Index of the model of largest level.
    rounds : list of dict
        Per active-set round: ``active`` (model count), ``active_worst``,
        ``set_worst``, ``evaluations``.
    """

    params: np.ndarray
    gammas: np.ndarray
    worst: int
    rounds: list


def synthesise_structured(plants: list, start: np.ndarray, tau_min: float,
                          first_active: list[int]) -> StructuredResult:
    """Minimise ``max_i ||F_l(P_i, K)||_inf`` over the structured controller.

    Parameters
    ----------
    plants : list of PartitionedPlant
        The whole model set.
    start : ndarray
        Starting parameters (as :func:`structured_controller`).
    tau_min : float
        Smallest roll-off time constant (s).
    first_active : list of int
        Models in the first active set.

    Returns
    -------
    StructuredResult
    """
    from scipy.optimize import minimize  # lazy: scipy.optimize, 240 modules

    p0 = np.asarray(start, float).reshape(2, 3).copy()
    p0[:, 2] = np.maximum(p0[:, 2] - tau_min, 1e-3 * tau_min)
    theta = np.log(p0.ravel())
    active = list(dict.fromkeys(first_active))
    rounds = []
    for _ in range(_ROUNDS):
        res = minimize(_cost, theta, args=([plants[i] for i in active], tau_min),
                       method="Nelder-Mead",
                       options={"maxfev": _MAXFEV, "xatol": 1e-4, "fatol": 1e-5,
                                "adaptive": True})
        theta = res.x
        K = structured_controller(_params(theta, tau_min))
        gammas = np.array([closed_loop_gamma(P, K) for P in plants])
        worst = int(np.argmax(gammas))
        rounds.append({"active": len(active), "active_worst": float(res.fun),
                       "set_worst": float(gammas[worst]), "evaluations": int(res.nfev)})
        if gammas[worst] <= res.fun * (1 + 1e-6) or worst in active:
            break
        active.append(worst)
    return StructuredResult(_params(theta, tau_min), gammas, worst, rounds)


def full_order_gamma(P: PartitionedPlant) -> float:
    """The optimal level of an unstructured (full-order 2x2) controller on one
    model by the gamma iteration of Theorem 1 (:mod:`._hinf_gamma`): a lower
    bound of any structured controller's level on that model."""
    return gamma_iteration(P)
