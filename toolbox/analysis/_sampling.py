"""Parameter sets of the robustness analyses: nominal point, box corners, Latin hypercube.

Shared by the robustness sweep (:mod:`toolbox.analysis.robustness`), the
coupled-loop box analysis (:func:`toolbox.analysis.margins.mimo_over_box`)
and the robust PI tuner's model set (``toolbox.design.robust_pi``); it
imports no other analysis module, so each of them can use it.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["DEFAULT_RANGES", "DEFAULT_BOX", "latin_hypercube", "sample_parameters"]

#: name -> (low, high, kind): "scale" multiplies the nominal value
#: (log-uniform), "offset" is an absolute value (uniform), "int" a count.
DEFAULT_RANGES: dict[str, tuple] = {
    "R": (0.5, 2.0, "scale"),
    "Ld": (0.5, 2.0, "scale"),
    "Lq": (0.5, 2.0, "scale"),
    "flux": (0.8, 1.2, "scale"),
    "speed_gain": (0.9, 1.1, "scale"),
    "speed_offset": (-10.0, 10.0, "offset"),   # rad/s mechanical
    "delay_samples": (0, 1, "int"),            # periods added to the design's delay
}


def latin_hypercube(n: int, d: int, seed: int) -> np.ndarray:
    """``n`` points of a scrambled Latin hypercube in ``[0, 1)^d`` (n, d).

    Each column puts one point in each of the ``n`` strata ``[(k-1)/n, k/n)``,
    at a uniform position inside it, the strata permuted independently per
    column (McKay, Beckman, Conover 1979). The same draws in the same order
    as ``scipy.stats.qmc.LatinHypercube(d, seed=seed).random(n)`` (tested
    equal), without importing scipy.stats (0.5 to 1 s of every ``cct``
    process).
    """
    rng = np.random.default_rng(seed)
    u = rng.uniform(size=(n, d))
    perms = np.tile(np.arange(1, n + 1), (d, 1))
    for row in perms:
        rng.shuffle(row)
    return (perms.T - u) / n


def sample_parameters(ranges: dict, n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Nominal point, box corners and a Latin hypercube of ``n`` sets.

    Returns ``{name: array}`` with scale factors (``scale``), offsets
    (``offset``) or integers (``int``); nominal is 1, 0 or the lower integer.
    """
    names = list(ranges)
    k = len(names)
    corners = np.array(np.meshgrid(*[[0.0, 1.0]] * k, indexing="ij")).reshape(k, -1).T
    u = latin_hypercube(n, k, seed) if n > 0 else np.zeros((0, k))
    nominal = []
    for name in names:
        lo, hi, kind = ranges[name]
        if kind == "scale":
            nominal.append((math.log(1.0) - math.log(lo)) / (math.log(hi) - math.log(lo))
                           if lo <= 1 <= hi and hi > lo else 0.0)
        elif kind == "offset":
            nominal.append((0 - lo) / (hi - lo) if lo <= 0 <= hi and hi > lo else 0.0)
        else:
            nominal.append(0.0)
    U = np.vstack([np.array(nominal)[None, :], corners, u])
    out = {}
    for j, name in enumerate(names):
        lo, hi, kind = ranges[name]
        x = U[:, j]
        if kind == "scale":
            out[name] = np.exp(math.log(lo) + x * (math.log(hi) - math.log(lo)))
        elif kind == "offset":
            out[name] = lo + x * (hi - lo)
        else:
            out[name] = np.minimum(np.floor(lo + x * (hi - lo + 1)), hi).astype(int)
    return out


#: The R, Ld, Lq part of :data:`DEFAULT_RANGES` as ``{name: (low, high)}`` scale factors:
#: the box of the coupled-loop analysis and of the robust PI tuner.
DEFAULT_BOX: dict[str, tuple] = {k: DEFAULT_RANGES[k][:2] for k in ("R", "Ld", "Lq")}
