"""The toolbox's own linear time-invariant systems (numpy and scipy.linalg only).

``import control`` pulls scipy.signal and matplotlib.pyplot (0.8-1.0 s of
every ``cct design``), while the toolbox needs only a handful of
operations on small systems: this module provides them. python-control stays
the independent route of the tests (``tests/test_lti.py``) and what users may
pass in: :func:`as_statespace` duck-types its ``StateSpace`` and
``TransferFunction`` objects without importing it, and
:meth:`StateSpace.to_control` hands a system back (lazy import).

Conventions follow python-control so that ported code reads the same:

* ``dt is None`` means continuous time; a discrete system has ``dt > 0`` (s).
* ``g2 * g1`` is the series connection "``g1`` then ``g2``", with the states
  of ``g1`` first (python-control's order); ``g1 + g2`` the parallel one
  (states of ``g1`` first); ``feedback(g, h, sign=-1)`` closes
  ``u = r + sign * h y`` around ``g``.
* :func:`c2d` reproduces ``scipy.signal.cont2discrete`` operation by
  operation (the route of ``control.sample_system`` without pre-warping), so
  that discretised laws are the same numbers within rounding.
* Polynomials are coefficient sequences, highest power first.

This package is the face (``__all__``); every other package imports only
these names. The implementation lives in private modules: ``_linalg``
(matrix kernels: balancing, modal form, LAPACK calls, invariant zeros),
``_poly`` (polynomial coefficients), ``_systems`` (:class:`StateSpace`,
:class:`TransferFunction`, interconnections, conversions, frequency
response), ``_c2d`` (discretisation, Pade, Ackermann), ``_minreal`` (minimal
realisation), ``_norms`` (L-infinity norm by SLICOT ab13dd, H2 norm by a
Lyapunov equation), ``_reduction`` (stable/unstable split, balanced
truncation, residualisation) and ``_margins`` (exact margins of a continuous
SISO loop). See ``toolbox/ARCHITECTURE.md`` "The linear-system layer".
"""

from __future__ import annotations

from ._linalg import (balanced, balanced_companion, diagonal_scaling, invariant_zeros,
                      pencil_eigvals)
from ._poly import minreal_coeffs, poly_roots, trimmed_coeffs
from ._systems import (append, as_statespace, evaluate, feedback, parallel, series, ss2tf, ss2zpk,
                       StateSpace, static_gain, tf2ss, TransferFunction)
from ._c2d import acker, c2d, C2D_METHODS, pade
from ._minreal import minreal
from ._margins import LoopMargins, loop_margins, loop_margins_and_poles, MARGIN_BAND
from ._reduction import balanced_truncation, residualise, stable_split
from ._norms import h2_norm, hinf_norm, linf_norm, linf_peak, spectral_norm

__all__ = [
    # systems and interconnections
    "StateSpace", "TransferFunction", "as_statespace", "static_gain", "series", "parallel",
    "feedback", "append",
    # frequency response and norms
    "evaluate", "linf_norm", "linf_peak", "hinf_norm", "h2_norm", "spectral_norm",
    # margins of a continuous SISO loop
    "LoopMargins", "loop_margins", "loop_margins_and_poles", "MARGIN_BAND",
    # realisation and discretisation
    "tf2ss", "ss2tf", "ss2zpk", "minreal", "c2d", "C2D_METHODS", "pade", "acker",
    # model reduction
    "stable_split", "balanced_truncation", "residualise",
    # balancing, zeros, polynomial coefficients
    "balanced", "balanced_companion", "diagonal_scaling", "invariant_zeros", "pencil_eigvals",
    "minreal_coeffs", "trimmed_coeffs", "poly_roots",
]
