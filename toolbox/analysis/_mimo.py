"""Multiloop disk margins of the coupled dq loop over speed.

For the coupled 2x2 loop at speed, :func:`mimo_disk_margins` uses the
multiloop (input, diagonal uncertainty) version with the upper bound of the
structured singular value obtained by D-scaling:
``mu(M) <= min_{d>0} sigma_max(D M D^-1)``, ``D = diag(d, 1)``,
``M = S_i + (sigma - 1)/2 I``, ``S_i = (I + C P)^-1`` - a guaranteed
multiloop disk margin ``alpha = 1/max_w mu_ub``; the minimum over ``d`` has a
closed form (:func:`mu_upper_2x2`), and for two scalar complex blocks the bound
equals mu. The unstructured ``1/max_w sigma_max(M)`` is reported next to it.

Disk margins after Seiler, Packard, Gahinet, "An introduction to disk
margins", IEEE Control Systems Magazine 40(5), 2020.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..plant import max_electrical_speed
from ._coupled import (coupled_closed_loop, coupled_plant, decoupling_matrix,
                       placement_error, rotation)
from ..artifact import json_ready
from ..errors import ArtifactError
from ._laws import AXES, axis_law, executed_laws
from ._sampling import DEFAULT_BOX, sample_parameters
from ._siso import disk_variations, log_grid
from ._statespace import FreqResponse, pade, zoh_2x2, zoh_coupled
from ..lti import StateSpace, append, feedback, static_gain

__all__ = ["MimoMarginsResult", "sigma_max_2x2", "mu_upper_2x2", "mimo_loop_response",
           "mimo_disk_margins", "multimodel_disk_margins", "MultiModelLoops",
           "MimoBoxResult", "mimo_over_box"]


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
    """Largest singular value of stacked 2x2 complex matrices (closed form).

    The largest eigenvalue of the Gram matrix ``M M^H = [[r0, c], [c*, r1]]``,
    ``(r0 + r1 + sqrt((r0 - r1)^2 + 4 |c|^2)) / 2``: the discriminant is a sum
    of squares, accurate to rounding even at a (nearly) repeated singular
    value, where the textbook ``sqrt(||M||_F^4 - 4 |det M|^2)`` subtracts two
    nearly equal numbers and keeps half the digits.
    """
    m00, m01, m10, m11 = M[..., 0, 0], M[..., 0, 1], M[..., 1, 0], M[..., 1, 1]
    r0 = _abs2(m00) + _abs2(m01)
    r1 = _abs2(m10) + _abs2(m11)
    return _gram_sigma_max(r0 + r1, r0 - r1, _abs2(m00 * np.conj(m10) + m01 * np.conj(m11)))


def _gram_sigma_max(trace: np.ndarray, diff: np.ndarray, c2: np.ndarray) -> np.ndarray:
    """Largest singular value from the Gram matrix ``[[r0, c], [c*, r1]]`` given
    as ``r0 + r1``, ``r0 - r1`` and ``|c|^2``: ``sqrt((trace + sqrt(diff^2 +
    4 |c|^2)) / 2)``, a sum of squares under the inner root."""
    return np.sqrt(0.5 * (trace + np.sqrt(diff * diff + 4.0 * c2)))


def _abs2(z: np.ndarray) -> np.ndarray:
    """``|z|^2`` of complex entries."""
    return z.real * z.real + z.imag * z.imag


def inv_2x2(M: np.ndarray) -> np.ndarray:
    """Inverses of stacked 2x2 matrices by the adjugate, ``adj(M)/det M``.

    ``numpy.linalg.inv`` calls LAPACK once per matrix: ~20 times slower on the
    tens of thousands of 2x2 sensitivities of a box analysis. The
    adjugate's rounding is of the order of ``cond(M) eps``, as LU's.
    """
    det = M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0]
    out = np.empty_like(M)
    out[..., 0, 0] = M[..., 1, 1]
    out[..., 1, 1] = M[..., 0, 0]
    out[..., 0, 1] = -M[..., 0, 1]
    out[..., 1, 0] = -M[..., 1, 0]
    return out / det[..., None, None]


def mu_upper_2x2(M: np.ndarray) -> np.ndarray:
    """Upper bound of mu for two 1x1 complex blocks: ``min_d sigma_max(D M D^-1)``.

    ``D = diag(d, 1)`` leaves ``|M00|``, ``|M11|`` and ``det M`` unchanged and
    scales ``|M01|`` by ``d``, ``|M10|`` by ``1/d``. With
    ``f = ||D M D^-1||_F^2``, ``sigma_max^2 = (f + sqrt(f^2 - 4 |det M|^2))/2``
    increases with ``f``, so the best ``d`` minimises
    ``f(d) = |M00|^2 + |M11|^2 + |M01|^2 d^2 + |M10|^2/d^2``: at
    ``d^2 = |M10|/|M01|``, ``f = |M00|^2 + |M11|^2 + 2 |M01| |M10|``
    (closed form: it replaced a 49-point grid plus a 40-step
    ternary search over ``log d``, 1300 evaluations per call, whose result it
    equals to rounding). With one off-diagonal entry zero the infimum is
    approached as ``d -> 0`` or ``inf``; it is still an upper bound of mu,
    which for two scalar complex blocks equals it.
    """
    return mu_upper_entries(M[..., 0, 0], M[..., 0, 1], M[..., 1, 0], M[..., 1, 1])


def mu_upper_entries(m00: np.ndarray, m01: np.ndarray, m10: np.ndarray,
                     m11: np.ndarray) -> np.ndarray:
    """:func:`mu_upper_2x2` of the matrices ``[[m00, m01], [m10, m11]]`` given
    entry by entry (arrays of one shape).

    :func:`sigma_max_2x2` of the scaled ``N = D M D^-1`` without forming it:
    with ``p = |m01| |m10|`` its Gram discriminant is
    ``(|m00|^2 - |m11|^2)^2 + 4 |p m00 + conj(m11) m01 m10|^2 / p`` (0 for
    ``p = 0``, its limit), a sum of squares: exact where ``f^2 - 4 |det M|^2``
    lost half the digits (a diagonal M with ``|m00| ~ |m11|``: equal
    inductances at zero speed).
    """
    a0, a1 = np.abs(m00), np.abs(m11)
    p = np.abs(m01) * np.abs(m10)
    h = p * m00 + np.conj(m11) * m01 * m10
    cross = np.divide(_abs2(h), p, out=np.zeros(np.shape(p)), where=p > 0)
    return _gram_sigma_max(a0 * a0 + a1 * a1 + 2.0 * p, (a0 - a1) * (a0 + a1), cross)


def mimo_loop_response(artifact, motor, omega: float, w: np.ndarray, *,
                       discrete: bool = True, omega_meas: float | None = None) -> np.ndarray:
    """Input loop ``L_i = (K - W) P`` (Nw, 2, 2) of the coupled dq loop.

    ``P`` is the plant ``v -> i`` at electrical speed ``omega`` (ZOH with
    ``z^-d`` in discrete time; ``exp(-s tau)``, ``tau = (d + 1/2) Ts``, in
    continuous time), ``K = diag(K_d, K_q)`` the error controllers (executed
    laws' measurement channels in discrete time) and ``W`` the decoupling
    with the controller's model parameters and measured speed; the voltage
    enters ``P`` rotated by the placement error of the digital loop
    (:func:`toolbox.analysis._coupled.placement_error`).
    """
    w = np.atleast_1d(np.asarray(w, float))
    x = _grid_point(artifact, w, discrete)
    return _loop_response(artifact, motor, omega, w, x, _controllers(artifact, x, discrete),
                          discrete, omega_meas)


def _grid_point(artifact, w: np.ndarray, discrete: bool) -> np.ndarray:
    """``z = e^{j w Ts}`` (discrete) or ``s = j w`` at the frequencies ``w``."""
    return np.exp(1j * w * artifact.sample_time) if discrete else 1j * w


def _controllers(artifact, x: np.ndarray, discrete: bool) -> np.ndarray:
    """``K = diag(K_d, K_q)`` (Nw, 2, 2), the error controllers at the grid points
    ``x`` (:func:`_grid_point`): the same at every speed, so
    :func:`mimo_disk_margins` evaluates them once."""
    C = np.zeros((x.size, 2, 2), complex)
    for k, name in enumerate(AXES):
        law = axis_law(artifact.axes[name], discrete)
        C[:, k, k] = FreqResponse(*law.error_controller())(x)[:, 0, 0]
    return C


def _loop_response(artifact, motor, omega: float, w: np.ndarray, x: np.ndarray,
                   C: np.ndarray, discrete: bool, omega_meas: float | None,
                   zoh: tuple | None = None) -> np.ndarray:
    """:func:`mimo_loop_response` with the grid points ``x`` (:func:`_grid_point`)
    and the controllers ``C`` (:func:`_controllers`) given; ``zoh`` (discrete
    only) the plant's ZOH ``(Phi, Gamma)`` (1, 2, 2) each at ``omega`` instead
    of the one of ``motor``'s constant parameters (the tangent plant of a
    saturated motor, cross inductance included:
    :mod:`toolbox.analysis.envelope_points`)."""
    Ts, d = artifact.sample_time, artifact.delay_samples
    om_meas = omega if omega_meas is None else omega_meas
    Rot = rotation(placement_error(artifact.decoupling, Ts, d, omega, om_meas))[0]
    if discrete:
        Phi, Gam = zoh if zoh is not None else zoh_coupled(
            *coupled_plant(motor.R, motor.Ld, motor.Lq, omega), Ts)
        P = inv_2x2(x[:, None, None] * np.eye(2) - Phi[0]) @ Gam[0]
        P = P * (x ** (-d))[:, None, None]
    else:
        Ac, Bc = coupled_plant(motor.R, motor.Ld, motor.Lq, omega)
        P = inv_2x2(x[:, None, None] * np.eye(2) - Ac[0]) @ Bc[0]
        P = P * np.exp(-1j * w * (d + 0.5) * Ts)[:, None, None]
    if artifact.cv is not None:
        if not discrete:
            raise ArtifactError("method", "a method with a continuous law for the continuous "
                                "MIMO loop (method cv is designed and executed in discrete "
                                "time)", artifact.method)
        # the complex-vector law at the measured speed (no static decoupling: cross off)
        return executed_laws(artifact).error_response(x, [om_meas])[0] @ P @ Rot
    W = decoupling_matrix(artifact.decoupling, om_meas)[0]
    return (C - W) @ P @ Rot


def mimo_disk_margins(artifact, motor, drive=None, *, n_speeds: int = 9,
                      n_grid: int = 1500, discrete: bool = True,
                      max_speed_rad_s: float | None = None, speed_gain: float = 1.0,
                      speed_offset: float = 0.0) -> MimoMarginsResult:
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
    speed_gain, speed_offset : float
        Speed sensor: the controller measures ``g w + o`` (offset in
        electrical rad/s) and uses it in the decoupling, the voltage
        placement and hence the stability check; default exact.

    Returns
    -------
    MimoMarginsResult
        Formula: ``alpha(omega) = 1/max_w mu_ub(S_i(jw) - I/2)`` with
        ``S_i = (I + L_i)^-1`` (module docstring); the residual coupling
        left by the delayed, sampled decoupling is in ``L_i``.
    """
    wmax = max_speed_rad_s if max_speed_rad_s is not None else max_electrical_speed(motor, drive)
    speeds = np.linspace(-wmax, wmax, n_speeds) if wmax > 0 else np.zeros(1)
    Ts = artifact.sample_time
    w_hi = math.pi / Ts if discrete else 1e7
    w = log_grid(1e-2, w_hi, n_grid, discrete)
    if discrete:
        w = w[:-1]  # z = -1 exactly can hit a Tustin controller's pole/zero
    laws = executed_laws(artifact)
    x = _grid_point(artifact, w, discrete)
    C = _controllers(artifact, x, discrete)
    dm, du, st = [], [], []
    for om in speeds:
        om_meas = speed_gain * om + speed_offset
        if discrete:
            loop = coupled_closed_loop(laws, artifact.decoupling, Ts, artifact.delay_samples,
                                       R=motor.R, Ld=motor.Ld, Lq=motor.Lq, omega=om,
                                       omega_meas=om_meas)
            stable = bool(loop.spectral_radius()[0] < 1 - 1e-9)
        else:
            stable = _continuous_coupled_stable(artifact, motor, om, om_meas)
        Li = _loop_response(artifact, motor, om, w, x, C, discrete, om_meas)
        S = inv_2x2(np.eye(2) + Li)
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


def _continuous_coupled_stable(artifact, motor, omega: float, omega_meas: float | None = None,
                               pade_order: int = 3) -> bool:
    """Closed-loop stability of the continuous coupled loop (Pade delay), the
    decoupling at the measured speed ``omega_meas`` (default ``omega``)."""
    Ts, d = artifact.sample_time, artifact.delay_samples
    Ac, Bc = coupled_plant(motor.R, motor.Ld, motor.Lq, omega)
    P = StateSpace(Ac[0], Bc[0], np.eye(2), np.zeros((2, 2)))
    Dl = StateSpace(*pade((d + 0.5) * Ts, pade_order))
    P = P * append(Dl, Dl)
    Ks = [StateSpace(*axis_law(artifact.axes[name], False).error_controller()) for name in AXES]
    om_meas = omega if omega_meas is None else omega_meas
    C = append(*Ks) - static_gain(decoupling_matrix(artifact.decoupling, om_meas)[0])
    cl = feedback(P * C, np.eye(2))
    return bool(np.all(np.real(cl.poles()) < 0))


class MultiModelLoops:
    """The coupled sampled dq loop over a set of plants and speeds, plant side precomputed.

    The plant responses ``P(e^{jwTs})`` (ZOH, ``z^-d``) of every (plant,
    speed) pair are computed once; :meth:`disk_margins` then closes them with
    the error controllers, the decoupling and the voltage placement of an
    artifact, exactly as :func:`mimo_loop_response` does for one pair, so a
    tuner evaluating many candidate controllers on one model set pays for the
    plant once.

    A model may carry a speed-sensor error: the measured electrical speed is
    ``w_meas = g w + o`` (the robustness sweep's sensor model,
    :mod:`toolbox.analysis.robustness`, paper 000 sect. 3). It enters what
    the controller computes from the measurement - the decoupling ``W``
    (:func:`decoupling_matrix`) and the placement rotation ``R(eps)``,
    ``eps = t_c w_meas - (d + 1/2) Ts w`` (:func:`placement_error`) - and
    the stability check (:func:`coupled_closed_loop` with ``omega_meas``);
    the plant responses depend on the true speed only, so models that differ
    only in their sensor share them.

    Parameters
    ----------
    motors : sequence of Motor
        True plants (R, Ld, Lq are read; the back-EMF does not enter a
        linear margin).
    speeds : array_like
        True electrical speeds (rad/s). The margin is even in the speed
        jointly with the sensor offset (the similarity ``diag(1, -1)`` maps
        the loop at ``(-w, o)`` onto the loop at ``(w, -o)`` and leaves the
        diagonal D-scaling unchanged), so ``speeds >= 0`` cover the range
        when every offset ``o`` of the set comes with ``-o`` (no offsets:
        always).
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay (periods).
    n_grid : int
        Frequency points (log grid 1e-2 rad/s .. Nyquist, Nyquist excluded).
    speed_gain, speed_offset : array_like, optional
        Per model (one entry per motor, or a scalar for all): the sensor's
        gain ``g`` and offset ``o`` (electrical rad/s); default 1 and 0
        (the speed measured exactly).
    paired : bool
        ``speeds`` holds one speed per motor (a sample of the box of
        parameters and speed, e.g. a dense check or a worst-case search):
        the margins are then ``(motors, 1)``, model ``i`` at ``speeds[i]``
        only, instead of every motor at every speed.
    """

    def __init__(self, motors, speeds, sample_time: float, delay_samples: int,
                 n_grid: int = 300, *, speed_gain=None, speed_offset=None,
                 paired: bool = False) -> None:
        self.speeds = np.atleast_1d(np.asarray(speeds, float))
        self.Ts, self.d = float(sample_time), int(delay_samples)
        self.R = np.array([m.R for m in motors], float)
        self.Ld = np.array([m.Ld for m in motors], float)
        self.Lq = np.array([m.Lq for m in motors], float)
        nm, ns = self.R.size, self.speeds.size
        self.paired = bool(paired)
        if self.paired and ns != nm:
            raise ValueError(f"paired: one speed per motor expected, got {ns} for {nm}")
        gain = np.broadcast_to(np.asarray(1.0 if speed_gain is None else speed_gain, float),
                               (nm,))
        offset = np.broadcast_to(np.asarray(0.0 if speed_offset is None else speed_offset,
                                            float), (nm,))
        if self.paired:
            #: measured electrical speeds ``g w + o`` (motors, 1), rad/s
            self.omega_meas = (gain * self.speeds + offset)[:, None]
            self.w = log_grid(1e-2, math.pi / self.Ts, n_grid, True)[:-1]
            self.z = np.exp(1j * self.w * self.Ts)
            # one plant per point (thousands in a dense check): the closed-form
            # ZOH of the coupled loop's stability check, equal to expm to rounding
            self.P = self._plant_entries(self.R, self.Ld, self.Lq, self.speeds, closed_form=True)
            self.shape = (nm, 1)
            return
        #: measured electrical speeds ``g w + o`` (motors, speeds), rad/s
        self.omega_meas = gain[:, None] * self.speeds[None, :] + offset[:, None]
        self.w = log_grid(1e-2, math.pi / self.Ts, n_grid, True)[:-1]
        self.z = np.exp(1j * self.w * self.Ts)
        # the plant depends on (R, Ld, Lq, w) only: each distinct plant once
        _, first, inverse = np.unique(np.column_stack([self.R, self.Ld, self.Lq]), axis=0,
                                         return_index=True, return_inverse=True)
        nu = first.size
        R, Ld, Lq, om = (np.repeat(self.R[first], ns), np.repeat(self.Ld[first], ns),
                         np.repeat(self.Lq[first], ns), np.tile(self.speeds, nu))
        rows = (inverse.reshape(-1)[:, None] * ns + np.arange(ns)[None, :]).reshape(-1)
        #: entries ``(P_00, P_01, P_10, P_11)`` of the plant responses, each (nm*ns, Nw)
        self.P = tuple(e[rows] for e in self._plant_entries(R, Ld, Lq, om))
        self.shape = (nm, ns)

    def _plant_entries(self, R, Ld, Lq, om, closed_form: bool = False) -> tuple:
        """``(P_00, P_01, P_10, P_11)``, each (N, Nw), of the plants ``(R, Ld, Lq)``
        at the electrical speeds ``om`` (N each); ZOH by ``expm`` or, with
        ``closed_form``, by :func:`zoh_2x2`."""
        Ac, Bc = coupled_plant(R, Ld, Lq, om)
        Phi, Gam = (zoh_2x2 if closed_form else zoh_coupled)(Ac, Bc, self.Ts)
        # P = (z I - Phi)^-1 Gamma z^-d entry by entry, as contiguous (N, Nw)
        # arrays (stacked 2x2 products and inverses cost 3x more)
        z = self.z[None, :]
        a, b = z - Phi[:, 0, 0, None], -Phi[:, 0, 1, None]
        c, d = -Phi[:, 1, 0, None], z - Phi[:, 1, 1, None]
        g = z ** (-self.d) / (a * d - b * c)
        G = Gam[:, :, :, None]
        return ((d * G[:, 0, 0] - b * G[:, 1, 0]) * g, (d * G[:, 0, 1] - b * G[:, 1, 1]) * g,
                (a * G[:, 1, 0] - c * G[:, 0, 0]) * g, (a * G[:, 1, 1] - c * G[:, 0, 1]) * g)

    def disk_margins(self, artifact) -> np.ndarray:
        """``(motors, speeds)`` balanced multiloop disk margins of ``artifact``.

        ``alpha = 1/max_w mu_ub(S_i - I/2)`` (module docstring), 0 where the
        coupled closed loop (:func:`coupled_closed_loop`, spectral radius,
        with each model's measured speed) is unstable.
        """
        laws = executed_laws(artifact)
        stable = np.zeros(self.shape, bool)
        for j, om in enumerate(self.speeds[:, None] if self.paired else self.speeds):
            loop = coupled_closed_loop(laws, artifact.decoupling, self.Ts, self.d,
                                       R=self.R, Ld=self.Ld, Lq=self.Lq, omega=om,
                                       omega_meas=self.omega_meas[:, j])
            stable[:, j] = loop.spectral_radius() < 1 - 1e-9
            if self.paired:
                break
        # L_i = (K - W) P R(eps) with K = diag(K_d, K_q), the off-diagonal W and
        # the placement rotation, entry by entry (W and eps from the measured speed);
        # for method cv, K - W is its law's 2x2 response at the measured speed
        speeds = self.speeds if self.paired else np.tile(self.speeds, self.shape[0])
        meas = self.omega_meas.reshape(-1)
        if isinstance(laws, dict):
            kd, kq = (FreqResponse(*laws[name].error_controller())(self.z)[:, 0, 0]
                      for name in AXES)
            W = decoupling_matrix(artifact.decoupling, meas)
            k00, k01, k10, k11 = kd, -W[:, 0, 1, None], -W[:, 1, 0, None], kq
        else:
            K = laws.error_response(self.z, meas)
            k00, k01, k10, k11 = K[..., 0, 0], K[..., 0, 1], K[..., 1, 0], K[..., 1, 1]
        eps = placement_error(artifact.decoupling, self.Ts, self.d, speeds, meas)[:, None]
        c, s = np.cos(eps), np.sin(eps)
        q00, q01, q10, q11 = self.P
        p00, p01 = q00 * c + q01 * s, q01 * c - q00 * s
        p10, p11 = q10 * c + q11 * s, q11 * c - q10 * s
        l00, l01 = k00 * p00 + k01 * p10, k00 * p01 + k01 * p11
        l10, l11 = k10 * p00 + k11 * p10, k10 * p01 + k11 * p11
        # S_i - I/2 with S_i = (I + L_i)^-1 = adj(I + L_i)/det
        det = (1.0 + l00) * (1.0 + l11) - l01 * l10
        mu = mu_upper_entries((1.0 + l11) / det - 0.5, -l01 / det, -l10 / det,
                              (1.0 + l00) / det - 0.5)
        return np.where(stable, 1.0 / np.max(mu, axis=-1).reshape(self.shape), 0.0)


def multimodel_disk_margins(artifact, motors, speeds, *, n_grid: int = 300,
                            speed_gain=None, speed_offset=None) -> np.ndarray:
    """Multiloop disk margins of one design over a set of plants and speeds.

    Each entry is what :func:`mimo_disk_margins` computes at one speed for
    one plant: the executed sampled loop (ZOH, the artifact's computation
    delay, the decoupling with the controller's parameters and the voltage
    placement, both from the measured speed ``g w + o``),
    ``alpha = 1/max_w mu_ub(S_i - I/2)``, 0 where the coupled closed loop is
    unstable (:class:`MultiModelLoops`, which the robust PI tuner
    ``toolbox.design.robust_pi`` reuses across candidates).

    Parameters
    ----------
    speed_gain, speed_offset : array_like, optional
        Speed-sensor gain and offset (electrical rad/s) per motor (or one for
        all); default an exact measurement.

    Returns
    -------
    ndarray
        ``(len(motors), len(speeds))`` balanced multiloop disk margins.
    """
    return MultiModelLoops(motors, speeds, artifact.sample_time, artifact.delay_samples,
                           n_grid, speed_gain=speed_gain,
                           speed_offset=speed_offset).disk_margins(artifact)


@dataclass(frozen=True)
class MimoBoxResult:
    """Multiloop disk margins of the coupled loop over a parameter box and the speed range.

    Attributes
    ----------
    box : dict
        ``{"R": [lo, hi], "Ld": .., "Lq": ..}`` scale factors.
    speeds_rad_s : list
        Electrical speeds ``linspace(0, w_max)`` (the margin is even in the speed).
    n_models : int
        Plants: the nominal motor and the ``2^3`` corners of the box.
    n_unstable : int
        (plant, speed) pairs whose coupled closed loop is unstable.
    worst_disk_margin : float
        Smallest balanced multiloop disk margin (0 when a pair is unstable).
    worst_speed_rad_s : float
        Electrical speed of the worst pair (rad/s).
    worst_params : dict
        Scale factors of the worst pair's plant.
    worst_gain_margin : tuple
        Simultaneous gain factors ``(low, high)`` at the worst pair.
    worst_phase_margin_deg : float
        Simultaneous phase variation at the worst pair (deg).
    nominal_worst_disk_margin : float
        Smallest margin of the nominal plant over the speeds.
    domain : str
    """

    box: dict
    speeds_rad_s: list
    n_models: int
    n_unstable: int
    worst_disk_margin: float
    worst_speed_rad_s: float
    worst_params: dict
    worst_gain_margin: tuple
    worst_phase_margin_deg: float
    nominal_worst_disk_margin: float
    domain: str = "discrete"

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready(asdict(self))


def mimo_over_box(artifact, motor, drive=None, *, box: dict | None = None, n_speeds: int = 5,
                  n_grid: int = 1500, max_speed_rad_s: float | None = None) -> MimoBoxResult:
    """Worst multiloop disk margin of the executed coupled loop over a box and the speeds.

    The ``mimo_at_speed`` analysis of :func:`mimo_disk_margins` on the nominal
    plant and every corner of ``box`` (:class:`MultiModelLoops`: ZOH, the
    artifact's delay, the decoupling with the controller's parameters), at
    ``n_speeds`` electrical speeds ``linspace(0, w_max)``.

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant; corners are ``scale * nominal``.
    drive : Drive, optional
        Speed range (:func:`toolbox.plant.max_electrical_speed`).
    box : dict, optional
        ``{"R": (lo, hi), "Ld": .., "Lq": ..}`` (default :data:`DEFAULT_BOX`).
    n_speeds : int
        Speeds from 0 to the maximum (1: standstill only).
    n_grid : int
        Frequency points.
    max_speed_rad_s : float, optional
        Electrical speed range override (rad/s).

    Returns
    -------
    MimoBoxResult
    """
    box = {k: tuple(v) for k, v in (box or DEFAULT_BOX).items()}
    P = sample_parameters({k: (lo, hi, "scale") for k, (lo, hi) in box.items()}, 0)
    params = [{k: float(P[k][i]) for k in box} for i in range(len(P[next(iter(box))]))]
    motors = [motor.with_overrides(None, p) for p in params]
    wmax = max_speed_rad_s if max_speed_rad_s is not None else max_electrical_speed(motor, drive)
    speeds = np.linspace(0.0, wmax, n_speeds) if (wmax > 0 and n_speeds > 1) else np.zeros(1)
    M = MultiModelLoops(motors, speeds, artifact.sample_time, artifact.delay_samples,
                        n_grid).disk_margins(artifact)
    i, j = np.unravel_index(int(np.argmin(M)), M.shape)
    worst = float(M[i, j])
    lo, hi, ph = disk_variations(worst, 0.0)
    return MimoBoxResult({k: list(v) for k, v in box.items()}, [float(s) for s in speeds],
                         len(motors), int(np.sum(M == 0.0)), worst, float(speeds[j]),
                         params[i], (lo, hi), ph, float(np.min(M[0])))
