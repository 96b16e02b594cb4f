"""Per-row draws of a campaign: deterministic whatever the chunking.

A campaign draws motors and runs each of them at every point of the
operating-point grid (``P`` points, 1 without a grid): row (``sample``) ``i``
is motor ``m = i // P`` at point ``p = i % P`` (mixed radix over the grid's
axes, the last axis fastest). Motor ``m`` draws from its own stream
``numpy.random.SeedSequence([seed, m])`` (PCG64), always in the same order:
one standard normal per drawn parameter (in the order of
``[campaign.parameters]``), then one uniform for the row of the
measured-motor table. The values of a row therefore depend on
``(seed, m, p)`` only: not on the chunk it falls in, nor on the worker that
runs it; and the rows of one motor share its parameters exactly, so that
"this motor passes everywhere" (the per-motor yield) is well defined.

Correlated parameters use a Gaussian copula: the normals of the listed
parameters are multiplied by the Cholesky factor of the correlation matrix,
then each normal ``z`` becomes a draw of its parameter's distribution through
``u = Phi(z)`` (uniform: ``low + (high - low) u``; normal: ``mean + std z``;
truncnormal: the inverse CDF of the truncated normal at ``u``). The rank
correlation between two parameters is therefore set by the matrix, whatever
their marginal distributions.
"""

from __future__ import annotations

import numpy as np

__all__ = ["draw_samples", "sample_streams", "point_values"]


def point_values(cfg, point: int) -> dict:
    """The operating point of grid index ``point``: ``{axis: value}``."""
    out, k = {}, int(point)
    for key, values in reversed(cfg.operating_points):  # mixed radix, last axis fastest
        out[key] = values[k % len(values)]
        k //= len(values)
    return {key: out[key] for key, _values in cfg.operating_points}


def sample_streams(seed: int, motors: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The raw draws of ``motors``: ``(Z, U)``.

    ``Z`` is ``(n, k)`` standard normals, ``U`` ``(n,)`` uniforms (measured
    row), each motor from ``SeedSequence([seed, m])``.
    """
    n = len(motors)
    Z = np.empty((n, k))
    U = np.empty(n)
    for j, m in enumerate(motors):
        rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, int(m)])))
        Z[j] = rng.standard_normal(k)
        U[j] = rng.random()
    return Z, U


def _marginal(p, z: np.ndarray) -> np.ndarray:
    from scipy.special import ndtr  # lazy: scipy.special, 193 modules
    from scipy.stats import truncnorm  # lazy: scipy.stats, 622 modules

    if p.distribution == "normal":
        return p.mean + p.std * z
    u = ndtr(z)
    if p.distribution == "uniform":
        return p.low + (p.high - p.low) * u
    a, b = (p.low - p.mean) / p.std, (p.high - p.mean) / p.std
    # ppf of the far tail is exact enough from the survival side
    x = truncnorm.ppf(u, a, b, loc=p.mean, scale=p.std)
    return np.clip(x, p.low, p.high)


def draw_samples(cfg, motor, start: int, stop: int) -> dict[str, np.ndarray]:
    """Drawn values of rows ``start .. stop - 1`` of a campaign.

    Parameters
    ----------
    cfg : toolbox.spec.CampaignCfg
    motor : toolbox.spec.Motor
        The nominal motor (``scale`` draws multiply its values, or the
        measured motor's).
    start, stop : int
        Row index range.

    Returns
    -------
    dict
        ``sample`` (the row, int64), ``motor`` and ``point`` (int64), one
        column per motor parameter that varies (absolute SI values),
        ``measured_row`` when a measured table is given, and one column per
        axis of the operating-point grid (``speed``, ``speed_gain_error``,
        ``speed_offset``, ``delay_samples``, ``vdc``): the row's point.
    """
    idx = np.arange(start, stop, dtype=np.int64)
    n_points = cfg.n_operating_points
    motor_of, point_of = idx // n_points, idx % n_points
    motors, which = np.unique(motor_of, return_inverse=True)
    names = [p.name for p in cfg.parameters]
    Zm, Um = sample_streams(cfg.seed, motors, len(names))
    Z, U = Zm[which], Um[which]
    if cfg.correlation:
        cnames, matrix = cfg.correlation
        cols = [names.index(c) for c in cnames]
        Lc = np.linalg.cholesky(np.array(matrix))
        Z[:, cols] = Z[:, cols] @ Lc.T
    out: dict[str, np.ndarray] = {"sample": idx, "motor": motor_of, "point": point_of}
    n = len(idx)
    values = {}
    if cfg.measured_rows:
        rows = np.array(cfg.measured_rows)
        r = np.minimum((U * len(rows)).astype(np.int64), len(rows) - 1)
        out["measured_row"] = r
        for j, c in enumerate(cfg.measured_columns):
            values[c] = rows[r, j]
    for j, p in enumerate(cfg.parameters):
        x = _marginal(p, Z[:, j])
        base = values.get(p.name, np.full(n, float(getattr(motor, p.name))))
        values[p.name] = base * x if p.mode == "scale" else x
    for name in sorted(values):
        out[name] = np.asarray(values[name], dtype=float)
    if cfg.operating_points:
        k = point_of.copy()
        point = {}
        for key, values in reversed(cfg.operating_points):  # mixed radix, last axis fastest
            point[key] = np.array(values)[k % len(values)]
            k = k // len(values)
        out.update((key, point[key]) for key, _values in cfg.operating_points)
    return out
