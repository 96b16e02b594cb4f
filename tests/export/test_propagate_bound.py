"""The quantisation error bound of the exported recursion stays an upper bound
and costs O(N log N): at sample_time = 1e-7 the 20 ms horizon is 2e5 periods and
the direct double sum made `cct design` run for hours (qa: sample_time 1e-7)."""

import numpy as np
import pytest

from toolbox.export._fixed import propagate_bound

A = np.array([[0.9, 0.1, 0.0], [0.0, 0.8, 0.05], [0.01, 0.0, 0.95]])
C = np.array([[1.0, -2.0, 0.5]])


def _direct(dx, dy):
    N, n = dx.shape
    out, P, g = dy.copy(), np.eye(n), []
    for _ in range(N):
        g.append(np.abs(C[0]) @ np.abs(P))
        P = P @ A
    for k in range(1, N):
        out[k] += sum(g[k - 1 - i] @ dx[i] for i in range(k))
    return out


def test_bound_matches_the_direct_sum_from_above():
    rng = np.random.default_rng(0)
    dx, dy = rng.random((300, 3)) * 1e-6, rng.random(300) * 1e-7
    direct, fast = _direct(dx, dy), propagate_bound(A, C, dx, dy)
    assert np.all(fast >= direct)
    assert np.max((fast - direct) / direct) < 1e-6


@pytest.mark.slow
def test_long_horizon_reaches_the_stationary_bound():
    """2e5 periods (the horizon that ran for hours): with unit local errors the
    bound tends to 1 + sum_j |C| |A^j| 1, summed here directly over 3000 terms
    (spectral radius of A < 0.96: the tail is below 1e-50). The bound may
    exceed it by its stated FFT widening, 1e-12 max|g| sum|delta_x| (about
    1.2e-6 here), plus 1e-9 relative for the convolution's own rounding."""
    N = 200_000
    out = propagate_bound(A, C, np.ones((N, 3)), np.ones(N))
    total, P, g_max = 1.0, np.eye(3), 0.0
    for _ in range(3000):
        g = np.abs(C[0]) @ np.abs(P)
        total += float(g.sum())
        g_max = max(g_max, float(g.max()))
        P = P @ A
    widening = 1e-12 * g_max * 3 * N
    assert np.all(np.isfinite(out))
    assert total * (1 - 1e-9) <= out[-1] <= total * (1 + 1e-9) + widening
