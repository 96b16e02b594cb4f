"""Export must not refuse a sound controller over numerical noise.

A held-out H-infinity design (paper 003's motor, first-order weights
w1 = (0.5 s + 100)/(s + 0.01), w2 = (1e-4 s + 0.05)/(1e-5 s + 1), gamma 1.2,
Ts = 200 us), built through the spec path, has integrator rows like
``[-1e-14, 1, -9e-16]``: counted as coefficients, they made the dynamic range
of a coefficient set ~1e13 and the export was refused. The export now
realises each law minimally and treats round-off as zero
(:mod:`toolbox.export._minimal`); the header must still equal the law.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import toolbox
from toolbox.export import check_exportable, write_header
from toolbox.export._minimal import EQUIV_RTOL, minimal_law
from toolbox.export.c_header import DYNAMIC_RANGE, reference_law

import export_c_helpers as C

W = {"w1": {"num": [0.5, 100], "den": [1, 0.01]},
     "w2": {"num": [1e-4, 0.05], "den": [1e-5, 1]}}
SPEC = {"title": "held-out H-infinity, first-order weights",
        "motor": {"catalog": "azaiz2007"},
        "drive": {"vdc": 150, "sample_time": 200e-6},
        "controller": {"method": "hinf", "hinf": {"gamma": 1.2, "weights": {"d": W, "q": W}}}}


@pytest.fixture(scope="module")
def held_out():
    spec = toolbox.spec_from_dict(SPEC)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        art = toolbox.design_spec(spec)
    return spec, art


def _raw_range(A: np.ndarray) -> float:
    a = np.abs(A[np.abs(A) > 0])
    return float(a.max() / a.min())


def test_held_out_design_has_roundoff(held_out):
    """Precondition, so that the next test can fail: the designed law carries
    round-off entries that span more than the 2**30 dynamic-range limit."""
    _, art = held_out
    worst = max(max(_raw_range(row) for row in art.axes[ax].law.A) for ax in "dq")
    assert worst > DYNAMIC_RANGE


def test_held_out_design_exports_and_matches(held_out, tmp_path):
    """It exports, compiles (-Werror) and the float32 header equals the double
    Python reference law (the artifact's own, uncleaned law) within the
    worst-case float32 rounding bound of tests/export/export_c_helpers.py."""
    spec, art = held_out
    chk = check_exportable(art, spec.motor, spec.drive)
    h = write_header(art, spec.motor, spec.drive)
    inp = C.test_inputs(i_step=4.0, speed=50.0)
    v_ref, s_ref = reference_law(art, inp, chk.v_max)
    assert not s_ref.any()
    v_c, _ = C.run_float(h, tmp_path, inp)
    err = np.abs(v_c - v_ref)
    bound = C.float_bound(chk, art, inp)
    print(f"\nheld-out hinf: max|err| {err.max():.3g} V, bound {bound.max():.3g} V")
    assert np.all(err <= bound)
    assert np.abs(v_ref).max() > 1.0          # the comparison is not between zeros


def _response(A, B, C_, D, z):
    n = A.shape[0]
    return np.array([(C_ @ np.linalg.solve(zk * np.eye(n) - A, B))[0] + D[0] for zk in z])


def test_minimal_law_removes_cancelled_pair_and_roundoff():
    """A PI (integrator) with an extra mode at z = 0.5 that neither input nor
    the anti-windup reaches (B, aw rows 1e-17: a cancelled pole-zero pair) and
    1e-15 round-off in the integrator row: one state is removed, the round-off
    is zeroed, and the map [i_ref, i_meas, dv] -> v is unchanged (200 points on
    the unit circle, relative 1e-9, well inside the accepted EQUIV_RTOL)."""
    ts = 1e-4
    A = np.array([[1.0, 1e-15], [0.0, 0.5]])
    B = np.array([[1e-3, -1e-3], [1e-17, -1e-17]])
    Cm = np.array([[300.0, 2.0]])
    D = np.array([[2.0, -2.0]])
    aw = np.array([0.4, 1e-17])
    m = minimal_law(A, B, Cm, D, aw, ts)
    assert m.removed_states == 1 and m.A.shape == (1, 1)
    assert m.A[0, 0] == 1.0                                   # an exact integrator
    z = np.exp(1j * np.pi * np.logspace(-4, 0, 200))
    h0 = _response(A, np.column_stack([B, aw]), Cm, np.column_stack([D, [[0]]]), z)
    h1 = _response(m.A, np.column_stack([m.B, m.aw]), m.C, np.column_stack([m.D, [[0]]]), z)
    assert np.all(np.abs(h1 - h0) <= 1e-9 * np.abs(h0)) and 1e-9 < EQUIV_RTOL


def test_minimal_law_keeps_what_matters():
    """A mode reached only through the anti-windup vector stays (it acts while
    the voltage limits), and an already clean minimal law is returned as is."""
    ts = 1e-4
    A = np.diag([1.0, 0.5])
    B = np.array([[1e-3, -1e-3], [0.0, 0.0]])
    Cm = np.array([[300.0, 2.0]])
    D = np.array([[2.0, -2.0]])
    m = minimal_law(A, B, Cm, D, np.array([0.4, 0.3]), ts)
    assert m.removed_states == 0 and m.zeroed == 0
    np.testing.assert_array_equal(m.A, A)
