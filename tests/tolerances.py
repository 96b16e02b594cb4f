"""Named tolerances of the tests that compare a number with an independent
route (scipy, slycot, python-control, a closed form, a golden value).

One place, one line of justification each: a library substitution or a
refactoring that changes rounding only must pass these, and a test that needs
a looser one says why here. Byte-identical comparisons are kept only where the
question is determinism (the same inputs on the same machine give the same
bytes), never as the regression rule between two routes.

``eps`` is the double-precision machine epsilon (2.2e-16).
"""

from __future__ import annotations

import numpy as np

EPS = float(np.finfo(float).eps)

#: Two routes through the same formula that only reorder floating-point
#: operations (power-of-two scalings, a product written once instead of via a
#: block matrix, scipy's LAPACK build against numpy's): a few ulps of the
#: largest entry of matrices of order <= ~20.
REORDERED_RTOL = 1e-13

#: Roots, eigenvalues and QZ eigenvalues of small (<= 12) well-separated
#: problems computed by two LAPACK builds or two equivalent pencils:
#: backward-stable, so ~cond * eps with conditions up to ~1e3.
EIG_RTOL = 1e-12

#: Discretisation (expm, bilinear solves) against scipy.signal.cont2discrete
#: with ``dt ||A|| <= ~1``: well-conditioned maps, a few hundred ulps of the
#: largest entry.
C2D_RTOL = 1e-12

#: Frequency response by the modal sum against an LU solve or SLICOT tb05ad:
#: the modal sum loses ~cond(V) eps with cond(V) <= 1e6 (``_MODAL_COND_MAX``
#: of toolbox.lti), i.e. <= ~2e-10; 1e-8 of the largest entry leaves margin.
FRESP_RTOL = 1e-8

#: Frequency responses of two realisations both evaluated by LU solves (the
#: same transfer function): ~cond(jw I - A) eps, <= ~1e-12 on these systems.
FRESP_SOLVE_RTOL = 1e-12

#: State-space interconnections against python-control: the same algebra with
#: solves for the algebraic loop in another order, ~cond(I - D1 D2) eps.
INTERCONNECT_RTOL = 1e-9

#: Polynomial coefficients of ss2tf / tf2ss round trips (np.poly of
#: eigenvalues of order <= 5 with roots spread over ~3 decades).
POLY_RTOL = 1e-9

#: L-infinity norm by SLICOT ab13dd (relative accuracy argument 1e-10) against
#: a second evaluation of the same peak (bounded-real lemma, a grid's maximum
#: refined, or python-control's norm): 1e-9 covers ab13dd's own tolerance.
LINF_RTOL = 1e-9

#: H2 norm by a Lyapunov equation (Bartels-Stewart) against SLICOT ab13bd or a
#: closed form: backward-stable, cond(Lyapunov) eps with cond <= ~1e4.
H2_RTOL = 1e-10

#: Pade coefficients: the same recurrence of exact integer ratios as
#: python-control, one rounding per product.
PADE_RTOL = 1e-13

#: Second-order-section coefficients (products of at most two roots of
#: modulus <= 1.2) of the export's zpk2sos port against scipy.signal: a few
#: ulps of numbers <= ~3, absolute.
SOS_ATOL = 1e-13

#: FFT convolution against scipy.signal.fftconvolve: an FFT's error is
#: ~eps log2(n) relative to the output's norm (n <= 6000 here).
FFT_RTOL = 1e-12

#: Loop margins refined off two frequency grids (1000 against 6000 points, the
#: tangent points' grid against the nominal analysis'): the refinements converge
#: on the same crossings and peaks, measured to 4e-13 on the gallery's laws; the
#: inductance of a linear flux map (central differences) adds ~1e-14.
REFINED_MARGIN_RTOL = 1e-11
