"""The simulator's flux-linkage state of saturated motors (toolbox/ARCHITECTURE.md
"Saturated motors"): agreement with motulator's saturated synchronous machine,
and the reduction to the constant-parameter plant for a linear flux map.

Shared case: the 5.5 kW PM-SyRM of motulator's example
``plot_flux_vector_pmsyrm_5kw.py`` (algebraic saturation model of Lelli,
Hinkkanen, Giulii Capponi 2024, R = 0.63 ohm, 2 pole pairs), at an imposed
mechanical speed of 60 rad/s, driven by an open-loop sequence of rotor-frame
voltages held over 100 us periods for 0.2 s. The toolbox side is the
kernel's plant loop (``_kernel_steps._steps_flux``: RK4 at 1 us, current read
from the 129 x 129 bilinear flux table of ``MagneticModel.inverse_table``),
fed with a flux map generated from the algebraic model on a 41 x 41 current
grid (the CSV route a user takes) ; motulator's side is its
``SynchronousMachine(par, i_s=...)`` right-hand side (the closed-form model)
integrated by scipy's ``solve_ivp`` (DOP853, rtol 1e-10).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from toolbox.spec import AlgebraicSaturation, MagneticModel, Motor, Scenario
from toolbox.sim import _kernel_plant as kp
from toolbox.sim import _kernel_steps as ks
from toolbox.sim._kernel_layout import LAYOUTS
from toolbox.sim._simulate import ControlLaw, DriveParams, discrete_pi, simulate
from toolbox.spec._flux_map import read_flux_map

from sim_helpers import placed

PMSYRM = AlgebraicSaturation(a_d0=3.96, a_dd=28.46, S=4, a_q0=5.89, a_qq=2.672, T=6,
                             a_dq=41.52, U=1, V=1, a_b=81.75, a_bp=1, k_q=0.1, psi_n=0.804,
                             W=2, current_range=30.0)
R, NP, TS, H = 0.63, 2, 1e-4, 1e-6
OMEGA = 5.0  # mechanical rad/s


def _voltages(n):
    """The open-loop dq voltage sequence (V): the steady-state voltages
    ``v = R i + w J psi(i)`` of the currents (0, 10), (-5, 18), (8, -12), (2, 3) A,
    50 ms each, so that the run crosses the saturated region without leaving
    the map."""
    mdl = MagneticModel("algebraic", PMSYRM)
    w = NP * OMEGA
    t = np.arange(n) * TS
    vd = np.empty(n)
    vq = np.empty(n)
    for j, (i_d, i_q) in enumerate(((0.0, 10.0), (-5.0, 18.0), (8.0, -12.0), (2.0, 3.0))):
        psd, psq = mdl.flux(i_d, i_q)
        sel = (t >= 0.05 * j) & (t < 0.05 * (j + 1)) if j < 3 else t >= 0.15
        vd[sel] = R * i_d - w * psq
        vq[sel] = R * i_q + w * psd
    return vd, vq


def _write_map(path, model, n=61):
    ids = np.linspace(-30, 30, n)
    iqs = np.linspace(-30, 30, n)
    D, Q = np.meshgrid(ids, iqs, indexing="ij")
    psd, psq = model.flux(D.ravel(), Q.ravel())
    rows = ["i_d [A],i_q [A],psi_d [Wb],psi_q [Wb]"]
    rows += [f"{a:.17g},{b:.17g},{c:.17g},{d:.17g}" for a, b, c, d in zip(D.ravel(), Q.ravel(), psd, psq)]
    path.write_text("\n".join(rows) + "\n")


def _plant_array(model):
    names = LAYOUTS["P"]
    Ld, Lq, flux = model.nominal()
    P = np.zeros(len(names))
    vals = dict(R=R, Ld=Ld, Lq=Lq, flux=flux, pole_pairs=NP, J=1.0, friction=0.0,
                torque_factor=1.5, magnetic=1.0)
    for i, name in enumerate(names):
        P[i] = vals[name]
    return np.concatenate([P, model.inverse_table()])


def _ours(model, vd, vq):
    """Currents at the start of each period from the kernel's flux-state loop."""
    pl = kp._plant(_plant_array(model))
    x = kp._initial_state(pl, OMEGA, True)
    acc_m = np.zeros(13)
    refs = (0.0, 0.0, 0.0, 0.0)
    mset = (0, 0.0, 0.0, 1e9, 1e9)
    t = 0.0
    out = np.empty((len(vd), 2))
    for k in range(len(vd)):
        out[k] = kp._current_of_flux(pl[12], x[0], x[1])
        t, x = ks._steps_flux(x, t, 100, TS / 100, vd[k], vq[k], 0, pl, 0.0, 1, 0.0, OMEGA,
                              acc_m, refs, mset)
    return out


def _motulator(vd, vq):
    """Currents at the start of each period from motulator's machine model."""
    from scipy.integrate import solve_ivp
    from motulator.drive import model
    from motulator.drive.utils import SynchronousMachinePars

    def i_s(psi):
        a, b = PMSYRM.current(np.real(psi), np.imag(psi))
        return a + 1j * b

    psi0 = MagneticModel("algebraic", PMSYRM).nominal()[2]
    machine = model.SynchronousMachine(SynchronousMachinePars(n_p=NP, R_s=R), i_s=i_s,
                                       psi_s0=psi0)

    def f(_t, y, u):
        machine.state.psi_s = complex(y[0], y[1])
        machine.state.exp_j_theta_m = np.exp(1j * y[2])
        machine.inp.u_ss = u * machine.state.exp_j_theta_m
        machine.inp.w_M = OMEGA
        machine.set_outputs(_t)
        d_psi, _ = machine.rhs()
        return [d_psi.real, d_psi.imag, NP * OMEGA]

    y = np.array([psi0, 0.0, 0.0])
    out = np.empty((len(vd), 2))
    for k in range(len(vd)):
        cur = i_s(complex(y[0], y[1]))
        out[k] = cur.real, cur.imag
        sol = solve_ivp(f, (0.0, TS), y, method="DOP853", rtol=1e-10, atol=1e-12,
                        args=(complex(vd[k], vq[k]),))
        y = sol.y[:, -1]
    return out


@pytest.mark.slow  # ~10 s: motulator's right-hand side in Python over 2000 periods
def test_flux_map_simulation_agrees_with_motulator(tmp_path):
    """Tolerance 0.05 A (0.2 % of the 25 A grid range). Budget: the flux map is
    the bilinear interpolant of the model on a 1.25 A grid and the simulator
    reads the current from a bilinear table of that map (two interpolation
    errors, each O(h^2 |d2 psi/di2|)); measured below on the same points as
    the table error; RK4 at 1 us against DOP853 at rtol 1e-10 adds < 1e-6 A
    (the electrical time constants are ~50 ms and 240 ms). Without saturation
    the currents would differ by amperes (checked: the constant-inductance
    plant at the same nominal point departs by more than 1 A)."""
    _write_map(tmp_path / "m.csv", MagneticModel("algebraic", PMSYRM))
    fmap = read_flux_map("m.csv", tmp_path)
    n = int(round(0.2 / TS))
    vd, vq = _voltages(n)
    ours = _ours(fmap, vd, vq)
    ref = _motulator(vd, vq)
    err = np.abs(ours - ref).max()
    assert np.abs(ref).max() > 10.0          # the run reaches the saturated region
    assert err < 0.05, err
    # the table's own error at the simulated states is of the same order
    mdl = MagneticModel("algebraic", PMSYRM)
    psd, psq = fmap.flux(ref[:, 0], ref[:, 1])
    back = np.column_stack(mdl.current(psd, psq))
    assert np.abs(back - ref).max() < 0.05
    # a constant-inductance plant at the nominal point is far off: the test can fail
    Ld, Lq, flux = mdl.nominal()
    lin = MagneticModel("map", _linear_map(Ld, Lq, flux))
    assert np.abs(_ours(lin, vd, vq) - ref).max() > 1.0


def _linear_map(Ld, Lq, flux):
    from toolbox.spec import FluxMapData
    ids = np.linspace(-40, 40, 9)
    iqs = np.linspace(-40, 40, 9)
    D, Q = np.meshgrid(ids, iqs, indexing="ij")
    return FluxMapData(i_d=ids, i_q=iqs, psi_d=Ld * D + flux, psi_q=Lq * Q)


def test_linear_flux_map_reduces_to_constant_parameters():
    """A linear flux map (psi_d = Ld i_d + flux, psi_q = Lq i_q) simulated by the
    public route (``simulate``: the kernel's flux-state variant) equals the
    constant-parameter plant under the same closed loop, a PI with decoupling
    stepping to (-5, 12) A at 60 rad/s: bilinear interpolation of a linear
    function is exact, so only round-off differs (1e-9 A; 2e-13 A measured).
    A map with 5 % more d-axis inductance departs by more than 1e-3 A, so the
    comparison can fail."""
    Ld, Lq, flux = 0.0298, 0.1497, 0.4767
    motor = Motor(R=R, Ld=Ld, Lq=Lq, flux=flux, pole_pairs=NP, J=1.0, friction=0.0,
                  convention="amplitude")
    wc = 500.0  # rad/s, pole-zero cancelling PI
    law = ControlLaw(d=discrete_pi(Ld * wc, R * wc, TS), q=discrete_pi(Lq * wc, R * wc, TS),
                     sample_time=TS, decoupling=placed(motor, TS))
    drive = DriveParams(vdc=600.0, sample_time=TS, delay_samples=1, v_limit="none")
    case = Scenario(kind="current_step", duration=0.03, id_ref=-5.0, iq_ref=12.0,
                    step_time=1e-3, initial_speed=60.0, keep_traces=True)

    def currents(L_map):
        mapped = replace(motor, Ld=L_map,
                         magnetics=MagneticModel("map", _linear_map(L_map, Lq, flux)))
        res = simulate(law, mapped, case, drive)
        return np.column_stack([res.id, res.iq])

    const = simulate(law, motor, case, drive)
    ref = np.column_stack([const.id, const.iq])
    assert abs(const.iq[-1] - 12.0) < 0.01 and abs(const.id[-1] + 5.0) < 0.05
    np.testing.assert_allclose(currents(Ld), ref, atol=1e-9, rtol=0)
    assert np.abs(currents(1.05 * Ld) - ref).max() > 1e-3
