"""Units in ``[controller.<method>]`` tables: ``bandwidth = "2 kHz"``.

The method readers (toolbox.design) read plain SI numbers; this module
converts the quantity strings of a method's table to them first, so that
every method accepts units the way ``[motor]`` does (toolbox/spec/_units.py:
``"12566 rad/s"``, ``"2 kHz"`` = 2 pi 2000 rad/s, ``"0.5 ms"``,
``"3000 rpm"`` for a speed). A key path may hold a number, a string with a
unit, a per-axis table ``{d = .., q = ..}`` or a list of them (pole pairs,
ranges); only strings are converted, everything else is left for the
reader's own checks. Paths use ``*`` for any key (``weights.*.*.crossover``:
every axis and weight of an H-infinity makeweight).
"""

from __future__ import annotations

from typing import Any, Mapping

from ._fields import Collector
from ._units import looks_like_quantity, parse_quantity

__all__ = ["METHOD_KINDS", "convert_method_units"]

_PI = {"bandwidth": "angular_rate", "response_time": "time",
       "integral_bandwidth": "angular_rate", "small_time_constant": "time",
       "lag_time_constant": "time", "Kp": "gain_ohm", "Ki": "gain_integral",
       "voltage_gain": "voltage", "sensor_gain": "per_current"}
_MODEL = {"model.R": "resistance", "model.Ld": "inductance", "model.Lq": "inductance",
          "model.flux": "flux"}
_SPEED_BOX = {"max_speed": "speed", "speed_offset": "speed"}

#: method -> {key path under [controller.<method>]: kind (toolbox/spec/_units.py KINDS)}
METHOD_KINDS: dict[str, dict[str, str]] = {
    "pi": _PI, "ip": _PI, "pi_lag": _PI,
    "tc": {"response_time": "time", "poles": "angular_rate", **_MODEL},
    "tci": {"natural_frequency": "angular_rate", "poles": "angular_rate", "Kp": "gain_ohm",
            "Ki": "gain_integral", "voltage_gain": "voltage", "sensor_gain": "per_current",
            **_MODEL},
    "ilq": {"poles": "angular_rate", "s1": "angular_rate", "s2": "angular_rate",
            "sigma": "rate"},
    "lq": {"bandwidth": "angular_rate", "current_limit": "current", "voltage_limit": "voltage"},
    "hinf": {"integrator_tol": "angular_rate", "weights.*.*.crossover": "angular_rate",
             "at_speed.max_speed": "speed", "at_speed.speed_offset": "speed"},
    "robust_pi": dict(_SPEED_BOX),
    "tune": dict(_SPEED_BOX),
    "fcs_mpc": {},
}


def _convert(value: Any, key: str, kind: str, errors: Collector) -> Any:
    """A number, a quantity string, a ``{d, q}`` table or a list of them, in SI."""
    if looks_like_quantity(value):
        with errors.check():
            return parse_quantity(value, key, kind)
        return value
    if isinstance(value, list):
        return [_convert(v, f"{key}[{i}]", kind, errors) for i, v in enumerate(value)]
    if isinstance(value, Mapping) and set(value) <= {"d", "q"}:
        return {ax: _convert(v, f"{key}.{ax}", kind, errors) for ax, v in value.items()}
    return value


def _walk(table: Any, parts: list[str], key: str, kind: str, errors: Collector) -> Any:
    if not isinstance(table, Mapping):
        return table
    head, rest = parts[0], parts[1:]
    out = dict(table)
    for name in (list(table) if head == "*" else [head] if head in table else []):
        path = f"{key}.{name}"
        out[name] = (_convert(table[name], path, kind, errors) if not rest
                     else _walk(table[name], rest, path, kind, errors))
    return out


def convert_method_units(method: str, table: Any, prefix: str, errors: Collector) -> Any:
    """``[controller.<method>]`` with its quantity strings in SI.

    Parameters
    ----------
    method : str
        The design method.
    table : mapping (or anything: returned as is when not a table)
        The method's table as written.
    prefix : str
        Its key path (``controller.pi``), named in errors.
    errors : Collector
        Receives one error per string that does not convert (the value is
        left as written, and the reader then reports it as a number).
    """
    for path, kind in METHOD_KINDS.get(method, {}).items():
        table = _walk(table, path.split("."), prefix, kind, errors)
    return table
