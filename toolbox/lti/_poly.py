"""Polynomial coefficients of :mod:`toolbox.lti`'s transfer functions: trimming,
roots, pole-zero cancellation and the companion realisation's arrays.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def trimmed_coeffs(coeffs: Any) -> list[float]:
    """The coefficients of a polynomial as Python floats without leading zeros
    (zero -> ``[0.0]``): the small transfer functions of a design need no array."""
    p = np.asarray(coeffs, dtype=float).reshape(-1).tolist()
    i = next((k for k, c in enumerate(p) if c), None)
    return [0.0] if i is None else p[i:]


def _poly(coeffs: Any) -> np.ndarray:
    """:func:`trimmed_coeffs` as a fresh 1-D float array."""
    return np.array(trimmed_coeffs(coeffs))


def poly_roots(p: np.ndarray) -> np.ndarray:
    """Roots of a trimmed polynomial; a first-order one without ``np.roots``'s
    companion-matrix eigenvalues (weights are mostly first-order)."""
    if p.size <= 1:
        return np.zeros(0, complex)
    if p.size == 2:
        return np.array([-p[1] / p[0]], complex)
    return np.roots(p)


#: Relative distance below which a pole and a zero of a
#: :class:`TransferFunction` cancel (python-control's ``minreal`` default).
_CANCEL_TOL = float(np.sqrt(np.finfo(float).eps))


def minreal_coeffs(num: np.ndarray, den: np.ndarray,
                    tol: float = _CANCEL_TOL) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`TransferFunction.minreal` on trimmed coefficients: the same
    ``num`` and ``den`` objects when nothing cancels, else new trimmed ones
    (the H-infinity augmentation realises four transfer functions per axis
    and needs no object of them)."""
    if num.size == 1 or den.size == 1:
        return num, den                        # no zero or no pole: nothing to cancel
    if num.size == 2 and den.size == 2:        # one zero, one pole (most weights): scalars
        (n0, n1), (d0, d1) = num.tolist(), den.tolist()
        z, p = -n1 / n0, -d1 / d0               # the roots poly_roots gives, as floats
        return (num[:1], den[:1]) if abs(p - z) <= tol * max(1.0, abs(z)) else (num, den)
    zeros = list(poly_roots(num)) if num.any() else []
    poles = list(poly_roots(den))
    kept = []
    for z in zeros:
        near = [i for i, p in enumerate(poles) if abs(p - z) <= tol * max(1.0, abs(z))]
        if near:
            poles.pop(min(near, key=lambda i: abs(poles[i] - z)))
        else:
            kept.append(z)
    if len(kept) == len(zeros):
        return num, den
    return (_poly(num[0] * np.real(np.poly(kept)) if kept else num[:1]),
            _poly(den[0] * np.real(np.poly(poles))))


def _tf2ss_arrays(num: np.ndarray, den: np.ndarray) -> tuple[np.ndarray, ...]:
    """A, B, C, D of :func:`tf2ss` for trimmed 1-D float polynomials (no
    system object: the H-infinity augmentation realises four transfer
    functions per axis and keeps only the arrays)."""
    if not den.any():
        raise ValueError("tf2ss: zero denominator")
    if num.size > den.size:
        raise ValueError(f"tf2ss: improper transfer function (numerator degree "
                         f"{num.size - 1} > denominator degree {den.size - 1})")
    num = np.concatenate([np.zeros(den.size - num.size), num]) / den[0]
    den = den / den[0]
    n = den.size - 1
    D = np.array([[num[0]]])
    A = np.zeros((n, n))
    A[:1] = -den[1:]                                # the first row (none when n = 0)
    A.reshape(-1)[n::n + 1] = 1.0                   # the subdiagonal (a view)
    B = np.zeros((n, 1))
    B[:1] = 1.0
    C = (num[1:] - num[0] * den[1:]).reshape(1, n)
    return A, B, C, D
