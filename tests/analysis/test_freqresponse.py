"""Vectorised frequency response (toolbox.analysis.FreqResponse; toolbox/ARCHITECTURE.md
"The linear-system layer").

Every path is compared with the per-point LU solve of ``freqresp`` (what the
H-infinity weight check and the loop margins used before): the modal sum for
a well-conditioned A, the LU fall-back for a nearly defective A, one point,
and a point on a pole.
"""

import numpy as np
import pytest

from toolbox.analysis import FreqResponse
from toolbox.analysis._statespace import freqresp

W = np.logspace(-3, 8, 3000)


def _rel_err(a, b):
    return np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300))


def test_modal_sum_matches_lu():
    """Poles over four decades, a complex pair, 2x3: the modal sum is used and
    agrees with LU within 1e-10 (cond(V) * eps with cond(V) <= 1e6 is the bound
    the class documents; the LU reference itself is good to ~cond(sI - A) * eps
    ~ 1e-12 here, so the spread is kept moderate: with poles from 1e-2 to 3e6
    the LU answer, not the modal one, loses 7 digits at low frequency)."""
    rng = np.random.default_rng(3)
    lam = np.array([-0.5, -3.0, -145.0, -2.4e3, -1e4])
    T = rng.standard_normal((5, 5))
    A = T @ np.diag(lam) @ np.linalg.inv(T)
    A[1:3, 1:3] = [[-50.0, 400.0], [-400.0, -50.0]]           # a lightly damped pair
    B, C, D = rng.standard_normal((5, 3)), rng.standard_normal((2, 5)), rng.standard_normal((2, 3))
    fr = FreqResponse(A, B, C, D)
    assert fr.modal is not None
    got = fr(1j * W)
    assert got.shape == (W.size, 2, 3)
    assert _rel_err(got, freqresp(A, B, C, D, 1j * W)) <= 1e-10


def test_nearly_defective_matrix_keeps_the_lu_solve():
    """A Jordan-like block (cond(V) ~ 1e16) must not use the modal sum."""
    A = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0], [0.0, 0.0, -1.0 - 1e-12]])
    B, C, D = np.ones((3, 1)), np.array([[1.0, 0.0, 0.0]]), np.zeros((1, 1))
    fr = FreqResponse(A, B, C, D)
    assert fr.modal is None
    assert _rel_err(fr(1j * W), freqresp(A, B, C, D, 1j * W)) <= 1e-14


def test_single_point_and_pole():
    A, B, C, D = np.array([[0.0]]), np.array([[1.0]]), np.array([[2.0]]), np.array([[0.5]])
    fr = FreqResponse(A, B, C, D)
    assert fr(np.array([2j]))[0, 0, 0] == pytest.approx(2.0 / 2j + 0.5, rel=1e-15)
    assert not np.isfinite(fr(np.array([0.0, 1j]))[0, 0, 0])    # 1/s at s = 0 (grid)


def test_static_gain():
    fr = FreqResponse(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[3.0]]))
    assert np.all(fr(1j * W[:5]) == 3.0)
