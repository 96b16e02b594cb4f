"""The certificate's LMIs assembled once, with a warm-started bisection (issue 13).

The reference is the plain bisection of before issue 13: a fresh cvxpy problem
and a cold solve at every scale. The bisection grid is dyadic (scales k/2^m),
so the certified scales are compared *exactly*: any change in a single
feasibility verdict moves the scale by at least ``tol/2``.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis_helpers import AZAIZ, DRIVE
from toolbox.analysis import certificate as C
from toolbox.plant import max_electrical_speed


def _reference_scale(art, motor, drive, *, tol: float, alpha: float = 0.0) -> float:
    """Bisection with a constant-data cvxpy problem per scale (no re-use, no warm start)."""
    wmax = max_electrical_speed(motor, drive)

    def ok(k: float) -> bool:
        box = C.ParameterBox.around(motor, k, omega_max=wmax)
        return C._certify(art, box, alpha, False, problems=None, guess=None)[0].certified

    if ok(1.0):
        return 1.0
    if not ok(0.0):
        return 0.0
    lo, hi = 0.0, 1.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


@pytest.mark.parametrize("alpha", [0.0, 200.0])
def test_same_scale_as_cold_bisection(pi, alpha, monkeypatch):
    """Assembled-once + warm start gives exactly the scale of the cold bisection,
    and builds one problem per vertex count (64 vertices, 1 at the nominal point)."""
    ref = _reference_scale(pi, AZAIZ, DRIVE, tol=0.05, alpha=alpha)
    built: list[tuple[int, int]] = []
    init = C._Lmi.__init__

    def counting(self, n_vertices, n, *args, **kwargs):
        built.append((n_vertices, n))
        init(self, n_vertices, n, *args, **kwargs)

    monkeypatch.setattr(C._Lmi, "__init__", counting)
    res = C.largest_certified_scale(pi, AZAIZ, DRIVE, tol=0.05, alpha=alpha)
    assert res.scale == ref
    assert sorted(built) == sorted(set(built)) and len(built) <= 2


def test_warm_start_is_used_and_checked(pi):
    """A P certified on a small box is re-used on a slightly larger one (no solve,
    status "warm start") only when the a posteriori check passes there; on a
    box where it fails the LMIs are solved."""
    small = C.ParameterBox.around(AZAIZ, 0.1, omega_max=920.0)
    res, P = C._certify(pi, small, 0.0, False, {})
    assert res.certified and P is not None
    # the same box: the certificate obviously holds, no solve
    again, P2 = C._certify(pi, small, 0.0, False, {}, guess=P)
    assert again.certified and again.status == "warm start" and P2 is P
    # a P that is not a certificate (indefinite) is rejected and the LMI solved
    bad = -np.eye(P.shape[0])
    solved, P3 = C._certify(pi, small, 0.0, False, {}, guess=bad)
    assert solved.certified and solved.status != "warm start"
    assert np.min(np.linalg.eigvalsh(P3)) > 0
