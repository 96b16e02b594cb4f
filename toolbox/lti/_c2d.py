"""Discretisation (:func:`c2d`), Pade delay approximation and Ackermann pole
placement of :mod:`toolbox.lti`.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import scipy.linalg

from ._systems import as_statespace, StateSpace


#: Discretisation methods of :func:`c2d` (python-control / scipy names); the
#: generalised bilinear transform of each is ``_GBT_ALPHA``.
_GBT_ALPHA = {"tustin": 0.5, "bilinear": 0.5, "euler": 0.0, "forward_diff": 0.0,
              "backward_diff": 1.0}


C2D_METHODS = ("zoh", "foh", *_GBT_ALPHA)


def c2d(sys: Any, dt: float, method: str = "zoh") -> StateSpace:
    """Discretise a continuous system at sample time ``dt``.

    ``method`` is ``zoh``, ``foh`` or a generalised bilinear transform
    (``tustin``/``bilinear``, ``euler``/``forward_diff``, ``backward_diff``).
    The formulas of ``scipy.signal.cont2discrete`` (``control.sample_system``
    without pre-warping), with numpy's solves for the bilinear transforms:
    the same numbers within rounding (``tests/test_lti.py``).
    """
    g = as_statespace(sys)
    if g.discrete:
        raise ValueError("c2d: the system is already discrete")
    dt = float(dt)
    a, b, c, d = g.A, g.B, g.C, g.D
    n, m = b.shape
    if method == "zoh":
        em = np.vstack([np.hstack([a, b]), np.zeros((m, n + m))])
        ms = scipy.linalg.expm(dt * em)[:n, :]
        return StateSpace(ms[:, :n], ms[:, n:], c, d, dt)
    if method == "foh":
        em_upper = scipy.linalg.block_diag(np.block([a, b]) * dt, np.eye(m))
        em = np.block([[em_upper], [np.zeros((m, n + 2 * m))]])
        ms = scipy.linalg.expm(em)
        ms11, ms12, ms13 = ms[:n, :n], ms[:n, n:n + m], ms[:n, n + m:]
        return StateSpace(ms11, ms12 - ms13 + ms11 @ ms13, c, d + c @ ms13, dt)
    if method in _GBT_ALPHA:
        alpha = _GBT_ALPHA[method]
        ima = np.eye(n) - alpha * dt * a
        # numpy's solve: scipy 1.17's batched one costs 0.1-4 ms a call here
        ad = np.linalg.solve(ima, np.eye(n) + (1.0 - alpha) * dt * a)
        bd = np.linalg.solve(ima, dt * b)
        cd = np.linalg.solve(ima.transpose(), c.transpose()).transpose()
        return StateSpace(ad, bd, cd, d + alpha * np.dot(c, bd), dt)
    raise ValueError(f"c2d: unknown method {method!r}; one of {list(C2D_METHODS)}")


def pade(T: float, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """``(num, den)`` of the order-``n`` Pade approximation of ``exp(-s T)``.

    Golub and Van Loan's accumulated coefficients (the recurrence of
    ``control.pade``), normalised so that ``den[0] = 1``.
    """
    if T < 0 or n < 0:
        raise ValueError(f"pade: need T >= 0 and n >= 0, got T={T}, n={n}")
    if T == 0:
        return np.array([1.0]), np.array([1.0])
    num, den = np.zeros(n + 1), np.zeros(n + 1)
    num[-1] = den[-1] = 1.0
    cn = cd = 1.0
    for k in range(1, n + 1):
        cn *= -T * (n - k + 1) / (2 * n - k + 1) / k
        cd *= T * (n - k + 1) / (2 * n - k + 1) / k
        num[-k - 1], den[-k - 1] = cn, cd
    return num / den[0], den / den[0]


def acker(A: Any, B: Any, poles: Sequence[complex]) -> np.ndarray:
    """Ackermann's gain K (1 x n) placing ``eig(A - B K)`` at ``poles``.

    ``K = e_n^T ctrb(A, B)^-1 p(A)`` with ``p`` the monic polynomial of the
    poles (single input). Raises ValueError when (A, B) is not controllable.
    """
    A, B = np.atleast_2d(np.asarray(A, float)), np.asarray(B, float).reshape(-1, 1)
    n = A.shape[0]
    ctrb = np.zeros((n, n))
    ctrb[:, :1] = B
    for k in range(1, n):                  # A^k B by repeated products, as control.ctrb
        ctrb[:, k:k + 1] = A @ ctrb[:, k - 1:k]
    if np.linalg.matrix_rank(ctrb) != n:
        raise ValueError("System not reachable; pole placement invalid")
    p = np.real(np.poly(poles))
    pmat = sum(p[n - i] * np.linalg.matrix_power(A, i) for i in range(n + 1))
    return np.linalg.solve(ctrb, pmat)[-1:, :]
