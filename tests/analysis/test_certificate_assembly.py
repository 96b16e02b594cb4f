"""The certificate's LMIs handed to Clarabel directly, with a warm-started bisection
(toolbox/ARCHITECTURE.md "Caches and lazy imports": no cvxpy on the design path).

The reference is the former cvxpy route: the same vertex LMIs written in
cvxpy (constant data, a fresh problem per scale, all vertices) and solved by
cvxpy's Clarabel interface, with a plain cold bisection. The bisection grid is dyadic
(scales k/2^m), so the certified scales are compared *exactly*: any change in
a single feasibility verdict moves the scale by at least ``tol/2``.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from analysis_helpers import AZAIZ, DRIVE, plain_bisection
from toolbox.analysis import certificate as C
from toolbox.plant import max_electrical_speed


def _cvxpy_solve(As: np.ndarray, alpha: float, eps: float = 1e-6):
    """The vertex LMIs as the certificate wrote them in cvxpy (the former route)."""
    import cvxpy as cp

    n = As.shape[1]
    P = cp.Variable((n, n), symmetric=True)
    cons = [P >> np.eye(n)]
    for A in As:
        M = A.T @ P + P @ A + 2 * alpha * P
        cons.append(0.5 * (M + M.T) << -eps * np.eye(n))
    prob = cp.Problem(cp.Minimize(0), cons)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            prob.solve(solver=cp.CLARABEL)
        except cp.error.SolverError:
            return None, "solver error"
    if P.value is None or prob.status not in ("optimal", "optimal_inaccurate"):
        return None, str(prob.status)
    return np.array(P.value), str(prob.status)


def _full_cvxpy_solve(As: np.ndarray, alpha: float, guess=None):
    """All vertex LMIs at once through cvxpy, normalised as the former cvxpy route did
    (``guess``, the active set's seed, is not used)."""
    norm = max(1.0, float(np.max(np.abs(As))))
    return _cvxpy_solve(As / norm, alpha / norm)


def _reference_scale(art, motor, drive, monkeypatch, *, tol: float, alpha: float = 0.0) -> float:
    """Cold bisection, the LMIs of every vertex solved through cvxpy (no warm
    start, no active vertex set)."""
    wmax = max_electrical_speed(motor, drive)
    with monkeypatch.context() as m:
        m.setattr(C, "_solve_active", _full_cvxpy_solve)

        def ok(k: float) -> bool:
            box = C.ParameterBox.around(motor, k, omega_max=wmax)
            return C._certify(art, box, alpha, False, guess=None)[0].certified

        return plain_bisection(ok, tol)


@pytest.mark.slow
@pytest.mark.parametrize("design", ["pi", "hinf"])
@pytest.mark.parametrize("alpha", [0.0, 200.0])
def test_same_scale_as_cvxpy_route(design, alpha, request, monkeypatch):
    """Direct Clarabel + warm start gives exactly the scale of the cold cvxpy
    bisection, on a PI and an H-infinity design (two state dimensions)."""
    art = request.getfixturevalue(design)
    ref = _reference_scale(art, AZAIZ, DRIVE, monkeypatch, tol=0.05, alpha=alpha)
    res = C.largest_certified_scale(art, AZAIZ, DRIVE, tol=0.05, alpha=alpha)
    assert res.scale == ref


def _normalised_vertices(art, k: float, alpha: float = 0.0) -> np.ndarray:
    box = C.ParameterBox.around(AZAIZ, k, omega_max=920.0)
    As = C._vertices(art, box)
    return As / np.max(np.abs(As))


@pytest.mark.slow
@pytest.mark.parametrize("design", ["pi", "hinf"])
@pytest.mark.parametrize("alpha", [0.0, 0.05])
def test_data_equal_cvxpy_problem_data(design, alpha, request):
    """The (A, b) handed to Clarabel are exactly the matrices cvxpy builds for
    the same LMIs (``get_problem_data``), cone by cone: same unknowns (the
    upper triangle of P) and the same svec rows."""
    import cvxpy as cp

    art = request.getfixturevalue(design)
    As = _normalised_vertices(art, 0.5)
    n = As.shape[1]
    P = cp.Variable((n, n), symmetric=True)
    cons = [P >> np.eye(n)]
    for A in As:
        M = A.T @ P + P @ A + 2 * alpha * P
        cons.append(0.5 * (M + M.T) << -1e-6 * np.eye(n))
    data, _, _ = cp.Problem(cp.Minimize(0), cons).get_problem_data(cp.CLARABEL)
    Amat, bvec, cones = C._lmi_data(As, alpha)
    assert len(cones) == As.shape[0] + 1
    # cvxpy's sums of products may round differently: 1e-12 of entries of order 1
    np.testing.assert_allclose(Amat, data["A"].toarray(), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(bvec, data["b"])


@pytest.mark.slow
@pytest.mark.parametrize("design", ["pi", "hinf"])
def test_same_solution_as_cvxpy(design, request):
    """On a certified box and on one that is not, the direct solve reports what
    cvxpy reported (status) and the same Lyapunov matrix: relative 1e-6, the
    same problem data (above) solved by the same solver with the same
    settings, so only floating-point ordering differs."""
    art = request.getfixturevalue(design)
    for k in (0.2, 1.0):
        As = _normalised_vertices(art, k)
        P_ref, st_ref = _cvxpy_solve(As, 0.0)
        P_new, st_new = C._solve(As, 0.0)
        assert st_new.startswith(st_ref)
        assert (P_new is None) == (P_ref is None)
        if P_new is not None:
            np.testing.assert_allclose(P_new, P_ref, rtol=1e-6, atol=1e-6 * np.abs(P_ref).max())


def test_solution_is_symmetric_and_satisfies_the_lmis(pi):
    """The P read back from Clarabel's svec is symmetric, >= I and makes every
    vertex LMI negative definite (eps = 1e-6 on the normalised data, relative
    slack 1e-7 for the interior-point tolerance)."""
    As = _normalised_vertices(pi, 0.2)
    P, status = C._solve(As, 0.0)
    assert status == "optimal" and np.array_equal(P, P.T)
    assert np.min(np.linalg.eigvalsh(P)) >= 1 - 1e-7
    M = np.transpose(As, (0, 2, 1)) @ P + P @ As
    assert np.max(np.linalg.eigvalsh(M)) <= -1e-6 * (1 - 1e-1)


#: Solves of the vertex LMIs made by this module's scale sweeps, keyed by their
#: data bit for bit: the sweeps of the two tests below solve the same problems
#: (the solver is deterministic), so whichever runs second reads them back.
_SOLVES: dict = {}


def _solved_once(solve):
    """``solve`` answering a problem solved before (same data, bit for bit) from
    :data:`_SOLVES`."""
    def once(As: np.ndarray, alpha: float, eps: float = 1e-6):
        key = (As.shape, As.tobytes(), alpha, eps)
        if key not in _SOLVES:
            _SOLVES[key] = solve(As, alpha, eps)
        return _SOLVES[key]

    return once


def _sweep():
    """The boxes of both sweeps: ``(box, alpha)`` at scales 0, 1/8, .., 1 and
    decay rates 0 and 200 1/s."""
    return [(C.ParameterBox.around(AZAIZ, k, omega_max=920.0), alpha)
            for k in np.linspace(0.0, 1.0, 9) for alpha in (0.0, 200.0)]


@pytest.mark.slow
@pytest.mark.parametrize("design", ["pi", "hinf"])
def test_active_vertex_set_gives_the_full_solve_verdict(design, request, monkeypatch):
    """Constraint generation (a few vertices, the violated ones added) reaches
    the verdict of the solve over all vertices on every box of a scale sweep,
    its certificate holds on all vertices, and it solves fewer vertex LMIs.
    The sweep must contain certified and uncertified (solved) boxes. The
    vertices are those the certificate solves: balanced (:func:`C._balanced_vertices`).

    Where constraint generation ends in the solve over all vertices (a subset
    failing numerically: most boxes with an unstable vertex), that solve is
    the reference's own, the same data bit for bit: it is read back rather
    than solved twice (the solver is deterministic; ~3 s of the test)."""
    art = request.getfixturevalue(design)
    monkeypatch.setattr(C, "_solve", _solved_once(C._solve))
    verdicts = set()
    for box, alpha in _sweep():
        Ab = C._balanced_vertices(art, box, C._vertices(art, box), False)[0]
        norm = max(1.0, float(np.max(np.abs(Ab))))
        P_full, _ = C._solve(Ab / norm, alpha / norm)
        full = P_full is not None and C._verified(Ab, P_full, alpha)
        P, _ = C._solve_active(Ab, alpha)
        assert (P is not None and C._verified(Ab, P, alpha)) == full, (box, alpha)
        verdicts.add(full)
    assert verdicts == {True, False}


def test_warm_start_is_used_and_checked(pi):
    """A P certified on a small box is re-used on a slightly larger one (no solve,
    status "warm start") only when the a posteriori check passes there; on a
    box where it fails the LMIs are solved."""
    small = C.ParameterBox.around(AZAIZ, 0.1, omega_max=920.0)
    res, P = C._certify(pi, small, 0.0, False)
    assert res.certified and P is not None
    # the same box: the certificate obviously holds, no solve
    again, P2 = C._certify(pi, small, 0.0, False, guess=P)
    assert again.certified and again.status == "warm start" and P2 is P
    # a P that is not a certificate (indefinite) is rejected and the LMI solved
    bad = -np.eye(P.shape[0])
    solved, P3 = C._certify(pi, small, 0.0, False, guess=bad)
    assert solved.certified and solved.status != "warm start"
    assert np.min(np.linalg.eigvalsh(P3)) > 0


@pytest.mark.slow
@pytest.mark.parametrize("design", ["pi", "hinf"])
def test_prescreen_rejects_only_what_the_solver_rejects(design, request, monkeypatch):
    """A box whose vertex set holds an unstable matrix is declared not certified
    without a solve; on every such box of a scale sweep the solver indeed finds
    no certificate, and a prescreened box is never one the solver certifies.
    The sweep must contain rejected boxes for the test to mean anything.
    (The solves are those of the sweep above, same boxes and same data: run
    after it in one process, they are read back from :data:`_SOLVES`.)"""
    art = request.getfixturevalue(design)
    monkeypatch.setattr(C, "_solve", _solved_once(C._solve))
    rejected = 0
    for box, alpha in _sweep():
        fast, _ = C._certify(art, box, alpha, False, prescreen=True)
        slow, _ = C._certify(art, box, alpha, False)
        if fast.status == "infeasible (unstable vertex)":
            rejected += 1
            assert not slow.certified
        else:
            assert fast.certified == slow.certified
    assert rejected >= 2
