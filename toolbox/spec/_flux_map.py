"""Saturated motors in a spec: ``[motor] flux_map = "file.csv"`` and
``[motor.saturation]`` (toolbox/ARCHITECTURE.md "Saturated motors").

Flux-map CSV format (the table FEA tools and dynamometer tests export): a
header row naming the four columns ``i_d, i_q, psi_d, psi_q`` in any order,
each optionally with its unit in brackets (``i_d [A]``, ``psi_d [mWb]``;
currents ``A`` or ``kA``, fluxes ``V s``/``Vs``/``Wb`` or ``mWb``/``mVs``;
no unit: A and V s), then one row per grid point. The points form a complete
rectangular grid over the distinct i_d and i_q values (any row order);
``psi_d`` increases strictly with ``i_d`` at every ``i_q`` and ``psi_q``
with ``i_q`` at every ``i_d`` (positive incremental self-inductances). Lines
starting with ``#`` are comments. The path is relative to the spec file.
"""

from __future__ import annotations

import csv
import hashlib
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import SpecError
from ._magnetics import AlgebraicSaturation, FluxMapData, MagneticModel

__all__ = ["read_flux_map", "read_saturation", "SATURATION_KEYS"]

_UNITS = {"i": {"a": 1.0, "ka": 1e3},
          "psi": {"vs": 1.0, "v s": 1.0, "v*s": 1.0, "v·s": 1.0, "wb": 1.0,
                  "mwb": 1e-3, "mvs": 1e-3, "mv s": 1e-3}}
_COLUMNS = ("i_d", "i_q", "psi_d", "psi_q")

#: ``[motor.saturation]`` keys: the algebraic model's parameters
#: (``toolbox.spec.AlgebraicSaturation``) and ``current_range`` (A), the
#: current amplitude the simulator's flux table covers.
SATURATION_KEYS = ("a_d0", "a_dd", "S", "a_q0", "a_qq", "T", "a_dq", "U", "V", "a_b",
                   "a_bp", "k_q", "psi_n", "W", "current_range", "source")
_REQUIRED = ("a_d0", "a_dd", "S", "a_q0", "a_qq", "T", "a_dq", "U", "V", "current_range")


def _header(cells: list[str], where: str) -> tuple[list[int], list[float]]:
    """Column order and SI factors of the header row."""
    index, factor = {}, {}
    for j, cell in enumerate(cells):
        name, _, unit = cell.strip().partition("[")
        name = name.strip().lower()
        if name not in _COLUMNS:
            raise SpecError(where, "columns i_d, i_q, psi_d, psi_q (units in [brackets] "
                            "optional)", cell.strip())
        unit = unit.rstrip("] ").strip().lower()
        table = _UNITS[name.split("_")[0]]
        if unit and unit not in table:
            raise SpecError(f"{where} column {name}", "a unit of " + ", ".join(table), unit)
        index[name] = j
        factor[name] = table[unit] if unit else 1.0
    missing = [c for c in _COLUMNS if c not in index]
    if missing:
        raise SpecError(where, "columns i_d, i_q, psi_d, psi_q", "missing " + ", ".join(missing))
    return [index[c] for c in _COLUMNS], [factor[c] for c in _COLUMNS]


def read_flux_map(value: Any, base: Path | None, key: str = "motor.flux_map"):
    """Read and validate a flux-map CSV (module docstring).

    Parameters
    ----------
    value : str
        The spec's path string, relative to ``base`` (the spec file's folder;
        the working directory when None).
    base : Path or None
    key : str
        Key path named in errors.

    Returns
    -------
    toolbox.spec.MagneticModel
        ``kind="map"`` over the grid (SI).

    Raises
    ------
    SpecError
        Unreadable file, bad header, a non-number (file, line and column),
        an incomplete grid, non-monotone flux; each naming the file and line.
    """
    if not isinstance(value, str) or not value:
        raise SpecError(key, "a path to a CSV file (string)", value)
    path = Path(value)
    if not path.is_absolute():
        path = (base or Path.cwd()) / path
    where = f"{key} ({path})"
    try:
        raw = path.read_bytes()
        text = raw.decode("utf-8")
    except (OSError, UnicodeError) as err:
        raise SpecError(key, "a readable UTF-8 CSV file", f"{path}: {err}") from None
    rows = [(n, r) for n, r in enumerate(csv.reader(text.splitlines()), 1)
            if r and not r[0].lstrip().startswith("#") and any(c.strip() for c in r)]
    if len(rows) < 5:
        raise SpecError(where, "a header row and at least 4 grid points", f"{len(rows)} rows")
    cols, factors = _header(rows[0][1], f"{where} line {rows[0][0]}")
    data = np.empty((len(rows) - 1, 4))
    for r, (line, cells) in enumerate(rows[1:]):
        if len(cells) != len(rows[0][1]):
            raise SpecError(f"{where} line {line}", f"{len(rows[0][1])} columns", len(cells))
        for c, j in enumerate(cols):
            try:
                v = float(cells[j])
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise SpecError(f"{where} line {line} column {_COLUMNS[c]}",
                                "a finite number", cells[j].strip())
            data[r, c] = v * factors[c]
    i_d = np.unique(data[:, 0])
    i_q = np.unique(data[:, 1])
    if len(i_d) < 2 or len(i_q) < 2:
        raise SpecError(where, "at least 2 distinct i_d and 2 distinct i_q values",
                        f"{len(i_d)} x {len(i_q)}")
    psi_d = np.full((len(i_d), len(i_q)), np.nan)
    psi_q = np.full_like(psi_d, np.nan)
    jd = np.searchsorted(i_d, data[:, 0])
    jq = np.searchsorted(i_q, data[:, 1])
    seen = np.zeros(psi_d.shape, dtype=int)
    np.add.at(seen, (jd, jq), 1)
    if seen.max() > 1:
        j, k = np.argwhere(seen > 1)[0]
        raise SpecError(where, "one row per (i_d, i_q) grid point",
                        f"{seen.max()} rows at i_d = {i_d[j]:g} A, i_q = {i_q[k]:g} A")
    psi_d[jd, jq] = data[:, 2]
    psi_q[jd, jq] = data[:, 3]
    if seen.min() == 0:
        j, k = np.argwhere(seen == 0)[0]
        raise SpecError(where, f"a complete rectangular grid ({len(i_d)} i_d x {len(i_q)} i_q "
                        f"= {len(i_d) * len(i_q)} points)",
                        f"{len(data)} points; missing i_d = {i_d[j]:g} A, i_q = {i_q[k]:g} A")
    for name, arr, axis, other, own in (("psi_d", psi_d, 0, i_q, i_d),
                                        ("psi_q", psi_q, 1, i_d, i_q)):
        bad = np.argwhere(np.diff(arr, axis=axis) <= 0)
        if len(bad):
            j, k = bad[0]
            at = (f"between i_d = {own[j]:g} and {own[j + 1]:g} A at i_q = {other[k]:g} A"
                  if axis == 0 else
                  f"between i_q = {own[k]:g} and {own[k + 1]:g} A at i_d = {other[j]:g} A")
            raise SpecError(where, f"{name} strictly increasing in {'i_d' if axis == 0 else 'i_q'}"
                            " (positive incremental inductance)", f"not increasing {at}")
    if not (i_d[0] <= 0.0 <= i_d[-1] and i_q[0] <= 0.0 <= i_q[-1]):
        raise SpecError(where, "a grid that contains i = 0 (the nominal point)",
                        f"i_d {i_d[0]:g}..{i_d[-1]:g} A, i_q {i_q[0]:g}..{i_q[-1]:g} A")
    return MagneticModel("map", FluxMapData(i_d=i_d, i_q=i_q, psi_d=psi_d, psi_q=psi_q,
                                            source=str(path),
                                            sha256=hashlib.sha256(raw).hexdigest()))


def read_saturation(value: Any, key: str = "motor.saturation"):
    """Read ``[motor.saturation]``: the algebraic model's parameters.

    Returns
    -------
    toolbox.spec.MagneticModel
        ``kind="algebraic"``.
    """
    if not isinstance(value, Mapping):
        raise SpecError(key, "a table of the saturation model's parameters", value)
    unknown = [k for k in value if k not in SATURATION_KEYS]
    if unknown:
        raise SpecError(f"{key}.{unknown[0]}", "one of " + ", ".join(SATURATION_KEYS),
                        unknown[0])
    kw = {}
    for k in SATURATION_KEYS:
        if k == "source":
            if k in value and not isinstance(value[k], str):
                raise SpecError(f"{key}.source", "a string (where the numbers come from)",
                                value[k])
            continue
        if k not in value:
            if k in _REQUIRED:
                raise SpecError(f"{key}.{k}", "a number (required)", "missing")
            continue
        v = value[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or v < 0:
            raise SpecError(f"{key}.{k}", "a finite number >= 0", v)
        kw[k] = float(v)
    for k in ("a_d0", "a_q0", "current_range"):
        if kw[k] <= 0:
            raise SpecError(f"{key}.{k}", "a number > 0", kw[k])
    return MagneticModel("algebraic", AlgebraicSaturation(**kw))
