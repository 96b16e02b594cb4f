"""The robustness sweep counts the loop the header runs (toolbox/ARCHITECTURE.md
"The digital loop").

An independent construction of the sampled coupled dq loop, written here from
the header's documented usage and not from ``toolbox.analysis._coupled``: the
executed laws' coefficients, the decoupling with the measured speed, the
voltage rotated by ``DELAY_COMP_TIME w_meas`` and placed by the inverse Park
transform at the SAMPLED angle, applied ``d`` periods later for one period,
the plant discretised by scipy's ``expm``. Two inverter holds:

* rotor frame (the analyses' and the simulator's default): the dq voltage of
  the mid-period angle, constant over the period;
* stationary frame (what a PWM inverter averages to): ``v_alpha_beta``
  constant, so the rotor-frame voltage turns by ``-w t`` inside the period;
  discretised exactly with the exosystem ``z' = -w J z``.

On 2,000 sets of the sweep's own box (R, Ld, Lq x0.5..2, flux, speed-sensor
gain and offset, the design's delay and one period more) at its nine speeds,
the sweep's count of unstable sets equals this construction's count with the
rotor hold, set by set; the stationary hold changes the verdict only of sets
whose spectral radius lies within 1e-3 of 1 (an O((w Ts)^2) effect).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

from toolbox.analysis import robustness_sweep
from toolbox.analysis._sampling import DEFAULT_RANGES, sample_parameters
from toolbox.design import design
from toolbox.plant import max_electrical_speed
from toolbox.spec import load_spec

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
N_SETS = 2000
J = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rot(a):
    c, s = np.cos(a), np.sin(a)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def _plant_zoh(R, Ld, Lq, w, Ts, eps, hold):
    """``(Phi, Gamma_v)`` (N, 2, 2): the commanded voltage's input matrix with
    the placement error ``eps`` for the rotor or the stationary hold."""
    N = R.size
    A = np.zeros((N, 4, 4))
    A[:, 0, 0], A[:, 0, 1] = -R / Ld, w * Lq / Ld
    A[:, 1, 0], A[:, 1, 1] = -w * Ld / Lq, -R / Lq
    A[:, 0, 2], A[:, 1, 3] = 1.0 / Ld, 1.0 / Lq
    if hold == "stationary":        # input z(t) = R(eps + w Ts/2 - w t) v: z' = -w J z
        A[:, 2:, 2:] = -w[:, None, None] * J
    E = expm(A * Ts)
    Phi, G = E[:, :2, :2], E[:, :2, 2:]
    if hold == "stationary":
        return Phi, G @ _rot(eps + w * Ts / 2)
    return Phi, G @ _rot(eps)


def _radius(art, R, Ld, Lq, w, w_meas, d, hold):
    """Spectral radius of each set's closed loop (independent assembly)."""
    Ts = art.sample_time
    t_c = art.decoupling.delay_compensation_time
    eps = t_c * w_meas - (d + 0.5) * Ts * w
    Phi, Gam = _plant_zoh(R, Ld, Lq, w, Ts, eps, hold)
    laws = [art.axes[ax].law for ax in "dq"]
    nd, nq = (law.A.shape[0] for law in laws)
    nx = 2 + nd + nq
    n = nx + 2 * d
    N = R.size
    dec = art.decoupling
    # commanded voltage v = K x (references 0)
    K = np.zeros((N, 2, n))
    K[:, 0, 1] = -dec.cross * w_meas * dec.Lq_c
    K[:, 1, 0] = dec.cross * w_meas * dec.Ld_c
    K[:, 0, 0] += laws[0].D[0, 1]
    K[:, 1, 1] += laws[1].D[0, 1]
    K[:, 0, 2:2 + nd] = laws[0].C[0]
    K[:, 1, 2 + nd:nx] = laws[1].C[0]
    M = np.zeros((N, n, n))
    M[:, :2, :2] = Phi
    M[:, 2:2 + nd, 2:2 + nd] = laws[0].A
    M[:, 2:2 + nd, 0] = laws[0].B[:, 1]
    M[:, 2 + nd:nx, 2 + nd:nx] = laws[1].A
    M[:, 2 + nd:nx, 1] = laws[1].B[:, 1]
    if d == 0:
        M[:, :2, :] += Gam @ K
    else:
        M[:, :2, nx:nx + 2] = Gam
        for j in range(d - 1):
            M[:, nx + 2 * j:nx + 2 * j + 2, nx + 2 * j + 2:nx + 2 * j + 4] = np.eye(2)
        M[:, nx + 2 * d - 2:, :] = K
    return np.max(np.abs(np.linalg.eigvals(M)), axis=-1)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["003_azaiz2007_hinf", "003_azaiz2007_pi",
                                  "002_cormerais2002_svm_pi"])
def test_sweep_counts_the_headers_loop(name):
    spec = load_spec(DESIGNS / f"{name}.toml")
    art = design(spec)
    motor = spec.motor
    n = N_SETS - 2 ** 7 - 1                        # the sweep adds nominal and corners
    sweep = robustness_sweep(art, motor, n=n, drive=spec.drive, n_grid=50)
    assert sweep.n_sets == N_SETS
    rng = dict(DEFAULT_RANGES)
    lo, hi, kind = rng["delay_samples"]
    rng["delay_samples"] = (art.delay_samples + lo, art.delay_samples + hi, kind)
    P = sample_parameters(rng, n, 0)
    R, Ld, Lq = motor.R * P["R"], motor.Ld * P["Ld"], motor.Lq * P["Lq"]
    g, off = P["speed_gain"], P["speed_offset"] * motor.pole_pairs
    d = P["delay_samples"].astype(int)
    wmax = max_electrical_speed(motor, spec.drive)
    rho = {h: np.zeros(N_SETS) for h in ("rotor", "stationary")}
    for dv in np.unique(d):
        sel = d == dv
        for w in np.linspace(-wmax, wmax, len(sweep.speeds_rad_s)):
            ww = np.full(sel.sum(), w)
            for h in rho:
                r = _radius(art, R[sel], Ld[sel], Lq[sel], ww, g[sel] * w + off[sel], int(dv), h)
                rho[h][sel] = np.maximum(rho[h][sel], r)
    unstable = {h: rho[h] >= 1 - 1e-9 for h in rho}
    print(f"\n{name}: sweep {sweep.n_unstable} / {N_SETS} unstable; header usage, rotor "
          f"hold {unstable['rotor'].sum()}, stationary hold {unstable['stationary'].sum()}")
    assert unstable["rotor"].sum() == sweep.n_unstable
    assert np.max(rho["rotor"]) == pytest.approx(sweep.worst_spectral_radius, rel=1e-9)
    differ = unstable["rotor"] != unstable["stationary"]
    assert np.all(np.abs(rho["rotor"][differ] - 1.0) < 1e-3)
