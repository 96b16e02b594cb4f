"""The ``[campaign]`` table: a Monte-Carlo robustness campaign.

Read here, with the spec stage's conventions (unknown keys are errors with
the key path and a did-you-mean, every value range-checked); executed by
:mod:`toolbox.campaign`. The table says how to draw the true plants of the
campaign's samples; the scenarios and the pass/fail bounds are the spec's
own ``[[scenario]]`` tables and ``[requirements]``.

Layout (README.md "Campaigns")::

    [campaign]
    motors = 1000             # drawn motors, each run at every operating point
    # samples = 18000         # or: rows (motor x point); give one of the two
    seed = 7                  # motor m draws from SeedSequence([seed, m])
    chunk_size = 500          # rows per task / per Parquet file
    scenarios = ["i_q step"]  # names of [[scenario]] tables (default: all)
    min_yield = 0.99          # exit 1 when the gated yield's 95 % lower bound is below
    gate = "per_sample"       # per_sample | per_motor | per_point

    [campaign.parameters.R]   # one table per motor parameter drawn
    distribution = "uniform"  # uniform | normal | truncnormal
    low = 1.0                 # uniform, truncnormal
    high = 1.4
    # mean, std               # normal, truncnormal
    mode = "scale"            # scale (x nominal, default) | value (SI)

    [campaign.operating_points]   # a grid: every motor runs at every point
    speed = [0.0, 100.0]      # rad/s (mechanical): the scenarios' initial speed
    speed_gain_error = [-0.02, 0.0, 0.02]   # speed sensor (scenario keys)
    speed_offset = [0.0, 2.0] # rad/s
    delay_samples = [1, 2]    # the drive's computation delay (the design keeps its own)
    vdc = [140.0, 150.0]      # V

    [campaign.correlation]    # Gaussian copula between drawn parameters
    parameters = ["R", "flux"]
    matrix = [[1.0, -0.5], [-0.5, 1.0]]

    [campaign.measured]       # a table of measured motors: one row per sample
    columns = ["R", "Ld", "Lq", "flux"]
    rows = [[0.61, 1.41e-3, 2.79e-3, 0.121], ...]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import SpecError
from ._fields import Table
from ._datasheet import MOTOR_KINDS
from ._model import MOTOR_PARAMETER_KEYS

__all__ = ["CampaignCfg", "ParameterDist", "read_campaign", "CAMPAIGN_PARAMETERS",
           "DISTRIBUTIONS", "GATES", "MAX_SAMPLES", "OPERATING_POINT_KEYS"]

#: Motor parameters a campaign may draw (pole pairs are not a spread).
CAMPAIGN_PARAMETERS = tuple(k for k in MOTOR_PARAMETER_KEYS if k != "pole_pairs")
DISTRIBUTIONS = ("uniform", "normal", "truncnormal")
#: Largest campaign (samples) a spec may ask for.
MAX_SAMPLES = 100_000_000
MAX_MEASURED_ROWS = 100_000
#: Parameters that must stay > 0 (the others, flux and friction, >= 0).
_POSITIVE = ("R", "Ld", "Lq", "J")
#: A normal draw is refused when its mean lies within this many standard
#: deviations of the physical bound (0): use truncnormal instead.
_NORMAL_SIGMAS = 6.0
CAMPAIGN_KEYS = ("samples", "motors", "seed", "chunk_size", "operating_points", "scenarios",
                 "min_yield", "gate", "parameters", "correlation", "measured")
#: What ``min_yield`` gates on (the 95 % Wilson lower bound of): the share
#: of passing rows, of motors passing at every point, of the worst point.
GATES = ("per_sample", "per_motor", "per_point")
#: ``[campaign.operating_points]`` keys, in the order of the grid's axes.
OPERATING_POINT_KEYS = ("speed", "speed_gain_error", "speed_offset", "delay_samples", "vdc")
MAX_OPERATING_POINTS = 100_000
_DIST_KEYS = {"uniform": ("low", "high"), "normal": ("mean", "std"),
              "truncnormal": ("mean", "std", "low", "high")}


@dataclass(frozen=True)
class ParameterDist:
    """The distribution of one drawn motor parameter.

    Attributes
    ----------
    name : str
        Motor parameter (one of :data:`CAMPAIGN_PARAMETERS`).
    distribution : str
        ``uniform`` (``low``, ``high``), ``normal`` (``mean``, ``std``) or
        ``truncnormal`` (``mean``, ``std`` truncated to ``[low, high]``).
    mode : str
        ``scale`` (the draw multiplies the nominal value, or the measured
        motor's) or ``value`` (the draw is the value, SI).
    """

    name: str
    distribution: str
    mode: str = "scale"
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = None


@dataclass(frozen=True)
class CampaignCfg:
    """A validated ``[campaign]`` table (module docstring).

    Attributes
    ----------
    samples : int
        Rows (closed-loop runs): row ``i`` is motor ``i // P`` at grid point
        ``i % P`` (``P``: :attr:`n_operating_points`); ``motors x P`` when
        ``motors`` is given.
    seed, chunk_size : int
    parameters : tuple of ParameterDist
        In the order written (the order of the per-sample normal draws).
    correlation : tuple
        ``(names, matrix)`` of the Gaussian copula, or ``()``.
    measured_columns : tuple of str
    measured_rows : tuple of tuple of float
    operating_points : tuple
        ``((key, values), ...)`` in the order of :data:`OPERATING_POINT_KEYS`:
        the axes of the operating-point grid; ``()`` keeps each scenario's and
        the drive's own values.
    scenarios : tuple of str
        Scenario names to run (``()``: every scenario of the spec).
    min_yield : float or None
    gate : str
        One of :data:`GATES`.
    """

    samples: int
    seed: int
    chunk_size: int
    parameters: tuple = ()
    correlation: tuple = ()
    measured_columns: tuple = ()
    measured_rows: tuple = ()
    operating_points: tuple = ()
    scenarios: tuple = ()
    min_yield: float | None = None
    gate: str = "per_sample"

    @property
    def n_motors(self) -> int:
        """Motors drawn (the last one incomplete when ``samples`` is not a
        multiple of the grid size)."""
        return -(-self.samples // self.n_operating_points)

    @property
    def complete_motors(self) -> int:
        """Motors run at every point of the grid (the per-motor yield's count)."""
        return self.samples // self.n_operating_points

    @property
    def n_operating_points(self) -> int:
        """Points of the operating-point grid (1 when none is given)."""
        n = 1
        for _key, values in self.operating_points:
            n *= len(values)
        return n

    @property
    def n_chunks(self) -> int:
        """Number of chunks (tasks, Parquet files)."""
        return -(-self.samples // self.chunk_size)


def _parameter(name: str, value: Any) -> ParameterDist:
    key = f"campaign.parameters.{name}"
    t = Table(value, key)
    dist = t.string("distribution", choices=DISTRIBUTIONS)
    t = Table(value, key, ("distribution", "mode") + _DIST_KEYS[dist])
    mode = t.string("mode", "scale", choices=("scale", "value"))
    # drawn values (mode "value") may carry the parameter's unit ("20 mohm")
    kind = MOTOR_KINDS.get(name) if mode == "value" else None
    nums = {k: t.number(k, kind=kind) for k in _DIST_KEYS[dist]}
    if "std" in nums and not nums["std"] > 0:
        raise SpecError(f"{key}.std", "a number > 0", nums["std"])
    if "low" in nums and not nums["high"] > nums["low"]:
        raise SpecError(f"{key}.high", f"a number > low ({nums['low']:g})", nums["high"])
    lowest = nums["low"] if "low" in nums else nums["mean"] - _NORMAL_SIGMAS * nums["std"]
    positive = name in _POSITIVE or mode == "scale"
    if (lowest <= 0) if positive else (lowest < 0):
        bound = "> 0" if positive else ">= 0"
        if dist == "normal":
            raise SpecError(f"{key}.mean", f"a mean at least {_NORMAL_SIGMAS:g} std above 0 "
                            f"(draws must stay {bound})", nums["mean"],
                            hint='use distribution = "truncnormal" with low ' + bound)
        raise SpecError(f"{key}.low", f"a number {bound} (a physical {name}"
                        + (" scale factor" if mode == "scale" else "") + ")", nums["low"])
    return ParameterDist(name=name, distribution=dist, mode=mode, **nums)


def _correlation(value: Any, drawn: tuple[str, ...]) -> tuple:
    t = Table(value, "campaign.correlation", ("parameters", "matrix"))
    names = t.raw("parameters")
    if (not isinstance(names, list) or len(names) < 2
            or not all(isinstance(n, str) for n in names)):
        raise SpecError("campaign.correlation.parameters",
                        "a list of at least two parameter names", names)
    for n in names:
        if n not in drawn:
            raise SpecError("campaign.correlation.parameters",
                            "names of [campaign.parameters.*] tables ("
                            + ", ".join(drawn) + ")", n)
    if len(set(names)) != len(names):
        raise SpecError("campaign.correlation.parameters", "distinct names", names)
    import numpy as np  # only when a correlation is given

    k = len(names)
    rows = t.raw("matrix")
    if not isinstance(rows, list) or len(rows) != k:
        raise SpecError("campaign.correlation.matrix", f"a {k} x {k} matrix (list of rows)",
                        rows)
    sub = Table({f"row{i}": r for i, r in enumerate(rows)}, "campaign.correlation.matrix")
    m = np.array([sub.numbers(f"row{i}", length=k) for i in range(k)])
    if not np.allclose(m, m.T, atol=1e-12) or not np.allclose(np.diag(m), 1.0, atol=1e-12):
        raise SpecError("campaign.correlation.matrix",
                        "a symmetric matrix with ones on the diagonal", rows)
    if np.any(np.abs(m) > 1) or np.min(np.linalg.eigvalsh(m)) <= 1e-10:
        raise SpecError("campaign.correlation.matrix",
                        "a positive definite correlation matrix (entries in [-1, 1])", rows)
    return (tuple(names), tuple(tuple(float(x) for x in r) for r in m))


def _measured(value: Any, drawn: dict[str, ParameterDist]) -> tuple[tuple, tuple]:
    t = Table(value, "campaign.measured", ("columns", "rows"))
    cols = t.raw("columns")
    if (not isinstance(cols, list) or not cols
            or not all(isinstance(c, str) and c in CAMPAIGN_PARAMETERS for c in cols)
            or len(set(cols)) != len(cols)):
        raise SpecError("campaign.measured.columns", "a list of distinct motor parameters ("
                        + ", ".join(CAMPAIGN_PARAMETERS) + ")", cols)
    for c in cols:
        if c in drawn and drawn[c].mode == "value":
            raise SpecError(f"campaign.parameters.{c}.mode", '"scale" for a measured column '
                            "(the draw multiplies the measured value)", "value")
    rows = t.raw("rows")
    if not isinstance(rows, list) or not rows:
        raise SpecError("campaign.measured.rows", "a non-empty list of rows", rows)
    if len(rows) > MAX_MEASURED_ROWS:
        raise SpecError("campaign.measured.rows", f"at most {MAX_MEASURED_ROWS} rows",
                        f"{len(rows)} rows")
    out = []
    for i, r in enumerate(rows):
        row = Table({f"rows[{i}]": r}, "campaign.measured").numbers(f"rows[{i}]",
                                                                     length=len(cols))
        for c, v in zip(cols, row):
            if (v <= 0) if c in _POSITIVE else (v < 0):
                raise SpecError(f"campaign.measured.rows[{i}]",
                                f"physical values ({c} {'> 0' if c in _POSITIVE else '>= 0'})",
                                list(r))
        out.append(row)
    return tuple(cols), tuple(out)


def _operating_points(value: Any) -> tuple:
    t = Table(value, "campaign.operating_points", OPERATING_POINT_KEYS)
    out, n = [], 1
    for key in OPERATING_POINT_KEYS:
        if not t.has(key):
            continue
        if key == "delay_samples":
            raw = t.raw(key)
            if (not isinstance(raw, list) or not raw or not all(
                    isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 10 for v in raw)):
                raise SpecError(t.key(key), "a non-empty list of integers in 0 .. 10", raw)
            values = tuple(int(v) for v in raw)
        else:
            unit, kind = {"speed": ("rad/s", "speed"), "speed_offset": ("rad/s", "speed"),
                          "vdc": ("V", None)}.get(key, ("", None))
            values = t.numbers(key, min_length=1, max_length=1000, unit=unit, kind=kind)
            if key == "vdc" and min(values) <= 0:
                raise SpecError(t.key(key), "DC-link voltages > 0 (V)", list(values))
            if key == "speed_gain_error" and min(values) <= -1:
                raise SpecError(t.key(key), "sensor gain errors > -1", list(values))
        if len(set(values)) != len(values):
            raise SpecError(t.key(key), "distinct values", list(values))
        n *= len(values)
        out.append((key, values))
    if n > MAX_OPERATING_POINTS:
        raise SpecError("campaign.operating_points", f"at most {MAX_OPERATING_POINTS} "
                        "points (the product of the list lengths)", n)
    return tuple(out)


def read_campaign(value: Any) -> CampaignCfg:
    """Validate a ``[campaign]`` table.

    Parameters
    ----------
    value : mapping
        The table as TOML gives it.

    Returns
    -------
    CampaignCfg

    Raises
    ------
    SpecError
        Naming the ``campaign.*`` key path (unknown keys with a did-you-mean).

    Examples
    --------
    >>> cfg = read_campaign({"samples": 100, "seed": 1,
    ...     "parameters": {"R": {"distribution": "uniform", "low": 1.0, "high": 1.4}}})
    >>> cfg.n_chunks, cfg.parameters[0].high
    (1, 1.4)
    """
    t = Table(value, "campaign", CAMPAIGN_KEYS)
    points = (_operating_points(t.raw("operating_points"))
              if t.has("operating_points") else ())
    n_points = 1
    for _key, values in points:
        n_points *= len(values)
    if t.has("motors") == t.has("samples"):
        raise SpecError("campaign.motors", "one of motors (drawn motors, each run at every "
                        "operating point) or samples (rows)",
                        hint="both given" if t.has("motors") else "none given")
    if t.has("motors"):
        motors = t.integer("motors", minimum=1, maximum=MAX_SAMPLES // n_points)
        samples = motors * n_points
    else:
        samples = t.integer("samples", minimum=1, maximum=MAX_SAMPLES)
    seed = t.integer("seed", minimum=0, maximum=2**63 - 1)
    chunk_size = t.integer("chunk_size", min(samples, 500), minimum=1, maximum=1_000_000)
    gate = t.string("gate", "per_sample", choices=GATES)
    params_t = t.table("parameters", CAMPAIGN_PARAMETERS)
    params = tuple(_parameter(n, v) for n, v in params_t.data.items())
    drawn = {p.name: p for p in params}
    correlation = (_correlation(t.raw("correlation"), tuple(drawn))
                   if t.has("correlation") else ())
    cols, rows = _measured(t.raw("measured"), drawn) if t.has("measured") else ((), ())
    if not params and not rows:
        raise SpecError("campaign.parameters", "at least one drawn parameter or a "
                        "[campaign.measured] table (nothing varies)")
    scen = t.raw("scenarios", [])
    if not isinstance(scen, list) or not all(isinstance(s, str) for s in scen):
        raise SpecError("campaign.scenarios", "a list of scenario names", scen)
    min_yield = t.number("min_yield", None, minimum=0.0, maximum=1.0)
    return CampaignCfg(samples=samples, seed=seed, chunk_size=chunk_size, parameters=params,
                       correlation=correlation, measured_columns=cols, measured_rows=rows,
                       operating_points=points, scenarios=tuple(scen),
                       min_yield=min_yield, gate=gate)
