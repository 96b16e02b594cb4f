"""toolbox.lti against independent routes (python-control, scipy, slycot,
closed forms).

Every comparison is within a named tolerance of ``tests/tolerances.py``
(justified there): frequency responses ``FRESP_RTOL`` (modal sum against
SLICOT tb05ad), interconnections ``INTERCONNECT_RTOL``, discretisation
``C2D_RTOL``, norms ``LINF_RTOL`` / ``H2_RTOL``. No test asserts identical
bits between two routes.
"""

from __future__ import annotations

import warnings

import control as ct
import numpy as np
import pytest
import scipy.linalg.lapack
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.tolerances import (C2D_RTOL, EIG_RTOL, FRESP_RTOL, FRESP_SOLVE_RTOL, H2_RTOL,
                              INTERCONNECT_RTOL, LINF_RTOL, PADE_RTOL, POLY_RTOL)
from toolbox import lti as L
from toolbox.lti import _linalg

W = np.logspace(-1, 4, 60)


def _fresp(sys, w=W) -> np.ndarray:
    return np.asarray(ct.frequency_response(sys, w).frdata)


def _close(ours: np.ndarray, ref: np.ndarray, rtol: float = FRESP_RTOL) -> bool:
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


@pytest.mark.parametrize("n", [1, 2, 5, 8])
def test_eig_follows_numpys_conventions(n):
    """``_eig`` (scipy's dgeev) gives numpy's ``eig``: real arrays when every
    eigenvalue is real, else complex ones with each conjugate pair's vectors
    assembled from dgeev's packed columns; the two LAPACK builds agree to
    rounding (1e-12), and ``A V = V diag(lam)``."""
    rng = np.random.default_rng(n)
    for A in (rng.standard_normal((n, n)), np.triu(rng.standard_normal((n, n)))):
        lam, V = _linalg._eig(A)
        ref_lam, ref_V = np.linalg.eig(A)
        assert lam.dtype == ref_lam.dtype and V.dtype == ref_V.dtype and V.flags.c_contiguous
        assert np.allclose(lam, ref_lam, rtol=EIG_RTOL, atol=EIG_RTOL * np.abs(ref_lam).max())
        assert np.allclose(V, ref_V, rtol=EIG_RTOL, atol=EIG_RTOL)
        assert np.allclose(A @ V, V * lam, atol=EIG_RTOL * np.abs(A).sum())


@pytest.mark.parametrize("method", ["zoh", "foh", "tustin", "euler", "backward_diff"])
@settings(max_examples=10, deadline=None)
@given(sys=systems())
def test_c2d_equals_sample_system(method, sys):
    """python-control's sample_system (scipy.signal.cont2discrete) as the
    independent route: the same formulas, rounded through other LAPACK calls
    (numpy's solve for the bilinear transforms). With ``dt ||A||`` <= ~1 for
    these draws the maps are well conditioned: agreement 1e-12 relative to
    each matrix's largest entry (a few hundred ulps)."""
    ref = ct.sample_system(sys, 1e-4, method=method)
    ours = L.c2d(L.as_statespace(sys), 1e-4, method)
    assert ours.dt == ref.dt
    for k in "ABCD":
        want = np.asarray(getattr(ref, k))
        scale = max(np.abs(want).max(initial=0.0), 1e-300)
        assert np.allclose(getattr(ours, k), want, rtol=0.0, atol=C2D_RTOL * scale), k


def test_c2d_refuses_discrete_and_unknown_methods():
    g = L.as_statespace(_rss(1, 2, 1, 1))
    with pytest.raises(ValueError):
        L.c2d(L.c2d(g, 1e-3), 1e-3)
    with pytest.raises(ValueError):
        L.c2d(g, 1e-3, "matched")


@pytest.mark.parametrize("n", range(0, 7))
def test_pade_equals_control(n):
    """python-control's Pade coefficients: the same recurrence of exact
    integer ratios, so agreement to rounding (rtol 1e-13)."""
    num, den = ct.pade(2.5e-4, n)
    ours = L.pade(2.5e-4, n)
    assert np.allclose(ours[0], num, rtol=PADE_RTOL, atol=0.0)
    assert np.allclose(ours[1], den, rtol=PADE_RTOL, atol=0.0)


def test_acker_equals_control_and_places_the_poles():
    rng = np.random.default_rng(3)
    A, B = rng.standard_normal((4, 4)), rng.standard_normal((4, 1))
    poles = [-1.0, -2.0 + 1.0j, -2.0 - 1.0j, -5.0]
    K = L.acker(A, B, poles)
    assert K.shape == (1, 4)
    # Ackermann's formula loses cond(ctrb) eps (~1e-12 for this draw): rtol 1e-9
    assert np.allclose(K.ravel(), np.asarray(ct.acker(A, B, poles)).ravel(), rtol=1e-9, atol=0.0)
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
                                   rtol=INTERCONNECT_RTOL,
                                   atol=INTERCONNECT_RTOL * max(1.0, np.abs(getattr(ref, k)).max()))
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
    g = L.tf2ss(num, den)
    with warnings.catch_warnings():  # python-control's own errstate: underflow on drawn
        warnings.filterwarnings("ignore", "underflow", RuntimeWarning)  # subnormal numerators
        expected = _fresp(ref)
    assert _close(g.freqresp(W), expected)
    n2, d2 = L.ss2tf(g)
    assert np.allclose(d2, den, rtol=POLY_RTOL)
    nref = np.concatenate([np.zeros(len(den) - len(num)), num])
    assert np.allclose(n2, nref, rtol=POLY_RTOL, atol=POLY_RTOL * max(1.0, np.abs(nref).max()))


def test_ss2tf_equals_control_on_a_minimal_system():
    sys = _rss(7, 4, 1, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = ct.ss2tf(sys)
    num, den = L.ss2tf(L.as_statespace(sys))
    assert np.allclose(den, np.asarray(ref.den[0][0]).ravel(), rtol=1e-9)
    rn = np.asarray(ref.num[0][0]).ravel()
    assert np.allclose(num[-rn.size:], rn, rtol=1e-8, atol=1e-8 * np.abs(rn).max())


@pytest.mark.parametrize("seed", range(20))
def test_ss2zpk_equals_scipy(seed):
    """scipy.signal.ss2zpk as the independent route (same polynomials and
    trimming rule): zeros and poles as sets within 1e-9 of their modulus
    (roots of polynomials of degree <= 5 with simple roots inside the unit
    disc: ~1e-13 for these draws) and the gain within 1e-12."""
    import scipy.signal

    rng = np.random.default_rng(seed)
    sys = _rss(seed, int(rng.integers(1, 6)), 1, 1)
    if seed % 2:                                         # strictly proper
        sys = ct.ss(sys.A, sys.B, sys.C, 0.0)
    sd = L.c2d(L.as_statespace(sys), 1e-3, "tustin" if seed % 3 else "zoh")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.signal.BadCoefficients)
        z, p, k = scipy.signal.ss2zpk(sd.A, sd.B, sd.C, sd.D)
    ours = L.ss2zpk(sd)
    for got, want in ((ours[0], z), (ours[1], p)):
        assert got.size == want.size
        assert np.allclose(np.sort_complex(got), np.sort_complex(want), rtol=1e-9, atol=1e-12)
    assert ours[2] == pytest.approx(k, rel=1e-12)


class _DuckTf:
    """A transfer function that is not python-control's (num/den lists)."""

    def __init__(self, num, den, dt=None):
        self.num, self.den, self.dt = num, den, dt


def test_mimo_transfer_function_and_improper_refused():
    num = [[[1.0], [2.0, 1.0]], [[1.0, 0.0], [3.0]]]
    den = [[[1.0, 1.0], [1.0, 5.0]], [[1.0, 2.0, 2.0], [1.0, 10.0]]]
    G = ct.tf(num, den)
    assert _close(L.as_statespace(_DuckTf(num, den)).freqresp(W), _fresp(G))
    assert _close(L.as_statespace(G).freqresp(W), _fresp(G))
    s = ct.tf("s")
    with pytest.raises(ValueError):
        L.as_statespace(_DuckTf([[[1.0, 0.0, 0.0]]], [[[1.0, 1.0]]]))
    with pytest.raises(ValueError):
        L.tf2ss([1.0, 0.0, 0.0], [1.0, 1.0])
    assert L.as_statespace(1 / (s + 1)).nstates == 1


def test_control_transfer_functions_keep_python_controls_realisation():
    """A user's python-control TF gets python-control's states (td04ad), so
    artifacts built from it are the numbers they were before toolbox.lti
    (the same state coordinates: entries within rounding, rtol 1e-14)."""
    tf = ct.tf([2.0, 30.0], [1.0, 0.0])
    ref = ct.ss(tf)
    g = L.as_statespace(tf)
    for k in "ABCD":
        assert np.allclose(getattr(g, k), np.asarray(getattr(ref, k)), rtol=1e-14, atol=0.0)


def test_minreal_removes_unreachable_and_unobservable_states():
    """A 3-state system with one unreachable and one unobservable mode added,
    in random coordinates: 3 states stay, the response is unchanged (rtol 1e-9),
    and python-control's minreal (SLICOT tb01pd) keeps as many. A minimal
    system loses nothing."""
    rng = np.random.default_rng(4)
    core = ct.ss(np.diag([-1.0, -10.0, -100.0]), rng.standard_normal((3, 1)),
                 rng.standard_normal((1, 3)), [[0.5]])
    A = scipy_block_diag(core.A, [[-7.0]], [[-11.0]])
    B = np.vstack([core.B, [[0.0]], [[1.0]]])            # mode -7 unreachable
    C = np.hstack([core.C, [[1.0]], [[0.0]]])            # mode -11 unobservable
    T = rng.standard_normal((5, 5)) + 3 * np.eye(5)
    Ti = np.linalg.inv(T)
    g = L.StateSpace(Ti @ A @ T, Ti @ B, C @ T, core.D)
    m = L.minreal(g)
    assert m.nstates == 3
    assert _close(m.freqresp(W), _fresp(core), 1e-9)
    # SLICOT's default tolerance (N^2 eps) misses the unobservable mode here; 1e-10 does not
    assert ct.minreal(g.to_control(), tol=1e-10, verbose=False).nstates == 3
    assert L.minreal(L.as_statespace(core)).nstates == 3


def scipy_block_diag(*blocks):
    import scipy.linalg

    return scipy.linalg.block_diag(*blocks)


def test_as_statespace_reads_duck_types_and_round_trips_through_control():
    sys = _rss(11, 3, 1, 2)
    g = L.as_statespace(sys)
    assert L.as_statespace(g) is g
    back = g.to_control()
    assert isinstance(back, ct.StateSpace) and _close(_fresp(back), _fresp(sys), 1e-15)
    gd = L.c2d(g, 1e-3, "tustin")
    assert gd.to_control().dt == 1e-3 and L.as_statespace(gd.to_control()).dt == 1e-3
    assert sys.__class__ is ct.StateSpace
    assert np.allclose(g(1j * 10.0), sys(1j * 10.0)) and g(1j * np.ones(3)).shape == (1, 2, 3)
    assert L.as_statespace(2.5).D.tolist() == [[2.5]]
    assert L.as_statespace(np.eye(2)).D.shape == (2, 2)
    with pytest.raises(TypeError):
        L.as_statespace("s")
    assert np.allclose(g.dcgain(), ct.dcgain(sys), rtol=1e-10)


# -- SISO transfer functions (weights) and the L-infinity norm -----------------
_S = ct.tf("s")
#: paper 003's weights eq (44)-(46) and plant eq (34)
_W1 = (1 / 1.51) * (_S + 177.3493) / (_S + 0.0117)
_W3 = 1e4 * (_S + 135.68) / (_S + 2.7135e6)
_G = 1 / (0.6 + 2.8e-3 * _S)


def _tf(sys) -> L.TransferFunction:
    return L.TransferFunction.from_system(sys)


def test_transfer_function_algebra_matches_control():
    """Products, sums, negation, inverse and responses of our SISO transfer
    functions equal python-control's (same polynomial arithmetic: rtol 1e-12
    on the responses, evaluated by Horner's rule on both sides)."""
    s = 1j * np.logspace(-3, 8, 80)
    for ours, ref in ((_tf(_W1) * _tf(_W3), _W1 * _W3), (_tf(_W1) + 2.0 * _tf(_G), _W1 + 2 * _G),
                      (-_tf(_W3), -_W3), (_tf(_W1) - _tf(_G), _W1 - _G),
                      (_tf(_W3).inverse(), 1 / _W3)):
        assert np.allclose(ours(s), ref(s), rtol=1e-12, atol=0)
        assert np.allclose(ours.freqresp(np.abs(s))[0, 0], ref(s), rtol=1e-12, atol=0)
    assert _tf(_W3).hf_gain() == pytest.approx(1e4) and _tf(_G).hf_gain() == 0.0
    assert np.allclose(sorted(_tf(_W1).poles().real), [-0.0117])
    assert _tf(3.0).num.tolist() == [3.0] and _tf(3.0).den.tolist() == [1.0]
    with pytest.raises(ValueError, match="zero denominator"):
        L.TransferFunction([1.0], [0.0, 0.0])


def test_transfer_function_reads_state_space_and_realises_it():
    """From a state-space system (ss2tf) and back (tf2ss): same response; our
    systems and python-control's are read alike; as_statespace realises ours."""
    g = _rss(3, 3, 1, 1)
    tf = _tf(g)
    assert _close(tf.freqresp(W), _fresp(g))
    assert _close(L.as_statespace(tf).freqresp(W), _fresp(g))
    assert _close(_tf(L.as_statespace(g)).freqresp(W), _fresp(g))
    with pytest.raises(ValueError, match="SISO"):
        _tf(ct.tf([[[1.0], [1.0]]], [[[1.0, 1.0], [1.0, 2.0]]]))


def test_transfer_function_minreal_cancels_like_control():
    """Common roots cancel (python-control's rule), nothing else changes."""
    tf = L.TransferFunction(np.polymul([1.0, 1.0], [1.0, 5.0]),
                            np.polymul([1.0, 1.0], [1.0, 2.0, 10.0]))
    red = tf.minreal()
    ref = ct.minreal(ct.tf(tf.num, tf.den), verbose=False)
    assert red.order == 2
    s = 1j * np.logspace(-2, 3, 40)
    assert np.allclose(red(s), ref(s), rtol=1e-12, atol=0)
    w1 = _tf(_W1)
    assert w1.minreal() is w1


def _grid_peak(g) -> float:
    """Largest singular value on a grid (a lower bound of the norm): 4001
    points over 1e-3 .. 1e5 rad/s (0.46 % apart, ten points across the
    lightly damped case's resonance), then 2001 points between the
    neighbours of each of the five largest local maxima (as dense as 1.1e6
    log-spaced points there)."""
    ss = L.as_statespace(g)

    def sigma(w):
        G = ss.freqresp(w)
        return np.linalg.svd(np.moveaxis(G, -1, 0), compute_uv=False)[:, 0]

    w = np.logspace(-3, 5, 4001)
    s = sigma(w)
    peaks = [k for k in range(len(w)) if s[k] >= s[max(k - 1, 0)] and s[k] >= s[min(k + 1, len(w) - 1)]]
    best = float(s.max())
    for k in sorted(peaks, key=lambda k: -s[k])[:5]:
        fine = np.linspace(w[max(k - 1, 0)], w[min(k + 1, len(w) - 1)], 2001)
        best = max(best, float(sigma(fine).max()))
    return best


def _below_level(g, level: float) -> bool:
    """Bounded real lemma (Zhou, Doyle & Glover, Corollary 4.4), an upper-bound
    test independent of SLICOT: for a stable system, ``||G||_inf < level`` iff
    ``sigma_max(D) < level`` and the Hamiltonian of that level has no
    eigenvalue on the imaginary axis (scipy's eigvals)."""
    A, B, C, D = (np.asarray(m, float) for m in (g.A, g.B, g.C, g.D))
    if np.linalg.norm(D, 2) >= level:
        return False
    R = level ** 2 * np.eye(D.shape[1]) - D.T @ D
    F = A + B @ np.linalg.solve(R, D.T @ C)
    H = np.block([[F, B @ np.linalg.solve(R, B.T)],
                  [-C.T @ (np.eye(D.shape[0]) + D @ np.linalg.solve(R, D.T)) @ C, -F.T]])
    ev = scipy.linalg.eigvals(H)
    return not np.any(np.abs(ev.real) <= 1e-8 * max(1.0, np.abs(ev).max()))


_LIGHTLY_DAMPED = ct.ss(ct.tf([1.0], [1.0, 0.02, 1.0]) * ct.tf([1.0, 3.0], [1.0, 30.0]))


@pytest.mark.parametrize("seed", range(4))
def test_linf_norm_between_a_dense_grid_and_the_bounded_real_lemma(seed):
    """SLICOT ab13dd (slycot) against independent bounds: at least the dense
    grid's peak and the Hamiltonian of 1 + 1e-5 times it has no imaginary
    eigenvalue; the frequency it reports attains it (rtol 1e-12). Seed 3 peaks
    1.8e-6 above sigma_max(D) (3.0374850548 at 2235.7 rad/s, D's 3.0374796533):
    there ab13dd stops 1.8e-6 below the peak, hence the grid's rtol 2e-6 (the
    earlier own Bruinsma-Steinbuch code found that peak; nothing the toolbox
    reports shows six digits)."""
    for g in (_rss(seed, 4, 2, 2), _LIGHTLY_DAMPED):
        A, B, C, D = (np.asarray(m, float) for m in (g.A, g.B, g.C, g.D))
        norm, w = L.linf_peak(A, B, C, D)
        assert norm == L.linf_norm(g)
        assert norm >= _grid_peak(g) * (1 - 2e-6)
        assert _below_level(g, norm * (1 + 1e-5))
        at = (np.linalg.norm(D, 2) if w == np.inf
              else np.linalg.svd(L.as_statespace(g).freqresp([w])[..., 0], compute_uv=False)[0])
        assert at == pytest.approx(norm, rel=1e-12)
    assert L.linf_norm(L.static_gain([[3.0, 4.0]])) == pytest.approx(5.0)
    assert L.linf_norm(ct.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]])) == np.inf


def test_linf_norm_of_an_unstable_system_is_on_the_axis():
    """1/(s - 1): the L-infinity norm on the imaginary axis, 1 at w = 0."""
    assert L.linf_norm(ct.ss([[1.0]], [[1.0]], [[1.0]], [[0.0]])) == pytest.approx(1.0, rel=1e-12)


def test_linf_norm_of_a_row_with_feedthrough():
    """A 1x2 system (a random draw) whose peak near 9 rad/s is 2.7 % above
    ``sigma_max(D)`` = 1.8627 (an earlier Hamiltonian lost it): at least the
    grid's peak, and certified by the bounded real lemma at 1 + 1e-9 times it."""
    g = ct.ss([[-8.9868423206264, -19.748330199988004],
               [3.0040925256469078, 3.8882347652660263]],
              [[-0.07311340574430161, -0.9605053229682254],
               [-0.8637866905636434, 0.6554044331864343]],
              [[0.0, 1.779155158669343]], [[1.8288497262824905, -0.3534918238247577]])
    ours = L.linf_norm(g)
    assert ours >= _grid_peak(g) * (1 - 1e-12)
    assert _below_level(g, ours * (1 + 1e-9))
    assert ours == pytest.approx(1.9137959740, rel=LINF_RTOL)


def test_zeros_refuse_a_system_with_two_inputs():
    """The invariant zeros are those of a SISO system (the balancing scales one
    input and one output): two inputs get a clear error, not a broadcast one."""
    A, B, C, D = -np.eye(2), np.ones((2, 2)), np.ones((1, 2)), np.zeros((1, 2))
    with pytest.raises(ValueError, match="a SISO system expected, got 1 outputs and 2 inputs"):
        L.invariant_zeros(A, B, C, D)


def test_pencil_eigval_list_is_numpys_quotient():
    """The finite generalised eigenvalues in Python numbers are numpy's
    ``alpha / beta`` (a product by ``1 / beta``: within 2 ulps); the
    infinite ones are dropped."""
    rng = np.random.default_rng(3)
    M = rng.standard_normal((7, 7))
    E = _linalg._leading_identity(7, 7, 5)
    ar, ai, beta, *_ = scipy.linalg.lapack.dggev(M, E, compute_vl=0, compute_vr=0)
    alpha = ar + 1j * ai
    fin = np.abs(beta) > 1e-13 * np.abs(alpha)
    assert np.count_nonzero(fin) == 5
    assert np.allclose(np.array(L.pencil_eigvals(M, E)), alpha[fin] / beta[fin],
                       rtol=5e-16, atol=0.0)


@settings(max_examples=20, deadline=None)
@given(systems())
def test_evaluate_modal_sum_and_lu_solves_agree(sys):
    """The two evaluations of :func:`toolbox.lti.evaluate` (modal sum, per-point
    LU solves) give the same response within ``FRESP_RTOL``, the LU one agrees
    with python-control's tb05ad within ``FRESP_SOLVE_RTOL`` (both solve the same
    linear systems), and the method and the function are one route."""
    g = L.as_statespace(sys)
    x = 1j * W
    modal = L.evaluate(g.A, g.B, g.C, g.D, x)
    lu = L.evaluate(g.A, g.B, g.C, g.D, x, solve=True)
    assert _close(modal, lu)
    assert _close(lu, _fresp(sys), FRESP_SOLVE_RTOL * 1e3)
    assert _close(g.evaluate(x), modal, FRESP_SOLVE_RTOL)
    assert _close(g.evaluate(x, solve=True), lu, FRESP_SOLVE_RTOL)


def test_h2_norm_against_slycot_and_a_closed_form():
    """``||1/(s + a)||_2 = 1/sqrt(2a)`` (closed form); random stable systems
    against SLICOT ab13bd (slycot, an independent Lyapunov solver), within
    ``H2_RTOL``; a feedthrough or an unstable pole gives inf."""
    from slycot import ab13bd

    assert L.h2_norm(ct.ss([[-4.0]], [[1.0]], [[1.0]], [[0.0]])) == pytest.approx(
        1.0 / np.sqrt(8.0), rel=H2_RTOL)
    for seed in range(5):
        g = _rss(seed, 4, 2, 3)
        A, B, C = (np.array(np.asarray(m, float), order="F") for m in (g.A, g.B, g.C))
        D = np.zeros((2, 3), order="F")
        ref = ab13bd("C", "H", 4, 3, 2, A, B, C, D)
        assert L.h2_norm(ct.ss(g.A, g.B, g.C, D)) == pytest.approx(ref, rel=H2_RTOL)
    assert L.h2_norm(ct.ss([[-1.0]], [[1.0]], [[1.0]], [[1.0]])) == np.inf
    assert L.h2_norm(ct.ss([[1.0]], [[1.0]], [[1.0]], [[0.0]])) == np.inf


@pytest.mark.parametrize("seed", range(4))
def test_balanced_truncation_against_slycot_ab09ad(seed):
    """Square-root balanced truncation against SLICOT ab09ad (slycot, its own
    Lyapunov solver and square-root method): the Hankel singular values within
    ``EIG_RTOL`` of the largest one, and the reduced responses within 1e-8 of
    the response's peak (two bases of the same truncated balanced system,
    differing by the conditioning of the kept singular values, >= 1e-3 here)."""
    from slycot import ab09ad

    g = _rss(seed, 6, 1, 1)
    A, B, C, D = (np.array(np.asarray(m, float), order="F") for m in (g.A, g.B, g.C, g.D))
    Kr, hsv, bound = L.balanced_truncation(g, 3)
    nr, Ar, Br, Cr, ref_hsv = ab09ad("C", "B", "N", 6, 1, 1, A.copy(order="F"),
                                     B.copy(order="F"), C.copy(order="F"), nr=3)
    assert nr == 3 and Kr.nstates == 3
    assert np.allclose(hsv, ref_hsv, rtol=0.0, atol=EIG_RTOL * ref_hsv[0] * 1e2)
    assert bound == pytest.approx(2 * ref_hsv[3:].sum(), rel=1e-9)
    ref = L.StateSpace(Ar, Br, Cr, D)
    assert _close(Kr.freqresp(W), ref.freqresp(W), 1e-8)


def test_balanced_series_is_the_loop_of_python_control():
    """The loop K then G that the exact margins start from (series in balanced
    coordinates) has python-control's ``G * K`` response within
    ``FRESP_RTOL`` (a similarity transform and another evaluation)."""
    from toolbox.lti import _margins

    s = ct.tf("s")
    G = ct.tf([1.0], [2.8e-3, 0.6])
    K = 49.7 * (s + 214.3) * (s + 5e4) / (s * (s**2 + 4814 * s + 6.17e6))
    A, B, C, d = _margins._balanced_series(_margins._siso(K), _margins._siso(G))
    w = np.logspace(-1, 7, 200)
    ours = L.StateSpace(A, B, C, [[d]]).freqresp(w)[0, 0]
    ref = np.asarray(ct.frequency_response(G * K, w).complex).ravel()
    assert np.allclose(ours, ref, rtol=FRESP_RTOL, atol=0.0)


def test_loop_margins_against_python_control():
    """Exact margins of a continuous loop against python-control's
    ``stability_margins`` (a grid refined by root finding): GM and PM within
    1e-6 relative (python-control's own refinement), M_m within 1e-6; a
    discrete or MIMO system is refused."""
    s = ct.tf("s")
    G = 1 / (2.8e-3 * s + 0.6) * ct.tf([1.0], [1e-4, 1.0])
    K = 3.0 * (s + 200) / s
    m = L.loop_margins(G, K)
    gm, pm, sm, wpc, wgc, wms = ct.stability_margins(G * K)
    assert m.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert m.gain_crossover_rad_s == pytest.approx(wgc, rel=1e-6)
    assert 10 ** (m.gain_margin_db / 20) == pytest.approx(gm, rel=1e-6)
    assert m.stability_margin == pytest.approx(sm, rel=1e-6)
    assert m.static_error == 0.0
    with pytest.raises(ValueError, match="continuous SISO"):
        L.loop_margins(L.c2d(L.as_statespace(G), 1e-4), K)
