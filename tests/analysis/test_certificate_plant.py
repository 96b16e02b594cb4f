"""The certificate's parameter-affine model is the plant's model (one dq model,
toolbox/ARCHITECTURE.md "Parameters and models"): its coordinates ``theta``
are the entries of the sympy-derived
:class:`toolbox.plant.ElectricalPlant` ``A(omega)``, ``B`` with the artifact's
decoupling ``W = g omega [[0, -Lq_c], [Ld_c, 0]]`` folded in, not a second
hand-typed dq model.
"""

import numpy as np
import pytest

from toolbox.analysis import certificate as C
from toolbox.artifact import Decoupling
from toolbox.plant import numeric_plant
from toolbox.spec import Motor

#: The two routes compute each coordinate with at most three roundings in a
#: different order (lambdified sympy vs. closed form), i.e. a few ulps
#: (~1e-15 relative); 1e-13 leaves a margin of ~100 while a wrong sign or a
#: missing term (relative error O(1)) fails at once.
RTOL = 1e-13

RNG = np.random.default_rng(11)


def _points(n: int = 40) -> np.ndarray:
    """Random (R, Ld, Lq, omega, g) of plausible motors, both speed signs."""
    return np.column_stack([RNG.uniform(0.01, 5.0, n), RNG.uniform(1e-4, 0.05, n),
                            RNG.uniform(1e-4, 0.05, n), RNG.uniform(-3000, 3000, n),
                            RNG.uniform(0.8, 1.2, n)])


def _decoupling(cross: bool) -> Decoupling:
    return Decoupling(cross=cross, emf=True, R_c=0.6, Ld_c=1.4e-3, Lq_c=2.8e-3,
                      flux_c=0.12, pole_pairs=4)


def _symbolic_entries(point, dec: Decoupling, convention: str):
    """``A``, ``B`` and the decoupled ``M = A + B W`` from the sympy route."""
    R, Ld, Lq, om, g = point
    plant = numeric_plant(Motor(R=R, Ld=Ld, Lq=Lq, flux=0.1, pole_pairs=4, J=1e-3,
                                convention=convention))
    h = (1.0 if dec.cross else 0.0) * g * om
    W = h * np.array([[0.0, -dec.Lq_c], [dec.Ld_c, 0.0]])
    A, B = plant.A(om), plant.B()
    return A, B, A + B @ W, h


@pytest.mark.parametrize("cross", [True, False])
@pytest.mark.parametrize("convention", ["amplitude", "power"])
def test_theta_is_read_off_the_derived_plant(cross, convention):
    """theta = (B_dd, B_qq, -M_dd, -M_qq, M_dq, -M_qd), M = A + B W (module
    docstring of toolbox.analysis.certificate)."""
    dec = _decoupling(cross)
    pts = _points()
    theta = C._theta(pts, dec)
    for k, p in enumerate(pts):
        _, B, M, _ = _symbolic_entries(p, dec, convention)
        ref = [B[0, 0], B[1, 1], -M[0, 0], -M[1, 1], M[0, 1], -M[1, 0]]
        np.testing.assert_allclose(theta[k], ref, rtol=RTOL, atol=0)


@pytest.mark.parametrize("cross", [True, False])
def test_delay_theta_is_read_off_the_derived_plant(cross):
    """The nine Pade-model coordinates: the plant entries, then h B_dd, h B_qq, h
    with h = cross g omega."""
    dec = _decoupling(cross)
    pts = _points()
    theta = C._theta_delay(pts, dec)
    for k, p in enumerate(pts):
        A, B, _, h = _symbolic_entries(p, dec, "amplitude")
        ref = [B[0, 0], B[1, 1], -A[0, 0], -A[1, 1], A[0, 1], -A[1, 0],
               h * B[0, 0], h * B[1, 1], h]
        np.testing.assert_allclose(theta[k], ref, rtol=RTOL, atol=0)


def test_theta_sees_the_decoupling():
    """The comparison can fail: without the W term the speed coordinates differ
    by ``g omega Lq_c / Ld`` (here tens of percent), far beyond RTOL."""
    pts = _points(5)
    with_w = C._theta(pts, _decoupling(True))
    without = C._theta(pts, _decoupling(False))
    np.testing.assert_array_equal(with_w[:, :4], without[:, :4])
    rel = np.abs(with_w[:, 4:] - without[:, 4:]) / np.abs(without[:, 4:])
    assert np.all(rel > 1e3 * RTOL)
