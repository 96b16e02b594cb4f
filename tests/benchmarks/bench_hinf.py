"""H-infinity design benchmark: ours against python-control's mixsyn and SLICOT.

Problem: paper 003's mixed-sensitivity design (q axis eq (44)-(46), plant
eq (34); d axis eq (47)-(49)). Routes, timed alternately in one run on the
same machine (A B A B, process CPU time, see ``_timing``); each ratio is the
median of the per-round ratios with its interquartile range:

1. ours, one axis, everything :func:`toolbox.design.hinf.design_hinf_axis`
   does: augment, gamma iteration (bisection, tol 1e-4), back-off until the
   controller is realisable at Ts = 1e-4 s, recomputed closed-loop norm,
   weight-bound check (eq 41-43, 4000 frequencies), reduction to 3 states
   and the margins of the full and reduced loops;
2. ours, the whole design stage for both axes (``toolbox.design.hinf.design``
   on ``designs/003_azaiz2007_hinf_optimal.toml``, spec read beforehand):
   both axes as in 1, discretisation and the artifact;
3. ours, synthesis only: augment, gamma iteration, back-off, reduction;
4. python-control ``mixsyn`` (augw + SLICOT sb10ad at the optimal gamma, no
   back-off, reduction, norm check or margins), the reference of 1-3;
5. ours, one central controller at fixed gamma = 1 vs one SLICOT ``sb10fd``
   call at gamma = 1, each on its augmented plant built beforehand (the
   solvers alone: neither ``control.augw`` nor our augmentation is timed).
   Ours includes the A1-A4 checks, balancing and normalisation at every call
   (as sb10fd does its own), and returns a ``toolbox.lti.StateSpace``.

Routes 1-4 are timed one call per route and round, so each call follows
another route's work: that is how a design runs in ``cct`` (once, after
reading the spec). A call of ~2 ms then finds the core's caches holding the
previous route's code and data. Measured (after the same ``mixsyn``
call): route 1 takes ~0.5-0.8 ms (30-50 %) more than when repeated, where a
2-3 ms loop of small numpy operations or of pure Python pays 1-2 %; a 20 ms
sleep costs route 1 as much as ``mixsyn`` does; re-running the twelve LAPACK
drivers it calls (dgees, dggev, dsyevd, ...) between ``mixsyn`` and route 1
recovers ~0.08 ms of it. The rest is the footprint of its Python and numpy
code paths. Routes 1 and 4 are therefore also timed with ten calls in a row
per round ("warm": what a sweep over many designs sees, and what ``timeit``
reports), both routes alike.

Run: ``python tests/benchmarks/bench_hinf.py`` from the repository root.
"""

from __future__ import annotations

import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _timing import fmt_ratio, fmt_time, interleaved, pin_blas_threads  # noqa: E402

pin_blas_threads(1)  # tiny matrices: threads only add variance (before numpy)

import control  # noqa: E402
import numpy as np  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, ROOT)

from toolbox.design import hinf  # noqa: E402
from toolbox.design._hinf_gamma import synthesize  # noqa: E402
from toolbox.design._hinf_plant import augment_mixed_sensitivity  # noqa: E402
from toolbox.design._hinf_riccati import central_controller  # noqa: E402
from toolbox.design._reduction import reduce_controller  # noqa: E402
from toolbox.spec import load_spec  # noqa: E402

G = control.tf([1.0], [2.8e-3, 0.6])
W1 = control.tf([1 / 1.51, 177.3493 / 1.51], [1, 0.0117])
W2 = control.tf([0.5e-3, 0.5], [2e-5, 1])
W3 = control.tf([1e4, 1e4 * 135.68], [1, 2.7135e6])
SPEC = os.path.join(ROOT, "designs", "003_azaiz2007_hinf_optimal.toml")


def ours_axis():
    return hinf.design_hinf_axis(G, W1, W2, W3, gamma="optimal", backoff=0.05,
                                 sample_time=1e-4, reduce_order=3)


def ours_design_setup():
    spec = load_spec(SPEC)
    return lambda: hinf.design(spec)


def ours_synthesis():
    P = augment_mixed_sensitivity(G, W1, W2, W3)
    res = synthesize(P, gamma="optimal", backoff=0.05, sample_time=1e-4)
    return reduce_controller(res.K, order=3)


def theirs_mixsyn():
    return control.mixsyn(G, W1, W2, W3)


def ours_fixed_setup():
    """Our central controller at gamma = 1 on an augmented plant built beforehand
    (the solver alone, like sb10fd below)."""
    P = augment_mixed_sensitivity(G, W1, W2, W3)
    return lambda: central_controller(P, 1.0)


def slicot_fixed_setup():
    """The augmented plant for sb10fd, built once outside the timing."""
    P = control.ss(control.augw(G, W1, W2, W3))
    args = (P.nstates, P.ninputs, P.noutputs, 1, 1, 1.0, P.A, P.B, P.C, P.D)

    def call():
        from slycot import sb10fd

        sb10fd(*args)

    return call


def main() -> None:
    warnings.simplefilter("ignore", FutureWarning)
    slicot_fixed = slicot_fixed_setup()
    ours_fixed = ours_fixed_setup()
    ours_design = ours_design_setup()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")        # mixsyn's near-singular optimum
        for f in (ours_axis, ours_design, ours_synthesis, theirs_mixsyn, ours_fixed,
                  slicot_fixed):
            f()  # warm up imports and caches
        design = interleaved({"axis": ours_axis, "design": ours_design,
                              "synthesis": ours_synthesis, "mixsyn": theirs_mixsyn},
                             rounds=15)
        warm = interleaved({"axis": ours_axis, "mixsyn": theirs_mixsyn}, rounds=15, repeat=10)
        fixed = interleaved({"ours": ours_fixed, "sb10fd": slicot_fixed}, rounds=30, repeat=20)
    ms = lambda v: fmt_time(v, 1e3, "ms")  # noqa: E731
    print("H-infinity design, paper 003 (alternating runs, process CPU time: median [IQR])")
    print(f"  ours, q axis: synthesis + norm check + weight bounds + reduction + margins "
          f"{ms(design['axis'])}")
    print(f"  ours, design stage, both axes (d and q as above + artifact)              "
          f"{ms(design['design'])}")
    print(f"  ours, q axis: synthesis only (augment, gamma iteration, back-off, reduction) "
          f"{ms(design['synthesis'])}")
    print(f"  python-control mixsyn, q axis (augw + sb10ad at the optimum, nothing else) "
          f"{ms(design['mixsyn'])}")
    print(f"  ratio ours/mixsyn, q axis everything:  {fmt_ratio(design['axis'], design['mixsyn'], 3)}")
    print(f"  warm (10 calls in a row per round): ours q axis everything {ms(warm['axis'])}, "
          f"mixsyn {ms(warm['mixsyn'])}")
    print(f"  ratio ours/mixsyn, q axis everything, warm: "
          f"{fmt_ratio(warm['axis'], warm['mixsyn'], 3)}")
    print(f"  ratio ours/mixsyn, both axes stage:    {fmt_ratio(design['design'], design['mixsyn'])}")
    print(f"  ratio ours/mixsyn, q synthesis only:   "
          f"{fmt_ratio(design['synthesis'], design['mixsyn'])}")
    print(f"  ours: central controller alone at gamma = 1 (with checks, _lti system out) "
          f"{ms(fixed['ours'])}")
    print(f"  SLICOT sb10fd alone at gamma = 1                                          "
          f"{ms(fixed['sb10fd'])}")
    print(f"  ratio ours/sb10fd: {fmt_ratio(fixed['ours'], fixed['sb10fd'])}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        K_mix = theirs_mixsyn()[0]
    print(f"  mixsyn's fastest controller pole: {np.min(np.real(control.poles(K_mix))):.3g} rad/s;"
          f" ours (back-off, reduced): "
          f"{np.min(np.real(control.poles(ours_synthesis().K))):.3g} rad/s")


if __name__ == "__main__":
    main()
