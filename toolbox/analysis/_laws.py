"""Executed control laws as matrices: the loops are built from what runs.

An :class:`AxisController` stores the executed discrete law ``[i_ref, i_meas] -> v``;
:func:`axis_law` reads it (or its continuous twin) into a :class:`Law`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from scipy.linalg import logm

from ..artifact import AxisController, CvLaw
from ..errors import ArtifactError

__all__ = ["AXES", "Law", "CvExecuted", "axis_law", "executed_laws", "law_to_continuous",
           "require_per_axis_laws"]

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


@dataclass(frozen=True)
class CvExecuted:
    """The complex-vector law of method ``cv`` as the sampled analyses execute it.

    Its gains depend on the measured speed (:meth:`gains`, the artifact's
    :meth:`toolbox.artifact.CvLaw.gains` with the controller's model and the
    voltage placement); :func:`toolbox.analysis._coupled.coupled_closed_loop`
    and the MIMO loop responses close the loop with them
    (toolbox/ARCHITECTURE.md "Direct discrete-time complex-vector control").
    """

    law: CvLaw
    R_c: float
    Ld_c: float
    Lq_c: float
    sample_time: float
    delay_samples: int
    delay_compensation_time: float

    def gains(self, omega_meas):
        """Stacked :class:`toolbox.artifact.CvGains` at the measured speeds."""
        return self.law.gains(self.R_c, self.Ld_c, self.Lq_c, omega_meas, self.sample_time,
                              self.delay_samples, self.delay_compensation_time)

    def error_response(self, z: np.ndarray, omega_meas) -> np.ndarray:
        """``K(z)`` (N, Nw, 2, 2) from the measured current to the voltage, sign
        of an error controller (``v = -K i`` at zero reference), at the grid
        points ``z`` for each measured speed: with ``p_j = z^-j v`` and
        ``x = -Ki i / (z - 1)``, ``K = (I + sum_j K2_j z^-j)^-1 (K1 + Ki / (z - 1))``."""
        g = self.gains(omega_meas)
        z = np.asarray(z, complex)[None, :, None, None]
        num = g.K1[:, None] + g.Ki[:, None] / (z - 1.0)
        den = np.broadcast_to(np.eye(2, dtype=complex), num.shape).copy()
        for j in range(g.K2.shape[1]):
            den = den + g.K2[:, None, j] * z ** (-(j + 1))
        return np.linalg.solve(den, num)


def executed_laws(artifact) -> dict | CvExecuted:
    """What the sampled coupled analyses close the loop with: the two axes'
    discrete laws (``{"d": Law, "q": Law}``, with the artifact's decoupling),
    or for method ``cv`` its complex-vector law (:class:`CvExecuted`)."""
    if artifact.cv is not None:
        dec = artifact.decoupling
        return CvExecuted(artifact.cv, dec.R_c, dec.Ld_c, dec.Lq_c, artifact.sample_time,
                          int(artifact.delay_samples), dec.delay_compensation_time)
    return {k: axis_law(artifact.axes[k], True) for k in AXES}


def require_per_axis_laws(artifact, what: str) -> None:
    """Refuse method ``cv`` where an analysis rests on per-axis laws plus the
    static decoupling (the certificates: their polytopes need a law affine in
    the measured speed, which the cv law's gains are not).

    Raises
    ------
    ArtifactError
        Key ``method``, naming ``what``.
    """
    if artifact.cv is not None:
        raise ArtifactError("method", f"a law of per-axis laws plus decoupling for {what} "
                            "(the cv law's gains are not affine in the measured speed)",
                            artifact.method)


def axis_law(axis, discrete: bool) -> Law:
    """The law of an :class:`AxisController`.

    Discrete: the executed two-input law. Continuous: for a one-degree-of-
    freedom law (reference channel = minus measurement channel) the
    continuous error controller as ``v = K (i_ref - i_meas)``; for a
    two-degree-of-freedom law (IP, total compensation, ILQ) the continuous
    twin of the executed law obtained by :func:`law_to_continuous` (the
    artifact stores no continuous law). Without a continuous error controller
    the discrete law is converted too.

    The continuous law of an :class:`AxisController` (frozen, hashed by
    identity) is converted once and kept while the controller lives: the
    certificate's bisection asks for it hundreds of times and a conversion
    can take a matrix logarithm.
    """
    s = axis.law
    if discrete:
        return Law(s.A, s.B, s.C, s.D, s.dt)
    if not isinstance(axis, AxisController):
        return _continuous_law(axis)
    law = _CONTINUOUS.get(axis)
    if law is None:
        law = _CONTINUOUS[axis] = _continuous_law(axis)
    return law


#: Continuous laws of live controllers (:func:`axis_law`).
_CONTINUOUS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _continuous_law(axis) -> Law:
    """The continuous law of :func:`axis_law` (computed)."""
    s = axis.law
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
