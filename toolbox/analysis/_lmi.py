"""Feasibility LMIs handed to Clarabel directly, and constraint generation.

Shared by the continuous certificate (:mod:`toolbox.analysis.certificate`)
and the sampled-loop certificate (:mod:`toolbox.analysis._sampled_certificate`):
both search a Lyapunov matrix ``P`` (plus, for the sampled one, an
S-procedure multiplier) that makes one LMI per polytope vertex hold. cvxpy's
canonicalisation of these constant-data problems cost more than the solve
(and a second of import), so the problems are written in Clarabel's form
here with numpy, once per box, and the vertex LMIs are solved by constraint
generation (:func:`solve_by_constraint_generation`).

Clarabel's form: find ``x`` with ``b - A x`` in a product of cones. An LMI
``D + sum_k x_k C_k >> 0`` (``d x d``) is the PSD-triangle cone constraint
with ``b = svec(D)`` and ``A = -[svec(C_1) ... svec(C_K)]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["ACTIVE_STEP", "STATUS", "above_identity", "lmi_rows", "problem_data",
           "solve_by_constraint_generation", "solve_feasibility", "svec_index", "symmetric_basis",
           "symmetric_matrix"]

#: Clarabel status -> the status names reported (those cvxpy gave them, so that
#: analysis.json reads as before).
STATUS = {"Solved": "optimal", "AlmostSolved": "optimal_inaccurate",
          "PrimalInfeasible": "infeasible", "AlmostPrimalInfeasible": "infeasible_inaccurate",
          "DualInfeasible": "unbounded", "AlmostDualInfeasible": "unbounded_inaccurate",
          "MaxIterations": "user_limit", "MaxTime": "user_limit"}

#: Vertices added to the active set per round of :func:`solve_by_constraint_generation`.
ACTIVE_STEP = 8


def svec_index(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and weights of Clarabel's ``svec`` of an n x n symmetric
    matrix: the upper triangle column by column, off-diagonal entries times
    sqrt(2) (so that ``svec(X) . svec(Y) = trace(X Y)``)."""
    rows, cols = zip(*[(i, j) for j in range(n) for i in range(j + 1)])
    rows, cols = np.array(rows), np.array(cols)
    return rows, cols, np.where(rows == cols, 1.0, math.sqrt(2.0))


def symmetric_basis(n: int) -> np.ndarray:
    """The 0/1 symmetric basis ``E_k`` (m, n, n) of the upper triangle row by row:
    the variables cvxpy made of a symmetric matrix (a scaling Clarabel's
    equilibration handles on stiff loops where an orthonormal basis stalls)."""
    ui, uj = np.triu_indices(n)
    E = np.zeros((ui.size, n, n))
    E[np.arange(ui.size), ui, uj] = 1.0
    E[np.arange(ui.size), uj, ui] = 1.0
    return E


def symmetric_matrix(x: np.ndarray, n: int) -> np.ndarray:
    """The symmetric matrix ``sum_k x_k E_k`` of :func:`symmetric_basis`."""
    ui, uj = np.triu_indices(n)
    P = np.zeros((n, n))
    P[ui, uj] = x
    P[uj, ui] = x
    return P


def lmi_rows(D: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clarabel rows of the LMIs ``D_j + sum_k x_k C_jk >> 0``.

    ``D`` (J, d, d), ``C`` (J, K, d, d) -> ``A`` (J, s, K), ``b`` (J, s) with
    ``s = d (d + 1) / 2``: one PSD-triangle block per LMI, so that a subset of
    LMIs is a subset of blocks.
    """
    rows, cols, w = svec_index(D.shape[-1])
    return -np.swapaxes(C[..., rows, cols] * w, -1, -2), D[..., rows, cols] * w


def above_identity(n: int, n_x: int) -> tuple[np.ndarray, np.ndarray]:
    """Clarabel rows ``(A (s, n_x), b (s,))`` of ``P >> I``, ``P`` (n x n) the
    symmetric matrix of the first ``n (n + 1) / 2`` unknowns (the
    normalisation of a Lyapunov matrix: its LMIs are homogeneous in ``P``)."""
    E = symmetric_basis(n)
    C = np.zeros((1, n_x, n, n))
    C[0, :E.shape[0]] = E
    A, b = lmi_rows(-np.eye(n)[None], C)
    return A[0], b[0]


def problem_data(blocks: Sequence[tuple[np.ndarray, np.ndarray]], n_x: int,
                 nonneg: Sequence[int] = ()):
    """``(A, b, cones)`` of Clarabel for ``x_i >= 0`` (``i`` in ``nonneg``) and
    the PSD blocks ``(A_j (s_j, n_x), b_j (s_j,))`` of :func:`lmi_rows`, in
    that order."""
    import clarabel  # lazy: the conic solver (compiled), only for certificates

    A = [-np.eye(n_x)[list(nonneg)]] if len(nonneg) else []
    b = [np.zeros(len(nonneg))] if len(nonneg) else []
    cones = [clarabel.NonnegativeConeT(len(nonneg))] if len(nonneg) else []
    for Aj, bj in blocks:
        A.append(Aj)
        b.append(bj)
        d = int(round((math.sqrt(8 * bj.size + 1) - 1) / 2))
        cones.append(clarabel.PSDTriangleConeT(d))
    return np.vstack(A), np.concatenate(b), cones


def solve_feasibility(A: np.ndarray, b: np.ndarray, cones) -> tuple[np.ndarray | None, str]:
    """Solve ``b - A x`` in ``cones`` with a zero objective, Clarabel's default
    settings (those cvxpy used). Returns ``(x, status)``; ``x`` is None
    unless the solver reports (almost) solved."""
    import clarabel  # lazy: the conic solver (compiled), only for certificates
    from scipy import sparse  # lazy: scipy.sparse, only for certificates

    n_x = A.shape[1]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(sparse.csc_matrix((n_x, n_x)), np.zeros(n_x),
                                    sparse.csc_matrix(A), b, cones, settings)
    sol = solver.solve()
    status = STATUS.get(str(sol.status), f"solver error: Clarabel {sol.status}")
    if status not in ("optimal", "optimal_inaccurate"):
        return None, status
    return np.asarray(sol.x, float), status


def solve_by_constraint_generation(solve: Callable[[list[int]], tuple[object, str]],
                                   slack: Callable[[object], np.ndarray], order: np.ndarray,
                                   margin: float = 0.0, step: int = ACTIVE_STEP):
    """Solve the LMIs of all vertices through those of a few (constraint generation).

    The LMIs of the first ``step`` vertices of ``order`` (those most likely
    binding: the most violated by a rejected warm start, else the least
    stable) are solved; the vertices whose LMI the solution violates
    (``slack >= -margin``) are added, most violated first, and so on, until
    the solution holds on every vertex (the certificates' boxes
    need a tenth to a fifth of their vertices, and a solve costs about
    linearly in the vertices). A subset the solver proves infeasible has no
    solution for all vertices either (status ``"infeasible"``). Any other
    failure on a subset (an inaccurate status, a numerical error: a few
    vertices leave ``P`` poorly bounded) or a solution violating only
    vertices already in the set (solver tolerance) ends in the solve over
    all vertices, whose verdict it then is; a subset's solution is returned
    only when it holds on every vertex.

    Parameters
    ----------
    solve : callable
        ``solve(indices) -> (solution or None, status)`` on a subset of vertices.
    slack : callable
        ``slack(solution) -> (N,)`` largest eigenvalue of each vertex LMI
        (negative: holds).
    order : array of int
        All N vertex indices, the most likely binding first.
    margin : float
        A vertex's LMI holds when its slack is below ``-margin``.
    step : int
        Vertices added per round.
    """
    n = len(order)
    active = [int(i) for i in order[:step]]
    while len(active) < n:
        sol, status = solve(active)
        if status == "infeasible":      # a subset without solution: none for all
            return sol, status
        if sol is None:
            break
        s = slack(sol)
        if not np.any(s >= -margin):
            return sol, status
        new = [int(i) for i in np.argsort(-s) if s[i] >= -margin and i not in active]
        if not new:
            break
        active += new[:step]
    return solve(list(range(n)))
