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
import warnings
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq, minimize_scalar

__all__ = ["MARGIN_KEYS", "MarginsResult", "MimoMarginsResult", "compute_margins",
           "axis_margins", "mimo_disk_margins", "disk_variations", "json_ready"]

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
        return self.A.shape[0]

    def error_controller(self) -> tuple[np.ndarray, ...]:
        """``(A, B, C, D)`` of the error controller ``K = -K_m`` (V/A)."""
        return self.A, -self.B[:, 1:2], self.C, -self.D[:, 1:2]


def axis_law(axis, discrete: bool) -> Law:
    """The law of an :class:`AxisController`.

    Discrete: the executed two-input law. Continuous: the one-degree-of-
    freedom law ``v = K (i_ref - i_meas)`` of the continuous error controller
    (the continuous twin of the executed law is not stored); the discrete
    error controller stands in when there is no continuous one.
    """
    if discrete:
        s = axis.law
        return Law(s.A, s.B, s.C, s.D, s.dt)
    s = axis.continuous if axis.continuous is not None else axis.discrete
    return Law(s.A, np.hstack([s.B, -s.B]), s.C, np.hstack([s.D, -s.D]), s.dt)


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
