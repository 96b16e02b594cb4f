"""The ``complex_vector`` PI rule against motulator itself (motulator's current controller
exactly, an independent implementation installed as a test dependency).

motulator 0.5 (``motulator.drive.control.sm.CurrentController``, a
``ComplexPIController`` with ``k_p = 2 alpha_c``, ``k_i = alpha_c^2``,
``k_t = alpha_c`` on the flux linkages ``psi = L i``) executes, per sample,

    u = alpha_c L (r - y) - alpha_c L y + u_i
    u_i <- u_i + Ts (alpha_c + j w) (u_realised - v),  v = u_i - alpha_c L y

(no feedforward: ``u_ff = 0`` in its synchronous-machine vector control).

What is asserted here, in the case where the two can agree (rotor at
standstill ``w = 0``, no voltage limit, our law discretised with ``euler``,
``integral_bandwidth = bandwidth``): our 2DOF law equals motulator's output
plus ``R y`` exactly (to 1e-12 V): our ``Kp = (alpha_c + alpha_i) L - R``
subtracts the resistance (poles exactly at -alpha_c, -alpha_i for the model's
R), motulator's ``k_p`` neglects it (its poles are those of
``L s^2 + (R + 2 alpha_c L) s + alpha_c^2 L``). Under a voltage limit our
anti-windup (Hanus conditioning, ``aw = Ts/Kt``) is motulator's realised-voltage
update, exactly (checked with R -> 0). They differ when the rotor turns (w != 0:
motulator's integrator is complex, with the ``j w`` cross term).
"""

from __future__ import annotations

import types

import numpy as np
import pytest

from toolbox.design import design
from toolbox.spec import spec_from_dict

try:
    from motulator.drive.control.sm import CurrentController
except ImportError:          # fail, never skip: it is a declared test dependency
    CurrentController = None

TS = 1e-4
A_C = 2 * np.pi * 200         # motulator's default current-control bandwidth (rad/s)


def _spec():
    return spec_from_dict({
        "motor": {"catalog": "lepioufle1992"},
        "drive": {"vdc": 150, "sample_time": TS},
        "controller": {"method": "pi", "pi": {"rule": "complex_vector", "bandwidth": A_C,
                                              "integral_bandwidth": A_C,
                                              "discretisation": "euler"}}})


def _ours(art, r, y):
    """Run the artifact's executed discrete law of each axis on (r, y) sequences."""
    out = np.zeros(r.shape)
    for j, ax in enumerate("dq"):
        law = art.axes[ax].law
        A, B, C, D = (np.atleast_2d(np.asarray(m, float)) for m in (law.A, law.B, law.C, law.D))
        x = np.zeros((A.shape[0], 1))
        for k in range(r.shape[0]):
            u = np.array([[r[k, j]], [y[k, j]]])
            out[k, j] = (C @ x + D @ u).item()
            x = A @ x + B @ u
    return out


def _motulator(motor, r, y, w=0.0, limit=np.inf):
    if CurrentController is None:
        pytest.fail("motulator not installed: it is in the test extras "
                    "(pip install -e '.[test]')", pytrace=False)
    cc = CurrentController(types.SimpleNamespace(L_d=motor.Ld, L_q=motor.Lq), A_C)
    out = np.zeros(r.shape)
    for k in range(r.shape[0]):
        u = cc.output(r[k, 0] + 1j * r[k, 1], y[k, 0] + 1j * y[k, 1])
        u = u if abs(u) <= limit else u * limit / abs(u)      # realised voltage
        cc.update(TS, u, w)
        out[k] = u.real, u.imag
    return out


@pytest.fixture(scope="module")
def case():
    spec = _spec()
    rng = np.random.default_rng(16)
    r, y = rng.normal(0, 5, (200, 2)), rng.normal(0, 5, (200, 2))
    return spec.motor, design(spec), r, y


def test_equal_to_motulator_plus_resistance_term(case):
    motor, art, r, y = case
    ours, theirs = _ours(art, r, y), _motulator(motor, r, y)
    err = np.abs(ours - theirs - motor.R * y).max()
    print(f"\nmax |ours - motulator - R y| = {err:.2e} V; max |ours - motulator| = "
          f"{np.abs(ours - theirs).max():.2f} V (R = {motor.R} ohm)")
    assert err < 1e-12
    assert np.abs(ours - theirs).max() > 1.0       # the R y term is not negligible


def test_differs_when_rotating(case):
    """w != 0: motulator's integrator is complex (``j w`` cross term); ours are two
    real per-axis integrators (the cross-coupling is in the decoupling feedforward)."""
    motor, art, r, y = case
    ours = _ours(art, r, y) - motor.R * y          # the part equal at standstill
    rotating = _motulator(motor, r, y, w=4 * 200.0)
    assert np.abs(ours - rotating).max() > 1e-3


def test_antiwindup_is_motulators_realised_voltage_update():
    """Under a voltage limit (circle, |v| <= 8 V, saturated most samples) our
    executed law with its anti-windup (Hanus conditioning, ``x += aw (v_sat -
    v_unsat)``, ``aw = Ts/Kt``) equals motulator's integrator fed the realised
    voltage (``u_i += Ts alpha_i (u_realised - v)``) when R -> 0 (1e-6 ohm: the
    R y term is then < 1e-5 V): the same anti-windup, to 1e-4 V."""
    spec = spec_from_dict({
        "motor": {"R": 1e-6, "Ld": 1.4e-3, "Lq": 2.8e-3, "flux": 0.12, "pole_pairs": 4, "J": 1e-3},
        "drive": {"vdc": 150, "sample_time": TS},
        "controller": {"method": "pi", "pi": {"rule": "complex_vector", "bandwidth": A_C,
                                              "integral_bandwidth": A_C,
                                              "discretisation": "euler"}}})
    art, lim = design(spec), 8.0
    rng = np.random.default_rng(16)
    r, y = rng.normal(0, 5, (300, 2)), rng.normal(0, 5, (300, 2))
    laws = []
    for ax in "dq":
        law = art.axes[ax].law
        laws.append([np.atleast_2d(np.asarray(m, float)) for m in (law.A, law.B, law.C, law.D)]
                    + [np.asarray(art.axes[ax].antiwindup, float).reshape(-1, 1)])
    xs = [np.zeros((law[0].shape[0], 1)) for law in laws]
    ours = np.zeros(r.shape)
    for k in range(r.shape[0]):
        inp = [np.array([[r[k, j]], [y[k, j]]]) for j in (0, 1)]
        un = [(C @ xs[j] + D @ inp[j]).item() for j, (A, B, C, D, aw) in enumerate(laws)]
        v = complex(*un)
        vs = v if abs(v) <= lim else v * lim / abs(v)
        ours[k] = vs.real, vs.imag
        for j, (A, B, C, D, aw) in enumerate(laws):
            xs[j] = A @ xs[j] + B @ inp[j] + aw * (ours[k, j] - un[j])
    theirs = _motulator(spec.motor, r, y, limit=lim)
    saturated = np.mean(np.hypot(*theirs.T) >= lim - 1e-9)
    print(f"\nlimited: max |ours - motulator| = {np.abs(ours - theirs).max():.1e} V, "
          f"{saturated:.0%} of samples saturated")
    assert saturated > 0.5
    assert np.abs(ours - theirs).max() < 1e-4
