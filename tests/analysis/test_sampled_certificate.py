"""Certificate of the sampled coupled dq loop as executed (issue 17 item 1).

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


# --- the corner LMIs handed to Clarabel directly (issue 13) -----------------------------

def _cvxpy_solve_lmi(A, G, U, order=None, step=None):
    """Step 4's corner LMIs as the certificate wrote them in cvxpy before issue 13
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
