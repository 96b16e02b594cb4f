"""The complex-vector law of method ``cv``: its typed artifact field and its gains.

:class:`CvLaw` is what controller.json stores (the placed poles);
:func:`cv_gains` is the Python route of the gains every executor computes
from it at the measured speed (toolbox/ARCHITECTURE.md "Direct discrete-time
complex-vector control"; the formulas are derived in
:mod:`toolbox.design.cv_discrete`): the analysis stage's coupled loop, and
``toolbox.design.cv_discrete.executed_gains``. The simulator kernel
(``toolbox/sim/_kernel_cv.py``) and the header (``cv.c.j2``) are its
compiled twins, tested equal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ..errors import ArtifactError
from ._fields import _number, _only

__all__ = ["CvLaw", "CvGains", "cv_gains"]


@dataclass(frozen=True)
class CvLaw:
    """The direct discrete-time complex-vector current law (method ``cv``).

    Executed, not informational: every period, at the measured electrical
    speed ``w = pole_pairs Omega_m``, the executor (simulator kernel
    ``sim._kernel_cv``, header ``export/templates/cv.c.j2``, reference
    :func:`toolbox.design.cv_discrete.executed_gains`) discretises the
    controller's model (the artifact's ``decoupling``: ``R_c``, ``Ld_c``,
    ``Lq_c``) exactly with the voltage held in the rotor frame, rotates
    ``Gamma`` by the placement error it expects, ``(t_c - (d + 1/2) Ts) w``
    (``t_c`` the decoupling's ``delay_compensation_time``), places the poles
    below by the formulas (P)-(T) of :mod:`toolbox.design.cv_discrete` and
    runs law (L) there (toolbox/ARCHITECTURE.md "Direct discrete-time
    complex-vector control").

    Attributes
    ----------
    bandwidth : float
        ``alpha_c`` (rad/s, > 0): the reference-tracking pole
        ``p_c = exp(-alpha_c Ts)``.
    integral_bandwidth : float
        ``alpha_i`` (rad/s, > 0): the integral pole ``p_i = exp(-alpha_i Ts)``
        (cancelled in the reference response by the feedforward).
    delay_pole : float
        z-plane pole of each of the ``d`` delay states, in [0, 1).
    """

    bandwidth: float
    integral_bandwidth: float
    delay_pole: float = 0.0

    def poles(self, sample_time: float, delay_samples: int) -> tuple[float, ...]:
        """``(p_c, p_i, delay_pole x d)`` in z at the sample time."""
        return ((math.exp(-self.bandwidth * sample_time),
                 math.exp(-self.integral_bandwidth * sample_time))
                + (self.delay_pole,) * int(delay_samples))

    def gains(self, R, Ld, Lq, omega_meas, sample_time: float, delay_samples: int,
              delay_compensation_time: float) -> "CvGains":
        """The executed gains at the measured speeds (stacked): :func:`cv_gains`."""
        return cv_gains(self, R, Ld, Lq, omega_meas, sample_time, delay_samples,
                        delay_compensation_time)

    def to_json(self) -> dict:
        return {"bandwidth": self.bandwidth, "integral_bandwidth": self.integral_bandwidth,
                "delay_pole": self.delay_pole}

    @classmethod
    def from_json(cls, data: Any, key: str = "cv") -> "CvLaw":
        """Validate ``{"bandwidth", "integral_bandwidth", "delay_pole"}``."""
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object with bandwidth, integral_bandwidth, "
                                "delay_pole", data)
        names = ("bandwidth", "integral_bandwidth", "delay_pole")
        _only(data, names, key)
        values = {}
        for name in names:
            if name not in data:
                raise ArtifactError(f"{key}.{name}", "a finite number (the cv law reads it)",
                                    "nothing (missing)")
            if name == "delay_pole":
                values[name] = _number(data[name], f"{key}.{name}", "a number in [0, 1)", 0.0)
                if not values[name] < 1.0:
                    raise ArtifactError(f"{key}.{name}", "a number in [0, 1)", data[name])
            else:
                values[name] = _number(data[name], f"{key}.{name}", "a finite number > 0 "
                                       "(rad/s)", 0.0, strict=True)
        return cls(**values)


@dataclass(frozen=True)
class CvGains:
    """Gains of law (L) at N measured speeds (stacked, dq order).

    Attributes
    ----------
    Kt, K1, Ki : ndarray
        (N, 2, 2): reference feedforward, current feedback, integral gain.
    K2 : ndarray
        (N, d, 2, 2): ``K2_j`` on the voltage of ``j`` periods ago.
    aw : float
        ``Aw = Ki Kt^-1 = (1 - p_i) I``: the realised-voltage gain of the
        integrator (a scalar multiple of the identity).
    """

    Kt: np.ndarray
    K1: np.ndarray
    K2: np.ndarray
    Ki: np.ndarray
    aw: float


def _zoh(R, Ld, Lq, w, Ts):
    """``Phi - I`` and ``Gamma`` (N, 2, 2) of the dq model at the speeds ``w``,
    rotor hold, the closed form of ``toolbox/sim/_kernel_cv.py`` vectorised."""
    a00, a11 = -R / Ld, -R / Lq
    a01, a10 = w * Lq / Ld, -w * Ld / Lq
    m, h = 0.5 * (a00 + a11), 0.5 * (a00 - a11)
    q = (h * h + a01 * a10) * Ts * Ts
    small = np.abs(q) < 1e-4
    x = np.sqrt(np.abs(np.where(small, 1.0, q)))
    pos = q > 0
    with np.errstate(over="ignore"):
        ch = np.where(small, 1.0 + q / 2 + q * q / 24 + q ** 3 / 720,
                      np.where(pos, np.cosh(x), np.cos(x)))
        half = np.where(pos, np.sinh(0.5 * x), np.sin(0.5 * x))
        ch1 = np.where(small, q / 2 + q * q / 24 + q ** 3 / 720,
                       np.where(pos, 2.0, -2.0) * half * half)
        shc = Ts * np.where(small, 1.0 + q / 6 + q * q / 120 + q ** 3 / 5040,
                            np.where(pos, np.sinh(x), np.sin(x)) / x)
    em1 = np.expm1(m * Ts)
    f = (em1 + 1.0) * shc
    d0 = em1 * ch + ch1
    E = np.stack([np.stack([d0 + f * h, f * a01], -1), np.stack([f * a10, d0 - f * h], -1)], -2)
    A = np.stack([np.stack([a00, a01], -1), np.stack([a10, a11], -1)], -2)
    B = np.zeros(E.shape)
    B[:, 0, 0], B[:, 1, 1] = 1.0 / Ld, 1.0 / Lq
    return E, np.linalg.solve(A, E) @ B


def cv_gains(law: CvLaw, R, Ld, Lq, omega_meas, sample_time: float, delay_samples: int,
             delay_compensation_time: float) -> CvGains:
    """The gains of law (L) the executors compute at the measured speeds.

    Parameters
    ----------
    law : CvLaw
        The placed poles.
    R, Ld, Lq : array_like
        The controller's model (the decoupling's ``R_c``, ``Ld_c``, ``Lq_c``),
        broadcast with ``omega_meas``.
    omega_meas : array_like
        Measured electrical speeds (rad/s).
    sample_time, delay_samples : float, int
        ``Ts`` and ``d``.
    delay_compensation_time : float
        ``t_c`` of the voltage placement: ``Gamma`` is rotated by
        ``(t_c - (d + 1/2) Ts) w``, the placement error the law expects.

    Returns
    -------
    CvGains
        ``kappa_m = C_m I + kappa_{m-1} Phi`` (``C_m = a_0 + .. + a_m``,
        ``kappa_0 = I``), ``Gamma K1 = (a_{d+1} + C_d) I + kappa_d Phi``,
        ``Gamma Ki = delta(1) I``, ``Gamma Kt = delta(1) / (1 - p_i) I``,
        ``K2_j = Gamma^-1 kappa_j Gamma``.
    """
    Ts, d = float(sample_time), int(delay_samples)
    R, Ld, Lq, w = (np.atleast_1d(v).astype(float).reshape(-1)
                    for v in np.broadcast_arrays(R, Ld, Lq, omega_meas))
    E, G = _zoh(R, Ld, Lq, w, Ts)
    eps = (delay_compensation_time - (d + 0.5) * Ts) * w
    c, s = np.cos(eps), np.sin(eps)
    Rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    G = G @ Rot
    poles = law.poles(Ts, d)
    a = np.real(np.poly(poles))
    I2 = np.eye(2)
    Phi = I2 + E
    C = 1.0
    kappa = np.broadcast_to(I2, E.shape)
    Gi = np.linalg.inv(G)
    K2 = np.zeros((w.size, d, 2, 2))
    for j in range(1, d + 1):
        C += a[j]
        kappa = C * I2 + kappa @ Phi
        K2[:, j - 1] = Gi @ kappa @ G
    K1 = Gi @ ((a[d + 1] + C) * I2 + kappa @ Phi)
    delta1 = C + a[d + 1] + a[d + 2]
    return CvGains(Kt=delta1 / (1.0 - poles[1]) * Gi, K1=K1, K2=K2, Ki=delta1 * Gi,
                   aw=1.0 - poles[1])
