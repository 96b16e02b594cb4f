"""Certificate of the sampled coupled dq loop as executed (toolbox/ARCHITECTURE.md
"Sampled-loop certificate").

toolbox.analysis._sampled_certificate: a common quadratic Lyapunov function
per speed cell over a polytope that contains the exact ZOH loop. What must
hold: (a) no parameter set of the certified box is unstable for the sampled
sweep (the sweep restricted to the box, and random sets drawn by hypothesis),
(b) the certified scale comes with the first uncertified corner, (c) where
the continuous certificate certifies a box that the sampled loop loses
(paper 002's PI, ``Kp Ts / L`` up to 3.6), the sampled one refuses it.
"""

import dataclasses
import functools
import itertools
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analysis_helpers import plain_bisection
from toolbox.analysis import (SampledBox, certify_sampled, largest_certified_sampled_scale,
                              largest_certified_scale, robustness_sweep)
from toolbox.analysis import _sampled_certificate as S
from toolbox.analysis._coupled import (coupled_closed_loop, coupled_state_matrix,
                                       placement_error, rotation)
from toolbox.analysis._laws import axis_law
from toolbox.analysis._statespace import zoh_2x2
from toolbox.pipeline import design_spec
from toolbox.plant import dq_matrices, max_electrical_speed
from toolbox.spec import load_spec

DESIGNS = {"pi002": "designs/002_cormerais2002_svm_pi.toml",
           "hinf003": "designs/003_azaiz2007_hinf.toml"}
PROFILE = settings(max_examples=60, deadline=None, derandomize=True,
                   suppress_health_check=[HealthCheck.function_scoped_fixture])


@functools.cache
def gallery_design(name: str):
    """(spec, artifact) of a gallery design, designed once per process
    (both are frozen; the tests only read them)."""
    spec = load_spec(DESIGNS[name])
    return spec, design_spec(spec)


@functools.cache
def largest_box_linearisation():
    """(Ts, box, linearisation) of 003's plant on the largest box (scale 1): the
    same for every example of the remainder test, so computed once."""
    spec = load_spec(DESIGNS["hinf003"])
    Ts = spec.drive.sample_time
    box = SampledBox.around(spec.motor, 1.0, omega_max=920.0)
    return Ts, box, S._linearisation(box, Ts)


@pytest.fixture(scope="module", params=sorted(DESIGNS))
def case(request):
    """(spec, artifact, certificate) of a gallery design (one bisection each)."""
    spec, art = gallery_design(request.param)
    return spec, art, largest_certified_sampled_scale(art, spec.motor, spec.drive)


def _laws(art):
    return {k: axis_law(art.axes[k], True) for k in "dq"}


def test_state_matrix_is_the_executed_loop():
    """coupled_state_matrix with the exact ZOH matrices and the voltage's input
    matrix ``Gamma R(eps)`` (the placement error) is coupled_closed_loop's
    state matrix (the certificate's loop is the sweep's loop), bit for bit."""
    spec, art = gallery_design("hinf003")
    rng = np.random.default_rng(3)
    R, Ld, Lq = (v * np.exp(rng.uniform(-0.7, 0.7, 20))
                 for v in (spec.motor.R, spec.motor.Ld, spec.motor.Lq))
    w, wm = rng.uniform(-900, 900, 20), rng.uniform(-900, 900, 20)
    loop = coupled_closed_loop(_laws(art), art.decoupling, art.sample_time, art.delay_samples,
                               R=R, Ld=Ld, Lq=Lq, omega=w, omega_meas=wm)
    Phi, Gam = zoh_2x2(*dq_matrices(R, Ld, Lq, w), art.sample_time)
    eps = placement_error(art.decoupling, art.sample_time, art.delay_samples, w, wm)
    assert np.all(eps != 0)           # the voltage placement is part of the loop
    A = coupled_state_matrix(_laws(art), art.decoupling, art.delay_samples, Phi,
                             Gam @ rotation(eps), wm)
    assert np.array_equal(A, loop.A)


@PROFILE
@given(st.lists(st.floats(0, 1), min_size=4, max_size=4))
def test_remainder_bounds_the_exact_discretisation(u):
    """Step 2: on the largest box (scale 1, 003's plant at 1e-4 s), the exact
    ``[Phi, Psi]`` is within ``rho`` (2-norm) of the linear parts at every
    point of the cell; ``rho`` is an over-bound (measured about 20x the worst
    error), so the test fails only if the bound were wrong."""
    Ts, box, lin = largest_box_linearisation()
    lo = np.array([box.R[0], box.Ld[0], box.Lq[0], box.omega[0]])
    hi = np.array([box.R[1], box.Ld[1], box.Lq[1], box.omega[1]])
    p = lo + np.array(u) * (hi - lo)
    A, B = dq_matrices(*p)
    Phi, Gam = zoh_2x2(A, B, Ts)
    Psi = Gam @ np.linalg.inv(B * Ts)
    Pl, Ql = lin.parts(A * Ts)
    err = np.linalg.norm(np.concatenate([Phi - Pl, Psi - Ql], axis=2)[0], 2)
    assert err <= lin.rho


@pytest.mark.slow
def test_certified_box_has_no_unstable_sweep_set(case):
    """(a) The robustness sweep restricted to the certified box (its R, Ld, Lq
    factors, speed-sensor gain and offset, the design delay, speeds up to the
    certified one) finds no unstable set; the full default sweep does find
    unstable sets, so the restriction is what keeps it clean."""
    spec, art, cert = case
    assert cert.certified and 0 < cert.scale < 1, cert
    m, b = spec.motor, cert.box
    ranges = {"R": [x / m.R for x in b["R"]], "Ld": [x / m.Ld for x in b["Ld"]],
              "Lq": [x / m.Lq for x in b["Lq"]], "speed_gain": b["speed_gain"],
              "speed_offset": [x / m.pole_pairs for x in b["speed_offset"]],
              "delay_samples": None}
    drive = dataclasses.replace(spec.drive, max_speed=b["omega"][1] / m.pole_pairs)
    inside = robustness_sweep(art, m, ranges, n=300, drive=drive, n_speeds=5, n_grid=100)
    assert inside.n_unstable == 0 and inside.worst_spectral_radius < 1
    full = robustness_sweep(art, m, n=300, drive=spec.drive, n_grid=100)
    assert full.n_unstable > 0


@pytest.mark.slow   # 60 random sets, on a certificate bisected first (~3.5 CPU-s)
@PROFILE
@given(st.lists(st.floats(0, 1), min_size=6, max_size=6))
def test_random_sets_in_the_certified_box_are_stable(case, u):
    """(a) Any set drawn in the certified box (true R, Ld, Lq, speed, sensor
    gain and offset) has a stable sampled coupled loop (exact eigenvalues)."""
    spec, art, cert = case
    b = cert.box
    names = ("R", "Ld", "Lq", "omega", "speed_gain", "speed_offset")
    R, Ld, Lq, w, g, o = (lo + x * (hi - lo) for x, (lo, hi) in zip(u, (b[k] for k in names)))
    loop = coupled_closed_loop(_laws(art), art.decoupling, art.sample_time, art.delay_samples,
                               R=R, Ld=Ld, Lq=Lq, omega=w, omega_meas=g * w + o)
    assert loop.spectral_radius()[0] < 1


@pytest.mark.slow   # the certificate bisected per design (~2 CPU-s for hinf003)
def test_scale_reported_with_first_uncertified_corner(case):
    """(b) The result names the certified scale and box, and the first refused
    scale within one bisection tolerance (0.05) above it, with a corner inside
    that refused box and its exact spectral radius; the JSON form is strict."""
    spec, art, cert = case
    first = cert.first_uncertified
    assert first is not None and 0 < first["scale"] - cert.scale <= 0.05
    c = first["corner"]
    k = first["scale"]
    for name in ("R", "Ld", "Lq"):
        assert 1 - k * 0.5 - 1e-12 <= c[name] <= 1 + k * 1.0 + 1e-12
    wmax = max_electrical_speed(spec.motor, spec.drive)
    assert abs(c["omega_rad_s"]) <= k * wmax + 1e-9
    radius = coupled_closed_loop(
        _laws(art), art.decoupling, art.sample_time, art.delay_samples,
        R=c["R"] * spec.motor.R, Ld=c["Ld"] * spec.motor.Ld, Lq=c["Lq"] * spec.motor.Lq,
        omega=c["omega_rad_s"],
        omega_meas=c["speed_gain"] * c["omega_rad_s"] + c["speed_offset_rad_s"],
    ).spectral_radius()[0]
    assert radius == pytest.approx(c["spectral_radius"], rel=1e-12)
    assert c["unstable"] == bool(radius >= 1)
    assert cert.speed_range_rad_s == [-cert.scale * wmax, cert.scale * wmax]
    json.dumps(cert.to_json(), allow_nan=False)


def test_continuous_certifies_where_sampled_refuses():
    """(c) Paper 002's PI (Ts = 1 ms, Kp = 0.2, L = 0.11 mH: Kp Ts/L = 1.8 at
    the nominal point) is certified by the continuous LMI on the whole default
    box, but half the inductance doubles the sampled loop gain past 2: the
    sampled certificate refuses that box and names an unstable corner."""
    spec, art = gallery_design("pi002")
    cont = largest_certified_scale(art, spec.motor, spec.drive)
    assert cont.certified and cont.scale == 1.0
    wmax = max_electrical_speed(spec.motor, spec.drive)
    box = SampledBox.around(spec.motor, 1.0, omega_max=wmax)
    ok, outcomes = certify_sampled(art, box)
    assert not ok
    assert outcomes[-1].worst_radius > 1 and "unstable" in outcomes[-1].reason


def test_warm_start_and_fresh_solve_agree_on_nominal_point():
    """The nominal point (scale 0) of a stable design is certified by a fresh
    LMI solve, and the matrix found certifies it again as a warm start; a
    Lyapunov matrix that is not one (indefinite) is rejected by the check."""
    spec, art = gallery_design("hinf003")
    box = SampledBox.around(spec.motor, 0.0)
    guesses: dict = {}
    ok, out = certify_sampled(art, box, speed_cells=1, guesses=guesses)
    assert ok and out[0].reason in ("optimal", "optimal_inaccurate")
    ok2, out2 = certify_sampled(art, box, speed_cells=1, guesses=dict(guesses))
    assert ok2 and out2[0].reason == "warm start"
    n = guesses[0].shape[0]
    bad = np.eye(n)
    bad[0, 0] = -1.0
    assert not S._verified(np.zeros((1, n, n)), np.zeros((1, n, n)), np.zeros((n, 2)), bad, 1.0)
    assert math.isfinite(out[0].condition_P)


# --- the corner LMIs handed to Clarabel directly (ARCHITECTURE.md "Caches and lazy imports") ---

def _cvxpy_solve_lmi(A, G, U, order=None, step=None):
    """Step 4's corner LMIs as the certificate wrote them in cvxpy (the former route)
    (every corner at once; ``order`` and ``step`` are not used)."""
    import warnings

    import cvxpy as cp

    N, n, _ = A.shape
    m = U.shape[1]
    P = cp.Variable((n, n), symmetric=True)
    lam = cp.Variable(nonneg=True)
    cons = [P >> np.eye(n)]
    for Ai, Gi in zip(A, G):
        AU = np.hstack([Ai, U])
        M = AU.T @ P @ AU - cp.bmat([[P - lam * Gi, np.zeros((n, m))],
                                     [np.zeros((m, n)), lam * np.eye(m)]])
        cons.append(0.5 * (M + M.T) << -S._EPS * np.eye(n + m))
    problem = cp.Problem(cp.Minimize(0), cons)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            problem.solve(solver=cp.CLARABEL)
        except cp.error.SolverError as err:
            return None, 0.0, f"solver error: {err}"
    status = str(problem.status)
    if P.value is None or status not in ("optimal", "optimal_inaccurate"):
        return None, 0.0, status
    return np.array(P.value), float(lam.value), status


def _reference_scale(art, motor, drive, tol: float, monkeypatch) -> float:
    """Cold bisection (no warm start, neither from a smaller box nor from the
    mirror cell), every corner LMI of every cell solved at once through cvxpy."""
    cold = S._certify_cell
    monkeypatch.setattr(S, "_certify_cell", lambda a, laws, cell, guesses=(): cold(a, laws, cell))
    monkeypatch.setattr(S, "_solve_lmi", _cvxpy_solve_lmi)
    wmax = max_electrical_speed(motor, drive)
    off = tuple(motor.pole_pairs * v for v in S.DEFAULT_RANGES["speed_offset"][:2])

    def ok(k: float) -> bool:
        box = SampledBox.around(motor, k, omega_max=wmax,
                                speed_gain=S.DEFAULT_RANGES["speed_gain"][:2], speed_offset=off)
        return certify_sampled(art, box, guesses={})[0]

    return plain_bisection(ok, tol)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_same_scale_as_cvxpy_route(name, monkeypatch):
    """Direct Clarabel, constraint generation and warm starts give exactly the
    scale of the cold bisection through cvxpy (all corners per solve) on the
    gallery designs' boxes: the grid is dyadic (tol 1/8, analysis.json's), so a
    single changed verdict would move the scale by at least 1/16."""
    spec, art = gallery_design(name)
    with monkeypatch.context() as m:
        ref = _reference_scale(art, spec.motor, spec.drive, 0.125, m)
    res = largest_certified_sampled_scale(art, spec.motor, spec.drive, tol=0.125)
    assert res.scale == ref


def test_clarabel_rows_are_the_corner_matrices():
    """The rows handed to Clarabel are step 4's corner matrices: for any
    ``x = [upper triangle of P, lam]``, ``b - A x`` is the svec of
    ``-M_i(P, lam) - eps I`` (:func:`_corner_matrices`, numpy) at every corner,
    and the first block is ``svec(P - I)``."""
    from toolbox.analysis._lmi import svec_index, symmetric_matrix

    rng = np.random.default_rng(0)
    N, n = 6, 7
    A = rng.normal(size=(N, n, n))
    V = rng.normal(size=(N, 4, n))
    G = np.transpose(V, (0, 2, 1)) @ V
    U = np.zeros((n, 2))
    U[0, 0] = U[1, 1] = 1.0
    (Ap, bp), (Ac, bc) = S._lmi_blocks(A, G, U)
    x = rng.normal(size=n * (n + 1) // 2 + 1)
    P, lam = symmetric_matrix(x[:-1], n), x[-1]
    r, c, w = svec_index(n + 2)
    ref = (-S._corner_matrices(A, G, U, P, lam) - S._EPS * np.eye(n + 2))[:, r, c] * w
    np.testing.assert_allclose(bc - Ac @ x, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    r, c, w = svec_index(n)
    np.testing.assert_allclose(bp - Ap @ x, (P - np.eye(n))[r, c] * w, rtol=0, atol=1e-14)


#: scales around each design's refusal: certified below, refused by the solver
#: (the polytope's corners stable) above
CUT_SCALES = {"pi002": (0.0, 0.203125, 0.21875), "hinf003": (0.27, 0.28)}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CUT_SCALES))
def test_constraint_generation_gives_the_full_solve_verdict(name):
    """Constraint generation over the corners (a few, the violated ones added)
    reaches the verdict of the solve over all corners on cells certified and
    refused, and its certificate passes the numpy check at every corner."""
    spec, art = gallery_design(name)
    laws = _laws(art)
    wmax = max_electrical_speed(spec.motor, spec.drive)
    verdicts = set()
    # one cell per scale: the two speed cells are mirror images (w -> -w)
    for k in CUT_SCALES[name]:
        cell = SampledBox.around(spec.motor, k, omega_max=wmax).speed_cells(2)[0]
        c = S._cell_lmi(art, laws, cell)
        assert np.max(c.radii) < 1.0
        order = np.argsort(-c.radii)
        P_full, lam_full, _ = S._solve_lmi(c.A, c.G, c.U, order, step=c.A.shape[0])
        full = P_full is not None and S._verified(c.A, c.G, c.U, P_full, lam_full)
        P, lam, _ = S._solve_lmi(c.A, c.G, c.U, order)
        assert (P is not None and S._verified(c.A, c.G, c.U, P, lam)) == full, (k, cell)
        verdicts.add(full)
    assert verdicts == {True, False}


def test_mirror_signs_map_a_cell_to_its_mirror():
    """The warm start of a speed cell from its mirror image is exact: at opposite
    true and measured speeds the executed loop is ``S A S`` (the sign of i_q,
    of the q law's states and of the delayed q voltages flipped); shown on
    random sets of 003's H-infinity design (3 law states per axis, one delay)."""
    spec, art = gallery_design("hinf003")
    rng = np.random.default_rng(5)
    R, Ld, Lq = (v * np.exp(rng.uniform(-0.7, 0.7, 20))
                 for v in (spec.motor.R, spec.motor.Ld, spec.motor.Lq))
    w, wm = rng.uniform(-900, 900, 20), rng.uniform(-900, 900, 20)

    def loop(sign):
        return coupled_closed_loop(_laws(art), art.decoupling, art.sample_time,
                                   art.delay_samples, R=R, Ld=Ld, Lq=Lq, omega=sign * w,
                                   omega_meas=sign * wm).A

    s = S._mirror_signs(_laws(art), art.delay_samples)
    assert art.delay_samples >= 1 and np.any(s < 0)
    np.testing.assert_allclose(s[:, None] * loop(1.0) * s[None, :], loop(-1.0),
                               rtol=1e-12, atol=1e-12)
    cell = SampledBox((0.1, 0.2), (1e-3, 2e-3), (1e-3, 3e-3), (100.0, 200.0), (0.9, 1.1),
                      (-20.0, 30.0))
    assert S._mirror(cell) == SampledBox(cell.R, cell.Ld, cell.Lq, (-200.0, -100.0),
                                         cell.speed_gain, (-30.0, 20.0))


# --- the voltage placement: Gamma R(eps) (toolbox/ARCHITECTURE.md "The digital loop") ---

@functools.cache
def placement_design(name: str, angle_compensation: str):
    """(spec, artifact) of a gallery design with ``drive.angle_compensation``
    replaced (``"none"``: ``t_c = 0``, the placement error ``-(d + 1/2) Ts w``)."""
    spec = load_spec(DESIGNS[name])
    spec = dataclasses.replace(spec, drive=dataclasses.replace(
        spec.drive, angle_compensation=angle_compensation))
    return spec, design_spec(spec)


#: boxes where the placement error varies over the cells: t_c = 0 at speed, and
#: speed-sensor errors far beyond the sweep's (the error t_c ((g - 1) w + o))
PLACEMENT_CASES = {
    "hinf003-none": ("hinf003", "none", dict(R=(0.9, 1.1), L=(0.9, 1.1), omega_max=3000.0)),
    "hinf003-sensor": ("hinf003", "mid_period",
                       dict(R=(0.9, 1.1), L=(0.9, 1.1), omega_max=3000.0,
                            speed_gain=(0.5, 1.5), speed_offset=(-100.0, 100.0))),
    "pi002-none-sensor": ("pi002", "none",
                          dict(R=(0.9, 1.1), L=(0.9, 1.1), omega_max=1000.0,
                               speed_gain=(0.8, 1.2), speed_offset=(-20.0, 20.0))),
}


@pytest.fixture(scope="module", params=sorted(PLACEMENT_CASES))
def placement_case(request):
    """(spec, artifact, certificate) on a box with a varying placement error."""
    name, comp, kw = PLACEMENT_CASES[request.param]
    spec, art = placement_design(name, comp)
    return spec, art, largest_certified_sampled_scale(art, spec.motor, spec.drive, **kw)


def _box_loops(art, b: dict, u: np.ndarray):
    """Spectral radii of coupled_closed_loop (rotation included) at the points
    ``lo + u (hi - lo)`` (u (N, 6)) of a certificate's box."""
    names = ("R", "Ld", "Lq", "omega", "speed_gain", "speed_offset")
    R, Ld, Lq, w, g, o = (lo + u[:, j] * (hi - lo)
                          for j, (lo, hi) in enumerate(b[k] for k in names))
    return coupled_closed_loop(_laws(art), art.decoupling, art.sample_time, art.delay_samples,
                               R=R, Ld=Ld, Lq=Lq, omega=w, omega_meas=g * w + o
                               ).spectral_radius()


@pytest.mark.slow
def test_placement_boxes_certified_and_stable(placement_case):
    """(a) With ``t_c = 0`` at speed or large speed-sensor errors the certified
    box's corners and random sets (uniform, 4000) are stable on
    coupled_closed_loop, which rotates the voltage by the placement error; the
    placement error does vary over these cells (512 corner matrices)."""
    spec, art, cert = placement_case
    assert cert.certified and cert.scale > 0 and cert.n_vertices == 512, cert
    b = cert.box
    eps = placement_error(art.decoupling, art.sample_time, art.delay_samples,
                          np.array(b["omega"]), np.array(b["omega"]))
    assert np.ptp(eps) > 0 or b["speed_gain"][0] < 1
    corners = np.array(list(itertools.product((0.0, 1.0), repeat=6)))
    assert np.max(_box_loops(art, b, corners)) < 1
    u = np.random.default_rng(11).uniform(size=(4000, 6))
    assert np.max(_box_loops(art, b, u)) < 1


@pytest.mark.slow   # 60 random sets, on a certificate bisected first (~3.5 CPU-s)
@PROFILE
@given(st.lists(st.floats(0, 1), min_size=6, max_size=6))
def test_random_sets_in_placement_boxes_are_stable(placement_case, u):
    """(a) Any set drawn in such a certified box is stable (exact eigenvalues,
    the rotation included)."""
    spec, art, cert = placement_case
    assert _box_loops(art, cert.box, np.array([u]))[0] < 1


def _multilinear_weights(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Weights (2^k,) of the box corners (itertools.product order of (lo, hi)
    pairs) that interpolate a multi-affine function exactly at ``x`` (k,)."""
    t = np.where(hi > lo, (x - lo) / np.where(hi > lo, hi - lo, 1.0), 0.0)
    assert np.all((t >= -1e-12) & (t <= 1 + 1e-12))
    return np.array([math.prod(tj if c else 1 - tj for tj, c in zip(t, corner))
                     for corner in itertools.product((0, 1), repeat=len(t))])


def _trapezoid_weights(delta: float, Q: np.ndarray) -> np.ndarray:
    """Convex weights of the placement polygon's vertices (the trapezoid of
    :func:`_placement_polygon`) giving ``(cos delta, sin delta)``."""
    a, s = math.cos(delta), math.sin(delta)
    cD, sD, t = Q[0, 0], Q[1, 1], Q[3, 1]
    lam = (a - cD) / (1.0 - cD)
    h = sD * (1 - lam) + t * lam
    assert -1e-12 <= lam <= 1 + 1e-12 and abs(s) <= h * (1 + 1e-12)
    mu = 0.5 * (s / h + 1.0)
    return np.array([(1 - lam) * (1 - mu), (1 - lam) * mu, lam * (1 - mu), lam * mu])


def test_polytope_and_remainder_contain_the_rotated_loop():
    """Steps 1-3 with the rotation, pointwise: at random sets of a cell with
    ``t_c = 0`` at speed and speed-sensor errors, the corners' convex
    combination (the multi-affine weights of Theta and of the measured speed,
    the trapezoid's weights of ``(cos delta, sin delta)``) is the linearised
    loop with ``Gamma_lin R(eps)`` and ``V = [i; diag(b) R(eps) u]`` exactly,
    and the exact loop differs from it by ``[r_Phi, r_Psi] V`` in the current
    rows only, with ``||[r_Phi, r_Psi]|| <= rho``."""
    spec, art = placement_design("hinf003", "none")
    laws, Ts, d, dec = _laws(art), art.sample_time, art.delay_samples, art.decoupling
    m = spec.motor
    cell = SampledBox((0.8 * m.R, 1.2 * m.R), (0.9 * m.Ld, 1.1 * m.Ld),
                      (0.9 * m.Lq, 1.1 * m.Lq), (600.0, 1400.0), (0.9, 1.1), (-20.0, 20.0))
    A, V, rho = S._vertices(art, laws, cell)
    eps_c, Q = S._placement_polygon(art, cell)
    assert A.shape[0] == 512 and Q.shape == (4, 2)
    lo, hi = S._theta_box(cell, Ts)
    wm_lo, wm_hi = cell.measured_speed()
    lin = S._linearisation(cell, Ts)
    rng = np.random.default_rng(7)
    for _ in range(40):
        p = np.array([lo_ + rng.uniform() * (hi_ - lo_) for lo_, hi_ in
                      (cell.R, cell.Ld, cell.Lq, cell.omega, cell.speed_gain,
                       cell.speed_offset)])
        w, wm = p[3], p[4] * p[3] + p[5]
        th = S._theta(p[None], Ts)[0]
        eps = placement_error(dec, Ts, d, w, wm)[()]
        weights = np.einsum("i,j,k->ijk", _multilinear_weights(th, lo, hi),
                            _multilinear_weights(np.array([wm]), np.array([wm_lo]),
                                                 np.array([wm_hi])),
                            _trapezoid_weights(eps - eps_c, Q)).reshape(-1)
        assert np.all(weights >= -1e-12) and math.isclose(weights.sum(), 1.0, rel_tol=1e-12)
        Pl, Ql = lin.parts(th[None, :4].reshape(1, 2, 2))
        bmat = np.diag(th[4:])[None]
        Rot = rotation(eps)
        A_lin = coupled_state_matrix(laws, dec, d, Pl, Ql @ bmat @ Rot, [wm])[0]
        one, zero = np.eye(2)[None], np.zeros((1, 2, 2))
        u = (coupled_state_matrix(laws, dec, d, zero, one, [wm])
             - coupled_state_matrix(laws, dec, d, zero, zero, [wm]))[0, :2]
        V_pt = np.vstack([np.eye(2, A.shape[-1]), (bmat @ Rot)[0] @ u])
        np.testing.assert_allclose(np.einsum("i,iab->ab", weights, A), A_lin,
                                   rtol=0, atol=1e-11 * np.abs(A_lin).max())
        np.testing.assert_allclose(np.einsum("i,iab->ab", weights, V), V_pt,
                                   rtol=0, atol=1e-11 * np.abs(V_pt).max())
        exact = coupled_closed_loop(laws, dec, Ts, d, R=p[0], Ld=p[1], Lq=p[2], omega=w,
                                    omega_meas=wm).A[0]
        Ac, Bc = dq_matrices(*p[:4])
        Phi, Gam = zoh_2x2(Ac, Bc, Ts)
        r = np.concatenate([Phi - Pl, Gam @ np.linalg.inv(Bc * Ts) - Ql], axis=2)[0]
        assert np.linalg.norm(r, 2) <= rho
        np.testing.assert_allclose(exact[2:], A_lin[2:], rtol=0, atol=1e-12)
        np.testing.assert_allclose(exact[:2] - A_lin[:2], r @ V_pt, rtol=0,
                                   atol=1e-10 * np.abs(exact).max())


def test_ignoring_the_rotation_would_certify_an_unstable_set(monkeypatch):
    """(b) Paper 002's PI with ``t_c = 0`` at 600..700 rad/s (about 4.6 times
    its top speed; the placement error -0.30..-0.35 rad): the loop as executed
    is unstable inside the cell, while the loop without the rotation is not
    (radius about 0.88; its polytope corners 0.91). The certificate refuses
    the cell, and so does its polytope alone; the polytope of the unrotated
    Gamma (the certificate before the placement) admits a Lyapunov matrix
    that passes the numpy check: it would have certified an unstable set."""
    spec, art = placement_design("pi002", "none")
    laws, m = _laws(art), spec.motor
    cell = SampledBox((m.R, m.R), (m.Ld, m.Ld), (m.Lq, m.Lq), (600.0, 700.0))
    loop = coupled_closed_loop(laws, art.decoupling, art.sample_time, art.delay_samples,
                               R=m.R, Ld=m.Ld, Lq=m.Lq, omega=np.linspace(600.0, 700.0, 11))
    assert np.max(loop.spectral_radius()) > 1
    ok, out = certify_sampled(art, cell, speed_cells=1)
    assert not ok and out[-1].worst_radius > 1
    c = S._cell_lmi(art, laws, cell)
    assert c.n_vertices == 512
    P, lam, _ = S._solve_lmi(c.A, c.G, c.U, np.argsort(-c.radii))
    assert np.max(c.radii) >= 1 or P is None or not S._verified(c.A, c.G, c.U, P, lam)
    monkeypatch.setattr(S, "_placement_polygon", lambda a, cell: (0.0, np.array([[1.0, 0.0]])))
    c0 = S._cell_lmi(art, laws, cell)
    assert c0.n_vertices == 128 and np.max(c0.radii) < 0.95
    P0, lam0, _ = S._solve_lmi(c0.A, c0.G, c0.U, np.argsort(-c0.radii))
    assert P0 is not None and S._verified(c0.A, c0.G, c0.U, P0, lam0)


def test_no_placement_error_keeps_128_corners():
    """(c) Where the placement error is constant over a cell, no corner is added:
    the default placement (``t_c = (d + 1/2) Ts``) without speed-sensor error
    (``eps = 0`` exactly) keeps the 128 corners and the unrotated polytope bit
    for bit, and so does ``t_c = 0`` at one speed (``eps`` constant, the
    polytope rotated by it: at a single parameter set its corner is the
    executed loop)."""
    spec, art = gallery_design("hinf003")
    laws, m = _laws(art), spec.motor
    box = SampledBox.around(m, 0.5, omega_max=max_electrical_speed(m, spec.drive))
    for cell in box.speed_cells(2):
        assert S._placement_polygon(art, cell) == (0.0, pytest.approx(np.array([[1.0, 0.0]])))
        A, V, rho = S._vertices(art, laws, cell)
        assert A.shape[0] == 128
        Phi, Gam, b, _ = S._zoh_polytope(cell, art.sample_time)
        wm = np.tile(np.array(cell.measured_speed()), Phi.shape[0])
        Phi, Gam = (np.repeat(M, 2, axis=0) for M in (Phi, Gam))
        assert np.array_equal(A, coupled_state_matrix(laws, art.decoupling, art.delay_samples,
                                                      Phi, Gam, wm))
    cert = largest_certified_sampled_scale(art, m, spec.drive, speed_gain=(1.0, 1.0),
                                           speed_offset=(0.0, 0.0), tol=0.125)
    assert cert.n_vertices == 128
    spec0, art0 = placement_design("hinf003", "none")
    point = SampledBox((m.R, m.R), (m.Ld, m.Ld), (m.Lq, m.Lq), (900.0, 900.0))
    eps_c, Q = S._placement_polygon(art0, point)
    assert eps_c == pytest.approx(-1.5 * art0.sample_time * 900.0) and Q.shape == (1, 2)
    A, _, _ = S._vertices(art0, _laws(art0), point)
    exact = coupled_closed_loop(_laws(art0), art0.decoupling, art0.sample_time,
                                art0.delay_samples, R=m.R, Ld=m.Ld, Lq=m.Lq, omega=900.0).A
    assert A.shape[0] == 128
    np.testing.assert_allclose(A, np.broadcast_to(exact, A.shape), rtol=0, atol=1e-12)


@pytest.mark.parametrize("case", ["pi002"], indirect=True)
def test_speed_range_stated_in_mechanical_and_electrical(case):
    """The certificate's JSON states the covered speed range in mechanical rad/s
    (as the spec's ``max_speed``) beside the electrical one, and the report
    renders the speeds as mechanical with electrical in brackets (electrical
    alone for a JSON without ``pole_pairs``). On paper 002's design (6 pole
    pairs) only: the units do not depend on the law, and 003's bisection
    (~2 s) is the slow tests' fixture."""
    from toolbox.report import _sampled_certificate_of

    spec, art, cert = case
    pp = spec.motor.pole_pairs
    assert cert.pole_pairs == pp
    assert cert.speed_range_mech_rad_s == [w / pp for w in cert.speed_range_rad_s]
    wmax = max_electrical_speed(spec.motor, spec.drive)
    assert cert.speed_range_mech_rad_s[1] == pytest.approx(cert.scale * wmax / pp, rel=1e-12)
    data = json.loads(json.dumps(cert.to_json(), allow_nan=False))
    facts = _sampled_certificate_of(data)
    lo, hi = cert.speed_range_rad_s
    covered = facts["sampled loop: speed range covered"]
    assert covered.endswith(f"rad/s mechanical ({lo:.4g} .. {hi:.4g} rad/s electrical)")
    assert covered.startswith(f"{lo / pp:.4g} .. {hi / pp:.4g}")
    assert "rad/s mechanical" in facts["sampled loop: box speed-sensor offset"]
    assert facts["sampled loop: box R"].endswith(" ohm")
    assert "mechanical (" in facts["sampled loop: first uncertified corner"]
    del data["pole_pairs"]
    assert _sampled_certificate_of(data)["sampled loop: speed range covered"] == (
        f"{lo:.4g} .. {hi:.4g} rad/s electrical")
