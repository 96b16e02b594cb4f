"""Weight-bound checks of eq (41)-(43) of paper 003: |S| < 1/|w1|, |KS| < 1/|w2|,
|T| < 1/|w3| on a frequency grid (numpy)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..lti import poly_roots, trimmed_coeffs
from ._hinf_plant import _tf_coeffs, _zpk

__all__ = ["WeightBound", "weight_bound_check"]


# --------------------------------------------------------------------------
# weight bounds, eq (41)-(43)
# --------------------------------------------------------------------------
@dataclass
class WeightBound:
    """Worst ratio of a closed-loop function to its bound, eq (41)-(43).

    Attributes
    ----------
    name : str
        ``"S"``, ``"KS"`` or ``"T"``.
    worst_ratio : float
        max over the grid of |F(jw)| |w_i(jw)| (< 1 means the bound holds).
    worst_freq : float
        Frequency of the worst ratio (rad/s).
    """

    name: str
    worst_ratio: float
    worst_freq: float


#: default grid of :func:`weight_bound_check` (rad/s), read-only and built once
_BOUND_GRID = np.logspace(-4, 9, 4000)
_BOUND_GRID.flags.writeable = False


@dataclass(frozen=True, slots=True)
class _Factor:
    """``gain * prod(s - roots)``, the numerator or denominator of a SISO
    response, evaluated with one rounding per factor: as accurate as the
    roots (the synthesis computed the controller's already,
    :func:`fastest_pole_modulus`; a first-order weight's root is one
    division). Measured on paper 003's q-axis controller at 109 of the 4000
    grid points against a 40-digit evaluation of its realisation: relative
    error 5e-15 median, 3e-12 at worst, where the modal sum of
    :meth:`toolbox.lti.StateSpace.evaluate` lost 2e-10 median."""

    gain: float
    roots: list[complex]

    def at(self, s: complex) -> complex:
        """The value at one point (Python complex numbers, :meth:`on_grid`'s order)."""
        v = complex(self.gain)
        for r in self.roots:
            v *= s - r
        return v

    def on_grid(self, s: np.ndarray) -> np.ndarray:
        """The values at the points ``s`` (the operations of :meth:`at`)."""
        v = np.full(s.size, complex(self.gain))
        for r in self.roots:
            v *= s - r
        return v


def _factors(sys: Any) -> tuple[_Factor, _Factor]:
    """Numerator and denominator of a SISO transfer function (ours or
    python-control's: its polynomials' roots, a first-order one's by one
    division), a number, or a state-space system (its zeros, poles and gain,
    :func:`_zpk`)."""
    if (coeffs := _tf_coeffs(sys)) is not None:
        return tuple(_Factor(c[0], poly_roots(np.array(c)).tolist()) for c in map(trimmed_coeffs, coeffs))
    if np.isscalar(sys):
        return _Factor(float(sys), []), _Factor(1.0, [])
    z, p, k = _zpk(sys)
    return _Factor(k, z.tolist()), _Factor(1.0, p.tolist())


#: the closed-loop function of each bound in terms of G = gn/gd and K = kn/kd
#: (1 + G K = c/(gd kd), c = gd kd + gn kn): S = gd kd/c, K S = gd kn/c, T = gn kn/c
_BOUND_FUNCTIONS = {"S": (1, 3), "KS": (1, 2), "T": (0, 2)}


def weight_bound_check(G: Any, K: Any, w1: Any, w2: Any = None, w3: Any = None,
                       freqs: np.ndarray | None = None) -> dict[str, WeightBound]:
    """Check |S| < 1/|w1|, |KS| < 1/|w2|, |T| < 1/|w3| (eq 41-43 of paper 003).

    Every system is a numerator and a denominator ``gain * prod(s - roots)``
    (:class:`_Factor`); the worst grid point of each bound is found by numpy
    (moduli of complex quotients, no squares to leave the floating-point
    range) and the ratio there is evaluated by :meth:`_Factor.at`.

    Parameters
    ----------
    G, K : LTI system (python-control or toolbox.lti)
        Plant (A/V) and controller (V/A).
    w1, w2, w3 : control.LTI or float or None
        Weights; ``None`` skips the function.
    freqs : ndarray, optional
        Grid (rad/s); default 4000 log-spaced points from 1e-4 to 1e9 rad/s,
        which brackets every pole/zero of paper 003's weights (1e-2 .. 1e7).

    Returns
    -------
    dict of str to WeightBound
        Keys ``"S"``, ``"KS"``, ``"T"`` for the weights given.
    """
    w = _BOUND_GRID if freqs is None else np.asarray(freqs, float).ravel()
    loop = [*_factors(G), *_factors(K)]                         # gn, gd, kn, kd
    bounds = {name: _factors(wt) for name, wt in (("S", w1), ("KS", w2), ("T", w3))
              if wt is not None}
    at = _worst_points(w, loop, bounds)
    out = {}
    for name, i in zip(bounds, at):
        s = 1j * float(w[i])
        v = [f.at(s) for f in loop]
        (a, b), (n, d) = _BOUND_FUNCTIONS[name], bounds[name]
        ratio = abs((v[a] * v[b] * n.at(s)) / ((v[1] * v[3] + v[0] * v[2]) * d.at(s)))
        out[name] = WeightBound(name, ratio, float(w[i]))
    return out


def _worst_points(w: np.ndarray, loop: list[_Factor],
                  bounds: dict[str, tuple[_Factor, _Factor]]) -> list[int]:
    """The grid index of each bound's worst ratio ``|w_i F_i(j w)|``."""
    s = 1j * w
    v = [f.on_grid(s) for f in loop]                            # gn, gd, kn, kd
    c = v[1] * v[3] + v[0] * v[2]
    out = []
    for name, (n, d) in bounds.items():
        a, b = _BOUND_FUNCTIONS[name]
        out.append(int(np.abs((v[a] * v[b] * n.on_grid(s)) / (c * d.on_grid(s))).argmax()))
    return out
