"""H-infinity design benchmark: ours against python-control's mixsyn and SLICOT.

Problem: paper 003's q-axis mixed-sensitivity design (eq (44)-(46), plant
eq (34)). Routes, timed in one run on the same machine (best of N):

1. ours, whole design: augment, gamma iteration (bisection, tol 1e-4),
   back-off central controller, order reduction to 3 states;
2. python-control ``mixsyn`` (augw + SLICOT sb10ad optimal gamma);
3. ours, one central controller at fixed gamma = 1 vs one SLICOT ``sb10fd``
   call at gamma = 1 (the solver alone).

Run: ``python tests/benchmarks/bench_hinf.py`` from the repository root.
"""

from __future__ import annotations

import os
import sys
import time
import warnings

import control
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

from toolbox.design._hinf_riccati import augment_mixed_sensitivity, central_controller, synthesize  # noqa: E402
from toolbox.design._reduction import reduce_controller  # noqa: E402

G = control.tf([1.0], [2.8e-3, 0.6])
W1 = control.tf([1 / 1.51, 177.3493 / 1.51], [1, 0.0117])
W2 = control.tf([0.5e-3, 0.5], [2e-5, 1])
W3 = control.tf([1e4, 1e4 * 135.68], [1, 2.7135e6])


def best_time(func, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        times.append(time.perf_counter() - t0)
    return min(times)


def ours_full():
    P = augment_mixed_sensitivity(G, W1, W2, W3)
    res = synthesize(P, gamma="optimal", backoff=0.05, sample_time=1e-4)
    return reduce_controller(res.K, order=3)


def theirs_mixsyn():
    return control.mixsyn(G, W1, W2, W3)


def ours_fixed():
    return central_controller(augment_mixed_sensitivity(G, W1, W2, W3), 1.0)


def slicot_fixed():
    from slycot import sb10fd

    P = control.ss(control.augw(G, W1, W2, W3))
    n = P.nstates
    sb10fd(n, P.ninputs, P.noutputs, 1, 1, 1.0, P.A, P.B, P.C, P.D)


def main() -> None:
    warnings.simplefilter("ignore", FutureWarning)
    repeat = 5
    for f in (ours_full, theirs_mixsyn, ours_fixed, slicot_fixed):
        f()  # warm up imports and caches
    t_ours = best_time(ours_full, repeat)
    t_mix = best_time(theirs_mixsyn, repeat)
    t_fix = best_time(ours_fixed, repeat * 4)
    t_sb = best_time(slicot_fixed, repeat * 4)
    print("H-infinity design, paper 003 q axis (best of runs, seconds)")
    print(f"  ours: augment + gamma iteration + back-off + reduction  {t_ours:9.4f} s")
    print(f"  python-control mixsyn (sb10ad, optimal gamma)          {t_mix:9.4f} s")
    print(f"  ratio ours/mixsyn                                       {t_ours / t_mix:9.2f}")
    print(f"  ours: central controller at gamma = 1                   {t_fix * 1e3:9.3f} ms")
    print(f"  SLICOT sb10fd at gamma = 1                              {t_sb * 1e3:9.3f} ms")
    print(f"  ratio ours/sb10fd                                       {t_fix / t_sb:9.2f}")
    K_mix = theirs_mixsyn()[0]
    print(f"  mixsyn's fastest controller pole: {np.min(np.real(control.poles(K_mix))):.3g} rad/s;"
          f" ours (back-off, reduced): "
          f"{np.min(np.real(control.poles(ours_full().K))):.3g} rad/s")


if __name__ == "__main__":
    main()
