"""Per-axis and coupled margins (toolbox.analysis.margins).

Independent routes: python-control ``stability_margins`` and ``disk_margins``
(continuous loops and the discrete loop built with python-control's own ZOH
``sample_system``), SLICOT ab13md (mu upper bound, through python-control),
analytic first-order step figures, and the symbolic plant
(``numeric_plant(motor).A``).
"""

import math
import warnings

import control as ct
import numpy as np
import pytest

from analysis_helpers import AZAIZ, DRIVE, pi_artifact
from toolbox.analysis import MARGIN_KEYS, compute_margins, disk_variations, mimo_disk_margins
from toolbox.analysis import margins as M
from toolbox.plant import numeric_plant

TS = 1e-4


def _pc_loop(artifact, axis, discrete):
    """L = K G built with python-control only (independent of our assembly)."""
    L_ = AZAIZ.Ld if axis == "d" else AZAIZ.Lq
    G = ct.tf([1], [L_, AZAIZ.R])
    ax = artifact.axes[axis]
    if not discrete:
        return ax.continuous.to_statespace().to_control() * ct.ss(G)
    law = ax.law.to_statespace().to_control()
    K = -law[0, 1]
    Gd = ct.sample_system(ct.ss(G), TS, method="zoh")
    z1 = ct.tf([1], [1, 0], TS)
    return ct.ss(K) * Gd * ct.ss(z1)


def _pc_margins(L):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm, pm, sm, wpc, wgc, wms = ct.stability_margins(L)
    return 20 * np.log10(gm), pm, wpc, wgc


@pytest.mark.slow
@pytest.mark.parametrize("axis", ["d", "q"])
def test_continuous_margins_match_python_control(hinf, axis):
    """GM within 0.02 dB, PM within 0.02 deg, crossover frequencies within 0.1 %
    (python-control refines crossings on the exact transfer function; our grid +
    Brent refinement converges to 1e-13 in log w); disk margin within 0.1 %
    of ``control.disk_margins`` on a 20000-point grid (grid-limited peak)."""
    m = compute_margins(hinf, AZAIZ, discrete=False, step=False)[axis]
    L = _pc_loop(hinf, axis, discrete=False)
    gm, pm, wpc, wgc = _pc_margins(L)
    assert m.gain_margin_db == pytest.approx(gm, abs=0.02)
    assert m.phase_margin_deg == pytest.approx(pm, abs=0.02)
    assert m.phase_crossover_rad_s == pytest.approx(wpc, rel=1e-3)   # GM read here
    assert m.gain_crossover_rad_s == pytest.approx(wgc, rel=1e-3)    # PM read here
    w = np.logspace(-3, 8, 20000)
    dm, dgm, dpm = ct.disk_margins(L, w, skew=0.0)
    assert m.disk_margin == pytest.approx(dm, rel=1e-3)
    lo, hi, ph = disk_variations(m.disk_margin)
    assert 20 * math.log10(min(1 / lo, hi)) == pytest.approx(dgm, abs=0.02)
    assert ph == pytest.approx(dpm, abs=0.05)
    for skew in (-1.0, 1.0):                         # S (skew 1) and T (skew -1) disks
        ref = ct.disk_margins(L, w, skew=skew)[0]
        ours = next(x["alpha"] for x in m.skewed_disk_margins if x["skew"] == skew)
        assert ours == pytest.approx(ref, rel=1e-3)


def test_margin_naming_matches_design_md(hinf):
    """toolbox/ARCHITECTURE.md "controller.json": gain margin read at the phase crossover (angle L = -180 deg),
    phase margin at the gain crossover (|L| = 1); to_json gives the nine keys."""
    loop = M.make_axis_loop(hinf.axes["q"], AZAIZ.R, AZAIZ.Lq, TS, 1)
    m = M.axis_margins(loop, step=False)
    Lgc = loop.loop([m.gain_crossover_rad_s])[0]
    Lpc = loop.loop([m.phase_crossover_rad_s])[0]
    assert abs(Lgc) == pytest.approx(1.0, abs=1e-9)
    assert np.angle(Lpc, deg=True) == pytest.approx(-180.0, abs=1e-6) or \
        np.angle(Lpc, deg=True) == pytest.approx(180.0, abs=1e-6)
    assert m.gain_margin_db == pytest.approx(-20 * np.log10(abs(Lpc)), abs=1e-9)
    assert tuple(m.to_json(extras=False)) == MARGIN_KEYS
    assert list(m.to_json())[:9] == list(MARGIN_KEYS)


@pytest.mark.slow
@pytest.mark.parametrize("axis", ["d", "q"])
def test_discrete_margins_match_independent_sweep(hinf, pi, axis):
    """Sampled loop with one period of delay: our assembly (ZOH formula, law
    measurement channel) against python-control's ``sample_system`` + ``z^-1``
    and its ``stability_margins`` (discrete), and against a 50000-point linear
    frequency sweep of that system (|1 + L| minimum). Tolerances: 0.02 dB / 0.02
    deg / 0.1 %; the sweep's minimum is within 1e-4 of ours (grid spacing)."""
    for art in (hinf, pi):
        m = compute_margins(art, AZAIZ, step=False)[axis]
        L = _pc_loop(art, axis, discrete=True)
        gm, pm, wpc, wgc = _pc_margins(L)
        assert m.gain_margin_db == pytest.approx(gm, abs=0.02)
        assert m.phase_margin_deg == pytest.approx(pm, abs=0.02)
        # python-control's discrete stability_margins puts the PI q-axis gain crossover
        # 0.3 % off (|L| = 1.003 there): frequencies at 0.5 %, and checked exactly on
        # python-control's own evaluation of L (|L| = 1, Im L = 0 to 1e-8)
        assert m.phase_crossover_rad_s == pytest.approx(wpc, rel=5e-3)
        assert m.gain_crossover_rad_s == pytest.approx(wgc, rel=5e-3)
        Lgc = complex(L(np.exp(1j * m.gain_crossover_rad_s * TS)))
        Lpc = complex(L(np.exp(1j * m.phase_crossover_rad_s * TS)))
        assert abs(Lgc) == pytest.approx(1.0, abs=1e-8)
        assert abs(Lpc.imag) < 1e-8 * abs(Lpc) and Lpc.real < 0
        w = np.linspace(1.0, math.pi / TS, 50000)
        Lw = np.asarray(ct.frequency_response(L, w).complex).ravel()
        assert m.stability_margin == pytest.approx(np.min(np.abs(1 + Lw)), abs=1e-4)
        assert m.stability_margin <= np.min(np.abs(1 + Lw)) + 1e-12   # refined, never above grid
        assert m.disk_margin == pytest.approx(1 / np.max(np.abs(1 / (1 + Lw) - 0.5)), rel=1e-4)


def test_paper003_q_axis_continuous_and_discrete(hinf):
    """Paper 003 sect. 3.3 (Fig. 7-8), q axis at gamma = 1: GM 31.2 dB at 2600 rad/s,
    PM 83.7 deg at 145 rad/s, M_m 0.92, e_ss 8e-5, settling 0.025 s, rise 0.013 s,
    no overshoot (continuous loop, no delay; tolerances as tests/papers/test_003_hinf.py).
    The sampled loop with one period of delay (what runs) loses about 5 dB of GM
    and 1.2 deg of PM: checked as a strict loss of at least 3 dB and less than 3 deg."""
    c = compute_margins(hinf, AZAIZ, discrete=False)["q"]
    dsc = compute_margins(hinf, AZAIZ)["q"]
    print(f"\nq continuous: GM {c.gain_margin_db:.2f} dB @ {c.phase_crossover_rad_s:.0f}, "
          f"PM {c.phase_margin_deg:.2f} @ {c.gain_crossover_rad_s:.1f}, Mm {c.stability_margin:.3f}; "
          f"discrete+delay: GM {dsc.gain_margin_db:.2f} dB @ {dsc.phase_crossover_rad_s:.0f}, "
          f"PM {dsc.phase_margin_deg:.2f}, Mm {dsc.stability_margin:.3f}, disk {dsc.disk_margin:.3f}")
    assert c.gain_margin_db == pytest.approx(31.2, abs=0.2)
    assert c.phase_crossover_rad_s == pytest.approx(2600, rel=0.03)
    assert c.phase_margin_deg == pytest.approx(83.7, abs=0.5)
    assert c.gain_crossover_rad_s == pytest.approx(145, rel=0.03)
    assert c.stability_margin == pytest.approx(0.92, rel=0.03)
    assert c.static_error == pytest.approx(8e-5, rel=0.03)
    assert c.settling_time_2pct == pytest.approx(0.025, abs=1.1e-3)
    assert c.rise_time_10_90 == pytest.approx(0.013, abs=1.1e-3)
    assert c.overshoot_pct < 0.01
    assert 3.0 < c.gain_margin_db - dsc.gain_margin_db < 8.0
    assert 0.0 < c.phase_margin_deg - dsc.phase_margin_deg < 3.0
    assert dsc.stable and dsc.static_error == pytest.approx(c.static_error, rel=1e-3)  # DC kept


def test_exact_and_pade_delay_agree_with_discrete(hinf):
    """Continuous loop with exp(-s 1.5 Ts) approximates the sampled loop with ZOH and
    one period of delay below ~1/10 of Nyquist: PM within 0.1 deg, GM within 0.1 dB
    for the q loop (its phase crossover, 1930 rad/s, is 6 % of Nyquist); the third-order
    Pade route gives the same as the exact delay within 0.01 dB / 0.01 deg."""
    d = compute_margins(hinf, AZAIZ, step=False)["q"]
    e = compute_margins(hinf, AZAIZ, discrete=False, delay="exact", step=False)["q"]
    p = compute_margins(hinf, AZAIZ, discrete=False, delay="pade", step=False)["q"]
    assert e.phase_margin_deg == pytest.approx(d.phase_margin_deg, abs=0.1)
    assert e.gain_margin_db == pytest.approx(d.gain_margin_db, abs=0.1)
    assert p.phase_margin_deg == pytest.approx(e.phase_margin_deg, abs=0.01)
    assert p.gain_margin_db == pytest.approx(e.gain_margin_db, abs=0.01)


def test_pi_step_figures_first_order():
    """PI by pole-zero cancellation: T = wc/(s + wc), so the continuous 5 % response
    time is ln(20)/wc, the 10-90 rise ln(9)/wc, the 2 % settling ln(50)/wc, bandwidth
    wc, static error 0 (integrator), PM 90 deg, no phase crossover. Tolerance
    5e-5 s: the response grid step (0.2 s / 8000)."""
    wc = 1000.0
    m = compute_margins(pi_artifact(wc), AZAIZ, discrete=False)["q"]
    assert m.response_time_5pct == pytest.approx(math.log(20) / wc, abs=5e-5)
    assert m.rise_time_10_90 == pytest.approx(math.log(9) / wc, abs=5e-5)
    assert m.settling_time_2pct == pytest.approx(math.log(50) / wc, abs=5e-5)
    assert m.bandwidth_rad_s == pytest.approx(wc, rel=1e-6)
    assert m.static_error == 0.0 and m.phase_margin_deg == pytest.approx(90.0, abs=1e-6)
    assert math.isinf(m.gain_margin_db) and m.delay_margin_s == pytest.approx(math.pi / 2 / wc)


def test_total_compensation_static_error_and_one_dof_formula(tc):
    """Total compensation (paper 000 eq 11) is a two-input law: the loop's error
    controller is L K - R, but the reference response is exactly K/(s + K) at the
    nominal plant, so the static error is 0 (not 1/(1 + L(0)) = R/(L K)); the
    continuous twin of the law gives the first-order 5 % time ln(20)/K."""
    for disc in (True, False):
        m = compute_margins(tc, AZAIZ, discrete=disc)
        assert m["q"].static_error == 0.0 and m["d"].static_error == 0.0
    c = compute_margins(tc, AZAIZ, discrete=False)["q"]
    assert c.response_time_5pct == pytest.approx(math.log(20) / 800.0, abs=5e-5)
    assert c.bandwidth_rad_s == pytest.approx(800.0, rel=1e-6)
    # one-degree-of-freedom P controller: static error is 1/(1 + L(0)) = R/(R + kp)
    from toolbox.artifact import AxisController
    from analysis_helpers import art
    kp = 1.2
    ax = {n: AxisController.from_error_controller(ct.tf([kp], [1]), TS) for n in "dq"}
    p = compute_margins(art("p", ax), AZAIZ, discrete=False, step=False)
    assert p["q"].static_error == pytest.approx(AZAIZ.R / (AZAIZ.R + kp), rel=1e-9)


def test_coupled_plant_equals_symbolic_plant():
    """Our stacked A(omega), B (written out for vectorisation) equal the plant
    derived symbolically (toolbox.plant, paper 003 eq (3)-(4)) to 1e-12."""
    plant = numeric_plant(AZAIZ)
    for om in (-900.0, 0.0, 350.0):
        A, B = M.coupled_plant(AZAIZ.R, AZAIZ.Ld, AZAIZ.Lq, om)
        np.testing.assert_allclose(A[0], plant.A(om), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(B[0], plant.B(), rtol=1e-12)


def test_coupled_loop_at_zero_speed_splits_into_axes(hinf):
    """At zero speed the coupled closed loop's poles are the union of the two
    single-axis sampled closed loops' poles (1e-8 relative)."""
    laws = {k: M.axis_law(hinf.axes[k], True) for k in "dq"}
    cl = M.coupled_closed_loop(laws, hinf.decoupling, TS, 1, R=AZAIZ.R, Ld=AZAIZ.Ld,
                               Lq=AZAIZ.Lq, omega=0.0)
    ev = np.sort_complex(np.linalg.eigvals(cl.A[0]))
    parts = []
    for k, L_ in (("d", AZAIZ.Ld), ("q", AZAIZ.Lq)):
        loop = M.make_axis_loop(hinf.axes[k], AZAIZ.R, L_, TS, 1)
        parts.append(np.linalg.eigvals(loop.reference_loop()[0]))
    ref = np.sort_complex(np.concatenate(parts))
    np.testing.assert_allclose(ev, ref, rtol=1e-8, atol=1e-10)


def test_mu_bound_matches_slicot_ab13md():
    """D-scaled upper bound for two scalar complex blocks (exact for <= 3 blocks)
    against SLICOT ab13md on random 2x2 matrices: within 1e-5 relative."""
    from slycot import ab13md
    rng = np.random.default_rng(1)
    Ms = rng.normal(size=(20, 2, 2)) + 1j * rng.normal(size=(20, 2, 2))
    Ms[:, 0, 1] *= 30.0                     # badly scaled off-diagonal terms
    ours = M.mu_upper_2x2(Ms)
    for Mx, o in zip(Ms, ours):
        ref = ab13md(Mx, np.array([1, 1]), np.array([2, 2]))[0]
        assert o == pytest.approx(ref, rel=1e-5)
        assert o >= ref * (1 - 1e-9)         # never below the bound
    np.testing.assert_allclose(M.sigma_max_2x2(Ms), np.linalg.norm(Ms, 2, axis=(1, 2)), rtol=1e-12)


@pytest.mark.parametrize("eps", [1e-6, 1e-9, 1e-12])
def test_mu_and_sigma_at_a_nearly_repeated_singular_value(eps):
    """At a nearly repeated singular value (equal inductances at zero speed: a
    diagonal M with |m00| ~ |m11|) both closed forms keep every digit: against
    the exact diag(1, 1 + eps) and numpy's SVD of a near-unitary matrix, 4 eps
    of double precision (the textbook sqrt(f^2 - 4 |det|^2) was off by
    ~eps / 2 here: 5e-10 at eps = 1e-9, five orders above this tolerance)."""
    tol = 4 * np.finfo(float).eps
    diag = np.array([[[1.0, 0.0], [0.0, 1.0 + eps]]], complex)
    assert M.mu_upper_2x2(diag)[0] == pytest.approx(1.0 + eps, rel=tol, abs=0)
    assert M.sigma_max_2x2(diag)[0] == pytest.approx(1.0 + eps, rel=tol, abs=0)
    near_unitary = np.array([[[1.0, 1e-3j], [1e-3j, 1.0 + eps]]])
    ref = np.linalg.svd(near_unitary[0], compute_uv=False)[0]
    assert M.sigma_max_2x2(near_unitary)[0] == pytest.approx(ref, rel=tol, abs=0)
    assert M.mu_upper_2x2(near_unitary)[0] == pytest.approx(ref, rel=tol, abs=0)   # |m01| = |m10|: D = I


@pytest.mark.parametrize("grid", [(49, 40), (25, 12)])
def test_mu_bound_equals_the_explicitly_scaled_matrices(grid):
    """mu_upper_2x2 is the closed-form minimum over d of sigma_max(D M D^-1)
    (a closed form instead of a search: one per speed and corner of the box). The
    reference rebuilds D M D^-1 at every d of a logarithmic grid and refines by
    ternary search (the former implementation, with its
    two grid sizes): the closed form is never above it (it is the infimum) and,
    against the fine search, equal to 1e-12 relative where the optimum lies
    inside the grid (observed 1e-15); the coarse search stops up to 0.25 %
    above it. A zero off-diagonal entry puts the infimum at d -> 0: the grid's
    end is then above it by |M_10|^2 1e-12 at most (1e-9 relative here). The
    optimal d of the closed form attains it (1e-13). The bound stays an upper
    bound of ab13md's mu (test above)."""
    import math

    def scaled(Mx, logd):
        dsc = np.exp(logd)
        Ms = np.array(Mx, complex, copy=True)
        Ms[..., 0, 1] = Mx[..., 0, 1] * dsc
        Ms[..., 1, 0] = Mx[..., 1, 0] / dsc
        return M.sigma_max_2x2(Ms)

    def reference(Mx, n_scale, n_refine):
        g = np.linspace(math.log(1e-6), math.log(1e6), n_scale)
        vals = np.stack([scaled(Mx, np.full(Mx.shape[:-2], x)) for x in g], axis=-1)
        j = np.argmin(vals, axis=-1)
        lo, hi = g[j] - (g[1] - g[0]), g[j] + (g[1] - g[0])
        for _ in range(n_refine):
            m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
            left = scaled(Mx, m1) < scaled(Mx, m2)
            hi, lo = np.where(left, m2, hi), np.where(left, lo, m1)
        return np.minimum(np.min(vals, axis=-1), scaled(Mx, 0.5 * (lo + hi)))

    rng = np.random.default_rng(7)
    Ms = rng.normal(size=(6, 50, 2, 2)) + 1j * rng.normal(size=(6, 50, 2, 2))
    Ms[0, :, 0, 1] = 0.0
    Ms[1, :, 1, 0] *= 1e4
    ours, ref = M.mu_upper_2x2(Ms), reference(Ms, *grid)
    assert np.all(ours <= ref * (1 + 1e-13))
    if grid == (49, 40):
        np.testing.assert_allclose(ours[1:], ref[1:], rtol=1e-12)
        np.testing.assert_allclose(ours[0], ref[0], rtol=1e-9)
    # the closed form's d^2 = |M10|/|M01| attains it: sigma_max of the scaled matrix
    logd = 0.25 * np.log(np.abs(Ms[1:, :, 1, 0]) ** 2 / np.abs(Ms[1:, :, 0, 1]) ** 2)
    np.testing.assert_allclose(ours[1:], scaled(Ms[1:], logd), rtol=1e-13)


def test_mimo_disk_margin_at_zero_speed_and_worst_speed(pi):
    """At zero speed with exact decoupling the two loops are independent, so the
    multiloop disk margin is the smaller SISO disk margin (0.5 % : grids differ).
    Over speed, the sampled compensation leaves residual coupling: the worst speed is
    an end of the range and its margin is below the zero-speed one. The continuous
    route (exp(-s 1.5 Ts)) agrees with the sampled one within 1 % for this 1000 rad/s loop."""
    r = mimo_disk_margins(pi, AZAIZ, DRIVE, n_speeds=5)
    siso = compute_margins(pi, AZAIZ, step=False)
    k0 = r.speeds_rad_s.index(0.0)
    assert r.disk_margin[k0] == pytest.approx(min(siso["d"].disk_margin, siso["q"].disk_margin), rel=5e-3)
    assert abs(r.worst_speed_rad_s) == pytest.approx(DRIVE.max_speed * AZAIZ.pole_pairs)
    assert r.worst_disk_margin < r.disk_margin[k0]
    assert all(a >= u - 1e-12 for a, u in zip(r.disk_margin, r.disk_margin_unstructured))
    c = mimo_disk_margins(pi, AZAIZ, DRIVE, n_speeds=5, discrete=False)
    assert c.worst_disk_margin == pytest.approx(r.worst_disk_margin, rel=0.01)
    assert all(r.stable) and all(c.stable)


def test_coupled_loop_at_speed_matches_python_control_interconnection(hinf):
    """Coupled sampled loop with parameter mismatch and speed-sensor error, against an
    independent python-control build: ``sample_system`` (ZOH) of the 2x2 plant at
    speed, a one-period delay per channel, the voltage placement's rotation
    (toolbox/ARCHITECTURE.md "The digital loop": placed with the measured speed),
    the laws' measurement channels and the decoupling gain W (measured speed),
    closed by ``feedback``. Poles agree to 1e-8; the H-infinity case R, L x0.5 at
    920 rad/s (a set the sweep reports unstable, with a pole of modulus 1.024) is
    unstable on both routes, while the continuous model
    of the same set is stable: the computation delay of the decoupling is the cause."""
    from toolbox.analysis.certificate import point_matrices
    R, Ld, Lq, om, g = 0.3, 0.7e-3, 1.4e-3, 920.0, 1.1
    laws = {k: M.axis_law(hinf.axes[k], True) for k in "dq"}
    ours = M.coupled_closed_loop(laws, hinf.decoupling, TS, 1, R=R, Ld=Ld, Lq=Lq,
                                 omega=om, omega_meas=g * om)
    A, B = M.coupled_plant(R, Ld, Lq, om)
    Pd = ct.sample_system(ct.ss(A[0], B[0], np.eye(2), np.zeros((2, 2))), TS, method="zoh")
    z1 = ct.ss([[0]], [[1]], [[1]], [[0]], TS)
    # the firmware places v at theta_k + t_c g w; it acts around theta_k + 1.5 Ts w
    eps = hinf.decoupling.delay_compensation_time * g * om - 1.5 * TS * om
    rot = np.array([[np.cos(eps), -np.sin(eps)], [np.sin(eps), np.cos(eps)]])
    Pd = Pd * ct.append(z1, z1) * ct.ss([], [], [], rot, TS)
    Km = ct.append(*[hinf.axes[k].law.to_statespace().to_control()[0, 1] for k in "dq"])   # v = Km i
    W = M.decoupling_matrix(hinf.decoupling, g * om)[0]
    Cm = Km + ct.ss([], [], [], W, TS)
    cl = ct.feedback(Pd, Cm, sign=+1)                     # v = (Km + W) i, positive loop
    ref = np.sort(np.abs(cl.poles()))[::-1]
    mine = np.sort(np.abs(np.linalg.eigvals(ours.A[0])))[::-1]
    np.testing.assert_allclose(mine[:6], ref[:6], rtol=1e-8)
    assert ref[0] > 1.0 and ours.spectral_radius()[0] == pytest.approx(ref[0], rel=1e-9)
    cont = point_matrices(hinf, np.array([R, Ld, Lq, om, g]))[0]
    assert np.max(np.linalg.eigvals(cont).real) < 0


@pytest.mark.parametrize("method", ["tustin", "zoh"])
def test_law_to_continuous_inverts_discretisation(method):
    """A two-input IP-like law (integral on the error, proportional on the
    measurement) discretised by python-control and converted back: frequency
    responses of both channels equal the original within 1e-8 relative."""
    law_c = ct.ss([[0.0]], [[500.0, -500.0]], [[1.0]], [[0.0, -2.5]])
    law_d = ct.sample_system(law_c, TS, method=method)
    back = M.law_to_continuous(M.Law(np.array(law_d.A), np.array(law_d.B), np.array(law_d.C),
                                     np.array(law_d.D), TS), method)
    w = np.logspace(0, 4, 50)
    ours = M.freqresp(back.A, back.B, back.C, back.D, 1j * w)
    ref = np.moveaxis(np.asarray(ct.frequency_response(law_c, w).complex), -1, 0)
    np.testing.assert_allclose(ours, ref, rtol=1e-8)


def test_continuous_law_and_margins_computed_once_per_controller(hinf):
    """The continuous law of an AxisController and its margins per loop are kept
    while the controller lives (computed once, not per caller): a second call returns the same
    objects, equal to a fresh computation (a copy of the controller, hashed
    apart, recomputes them)."""
    import copy

    from toolbox.analysis._laws import _continuous_law, axis_law

    axis = hinf.axes["q"]
    law = axis_law(axis, False)
    assert axis_law(axis, False) is law
    fresh = _continuous_law(axis)
    for name in ("A", "B", "C", "D"):
        assert np.array_equal(getattr(law, name), getattr(fresh, name))
    first = M.compute_margins(hinf, AZAIZ, discrete=False, delay="exact")
    assert M.compute_margins(hinf, AZAIZ, discrete=False, delay="exact")["q"] is first["q"]
    twin = copy.copy(hinf)
    object.__setattr__(twin, "axes", {k: copy.copy(v) for k, v in hinf.axes.items()})
    again = M.compute_margins(twin, AZAIZ, discrete=False, delay="exact")
    assert again["q"] is not first["q"]
    assert again["q"].to_json() == first["q"].to_json()
    assert M.compute_margins(hinf, AZAIZ)["q"] is not first["q"]    # another loop
