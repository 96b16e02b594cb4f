"""H-infinity design benchmark: ours against python-control's mixsyn and SLICOT.

Problem: paper 003's q-axis mixed-sensitivity design (eq (44)-(46), plant
eq (34)). Routes, timed alternately in one run on the same machine (A B A B,
medians; each ratio with the interquartile range of its per-round values):

1. ours, whole design: augment, gamma iteration (bisection, tol 1e-4),
   back-off central controller, order reduction to 3 states;
2. python-control ``mixsyn`` (augw + SLICOT sb10ad optimal gamma);
3. ours, one central controller at fixed gamma = 1 vs one SLICOT ``sb10fd``
   call at gamma = 1, each on its augmented plant built beforehand (the
   solvers alone: neither ``control.augw`` nor our augmentation is timed).

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

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

from toolbox.design._hinf_riccati import augment_mixed_sensitivity, central_controller, synthesize  # noqa: E402
from toolbox.design._reduction import reduce_controller  # noqa: E402

G = control.tf([1.0], [2.8e-3, 0.6])
W1 = control.tf([1 / 1.51, 177.3493 / 1.51], [1, 0.0117])
W2 = control.tf([0.5e-3, 0.5], [2e-5, 1])
W3 = control.tf([1e4, 1e4 * 135.68], [1, 2.7135e6])


def ours_full():
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
    for f in (ours_full, theirs_mixsyn, ours_fixed, slicot_fixed):
        f()  # warm up imports and caches
    design = interleaved({"ours": ours_full, "mixsyn": theirs_mixsyn}, rounds=15)
    fixed = interleaved({"ours": ours_fixed, "sb10fd": slicot_fixed}, rounds=60)
    print("H-infinity design, paper 003 q axis (alternating runs: median [IQR])")
    print(f"  ours: augment + gamma iteration + back-off + reduction  "
          f"{fmt_time(design['ours'], 1e3, 'ms')}")
    print(f"  python-control mixsyn (augw + sb10ad, optimal gamma)   "
          f"{fmt_time(design['mixsyn'], 1e3, 'ms')}")
    print(f"  ratio ours/mixsyn: {fmt_ratio(design['ours'], design['mixsyn'])}")
    print(f"  ours: central controller alone at gamma = 1            "
          f"{fmt_time(fixed['ours'], 1e3, 'ms')}")
    print(f"  SLICOT sb10fd alone at gamma = 1                       "
          f"{fmt_time(fixed['sb10fd'], 1e3, 'ms')}")
    print(f"  ratio ours/sb10fd: {fmt_ratio(fixed['ours'], fixed['sb10fd'])}")
    K_mix = theirs_mixsyn()[0]
    print(f"  mixsyn's fastest controller pole: {np.min(np.real(control.poles(K_mix))):.3g} rad/s;"
          f" ours (back-off, reduced): "
          f"{np.min(np.real(control.poles(ours_full().K))):.3g} rad/s")


if __name__ == "__main__":
    main()
