"""Unit tests for toolbox.design._reduction (controller order reduction)."""

import numpy as np
import pytest
import control as ct

from tests.tolerances import REORDERED_RTOL
from toolbox import lti
from toolbox.design import _reduction as R

s = ct.tf("s")


def ctl(sys):
    """python-control's view of a system (ours are toolbox.lti.StateSpace)."""
    return sys.to_control() if hasattr(sys, "to_control") else sys


def fr(sys, w):
    return np.asarray(ct.frequency_response(ct.ss(ctl(sys)), w).complex).ravel()


def hinf_err(a, b, w=np.logspace(-3, 7, 3000)):
    return float(np.max(np.abs(fr(a, w) - fr(b, w))))


def test_remove_cancellations_keeps_dc_or_hf():
    K = 10 * (s + 1000) / (s + 1001) / (s + 5)
    Kdc, acts = R.remove_cancellations(K, tol=1e-2, keep="dc")
    assert Kdc.nstates == 1 and len(acts) == 1
    assert ct.dcgain(ctl(Kdc)) == pytest.approx(ct.dcgain(K), rel=1e-12)
    Khf, _ = R.remove_cancellations(K, tol=1e-2, keep="hf")
    assert abs(complex(ctl(Khf)(1e6j))) == pytest.approx(abs(complex(K(1e6j))), rel=1e-3)
    K2, acts2 = R.remove_cancellations(K, tol=1e-4)
    assert K2.nstates == 2 and not acts2


def test_replace_integrators_eq71_style():
    K = 49.7 * (s + 214.3) / ((s + 0.0117) * (s + 3000))
    Kr, acts = R.replace_integrators(K, tol=0.1)
    p = np.sort(np.abs(Kr.poles()))
    assert p[0] == 0.0 and p[1] == pytest.approx(3000.0)
    # leading gain unchanged: identical above the old pole
    assert abs(complex(ctl(Kr)(100j))) == pytest.approx(abs(complex(K(100j))), rel=1e-5)
    assert acts


def test_stable_split_adds_up():
    K = (s + 3) / (s * (s + 1) * (s + 50))
    Ks, Ku = lti.stable_split(K)
    assert Ks.nstates == 2 and Ku.nstates == 1
    w = np.logspace(-2, 3, 50)
    assert np.allclose(fr(Ks, w) + fr(Ku, w), fr(K, w), rtol=1e-9)


def test_balanced_truncation_bound_and_hsv():
    np.random.seed(0)  # control.rss draws from numpy's global generator: a fixed system
    sys = ct.rss(8, 1, 1)
    while np.any(sys.poles().real > -1e-3):
        sys = ct.rss(8, 1, 1)
    Kr, hsv, bound = lti.balanced_truncation(sys, 3)
    assert Kr.nstates == 3
    assert np.all(np.diff(hsv) <= 1e-12 * hsv[0])
    assert bound == pytest.approx(2 * hsv[3:].sum())
    # the 2 * sum bound holds (grid estimate of the norm, 1 % slack for the grid)
    assert hinf_err(sys, Kr, np.logspace(-4, 4, 4000)) <= 1.01 * bound + 1e-12


def test_residualise_keeps_dc():
    K = 5 * (s + 10) / ((s + 1) * (s + 1e5))
    Kr, acts = lti.residualise(K, fast=1e4)
    assert Kr.nstates == 1 and acts
    assert ct.dcgain(ctl(Kr)) == pytest.approx(ct.dcgain(K), rel=1e-9)


def test_reduce_controller_balanced_target_order_keeps_integrator():
    K = 100 * (s + 200) / (s * (s + 2000) * (s + 3e5))
    res = R.reduce_controller(K, order=2, cancel_tol=None)
    assert res.order_before == 3 and res.order_after == 2
    assert np.min(np.abs(res.K.poles())) < 1e-9          # integrator kept aside
    assert res.error_bound is not None and res.hankel_sv is not None


def test_compare_margins_flags_a_bad_reduction():
    G = 1 / (0.6 + 2.8e-3 * s)
    K = 50 * (s + 214.3) / (s * (s + 3000))
    ok = R.compare_margins(G, K, K)
    assert ok.ok
    bad = R.compare_margins(G, K, 50 * (s + 214.3) / (s * (s + 300)))
    assert not bad.ok and any("phase margin" in f for f in bad.flags)


def test_compare_margins_flags_a_destabilising_reduction():
    """The stability test reads the poles of S that the norm giving M_m
    computed: python-control's closed loop of G Kr has a pole at +1 rad/s
    (L = -2/(s + 1)), the full loop (K = 1) none in the right half-plane."""
    G, K, Kr = 1 / (s + 1), 1 / (1 + s / 1e3), -2 / (1 + s / 1e3)
    assert np.all(ct.poles(ct.feedback(G * K)).real < 0)
    assert np.max(ct.poles(ct.feedback(G * Kr)).real) == pytest.approx(1.0, rel=1e-2)
    res = R.compare_margins(G, K, Kr)
    assert "the reduced controller destabilises the loop" in res.flags
    assert "the reduced controller destabilises the loop" not in R.compare_margins(G, K, K).flags


def test_loop_margins_static_error():
    G = 1 / (s + 1)
    m = R.loop_margins(G, 9.0)
    assert m.static_error == pytest.approx(0.1)
    assert R.loop_margins(G, 9.0 / s).static_error == 0.0


@pytest.mark.parametrize("K", [50 * (s + 214.3) / (s * (s + 3000)),
                               50 * (s + 214.3) / (s * (s + 300)),
                               49.7 * (s + 5e4) * (s + 214.3) / ((s + 0.0117) * (s * s + 4793 * s + 6.104e6)),
                               2e3 * (s + 10) / ((s + 1) * (s + 40) * (s + 500))])
def test_loop_margins_match_the_grid_route_and_python_control(K):
    """The exact crossings and ab13dd's M_m give the numbers of the toolbox's grid
    route (lti_loop_margins: 20000 points, refined crossings and peak) to 1e-7
    (both are converged: Brent to 1e-13, ab13dd to 1e-10) and python-control's
    stability_margins to 1e-5 (its polynomial route loses digits)."""
    from toolbox.analysis import lti_loop_margins

    G = 1 / (0.6 + 2.8e-3 * s)
    m = R.loop_margins(G, K)
    L = ct.ss(G) * ct.ss(K)
    g = lti_loop_margins(L)
    gm, pm, sm, wpc, wgc, _ = ct.stability_margins(L)
    for ours, grid, theirs in ((m.gain_margin_db, g.gain_margin_db, 20 * np.log10(gm)),
                               (m.phase_crossover_rad_s, g.phase_crossover_rad_s, wpc),
                               (m.phase_margin_deg, g.phase_margin_deg, pm),
                               (m.gain_crossover_rad_s, g.gain_crossover_rad_s, wgc),
                               (m.stability_margin, g.stability_margin, sm)):
        if np.isnan(grid) or np.isinf(grid):
            assert (np.isnan(ours) and np.isnan(grid)) or ours == grid
            continue
        assert ours == pytest.approx(grid, rel=1e-7)
        assert ours == pytest.approx(theirs, rel=1e-5)


@pytest.mark.parametrize("dG", [0.3, 0.9])
def test_loop_margins_with_feedthrough_match_the_grid_route(dG):
    """A biproper loop (L(inf) = d = dG, with |d| far from and near 1, where
    ``L(s) L(-s) - 1`` loses its feedthrough d^2 - 1): the crossings of the
    QZ pencils give the grid route's numbers to 1e-7, as for the strictly
    proper loops above."""
    from toolbox.analysis import lti_loop_margins

    G = dG * (s + 100) / (s + 1)            # K(inf) = 1 (lag and an all-pass): d = dG
    K = (s + 200) / (s + 2) * (s * s / 4e6 - s / 1e3 + 1) / (s * s / 4e6 + s / 1e3 + 1)
    m = R.loop_margins(G, K)
    g = lti_loop_margins(ct.ss(G) * ct.ss(K))
    for ours, grid in ((m.gain_margin_db, g.gain_margin_db),
                       (m.phase_crossover_rad_s, g.phase_crossover_rad_s),
                       (m.phase_margin_deg, g.phase_margin_deg),
                       (m.gain_crossover_rad_s, g.gain_crossover_rad_s),
                       (m.stability_margin, g.stability_margin)):
        assert np.isfinite(ours) and ours == pytest.approx(grid, rel=1e-7)


def _random_roots(rng, n):
    """Real roots and conjugate pairs within 1e-3..1e7 rad/s, shuffled."""
    r = []
    while len(r) < n:
        if rng.random() < 0.5 or len(r) == n - 1:
            r.append(complex(-10 ** rng.uniform(-3, 7), 0.0))
        else:
            x = complex(-10 ** rng.uniform(-3, 7), 10 ** rng.uniform(-3, 7))
            r += [x, x.conjugate()]
    rng.shuffle(r)
    return r


def test_poly_from_roots_is_as_accurate_as_np_poly():
    """Real linear and quadratic factors: coefficients within 2e-15 (relative)
    of a 60-digit product (measured worst over 3000 sets: 5e-16; np.poly's
    complex products reach 4e-13), and np.poly's up to rounding."""
    mpmath = pytest.importorskip("mpmath")
    mpmath.mp.dps = 60
    rng = np.random.default_rng(11)
    for _ in range(200):
        r = _random_roots(rng, int(rng.integers(1, 7)))
        exact = [mpmath.mpc(1)]
        for x in r:
            x = mpmath.mpc(x.real, x.imag)
            exact = [exact[0]] + [u - x * v for u, v in zip(exact[1:], exact)] + [-x * exact[-1]]
        ours = R._poly_from_roots(r)
        assert all(abs((mpmath.mpf(u) - v.real) / v.real) <= 2e-15 for u, v in zip(ours, exact))
        assert np.allclose(ours, np.poly(r).real, rtol=1e-12, atol=0.0)


def test_poly_from_roots_refuses_an_unpaired_complex_root():
    with pytest.raises(ValueError, match="not closed under conjugation"):
        R._poly_from_roots([-1.0 + 2.0j, -3.0 + 0.0j])
    with pytest.raises(ValueError, match="not closed under conjugation"):
        R._poly_from_roots([-1.0 + 2.0j, -1.0 - 2.1j])


def test_poly_from_roots_pairs_conjugates_that_differ_in_the_last_bits():
    """Zeros from a QZ pencil (the reduced H-infinity controller's, which the
    saturation tests execute) form pairs whose members differ in the last
    bits: each pair is its real quadratic (x + y, x y), within 1e-15 of
    np.poly's real part (complex products whose imaginary parts cancel)."""
    r = [-608.4767775829737 + 306.3858412957058j, -608.4767775829738 - 306.38584129570575j,
         -62.499999999989974 + 0j]
    ours = R._poly_from_roots(r)
    assert np.allclose(ours, np.poly(r).real, rtol=1e-15, atol=0.0)
    # exact conjugates: -2 Re(x) and |x|^2, the same bits as before pairing
    x = r[0]
    assert R._poly_from_roots([x, x.conjugate()]) == [1.0, -2.0 * x.real, x.real ** 2 + x.imag ** 2]


def test_zpk_realisation_is_tf2ss_then_balanced():
    """The companion system matrix written from the coefficients is tf2ss's
    canonical form in the coordinates of toolbox.lti.balanced: the same
    matrices within ``REORDERED_RTOL`` of their largest entry (the same
    formula, products ordered differently), C-contiguous."""
    from toolbox.lti import balanced, tf2ss
    z, p, k = np.array([-214.3, -5e4]), np.array([0.0, -2407.0 + 612.8j, -2407.0 - 612.8j]), 50.2
    A, B, C, D = R._zpk_realisation(z, p, k)
    num = k * np.array(R._poly_from_roots(list(z.astype(complex))))
    ref = tf2ss(num, np.array(R._poly_from_roots(list(p))))
    for ours, want in zip((A, B, C, D), (*balanced(ref.A, ref.B, ref.C), ref.D)):
        assert ours.flags.c_contiguous and ours.shape == want.shape
        assert np.allclose(ours, want, rtol=0.0, atol=REORDERED_RTOL * np.abs(want).max())
