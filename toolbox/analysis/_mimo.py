"""Multiloop disk margins of the coupled dq loop over speed.

For the coupled 2x2 loop at speed, :func:`mimo_disk_margins` uses the
multiloop (input, diagonal uncertainty) version with the upper bound of the
structured singular value obtained by D-scaling:
``mu(M) <= min_{d>0} sigma_max(D M D^-1)``, ``D = diag(d, 1)``,
``M = S_i + (sigma - 1)/2 I``, ``S_i = (I + C P)^-1`` - a guaranteed
(possibly conservative) multiloop disk margin ``alpha = 1/max_w mu_ub``; the
unstructured ``1/max_w sigma_max(M)`` is reported next to it.

Disk margins after Seiler, Packard, Gahinet, "An introduction to disk
margins", IEEE Control Systems Magazine 40(5), 2020.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..plant import max_electrical_speed
from ._coupled import coupled_closed_loop, coupled_plant, decoupling_matrix
from ..artifact import json_ready
from ._laws import AXES, axis_law
from ._siso import disk_variations, log_grid
from ._statespace import freqresp, zoh_coupled

__all__ = ["MimoMarginsResult", "sigma_max_2x2", "mu_upper_2x2", "mimo_loop_response",
           "mimo_disk_margins"]


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
    wmax = max_speed_rad_s if max_speed_rad_s is not None else max_electrical_speed(motor, drive)
    speeds = np.linspace(-wmax, wmax, n_speeds) if wmax > 0 else np.zeros(1)
    Ts = artifact.sample_time
    w_hi = math.pi / Ts if discrete else 1e7
    w = log_grid(1e-2, w_hi, n_grid, discrete)
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
