"""Unit tests for toolbox.design._weights (weighting filters of paper 003, eq 44-49)."""

import numpy as np
import pytest
import control as ct

from toolbox.lti import TransferFunction
from toolbox.design._weights import makeweight, validate_weight, weight_from_tf, weight_from_zpk
from toolbox.errors import SpecError

KEY = "controller.hinf.weights.q.w1"


def mag(w, freq):
    return float(abs(complex(w(1j * freq))))


def test_from_tf_returns_transfer_function():
    w = weight_from_tf([1e4, 1.3568e6], [1, 2.7135e6], key=KEY)
    assert isinstance(w, TransferFunction)      # toolbox.lti's: no python-control needed
    # DC gain 1e4 * 135.68 / 2.7135e6 = 0.5 (exact to the 5 digits given)
    assert mag(w, 0.0) == pytest.approx(0.5, rel=1e-4)


def test_leading_zeros_are_dropped():
    w = weight_from_tf([0, 0, 2.0], [0, 1, 3.0])
    assert mag(w, 0.0) == pytest.approx(2.0 / 3.0)


def test_from_zpk_matches_tf():
    a = weight_from_zpk([-177.3493], [-0.0117], 1 / 1.51)
    b = weight_from_tf([1 / 1.51, 177.3493 / 1.51], [1, 0.0117])
    for f in (1e-3, 1.0, 156.0, 1e5):
        assert mag(a, f) == pytest.approx(mag(b, f), rel=1e-12)


def test_zpk_conjugate_pairs_required():
    with pytest.raises(SpecError) as err:
        weight_from_zpk([], [-1 + 2j], 1.0, key=KEY)
    assert "conjugate" in str(err.value)
    w = weight_from_zpk([], [-1 + 2j, -1 - 2j], 5.0)
    assert mag(w, 0.0) == pytest.approx(1.0)


@pytest.mark.parametrize("dc, wc, mc, hf, order", [
    (1e4, 156.0, 1.0, 1 / 1.51, 1),     # sensitivity weight, eq (44)-like
    (0.5, 235.0, 1.0, 1e4, 1),          # complementary weight, eq (46)-like
    (100.0, 10.0, 1.0, 0.1, 2),
])
def test_makeweight_gains(dc, wc, mc, hf, order):
    w = makeweight(dc, wc, mc, hf, order=order, key=KEY)
    # exact by construction; 1e-9 covers rounding and the 1e-12 rad/s "DC" point
    assert mag(w, 1e-12 * wc) == pytest.approx(dc, rel=1e-9)
    assert mag(w, wc) == pytest.approx(mc, rel=1e-9)
    assert mag(w, 1e12 * wc) == pytest.approx(hf, rel=1e-6)
    assert np.all(np.real(w.poles()) < 0)


def test_makeweight_rejects_bad_gains():
    with pytest.raises(SpecError) as err:
        makeweight(1.0, 10.0, 2.0, 0.5, key=KEY)
    assert err.value.key == f"{KEY}.crossover_gain"
    with pytest.raises(SpecError):
        makeweight(float("nan"), 10.0, 1.0, 0.5)
    with pytest.raises(SpecError):
        makeweight(10.0, -1.0, 1.0, 0.5)
    with pytest.raises(SpecError):
        makeweight(10.0, 1.0, 1.0, 0.5, order=0)


def test_improper_weight_rejected():
    with pytest.raises(SpecError) as err:
        weight_from_tf([1, 2, 3], [1, 4], key=KEY)
    assert err.value.key == KEY
    assert "proper" in str(err.value)


def test_pole_at_zero_rejected_with_remedy():
    with pytest.raises(SpecError) as err:
        weight_from_tf([1, 177.3493], [1, 0], key=KEY)
    text = str(err.value)
    assert "s = 0" in text and "small negative value" in text


def test_unstable_weight_rejected():
    with pytest.raises(SpecError):
        weight_from_tf([1], [1, -3])


def test_nan_rejected():
    with pytest.raises(SpecError) as err:
        weight_from_tf([1, float("nan")], [1, 2], key=KEY)
    assert err.value.key == f"{KEY}.num"


def test_validate_weight_allows_integrator_when_asked():
    w = TransferFunction([1, 1], [1, 0])
    assert validate_weight(w, allow_integrator=True) is w
    # a user's python-control weight is read into the toolbox's form, unchanged
    got = validate_weight(ct.tf([1, 1], [1, 0]), allow_integrator=True)
    assert (got.num.tolist(), got.den.tolist()) == ([1.0, 1.0], [1.0, 0.0])
