"""Per-sample draws of a campaign: deterministic whatever the chunking.

Sample ``i`` draws from its own stream ``numpy.random.SeedSequence([seed, i])``
(PCG64), always in the same order: one standard normal per drawn parameter
(in the order of ``[campaign.parameters]``), then one uniform for the row of
the measured-motor table, then one uniform for the operating point. The
values of a sample therefore depend on ``(seed, i)`` only: not on the chunk
it falls in, nor on the worker that runs it.

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

__all__ = ["draw_samples", "sample_streams"]


def sample_streams(seed: int, indices: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The raw draws of samples ``indices``: ``(Z, U)``.

    ``Z`` is ``(n, k)`` standard normals, ``U`` ``(n, 2)`` uniforms (measured
    row, operating point), each row from ``SeedSequence([seed, i])``.
    """
    n = len(indices)
    Z = np.empty((n, k))
    U = np.empty((n, 2))
    for j, i in enumerate(indices):
        rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, int(i)])))
        Z[j] = rng.standard_normal(k)
        U[j] = rng.random(2)
    return Z, U


def _marginal(p, z: np.ndarray) -> np.ndarray:
    from scipy.special import ndtr
    from scipy.stats import truncnorm

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
    """Drawn values of samples ``start .. stop - 1`` of a campaign.

    Parameters
    ----------
    cfg : toolbox.spec.CampaignCfg
    motor : toolbox.spec.Motor
        The nominal motor (``scale`` draws multiply its values, or the
        measured motor's).
    start, stop : int
        Sample index range.

    Returns
    -------
    dict
        ``sample`` (int64), one column per motor parameter that varies
        (absolute SI values), ``measured_row`` when a measured table is given,
        and one column per axis of the operating-point grid (``speed``,
        ``speed_gain_error``, ``speed_offset``, ``delay_samples``, ``vdc``):
        the sample's point, drawn uniformly from the grid.
    """
    idx = np.arange(start, stop, dtype=np.int64)
    names = [p.name for p in cfg.parameters]
    Z, U = sample_streams(cfg.seed, idx, len(names))
    if cfg.correlation:
        cnames, matrix = cfg.correlation
        cols = [names.index(c) for c in cnames]
        Lc = np.linalg.cholesky(np.array(matrix))
        Z[:, cols] = Z[:, cols] @ Lc.T
    out: dict[str, np.ndarray] = {"sample": idx}
    n = len(idx)
    values = {}
    if cfg.measured_rows:
        rows = np.array(cfg.measured_rows)
        r = np.minimum((U[:, 0] * len(rows)).astype(np.int64), len(rows) - 1)
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
        n_points = cfg.n_operating_points
        k = np.minimum((U[:, 1] * n_points).astype(np.int64), n_points - 1)
        point = {}
        for key, values in reversed(cfg.operating_points):  # mixed radix, last axis fastest
            point[key] = np.array(values)[k % len(values)]
            k = k // len(values)
        out.update((key, point[key]) for key, _values in cfg.operating_points)
    return out
