"""The coupled dq current loop at constant speed, as executed (stacked numpy).

The plant ``A(omega) = [[-R/Ld, omega Lq/Ld], [-omega Ld/Lq, -R/Lq]]``,
``B = diag(1/Ld, 1/Lq)`` (paper 003 eq (3)-(4)) is discretised exactly (ZOH)
at each speed and closed with both executed laws, the decoupling (with the
controller's model parameters and the measured speed) and the delay line.
The voltage enters the plant rotated by the placement error of the digital
loop (toolbox/ARCHITECTURE.md "The digital loop"): the firmware places the
voltage computed at ``t_k`` at ``theta_k + t_c w_meas`` and it acts around
the middle of its application period, ``theta_k + (d + 1/2) Ts w``, so the
rotor-frame hold sees ``R(eps) v`` with ``eps = t_c w_meas - (d + 1/2) Ts w``
(the simulator's rotor hold, exactly). Shared by the MIMO margins and the
robustness sweep.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..plant import dq_matrices
from ._laws import CvExecuted
from ._statespace import zoh_2x2

__all__ = ["coupled_plant", "decoupling_matrix", "CoupledLoop", "coupled_closed_loop",
           "coupled_state_matrix", "placement_error", "rotation"]


def coupled_plant(R, Ld, Lq, omega) -> tuple[np.ndarray, np.ndarray]:
    """Stacked ``A(omega)`` (N, 2, 2) and ``B`` (N, 2, 2) of the dq plant:
    :func:`toolbox.plant.dq_matrices` (the one closed form of the model)."""
    return dq_matrices(R, Ld, Lq, omega)


def decoupling_matrix(decoupling, omega_meas) -> np.ndarray:
    """``W`` (N, 2, 2) with ``v += W i``: ``W = cross w_m [[0, -Lq_c], [Ld_c, 0]]``."""
    wm = np.atleast_1d(np.asarray(omega_meas, float)).reshape(-1)
    W = np.zeros((wm.size, 2, 2))
    if decoupling.cross:
        W[:, 0, 1] = -wm * decoupling.Lq_c
        W[:, 1, 0] = wm * decoupling.Ld_c
    return W


def placement_error(decoupling, sample_time: float, delay_samples: int, omega,
                    omega_meas) -> np.ndarray:
    """Angle ``eps`` (rad) by which the applied voltage leads the commanded
    one in the rotor frame: ``t_c w_meas - (d + 1/2) Ts w`` (``t_c`` the
    decoupling's ``delay_compensation_time``; speeds electrical, rad/s)."""
    t_c = decoupling.delay_compensation_time
    return (t_c * np.asarray(omega_meas, float)
            - (int(delay_samples) + 0.5) * sample_time * np.asarray(omega, float))


def rotation(eps) -> np.ndarray:
    """Stacked rotation matrices ``R(eps)`` (N, 2, 2)."""
    eps = np.atleast_1d(np.asarray(eps, float)).reshape(-1)
    c, s = np.cos(eps), np.sin(eps)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


@dataclass(frozen=True)
class CoupledLoop:
    """Stacked discrete closed loops of the coupled dq current control.

    ``x+ = A x + B r + c`` with states ``[i_d, i_q, x_law_d, x_law_q,
    q_1 .. q_d]`` (``q_j``: commanded dq voltages waiting in the delay line,
    ``q_1`` is applied) and the dq current references ``r`` (A); ``c`` holds
    the back-EMF and its (possibly wrong) compensation. ``A`` (N, n, n).
    """

    A: np.ndarray
    B: np.ndarray
    c: np.ndarray

    def spectral_radius(self) -> np.ndarray:
        """Largest pole modulus of each closed loop (N,)."""
        return np.max(np.abs(np.linalg.eigvals(self.A)), axis=-1)

    def steady_currents(self, r) -> np.ndarray:
        """Static dq currents (N, 2) for constant references ``r`` (A)."""
        N, n, _ = self.A.shape
        rhs = self.B @ np.asarray(r, float).reshape(2) + self.c
        x = np.linalg.solve(np.eye(n) - self.A, rhs[..., None])[..., 0]
        return x[:, :2]


def coupled_closed_loop(laws: dict, decoupling, sample_time: float, delay_samples: int, *,
                        R, Ld, Lq, omega, omega_meas=None, flux=0.0) -> CoupledLoop:
    """Vectorised closed loops of the executed dq control at fixed speeds.

    Parameters
    ----------
    laws : dict or CvExecuted
        ``{"d": Law, "q": Law}`` discrete executed laws (:func:`axis_law`), or
        the complex-vector law of method ``cv`` (:func:`executed_laws`; its
        states ``[x, p_1 .. p_d]``, gains at each model's measured speed).
    decoupling : Decoupling
        Compensation terms and the controller's model parameters.
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay (periods).
    R, Ld, Lq : array_like
        True plant parameters (ohm, H, H), broadcast to N sets.
    omega : array_like
        True electrical speed (rad/s).
    omega_meas : array_like, optional
        Measured electrical speed used by the compensation and the voltage
        placement (rad/s); default ``omega`` (paper 000 eq (14)-(17) study its
        errors).
    flux : array_like
        True magnet flux (Wb), for the back-EMF term ``c``.

    Returns
    -------
    CoupledLoop
        The plant is ZOH-discretised at each speed (exact for constant speed);
        the commanded voltage enters through ``Gamma R(eps)``
        (:func:`placement_error`), the back-EMF through ``Gamma``.
    """
    Ts, d = sample_time, int(delay_samples)
    omega_meas = omega if omega_meas is None else omega_meas
    R, Ld, Lq, omega, omega_meas, flux = (
        np.atleast_1d(v).astype(float).reshape(-1)
        for v in np.broadcast_arrays(R, Ld, Lq, omega, omega_meas, flux))
    N = R.size
    Ac, Bc = coupled_plant(R, Ld, Lq, omega)
    Phi, Gam = zoh_2x2(Ac, Bc, Ts)
    Gam_v = Gam @ rotation(placement_error(decoupling, Ts, d, omega, omega_meas))
    A, Kx, Kr, Bs = _state_matrix(laws, decoupling, d, Phi, Gam_v, omega_meas)
    n = A.shape[-1]
    nx = n - 2 * d
    k0 = np.zeros((N, 2))
    if decoupling.emf:
        k0[:, 1] = omega_meas * decoupling.flux_c
    emf = np.zeros((N, 2))
    emf[:, 1] = -omega * flux          # back-EMF as a voltage
    B = np.zeros((N, n, 2))
    c = np.zeros((N, n))
    c[:, :2] = (Gam @ emf[..., None])[..., 0]
    B[:, 2:nx, :] = Bs
    if d == 0:
        B[:, :2, :] += Gam_v @ Kr
        c[:, :2] += (Gam_v @ k0[..., None])[..., 0]
    else:
        last = slice(nx + 2 * (d - 1), nx + 2 * d)      # q_d+ = v
        B[:, last, :] = Kr
        c[:, last] = k0
    return CoupledLoop(A, B, c)


def coupled_state_matrix(laws: dict, decoupling, delay_samples: int, Phi: np.ndarray,
                         Gam: np.ndarray, omega_meas) -> np.ndarray:
    """State matrix (N, n, n) of the executed coupled loop for given ZOH matrices.

    The loop of :func:`coupled_closed_loop` (same states) with the plant's
    ``Phi`` (N, 2, 2) and the commanded voltage's input matrix ``Gamma`` (N,
    2, 2; the placement rotation included) given rather than computed from
    parameters: the sampled-loop certificate evaluates it on matrices that
    bound the exact discretisation. Affine in ``(Phi, Gamma)`` for a fixed
    measured speed, and in the measured speed ``omega_meas`` (rad/s) for a
    fixed ``Gamma``.
    """
    return _state_matrix(laws, decoupling, int(delay_samples), Phi, Gam,
                         np.broadcast_to(np.asarray(omega_meas, float),
                                         (Phi.shape[0],)))[0]


def _state_matrix(laws, decoupling, d, Phi, Gam, omega_meas):
    """``(A, Kx, Kr, Bs)``: the closed loop's state matrix, the commanded voltage's
    state gain ``v = Kx x + Kr r + k0`` (N, 2, n), reference gain (2, 2) or
    (N, 2, 2), and the law states' reference input (N, n_law, 2)."""
    if isinstance(laws, CvExecuted):
        return _cv_state_matrix(laws, d, Phi, Gam, omega_meas)
    N = Phi.shape[0]
    W = decoupling_matrix(decoupling, omega_meas)
    ld, lq = laws["d"], laws["q"]
    nd, nq = ld.n, lq.n
    nx = 2 + nd + nq
    n = nx + 2 * d
    # commanded voltage v = Kx x + Kr r + k0
    Kx = np.zeros((N, 2, n))
    Kx[:, :, :2] = W
    Kx[:, 0, 0] += ld.D[0, 1]
    Kx[:, 1, 1] += lq.D[0, 1]
    Kx[:, 0, 2:2 + nd] = ld.C[0]
    Kx[:, 1, 2 + nd:nx] = lq.C[0]
    Kr = np.diag([ld.D[0, 0], lq.D[0, 0]])
    A = np.zeros((N, n, n))
    A[:, :2, :2] = Phi
    # law states
    A[:, 2:2 + nd, 0] = ld.B[:, 1]
    A[:, 2:2 + nd, 2:2 + nd] = ld.A
    A[:, 2 + nd:nx, 1] = lq.B[:, 1]
    A[:, 2 + nd:nx, 2 + nd:nx] = lq.A
    if d == 0:
        A[:, :2, :] += Gam @ Kx
    else:
        A[:, :2, nx:nx + 2] = Gam                       # q_1 applied
        for j in range(d - 1):                          # q_j+ = q_{j+1}
            A[:, nx + 2 * j:nx + 2 * j + 2, nx + 2 * j + 2:nx + 2 * j + 4] = np.eye(2)
        last = slice(nx + 2 * (d - 1), nx + 2 * d)      # q_d+ = v
        A[:, last, :] = Kx
    Bs = np.zeros((N, nd + nq, 2))
    Bs[:, :nd, 0] = ld.B[:, 0]
    Bs[:, nd:, 1] = lq.B[:, 0]
    return A, Kx, Kr, Bs


def _cv_state_matrix(law: CvExecuted, d, Phi, Gam, omega_meas):
    """:func:`_state_matrix` of the complex-vector law: law states ``[x, p_1 ..
    p_dl]`` (``p_j`` its linear voltage of ``j`` periods ago, ``dl`` the
    design's delay, which the loop's ``d`` may exceed), gains at each measured
    speed; ``v = Kt r - K1 i - sum_j K2_j p_j + x`` (+ the EMF feed-forward
    ``k0``), ``x+ = x + Ki (r - i)``, ``p_1+ = v - k0``."""
    N = Phi.shape[0]
    g = law.gains(np.broadcast_to(np.asarray(omega_meas, float), (N,)))
    dl = int(law.delay_samples)
    m = 2 + 2 * dl
    nx = 2 + m
    n = nx + 2 * d
    Kx = np.zeros((N, 2, n))
    Kx[:, :, :2] = -g.K1
    Kx[:, :, 2:4] = np.eye(2)
    for j in range(dl):
        Kx[:, :, 4 + 2 * j:6 + 2 * j] = -g.K2[:, j]
    A = np.zeros((N, n, n))
    A[:, :2, :2] = Phi
    A[:, 2:4, :2] = -g.Ki                               # x+ = x + Ki (r - i)
    A[:, 2:4, 2:4] = np.eye(2)
    Bs = np.zeros((N, m, 2))
    Bs[:, :2] = g.Ki
    if dl:
        A[:, 4:6, :] = Kx                               # p_1+ = the linear voltage
        Bs[:, 2:4] = g.Kt
        for j in range(1, dl):                          # p_j+ = p_{j-1}
            A[:, 4 + 2 * j:6 + 2 * j, 2 + 2 * j:4 + 2 * j] = np.eye(2)
    if d == 0:
        A[:, :2, :] += Gam @ Kx
    else:
        A[:, :2, nx:nx + 2] = Gam                       # q_1 applied
        for j in range(d - 1):                          # q_j+ = q_{j+1}
            A[:, nx + 2 * j:nx + 2 * j + 2, nx + 2 * j + 2:nx + 2 * j + 4] = np.eye(2)
        A[:, nx + 2 * (d - 1):nx + 2 * d, :] = Kx       # q_d+ = v
    return A, Kx, g.Kt, Bs
