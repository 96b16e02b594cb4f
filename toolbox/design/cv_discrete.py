"""Direct discrete-time complex-vector current control: method ``cv``.

A registered design method (``controller.method = "cv"``, parameters in
``[controller.cv]``: :func:`read_cfg`, :func:`design`). Its gains are
functions of the measured speed (the exact discretisation at ``omega Ts``),
so the artifact carries the law itself, the typed field
:class:`toolbox.artifact.CvLaw` (the placed poles), and every executor
computes the gains from it each period by the formulas below: the simulator
kernel (``toolbox/sim/_kernel_cv.py``), the header
(``toolbox/export/templates/cv.c.j2``) and, in Python, :func:`executed_gains`
with :class:`CvDiscreteLaw`. The artifact's ``axes`` hold the law at
standstill (exact there: at zero speed the plant and the gains decouple),
from which the per-axis views (margins, Bode, step figures) are drawn.

Source
------
M. Hinkkanen, H. A. A. Awan, Z. Qu, T. Tuovinen, F. Briz, "Current control
for synchronous motor drives: direct discrete-time pole-placement design",
IEEE Trans. Ind. Appl. 52(2), 2016 (doi 10.1109/TIA.2015.2495288): the
plant is discretised exactly at the sample time in rotor coordinates at the
(measured) speed, the computation delay is a state, and a two-degree-of-
freedom state-feedback law with integral action (reference feedforward,
feedback of the current and of the delayed voltage, an integrator) places
the closed-loop poles directly in z. What is implemented here, written out
(the paper's equation numbers are not cited: its text was not at hand; every
formula below is derived in this docstring and checked by the tests):

(M1) Plant, rotor coordinates, constant speed ``w`` (003 eq (3)-(4),
     :func:`toolbox.plant.dq_matrices`): ``di/dt = A(w) i + B u``,
     ``A = [[-R/Ld, w Lq/Ld], [-w Ld/Lq, -R/Lq]]``, ``B = diag(1/Ld, 1/Lq)``;
     the back-EMF ``(0, -w psi_f)`` is cancelled by a feedforward (or
     rejected by the integrator) and left out of the linear design.
(M2) Hold (toolbox/ARCHITECTURE.md "The digital loop"): the voltage
     ``v_k`` computed at ``t_k`` is placed at ``theta_k + t_c w_meas`` and
     applied over ``[t_k + d Ts, t_k + (d + 1) Ts)``.
     ``hold = "rotor"`` (the simulator's default and the analysis' model):
     constant ``R(eps) v_k`` in rotor coordinates,
     ``Phi = e^{A Ts}``, ``Gamma = int_0^Ts e^{A s} ds B R(eps)``;
     ``hold = "stationary"`` (a PWM inverter, the paper's hold): constant in
     stationary coordinates, i.e. ``R(-w (s - Ts/2)) R(eps) v_k`` in rotor
     coordinates over the period, ``Gamma = int_0^Ts e^{A (Ts - s)} B
     R(-w (s - Ts/2)) ds R(eps)``. ``eps = t_c w_meas - (d + 1/2) Ts w`` is 0
     with the default mid-period placement and an exact speed.
     Discrete plant: ``i_{k+1} = Phi i_k + Gamma v_{k-d}``.
(L)  Law (two degrees of freedom, the paper's structure; matrix gains, the
     complex gains of a surface PMSM being 2x2 rotation-scalings):
     ``v_k = Kt r_k - K1 i_k - sum_{j=1..d} K2_j v_{k-j} + x_k``,
     ``x_{k+1} = x_k + Ki (r_k - i_k) + Aw (v_real,k - v_k)``
     (``Aw = Ki Kt^-1``: the integrator sees the realised voltage, as in
     motulator's ``ComplexPIController.update``); the delayed voltages
     ``v_{k-j}`` are the realised ones; the EMF feedforward
     ``(0, emf w_m flux_c)`` is added after the linear law and kept out of
     the delay states.
(P)  Pole placement. Eliminating ``v`` and ``x`` (with ``K2_j = Gamma^-1
     kappa_j Gamma``) gives the matrix characteristic polynomial
     ``Delta(z) = (z - 1) Q(z) (z - Phi) + (z - 1) Gamma K1 + Gamma Ki``,
     ``Q(z) = z^d + kappa_1 z^(d-1) + ... + kappa_d``. Equating it with
     ``delta(z) I``, ``delta(z) = prod (z - p_m) = sum a_m z^(d+2-m)``
     (``d + 2`` poles), coefficient by coefficient:
     ``c_0 = I``, ``c_m = a_m I + c_{m-1}``, ``kappa_m = c_m + kappa_{m-1} Phi``
     (``m = 1..d``, ``kappa_0 = I``), ``c_{d+1} = -kappa_d Phi``,
     ``Gamma K1 = a_{d+1} I + c_d - c_{d+1}``,
     ``Gamma Ki = a_{d+2} I + c_{d+1} + Gamma K1``.
     Then ``det(zI - A_cl) = delta(z)^2``: every placed pole is a pole of
     the coupled dq loop (twice), at every speed, for a surface or an
     interior PMSM (``Gamma`` invertible; no approximation of the saliency).
(T)  Reference feedforward: ``Gamma Kt = Gamma Ki / (1 - p_i)`` puts the
     zero of ``Gamma (Kt (z - 1) + Ki)`` on the integral pole ``p_i``, so
     ``i = (1 - p_c) / (z^d (z - p_c)) r`` at the sample instants, without
     cross-coupling, whatever the speed.
(D)  Poles: ``p_c = exp(-alpha_c Ts)`` (reference tracking, ``alpha_c`` the
     closed-loop bandwidth), ``p_i = exp(-alpha_i Ts)`` (integral action,
     disturbance rejection), and the ``d`` delay poles at ``delay_pole``
     (default 0: the delay states dead-beat). Defaults: ``alpha_c`` from
     :func:`toolbox.design.default_bandwidth` (as every method),
     ``alpha_i = alpha_c / 4`` (the integral zero ratio of
     :mod:`toolbox.design._defaults`).

For a surface PMSM with the rotor hold ``Phi = e^{-(R/L + j w) Ts}``,
``Gamma = (1 - Phi)/(R + j w L)`` and with the stationary hold
``Gamma = e^{-j w Ts/2} (1 - e^{-R Ts/L})/R``: the gains are then the
complex numbers of the paper's complex-vector design (tested against these
closed forms).

motulator 0.5 has no direct discrete-time pole-placement controller; its
discrete-time current controller, ``ComplexPIController`` (forward-Euler
complex-vector 2DOF PI, Briz, Degner, Lorenz 2000, complex integrator
``u_i += Ts (alpha_i + j w)(u - v)``), is law (L) with ``Kt = k_t L``,
``K1 = k_p L``, ``K2 = 0``, ``Ki = Ts (alpha_i I + w J) k_t L``,
``Aw = Ts (alpha_i I + w J)`` (:func:`motulator_gains`; equal outputs tested).

The executed law (method ``cv``)
--------------------------------
Each period, at the measured electrical speed ``w``: ``(Phi, Gamma)`` of
(M2) with ``hold = "rotor"`` for the controller's model (the decoupling's
``R_c``, ``Ld_c``, ``Lq_c``) and ``eps = (t_c - (d + 1/2) Ts) w``, the
placement error the law expects with an exact speed (0 for the default
``angle_compensation = "mid_period"``; ``-(d + 1/2) Ts w`` for ``"none"``,
which the gains then compensate); gains (P)-(T) for the artifact's poles;
law (L) with the EMF feedforward and the voltage limit of the drive. Two
consequences of (P)-(T) the executors use: ``c_m`` are scalars
(``c_m = (a_0 + .. + a_m) I``), hence ``Gamma Ki = delta(1) I`` and
``Aw = Ki Kt^-1 = (1 - p_i) I``. The rotor hold is the model of every
executor (the stationary hold of a PWM differs by ``O((w Ts)^2)``, covered
by the robustness checks); :func:`executed_gains` is the Python route.

What is not yet executed: the coupled-loop analysis at speed
(``analysis._coupled``, the MIMO margins, the sweep, the drift verdict and
the certificates) still reads the artifact's ``axes`` and ``decoupling``,
i.e. the standstill law; :func:`closed_loop_matrix` is the exact loop at
speed (toolbox/ARCHITECTURE.md "Direct discrete-time complex-vector
control").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from ..artifact import AxisController, CvLaw
from ..lti import StateSpace
from ..metrics import step_metrics
from ..plant import dq_matrices, max_electrical_speed
from ..spec import Table, check_rate
from . import _defaults
from ._common import decoupling_from_motor, make_artifact

__all__ = ["HOLDS", "CvDiscreteGains", "CvDiscreteLaw", "dq_zoh", "cv_discrete_poles",
           "place_gains", "design_cv_discrete", "motulator_gains", "closed_loop_matrix",
           "closed_loop_poles", "step_response", "step_figures", "executed_gains",
           "standstill_axes", "CvCfg", "read_cfg", "design"]

HOLDS = ("rotor", "stationary")
_J = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rot(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _augmented(R, Ld, Lq, omega, hold):
    """Continuous ``[[A, B], [0, H]]`` (4x4): the voltage held constant in the
    rotor frame (``H = 0``) or in the stationary frame (``H = -w J``)."""
    A, B = dq_matrices(R, Ld, Lq, omega)
    M = np.zeros((4, 4))
    M[:2, :2], M[:2, 2:] = A[0], B[0]
    if hold == "stationary":
        M[2:, 2:] = -omega * _J
    elif hold != "rotor":
        raise ValueError(f"hold must be one of {HOLDS}, not {hold!r}")
    return M


def dq_zoh(R: float, Ld: float, Lq: float, omega: float, sample_time: float, *,
           hold: str = "rotor", eps: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Exact discrete dq plant (M2) at a constant electrical speed.

    Parameters
    ----------
    R, Ld, Lq : float
        Resistance (ohm) and inductances (H).
    omega : float
        Electrical speed (rad/s).
    sample_time : float
        Period (s).
    hold : {"rotor", "stationary"}
        Frame in which the voltage is held over the period.
    eps : float
        Placement error (rad), 0 with the default mid-period placement.

    Returns
    -------
    Phi, Gamma : ndarray
        2x2 each: ``i_{k+1} = Phi i_k + Gamma v`` (``v`` the placed voltage).
    """
    E = expm(_augmented(R, Ld, Lq, omega, hold) * sample_time)
    Gam = E[:2, 2:]
    if hold == "stationary":
        Gam = Gam @ _rot(omega * sample_time / 2)   # v is the mid-period rotor-frame voltage
    return E[:2, :2], Gam @ _rot(eps)


@dataclass(frozen=True)
class CvDiscreteGains:
    """Gains of law (L) at one speed (all 2x2 arrays, dq order).

    Attributes
    ----------
    Kt, K1, Ki, Aw : ndarray
        Reference feedforward, current feedback, integral gain, realised-
        voltage (anti-windup) gain ``Ki Kt^-1``.
    K2 : tuple of ndarray
        ``K2_j`` on ``v_{k-j}``, ``j = 1..d``.
    poles : tuple of float
        The ``d + 2`` placed poles (z); empty for given gains.
    """

    Kt: np.ndarray
    K1: np.ndarray
    K2: tuple
    Ki: np.ndarray
    Aw: np.ndarray
    poles: tuple = ()

    @property
    def delay_samples(self) -> int:
        """``d``: the number of delayed-voltage gains."""
        return len(self.K2)


def cv_discrete_poles(sample_time: float, delay_samples: int, bandwidth: float,
                      integral_bandwidth: float, delay_pole: float = 0.0) -> tuple:
    """Placed poles (D): ``(p_c, p_i, delay_pole x d)`` (z-plane)."""
    p_c = math.exp(-bandwidth * sample_time)
    p_i = math.exp(-integral_bandwidth * sample_time)
    return (p_c, p_i) + (float(delay_pole),) * int(delay_samples)


def place_gains(Phi: np.ndarray, Gam: np.ndarray, poles) -> CvDiscreteGains:
    """Gains (P)-(T) placing ``poles`` (``p_c, p_i, ...``) for the plant ``(Phi, Gamma)``.

    Parameters
    ----------
    Phi, Gam : ndarray
        2x2 discrete plant (:func:`dq_zoh`).
    poles : sequence of float
        ``d + 2`` real poles; ``poles[1]`` is the integral pole cancelled by
        the reference feedforward (``!= 1``).

    Returns
    -------
    CvDiscreteGains
    """
    poles = tuple(float(p) for p in poles)
    d = len(poles) - 2
    if d < 0:
        raise ValueError("at least two poles (delay 0)")
    a = np.real(np.poly(poles))            # a_0 = 1 .. a_{d+2}
    I2 = np.eye(2)
    c = I2
    kappa = I2
    kappas = []
    for m in range(1, d + 1):
        c = a[m] * I2 + c
        kappa = c + kappa @ Phi
        kappas.append(kappa)
    c_last = -kappa @ Phi
    G1 = a[d + 1] * I2 + c - c_last
    Gi = a[d + 2] * I2 + c_last + G1
    Gt = Gi / (1.0 - poles[1])
    Gam_inv = np.linalg.inv(Gam)
    Kt, Ki = Gam_inv @ Gt, Gam_inv @ Gi
    return CvDiscreteGains(Kt=Kt, K1=Gam_inv @ G1, K2=tuple(Gam_inv @ k @ Gam for k in kappas),
                           Ki=Ki, Aw=Ki @ np.linalg.inv(Kt), poles=poles)


def design_cv_discrete(R: float, Ld: float, Lq: float, sample_time: float,
                       delay_samples: int, omega: float, *, bandwidth: float | None = None,
                       integral_bandwidth: float | None = None, delay_pole: float = 0.0,
                       hold: str = "rotor") -> CvDiscreteGains:
    """The direct discrete-time design at the (measured) electrical speed ``omega``.

    Parameters
    ----------
    R, Ld, Lq : float
        The controller's model (ohm, H, H).
    sample_time : float
        ``Ts`` (s).
    delay_samples : int
        Computation delay ``d`` (periods).
    omega : float
        Electrical speed (rad/s) the gains are computed at (each period: the
        measured one).
    bandwidth : float, optional
        ``alpha_c`` (rad/s); default :func:`toolbox.design.default_bandwidth`.
    integral_bandwidth : float, optional
        ``alpha_i`` (rad/s); default ``alpha_c / 4``.
    delay_pole : float
        z-plane pole of each delay state (default 0).
    hold : {"rotor", "stationary"}
        Voltage hold of the model (M2).

    Returns
    -------
    CvDiscreteGains
    """
    if bandwidth is None:
        drive = _DriveTiming(sample_time, int(delay_samples))
        bandwidth = _defaults.default_bandwidth(drive).value
    if integral_bandwidth is None:
        integral_bandwidth = bandwidth / _defaults.ZERO_RATIO
    Phi, Gam = dq_zoh(R, Ld, Lq, omega, sample_time, hold=hold)
    return place_gains(Phi, Gam, cv_discrete_poles(sample_time, delay_samples, bandwidth,
                                                   integral_bandwidth, delay_pole))


@dataclass(frozen=True)
class _DriveTiming:
    """The two drive values :func:`toolbox.design.default_bandwidth` reads."""

    sample_time: float
    delay_samples: int


def motulator_gains(Ld: float, Lq: float, sample_time: float, omega: float,
                    alpha_c: float, delay_samples: int = 1) -> CvDiscreteGains:
    """Law (L) gains equal to motulator 0.5's ``sm.CurrentController``.

    ``k_p = 2 alpha_c``, ``k_i = alpha_c^2``, ``k_t = alpha_c`` on ``psi = L i``
    (``L = diag(Ld, Lq)``), integrator ``u_i += Ts (alpha_i + j w)(u - v)``,
    ``alpha_i = k_i/k_t``: ``Kt = k_t L``, ``K1 = k_p L``, ``K2 = 0``,
    ``Ki = Ts (alpha_i I + w J) k_t L``, ``Aw = Ts (alpha_i I + w J)``.
    """
    L = np.diag([Ld, Lq])
    k_p, k_i, k_t = 2 * alpha_c, alpha_c ** 2, alpha_c
    Aw = sample_time * (k_i / k_t * np.eye(2) + omega * _J)
    return CvDiscreteGains(Kt=k_t * L, K1=k_p * L, K2=(np.zeros((2, 2)),) * delay_samples,
                           Ki=Aw @ (k_t * L), Aw=Aw)


class CvDiscreteLaw:
    """Law (L) executed sample by sample (the Python reference of the simulator's
    ``_kernel_cv`` and of the header, tested equal to them).

    Parameters
    ----------
    gains : callable
        ``gains(omega_meas) -> CvDiscreteGains`` (recomputed each period).
    flux_c : float
        EMF feedforward flux (Wb), ``v_q += w_m flux_c`` (0: none).
    limit : float
        Circle voltage limit (V), ``inf`` for none.
    """

    def __init__(self, gains, *, flux_c: float = 0.0, limit: float = math.inf) -> None:
        self.gains = gains
        self.flux_c = float(flux_c)
        self.limit = float(limit)
        self.x = np.zeros(2)
        self.past: list = []          # realised linear voltages v_{k-1}, v_{k-2}, ...

    def step(self, r, i, omega_meas: float) -> np.ndarray:
        """Realised dq voltage (V) for the reference ``r`` and measured ``i`` (A)."""
        g = self.gains(omega_meas)
        r, i = np.asarray(r, float), np.asarray(i, float)
        if len(self.past) < g.delay_samples:
            self.past += [np.zeros(2)] * (g.delay_samples - len(self.past))
        v = g.Kt @ r - g.K1 @ i + self.x
        for K2, past in zip(g.K2, self.past):
            v = v - K2 @ past
        ff = np.array([0.0, omega_meas * self.flux_c])
        v_cmd = v + ff
        size = float(np.hypot(*v_cmd))
        v_real = v_cmd * (self.limit / size) if size > self.limit else v_cmd
        self.x = self.x + g.Ki @ (r - i) + g.Aw @ (v_real - v_cmd)
        if g.delay_samples:
            self.past = [v_real - ff] + self.past[:g.delay_samples - 1]
        return v_real


def closed_loop_matrix(gains: CvDiscreteGains, R: float, Ld: float, Lq: float, omega: float,
                       sample_time: float, *, hold: str = "rotor",
                       eps: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Closed loop of law (L) (gains given, e.g. at the measured speed) and the
    true plant at ``omega``: ``z+ = A z + B r``, ``z = [i, q_1 .. q_d, x]``
    (``q_1`` the voltage applied now, ``q_d`` the newest), EMF cancelled.

    Returns
    -------
    A, B : ndarray
        ``(2d + 4)`` square and ``(2d + 4) x 2``.
    """
    d = gains.delay_samples
    Phi, Gam = dq_zoh(R, Ld, Lq, omega, sample_time, hold=hold, eps=eps)
    n = 2 * d + 4
    ix, xx = slice(0, 2), slice(n - 2, n)
    # v = Kv z + Kt r
    Kv = np.zeros((2, n))
    Kv[:, ix] = -gains.K1
    Kv[:, xx] = np.eye(2)
    for j, K2 in enumerate(gains.K2, start=1):          # v_{k-j} is q_{d+1-j}
        q = 2 + 2 * (d - j)
        Kv[:, q:q + 2] -= K2
    A = np.zeros((n, n))
    B = np.zeros((n, 2))
    A[ix, ix] = Phi
    if d == 0:
        A[ix, :] += Gam @ Kv
        B[ix, :] = Gam @ gains.Kt
    else:
        A[ix, 2:4] = Gam
        for j in range(d - 1):
            A[2 + 2 * j:4 + 2 * j, 4 + 2 * j:6 + 2 * j] = np.eye(2)
        A[2 * d:2 * d + 2, :] = Kv
        B[2 * d:2 * d + 2, :] = gains.Kt
    A[xx, ix] -= gains.Ki
    A[xx, xx] += np.eye(2)
    B[xx, :] = gains.Ki
    return A, B


def closed_loop_poles(gains: CvDiscreteGains, R: float, Ld: float, Lq: float, omega: float,
                      sample_time: float, **kw) -> np.ndarray:
    """Eigenvalues of :func:`closed_loop_matrix` (z), sorted."""
    return np.sort_complex(np.linalg.eigvals(closed_loop_matrix(gains, R, Ld, Lq, omega,
                                                                sample_time, **kw)[0]))


def step_response(gains: CvDiscreteGains, R: float, Ld: float, Lq: float, omega: float,
                  sample_time: float, r, *, n_periods: int = 200, substeps: int = 20,
                  hold: str = "rotor", eps: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Exact fine-grid response of the currents to a reference step ``r`` (A, dq).

    The sampled loop (:func:`closed_loop_matrix`) gives the applied voltage of
    each period; the current between samples is the exact solution of (M1)
    under the hold (M2) (``substeps`` points per period).

    Returns
    -------
    t : ndarray
        Times (s), ``n_periods * substeps`` points from 0.
    i : ndarray
        ``(len(t), 2)`` dq currents (A).
    """
    A, B = closed_loop_matrix(gains, R, Ld, Lq, omega, sample_time, hold=hold, eps=eps)
    d = gains.delay_samples
    r = np.asarray(r, float)
    h = sample_time / substeps
    E = expm(_augmented(R, Ld, Lq, omega, hold) * h)
    place = _rot(eps) if hold == "rotor" else _rot(omega * sample_time / 2 + eps)
    z = np.zeros(A.shape[0])
    out = np.empty((n_periods * substeps, 2))
    for k in range(n_periods):
        u = z[2:4] if d else gains.Kt @ r - gains.K1 @ z[:2] + z[-2:]
        s = np.concatenate([z[:2], place @ u])
        for m in range(substeps):
            out[k * substeps + m] = s[:2]
            s = E @ s
        z = A @ z + B @ r
    return np.arange(n_periods * substeps) * h, out


def step_figures(gains: CvDiscreteGains, R: float, Ld: float, Lq: float, omega: float,
                 sample_time: float, *, axis: str = "q", size: float = 1.0, **kw) -> dict:
    """Step metrics (:func:`toolbox.metrics.step_metrics`) of one axis' current for a
    reference step ``size`` (A) on that axis, plus the other axis' peak
    excursion ``cross_peak`` (A)."""
    k = "dq".index(axis)
    r = np.zeros(2)
    r[k] = size
    t, i = step_response(gains, R, Ld, Lq, omega, sample_time, r, **kw)
    figs = {key: float(v) for key, v in step_metrics(t, i[:, k], 0.0, size, 0.0).items()}
    figs["cross_peak"] = float(np.max(np.abs(i[:, 1 - k])))
    return figs


# ------------------------------------------------------------------ method cv
def executed_gains(law: CvLaw, R: float, Ld: float, Lq: float, omega_meas: float,
                   sample_time: float, delay_samples: int,
                   delay_compensation_time: float) -> CvDiscreteGains:
    """The gains the executors of method ``cv`` compute at one measured speed.

    :meth:`toolbox.artifact.CvLaw.gains` (the one Python route, closed-form
    ZOH) at one speed, as :class:`CvDiscreteGains`; the tests check it
    against :func:`place_gains` on :func:`dq_zoh` (scipy ``expm``) with
    ``eps = (t_c - (d + 1/2) Ts) w``.

    Parameters
    ----------
    law : CvLaw
        The artifact's poles.
    R, Ld, Lq : float
        The controller's model (the decoupling's ``R_c``, ``Ld_c``, ``Lq_c``).
    omega_meas : float
        Measured electrical speed (rad/s).
    sample_time, delay_samples : float, int
        ``Ts`` and ``d``.
    delay_compensation_time : float
        ``t_c`` of the voltage placement.
    """
    g = law.gains(R, Ld, Lq, omega_meas, sample_time, delay_samples, delay_compensation_time)
    return CvDiscreteGains(Kt=g.Kt[0], K1=g.K1[0], K2=tuple(g.K2[0]), Ki=g.Ki[0],
                           Aw=g.aw * np.eye(2), poles=law.poles(sample_time, delay_samples))


def standstill_axes(gains: CvDiscreteGains, sample_time: float) -> dict[str, AxisController]:
    """Law (L) at zero speed as two two-input axis laws ``[i_ref, i_meas] -> v``.

    At standstill ``Phi`` and ``Gamma`` are diagonal and so are the gains:
    the law is exactly two SISO laws, state ``[x, v_{k-1} .. v_{k-d}]``
    (the realised linear voltages), back-calculation gain ``[1 - p_i, 1, 0 ..]``
    (the integrator sees ``Aw (v_real - v)``, the newest delay state the
    realised voltage). The simulator's ``cv`` path keeps its states in the
    same coordinates.
    """
    d = gains.delay_samples
    n = d + 1
    axes = {}
    for k, ax in enumerate("dq"):
        A = np.zeros((n, n))
        B = np.zeros((n, 2))
        C = np.zeros((1, n))
        A[0, 0] = 1.0
        B[0] = [gains.Ki[k, k], -gains.Ki[k, k]]
        C[0, 0] = 1.0
        D = np.array([[gains.Kt[k, k], -gains.K1[k, k]]])
        for j, K2 in enumerate(gains.K2, start=1):
            C[0, j] = -K2[k, k]
        if d:
            A[1] = C[0]
            B[1] = D[0]
            for j in range(2, n):
                A[j, j - 1] = 1.0
        aw = np.zeros(n)
        aw[0] = gains.Aw[k, k]
        if d:
            aw[1] = 1.0
        axes[ax] = AxisController.from_law(StateSpace(A, B, C, D, sample_time),
                                           sample_time=sample_time, method="native",
                                           antiwindup=aw)
    return axes


@dataclass(frozen=True)
class CvCfg:
    """Validated ``[controller.cv]``.

    Attributes
    ----------
    bandwidth, integral_bandwidth : float
        ``alpha_c``, ``alpha_i`` (rad/s).
    delay_pole : float
        z-plane pole of the delay states.
    details : dict
        Defaults applied, for the report.
    """

    bandwidth: float
    integral_bandwidth: float
    delay_pole: float
    details: dict

    def to_spec(self, spec=None) -> dict:
        """``[controller.cv]`` keys that read back to this configuration (defaults
        filled in; ``spec`` unused, the signature of the other methods')."""
        return {"bandwidth": self.bandwidth, "integral_bandwidth": self.integral_bandwidth,
                "delay_pole": self.delay_pole}


_KEYS = ("bandwidth", "integral_bandwidth", "delay_pole")


def read_cfg(method: str, table, motor, drive) -> CvCfg:
    """Validate ``[controller.cv]``: ``bandwidth`` (``alpha_c``, rad/s, default
    :func:`toolbox.design.default_bandwidth`), ``integral_bandwidth``
    (``alpha_i``, default ``alpha_c / 4``), ``delay_pole`` (z, [0, 1), default 0).

    Raises
    ------
    SpecError
        Unknown key (did-you-mean) or a value out of range; key path
        ``controller.cv.<key>``.
    """
    t = Table(table.data, table.prefix, _KEYS)
    details = {}
    if t.has("bandwidth"):
        bw = check_rate(t.key("bandwidth"), t.number("bandwidth", positive=True,
                                                     unit="rad/s"), drive)
    else:
        bw = _defaults.default_bandwidth(drive).value
        details["bandwidth"] = "default_bandwidth (phase-margin rule of the sampled loop)"
    if t.has("integral_bandwidth"):
        bi = check_rate(t.key("integral_bandwidth"),
                        t.number("integral_bandwidth", positive=True, unit="rad/s"), drive)
    else:
        bi = bw / _defaults.ZERO_RATIO
        details["integral_bandwidth"] = f"bandwidth / {_defaults.ZERO_RATIO:g}"
    pd = t.number("delay_pole", 0.0, minimum=0.0, maximum=0.95)
    return CvCfg(float(bw), float(bi), float(pd), details)


def design(spec):
    """Method ``cv``: the artifact of the direct discrete-time complex-vector law.

    Returns
    -------
    ControllerArtifact
        ``cv`` the poles (executed), ``axes`` the standstill law, decoupling
        with the motor's model, cross-coupling off (in the gains), EMF
        feedforward on; ``design_parameters``: poles, the gains at standstill
        and at the largest speed, the closed-loop poles there.
    """
    cfg: CvCfg = spec.controller.cfg
    m, dr = spec.motor, spec.drive
    ts, d = dr.sample_time, dr.delay_samples
    law = CvLaw(cfg.bandwidth, cfg.integral_bandwidth, cfg.delay_pole)
    t_c = dr.angle_compensation_time
    g0 = executed_gains(law, m.R, m.Ld, m.Lq, 0.0, ts, d, t_c)
    w_max = float(max_electrical_speed(m, dr))

    def gains_json(g):
        return {"Kt": g.Kt, "K1": g.K1, "K2": list(g.K2), "Ki": g.Ki}

    g_top = executed_gains(law, m.R, m.Ld, m.Lq, w_max, ts, d, t_c)
    params = {
        "structure": "v = Kt r - K1 i - sum_j K2_j v_(k-j) + x, x+ = x + Ki (r - i) "
                     "+ (1 - p_i) (v_real - v); gains recomputed each period at the "
                     "measured speed",
        "bandwidth": cfg.bandwidth, "integral_bandwidth": cfg.integral_bandwidth,
        "delay_pole": cfg.delay_pole,
        "poles_z": list(law.poles(ts, d)),
        "gains_standstill": gains_json(g0),
        "max_speed_rad_s": w_max,
        "gains_max_speed": gains_json(g_top),
        "closed_loop_poles_max_speed": [complex(p) for p in closed_loop_poles(
            g_top, m.R, m.Ld, m.Lq, w_max, ts)],
    }
    if cfg.details:
        params["defaults"] = cfg.details
    eqs = ["Hinkkanen et al. 2016 (direct discrete-time pole placement)",
           "003 eq (3)-(4)"]
    return make_artifact(spec, standstill_axes(g0, ts),
                         decoupling_from_motor(m, cross=False, emf=True), params, eqs,
                         cv=law)
