"""Linear step responses of a current loop and their figures.

The discrete loop is simulated at the sample instants and the plant's
intersample current is reconstructed exactly (first-order ZOH plant), so
the figures match the simulator's (:mod:`toolbox.sim`) definitions.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import expm

from ..plant import zoh_first_order
from ..sim import step_metrics

if TYPE_CHECKING:
    from ._axis import AxisLoop

__all__ = ["step_response", "step_figures"]


def step_response(loop: "AxisLoop", A, B, C, D) -> tuple[np.ndarray, np.ndarray]:
    """Fine-grid step response ``(t, y)`` of the reference loop ``(A, B, C, D)``
    (doubling the horizon until settled, at most 32000 periods or 3.2 s)."""
    Ts = loop.sample_time
    if loop.discrete:
        n_steps = 2000
        while True:
            x = np.zeros(A.shape[0])
            X = np.empty((n_steps + 1, A.shape[0]))
            Bv = B[:, 0]
            # an unstable loop's response overflows to inf: expected, and judged
            # by the stability verdict, not a warning for the user
            with np.errstate(over="ignore", invalid="ignore"):
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
            e, g = zoh_first_order(loop.R, loop.L, s)   # the plant held over s
            y = (i_k[:, None] * e + u_k[:, None] * g).reshape(-1)
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


def step_figures(loop: "AxisLoop", cl: tuple) -> dict:
    """Response time, rise time, settling time and overshoot of the reference
    step of ``cl`` (the definitions of :func:`toolbox.sim.step_metrics`)."""
    t, y = step_response(loop, *cl)
    figs = step_metrics(t, y, 0.0, 1.0, 0.0)
    return {k: float(v) for k, v in figs.items()}
