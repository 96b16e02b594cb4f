"""The analysis's scalar root and bounded minimum (toolbox/analysis/_scalar.py)
against SciPy's, the independent route they are ported from: the same
operations in the same order, so the same floating-point results (bit for
bit: this is a determinism-grade check of a port, not a tolerance)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq, minimize_scalar

from toolbox.analysis._scalar import bounded_minimum, brentq


def _functions(n: int, seed: int = 0):
    """Smooth test functions with several extrema and roots on [-3, 3]."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        c = [float(v) for v in rng.normal(size=5)]
        lo, hi = sorted(float(v) for v in rng.uniform(-3.0, 3.0, 2))
        yield (lambda x, c=c: c[0] + c[1] * x + c[2] * math.sin(3 * x) + c[3] * x ** 3
               + c[4] * math.exp(-x * x)), lo, hi


def test_roots_equal_scipy():
    n = 0
    for f, _, _ in _functions(400):
        if f(-3.0) * f(3.0) < 0:
            for tol in ({"xtol": 1e-13, "rtol": 1e-13}, {}):
                assert brentq(f, -3.0, 3.0, **tol) == scipy_brentq(f, -3.0, 3.0, **tol)
            n += 1
    assert n > 300


def test_bounded_minima_equal_scipy():
    for f, lo, hi in _functions(400, seed=1):
        for xatol in (1e-10, 1e-5):
            res = minimize_scalar(f, bounds=(lo, hi), method="bounded",
                                  options={"xatol": xatol})
            assert bounded_minimum(f, lo, hi, xatol=xatol) == (res.x, res.fun)


def test_refusals_as_scipy():
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="rtol too small"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-17)
    assert brentq(lambda x: x, 0.0, 1.0) == 0.0          # a bound that is a root
