"""toolbox._lti against python-control (the independent route).

Tolerances: c2d, pade and acker repeat python-control's / scipy's arithmetic
operation by operation, so they are compared with ``==``. Frequency
responses are a modal sum (relative error ~cond(V) eps <= ~1e-10) against
SLICOT tb05ad: rtol 1e-8 of the largest entry. Interconnections reorder
floating-point sums: rtol 1e-9 on matrices, 1e-8 on responses.
"""

from __future__ import annotations

import warnings

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from toolbox import _lti as L

W = np.logspace(-1, 4, 60)


def _fresp(sys, w=W) -> np.ndarray:
    return np.asarray(ct.frequency_response(sys, w).frdata)


def _close(ours: np.ndarray, ref: np.ndarray, rtol: float = 1e-8) -> bool:
    return bool(np.max(np.abs(ours - ref)) <= rtol * max(1.0, np.max(np.abs(ref))))


def _rss(seed: int, n: int, p: int, m: int) -> ct.StateSpace:
    """A random stable system with well separated poles (seeded)."""
    rng = np.random.default_rng(seed)
    poles = -np.sort(rng.uniform(1.0, 1e3, n))
    V = rng.standard_normal((n, n)) + 3 * np.eye(n)
    A = V @ np.diag(poles) @ np.linalg.inv(V)
    return ct.ss(A, rng.standard_normal((n, m)), rng.standard_normal((p, n)),
                 rng.standard_normal((p, m)))


@st.composite
def systems(draw, max_n: int = 5):
    seed = draw(st.integers(0, 2**31 - 1))
    n = draw(st.integers(1, max_n))
    p, m = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    return _rss(seed, n, p, m)


def test_shapes_are_validated():
    with pytest.raises(ValueError):
        L.StateSpace(np.zeros((2, 3)), np.zeros((2, 1)), np.zeros((1, 2)), np.zeros((1, 1)))
    with pytest.raises(ValueError):
        L.StateSpace(np.eye(2), np.zeros((3, 1)), np.zeros((1, 2)), np.zeros((1, 1)))
    with pytest.raises(ValueError):
        L.StateSpace(np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)), np.zeros((2, 1)))
    with pytest.raises(ValueError):
        L.StateSpace(np.eye(1), np.ones((1, 1)), np.ones((1, 1)), np.zeros((1, 1)), dt=0.0)
    g = L.StateSpace([], [], [], [[2.0]])
    assert (g.nstates, g.ninputs, g.noutputs) == (0, 1, 1)
    with pytest.raises(ValueError):
        g.A[...] = 1.0           # frozen: the arrays are read-only too


@settings(max_examples=30, deadline=None)
@given(systems())
def test_freqresp_matches_control(sys):
    g = L.as_statespace(sys)
    assert (g.nstates, g.ninputs, g.noutputs) == (sys.nstates, sys.ninputs, sys.noutputs)
    assert _close(g.freqresp(W), _fresp(sys))
    sd = ct.sample_system(sys, 1e-4, method="zoh")
    assert _close(L.as_statespace(sd).freqresp(W), _fresp(sd))
    assert np.allclose(np.sort_complex(g.poles()), np.sort_complex(sys.poles()), rtol=1e-9)


def test_freqresp_defective_a_takes_the_lu_route():
    """A Jordan block (integrator chain): eigenvectors singular, LU solves."""
    sys = ct.ss([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]])
    g = L.as_statespace(sys)
    assert np.allclose(g.freqresp(W)[0, 0], -1.0 / W**2, rtol=1e-12)
    assert _close(g.freqresp(W), _fresp(sys), 1e-12)


@pytest.mark.parametrize("method", ["zoh", "foh", "tustin", "euler", "backward_diff"])
@settings(max_examples=10, deadline=None)
@given(sys=systems())
def test_c2d_equals_sample_system_bitwise(method, sys):
    ref = ct.sample_system(sys, 1e-4, method=method)
    ours = L.c2d(L.as_statespace(sys), 1e-4, method)
    assert ours.dt == ref.dt
    for k in "ABCD":
        assert np.array_equal(getattr(ours, k), np.asarray(getattr(ref, k))), k


def test_c2d_refuses_discrete_and_unknown_methods():
    g = L.as_statespace(_rss(1, 2, 1, 1))
    with pytest.raises(ValueError):
        L.c2d(L.c2d(g, 1e-3), 1e-3)
    with pytest.raises(ValueError):
        L.c2d(g, 1e-3, "matched")


@pytest.mark.parametrize("n", range(0, 7))
def test_pade_equals_control(n):
    num, den = ct.pade(2.5e-4, n)
    ours = L.pade(2.5e-4, n)
    assert np.array_equal(ours[0], num) and np.array_equal(ours[1], den)


def test_acker_equals_control_and_places_the_poles():
    rng = np.random.default_rng(3)
    A, B = rng.standard_normal((4, 4)), rng.standard_normal((4, 1))
    poles = [-1.0, -2.0 + 1.0j, -2.0 - 1.0j, -5.0]
    K = L.acker(A, B, poles)
    assert K.shape == (1, 4)
    assert np.array_equal(K.ravel(), np.asarray(ct.acker(A, B, poles)).ravel())
    assert np.allclose(np.sort_complex(np.linalg.eigvals(A - B @ K)), np.sort_complex(poles))
    with pytest.raises(ValueError):
        L.acker(np.eye(2), np.array([[1.0], [1.0]]), [-1.0, -2.0])


@settings(max_examples=25, deadline=None)
@given(systems(), systems())
def test_interconnections_match_control(s1, s2):
    g1, g2 = L.as_statespace(s1), L.as_statespace(s2)
    if s1.ninputs == s2.noutputs:
        assert _close((g1 * g2).freqresp(W), _fresp(s1 * s2))
        assert _close(L.series(g2, g1).freqresp(W), _fresp(s1 * s2))
    if (s1.ninputs, s1.noutputs) == (s2.ninputs, s2.noutputs):
        assert _close((g1 + g2).freqresp(W), _fresp(s1 + s2))
        assert _close((g1 - g2).freqresp(W), _fresp(s1 - s2))
    if (s1.ninputs, s1.noutputs) == (s2.noutputs, s2.ninputs):
        for sign in (-1, 1):
            try:
                ref = ct.feedback(s1, s2, sign=sign)
            except (ValueError, np.linalg.LinAlgError):
                continue              # algebraic loop singular: both refuse
            ours = L.feedback(g1, g2, sign=sign)
            assert _close(ours.freqresp(W), _fresp(ref), 1e-6)
            for k in "ABCD":
                assert np.allclose(getattr(ours, k), np.asarray(getattr(ref, k)),
                                   rtol=1e-9, atol=1e-9 * max(1.0, np.abs(getattr(ref, k)).max()))
    assert _close((-g1).freqresp(W), _fresp(-s1))
    assert _close(L.append(g1, g2).freqresp(W), _fresp(ct.append(s1, s2)))


def test_scalar_operands_and_static_feedback():
    sys = _rss(5, 3, 2, 2)
    g = L.as_statespace(sys)
    assert _close((2.0 * g).freqresp(W), _fresp(2.0 * sys))
    assert _close((g * 2.0).freqresp(W), _fresp(sys * 2.0))
    assert _close(g.feedback(1.0).freqresp(W), _fresp(ct.feedback(sys, np.eye(2))))
    assert _close(L.feedback(g, np.eye(2), sign=1).freqresp(W),
                  _fresp(ct.feedback(sys, np.eye(2), sign=1)))
    assert _close(g[1, 0].freqresp(W), _fresp(sys[1, 0]))


def test_discrete_connections_keep_dt_and_refuse_mixed():
    gd = L.c2d(L.as_statespace(_rss(2, 2, 1, 1)), 1e-4)
    assert (gd * 3.0).dt == 1e-4 and L.feedback(gd, 1.0).dt == 1e-4
    with pytest.raises(ValueError):
        _ = gd * L.as_statespace(_rss(3, 1, 1, 1))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=1, max_size=4).filter(lambda v: v[0] != 0.0),
       st.lists(st.floats(0.1, 10), min_size=4, max_size=4))
def test_tf2ss_and_ss2tf_match_control(num, den_roots):
    den = np.poly(-np.asarray(den_roots))
    ref = ct.tf(num, den)
    g = L.as_statespace(ref)
    assert _close(g.freqresp(W), _fresp(ref))
    n2, d2 = L.ss2tf(g)
    assert np.allclose(d2, den, rtol=1e-9)
    nref = np.concatenate([np.zeros(len(den) - len(num)), num])
    assert np.allclose(n2, nref, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(nref).max()))


def test_ss2tf_equals_control_on_a_minimal_system():
    sys = _rss(7, 4, 1, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = ct.ss2tf(sys)
    num, den = L.ss2tf(L.as_statespace(sys))
    assert np.allclose(den, np.asarray(ref.den[0][0]).ravel(), rtol=1e-9)
    rn = np.asarray(ref.num[0][0]).ravel()
    assert np.allclose(num[-rn.size:], rn, rtol=1e-8, atol=1e-8 * np.abs(rn).max())


def test_mimo_transfer_function_and_improper_refused():
    s = ct.tf("s")
    G = ct.tf([[[1.0], [2.0, 1.0]], [[1.0, 0.0], [3.0]]],
              [[[1.0, 1.0], [1.0, 5.0]], [[1.0, 2.0, 2.0], [1.0, 10.0]]])
    assert _close(L.as_statespace(G).freqresp(W), _fresp(G))
    with pytest.raises(ValueError):
        L.as_statespace(s * s / (s + 1))


def test_as_statespace_reads_duck_types_and_round_trips_through_control():
    sys = _rss(11, 3, 1, 2)
    g = L.as_statespace(sys)
    assert L.as_statespace(g) is g
    back = g.to_control()
    assert isinstance(back, ct.StateSpace) and _close(_fresp(back), _fresp(sys), 1e-15)
    gd = L.c2d(g, 1e-3, "tustin")
    assert gd.to_control().dt == 1e-3 and L.as_statespace(gd.to_control()).dt == 1e-3
    assert L.as_statespace(2.5).D.tolist() == [[2.5]]
    assert L.as_statespace(np.eye(2)).D.shape == (2, 2)
    with pytest.raises(TypeError):
        L.as_statespace("s")
    assert np.allclose(g.dcgain(), ct.dcgain(sys), rtol=1e-10)
