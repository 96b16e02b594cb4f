"""The numba kernel against an independent slow pure-Python implementation
(sim_reference.py) on short runs: same numbers to 1e-9 relative (both are
the same arithmetic in double precision; only the operation order differs)."""

import numpy as np
import pytest

from toolbox.spec import Scenario
from toolbox.sim._simulate import DriveParams, simulate

from sim_helpers import PAPER000 as M, tc_law, tci_law
from sim_reference import reference

Ts = 1e-4


def _close(a, b, rel=1e-9):
    scale = np.maximum(np.abs(b), 1e-3 * np.max(np.abs(b)) + 1e-12)
    return np.max(np.abs(a - b) / scale) < rel


@pytest.mark.parametrize("case", ["tci_free_saturating", "tc_imposed_speed_error"])
def test_kernel_matches_python_reference(case):
    if case == "tci_free_saturating":
        # free acceleration from 150 rad/s, voltage limit active, anti-windup used
        law = tci_law(M, 3750, 707100, 3750, 707100, Ts)
        sc = Scenario(kind="unloaded_start", duration=3e-3, iq_ref=10.0,
                      initial_speed=150.0, speed_gain_error=0.05, keep_traces=True)
        kw = dict(omega0=150.0, gain=0.05)
        v_max = 70.0
    else:
        law = tc_law(M, 800, 800, Ts)
        sc = Scenario(kind="constant_acceleration", duration=3e-3, iq_ref=10.0,
                      id_ref=-2.0, initial_speed=100.0, acceleration=5000.0,
                      speed_offset=-23.0, keep_traces=True)
        kw = dict(omega0=100.0, imposed_acc=5000.0, offset=-23.0, id_ref=-2.0)
        v_max = 1e9
    drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=1, v_max=v_max)
    res = simulate(law, M, sc, drive)
    rows, mse_t, mse_id = reference(M, law, Ts, 1, v_max, sc.duration, 1e-6,
                                    sc.iq_ref, **kw)
    ours = np.column_stack([res.t, res.id, res.iq, res.vd, res.vq, res.speed])
    assert ours.shape == rows.shape
    assert _close(ours, rows)
    assert abs(res.metrics["mse_torque"] - mse_t) <= 1e-9 * mse_t
    assert abs(res.metrics["mse_id"] - mse_id) <= 1e-9 * max(mse_id, 1e-12)
    if case == "tci_free_saturating":
        assert res.metrics["saturation_time"] > 0


@pytest.mark.slow
@pytest.mark.parametrize("inverter", ["svm", "fcs_mpc"])
def test_compiled_kernel_equals_interpreted_kernel(inverter, monkeypatch):
    """The switching-level paths (SVM segments, predictive choice, seeded
    sensor noise, hexagon limit) compiled by numba equal the same source run
    by the Python interpreter (``_run.py_func`` of the switching variant and
    its period loop ``_periods.py_func``) to 1e-9 relative: no numba-specific semantics
    (integer division, wrap-around, casts) leak in."""
    from toolbox.sim import _kernel
    from toolbox.sim._simulate import FcsWeights, _pack, _pack_law, _plant_array
    from dataclasses import replace

    law = replace(tci_law(M, 3750, 707100, 3750, 707100, Ts), fcs=FcsWeights(1.0, 1.0, 5.0))
    drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=1, v_limit="hexagon",
                        inverter=inverter)
    sc = Scenario(kind="unloaded_start", duration=1e-3, iq_ref=10.0, initial_speed=120.0,
                  speed_noise=3.0, current_noise=0.02, noise="gaussian", seed=7,
                  keep_traces=True)
    A, B, C, D, W, LP = _pack_law(law)
    DP, SP, SC = _pack(law, M, sc, drive)
    args = (_plant_array(M), A, B, C, D, W, LP, SP, DP, SC, True)
    m1, t1 = _kernel.run(*args)
    monkeypatch.setattr(_kernel, "_periods", _kernel._periods.py_func)
    m2, t2 = _kernel._run.py_func(*args, None, None, True, None)
    assert _close(t1, t2)
    both = np.isfinite(m1)
    assert np.array_equal(both, np.isfinite(m2))
    assert np.allclose(m1[both], m2[both], rtol=1e-9, atol=0)
    assert m1[7] > 0   # commutations counted


@pytest.mark.parametrize("delta", [3.7, -0.41, 1e-3])
def test_overshoot_from_the_extreme_equals_the_largest_quotient(delta):
    """The kernel keeps the extreme y of the step's direction and divides once
    (``_kernel._overshoot``): bit for bit the largest per-step quotient
    ``max(0, (y - yf)/delta)`` it computed before (correctly rounded
    subtraction and division are monotone)."""
    from toolbox.sim import _kernel

    rng = np.random.default_rng(11)
    yf = 2.3
    for _ in range(200):
        y = yf + delta * rng.normal(0.0, 0.05, rng.integers(1, 50))
        largest = 0.0
        for v in y:  # the per-step rule of the former accumulator
            q = (v - yf) / delta
            if q > largest:
                largest = q
        ext = yf
        for v in y:
            if (v > ext) if delta > 0 else (v < ext):
                ext = v
        got = _kernel._overshoot(ext, yf, delta)
        assert got == largest and np.signbit(got) == np.signbit(largest)
