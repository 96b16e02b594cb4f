"""The closed-form ZOH of the 2x2 dq plant stays finite for a stiff plant.

``exp(m T) cosh(D T)`` underflowed to 0 x inf = NaN when L/R is far below the
sample time (``motor.R = 1e4`` or ``drive.sample_time = 1.0`` with the box
corners R x2, L x0.5 of the MIMO analysis), and ``numpy.linalg.eigvals`` of
the coupled loop then raised ``LinAlgError``. The exponents are now added
first where the product form fails; elsewhere the bits are unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from toolbox.analysis._statespace import zoh_2x2, zoh_coupled


def _plant(R, Ld, Lq, w):
    A = np.array([[-R / Ld, w * Lq / Ld], [-w * Ld / Lq, -R / Lq]])
    B = np.diag([1 / Ld, 1 / Lq])
    return A[None], B[None]


@pytest.mark.parametrize("R, Ld, Lq, w, Ts", [
    (2e4, 0.7e-3, 1.4e-3, 0.0, 1e-4),      # motor.R = 1e4 at the box corner
    (2e4, 0.7e-3, 1.4e-3, 3e3, 1e-4),
    (1.2, 0.7e-3, 5.6e-3, 1e3, 1.0),       # drive.sample_time = 1 s
    (1.2, 0.7e-3, 5.6e-3, 0.0, 1.0),
])
def test_stiff_plant_is_finite_and_matches_the_matrix_exponential(R, Ld, Lq, w, Ts):
    A, B = _plant(R, Ld, Lq, w)
    Phi, Gam = zoh_2x2(A, B, Ts)
    assert np.all(np.isfinite(Phi)) and np.all(np.isfinite(Gam))
    Phi_ref, Gam_ref = zoh_coupled(A, B, Ts)
    assert np.allclose(Phi, Phi_ref, atol=1e-12)
    assert np.allclose(Gam, Gam_ref, rtol=1e-9, atol=1e-12)


def test_ordinary_plant_keeps_its_bits():
    """The fallback is used only where the product form is not finite."""
    A, B = _plant(0.6, 1.4e-3, 2.8e-3, 500.0)
    Phi, Gam = zoh_2x2(A, B, 1e-4)
    m = 0.5 * (A[:, 0, 0] + A[:, 1, 1])
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    x = np.sqrt((m * m - det).astype(complex)) * 1e-4
    c0 = np.real(np.exp(m * 1e-4) * np.cosh(x))
    assert Phi[0, 0, 0] == c0[0] + np.real(np.exp(m * 1e-4) * 1e-4 * np.sinh(x) / x)[0] * (
        A[0, 0, 0] - m[0])
