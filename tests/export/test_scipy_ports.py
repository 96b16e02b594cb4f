"""The export's ports of scipy.signal routines against scipy.signal itself.

``cct design`` writes the header without importing scipy.signal (~0.4 s):
second-order sections (``zpk2sos``, nearest pairing) and the FFT
convolution of the fixed-point bound are ported. scipy.signal is the
independent route; the ports may round differently, so the numbers are
compared within the named tolerances of ``tests/tolerances.py``: the
sections' coefficients within ``SOS_ATOL`` absolute, the convolution within
``FFT_RTOL`` of its largest value. The pairing itself (which roots share a section) is
structure, and shows as the coefficients.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.fft
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.tolerances import FFT_RTOL, SOS_ATOL
from toolbox.export._fixed import _fftconvolve
from toolbox.export._sos import zpk2sos_nearest


def _roots(rng: np.random.Generator, n: int) -> np.ndarray:
    """n roots in and around the unit disc: conjugate pairs, reals, zeros."""
    out: list[complex] = []
    while len(out) < n:
        if n - len(out) >= 2 and rng.random() < 0.5:
            c = rng.uniform(0.0, 1.2) * np.exp(1j * rng.uniform(0.01, 3.1))
            out += [c, np.conj(c)]
        else:
            out.append(rng.uniform(-1.2, 1.2) if rng.random() < 0.9 else 0.0)
    arr = np.array(out)
    return arr if np.iscomplexobj(arr) and np.any(arr.imag) else arr.real


@pytest.mark.parametrize("seed", range(300))
def test_zpk2sos_nearest_equals_scipy(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 8))
    z, p = _roots(rng, n), _roots(rng, n)
    ref = scipy.signal.zpk2sos(z, p, 1.0, pairing="nearest")
    got = zpk2sos_nearest(z, p)
    assert got.shape == ref.shape
    assert np.allclose(got, ref, rtol=0.0, atol=SOS_ATOL)


def test_zpk2sos_nearest_on_repeated_and_unit_circle_roots():
    z = np.array([-1.0, -1.0, 1.0, 0.5 + 0.5j, 0.5 - 0.5j])
    p = np.array([1.0, 0.9, 0.9, 0.3 + 0.6j, 0.3 - 0.6j])
    ref = scipy.signal.zpk2sos(z, p, 1.0, pairing="nearest")
    assert np.allclose(zpk2sos_nearest(z, p), ref, rtol=0.0, atol=SOS_ATOL)


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 3000), st.integers(1, 3000), st.integers(0, 2**31 - 1))
def test_fftconvolve_equals_scipy(na, nb, seed):
    rng = np.random.default_rng(seed)
    a, b = rng.random(na), rng.random(nb)
    ref = scipy.signal.fftconvolve(a, b)
    got = _fftconvolve(a, b)
    assert got.shape == ref.shape
    assert np.allclose(got, ref, rtol=0.0, atol=FFT_RTOL * np.abs(ref).max())
