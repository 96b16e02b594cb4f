"""A resolved spec printed back as a TOML spec file (``cct check``).

Motor, drive, the method's parameters and scenarios are printed with every
default filled in, the motor as per-phase dq model values; datasheet keys and unit strings appear as
comments next to the value derived from them, with the formula and the dq
convention. Loading the printed text gives the same spec (a test round-trips
it); floats are printed with ``repr`` so that no digit is lost.
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, fields
from typing import Any, Iterable, Mapping

from ._datasheet import CONVENTION_TEXT, Conversion
from ._model import Spec

__all__ = ["spec_to_toml", "toml_value"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")  # fullmatch (no trailing newline)


def _string(text: str) -> str:
    """A TOML basic string: escapes for quote, backslash and control characters."""
    out = []
    for ch in text:
        code = ord(ch)
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif code < 0x20 or code == 0x7F:
            out.append({"\n": "\\n", "\t": "\\t", "\r": "\\r"}.get(ch, f"\\u{code:04X}"))
        elif 0xD800 <= code <= 0xDFFF:  # lone surrogate: not representable in TOML
            out.append("\\uFFFD")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _key(name: Any) -> str:
    name = str(name)
    return name if _BARE_KEY.fullmatch(name) else _string(name)


def toml_value(value: Any) -> str:
    """One value in TOML syntax (inline tables for nested mappings).

    Examples
    --------
    >>> toml_value({"d": 1.5, "q": [1, 2]})
    '{d = 1.5, q = [1, 2]}'
    >>> toml_value(float("inf"))
    'inf'
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def _comment(text: str) -> str:
    """A comment line's text: control characters would end or break it."""
    return "".join(ch if ch.isprintable() else " " for ch in text)


def _lines(table: Mapping[str, Any], notes: Mapping[str, str]) -> Iterable[str]:
    for key, value in table.items():
        if value is None:  # TOML has no null: an absent optional key
            continue
        line = f"{_key(key)} = {toml_value(value)}"
        if key in notes:
            line += f"  # {_comment(notes[key])}"
        yield line


def _note(conv: Conversion) -> str:
    given = ", ".join(f"{k} = {toml_value(v)}" for k, v in conv.given.items())
    if conv.formula.endswith("in SI units"):
        return f"given {given}"
    return f"from {given}: {conv.formula}"


def _method_table(spec: Spec) -> Mapping[str, Any] | None:
    """The method's parameters with every default filled in, or None.

    The design method's validated configuration renders itself
    (``cfg.to_spec(spec)``, e.g. :meth:`toolbox.design.lq.LqCfg.to_spec`):
    the spec stage does not import the design stage (toolbox/ARCHITECTURE.md
    "Layers"), it asks the object it was handed.
    """
    to_spec = getattr(spec.controller.cfg, "to_spec", None)
    return to_spec(spec) if callable(to_spec) else None


def _controller_lines(spec: Spec) -> list[str]:
    """``[controller]`` and ``[controller.<method>]``, defaults filled in when the
    method can render them, else as given."""
    method = spec.controller.method
    table = _method_table(spec)
    if table is None:
        given = spec.raw.get("controller")
        given = dict(given) if isinstance(given, Mapping) else {"method": method}
        return (["", "[controller]", "# method parameters as given; the design method "
                 "applies its defaults"] + list(_lines(given, {})))
    return (["", "[controller]", f"method = {toml_value(method)}", "",
             f"[controller.{_key(method)}]",
             "# every parameter, defaults filled in (the values the design uses)"]
            + list(_lines(table, {})))


def spec_to_toml(spec: Spec, source: str | None = None) -> str:
    """The resolved spec as TOML text that loads back to the same spec.

    Parameters
    ----------
    spec : Spec
        A validated spec.
    source : str, optional
        File named in the header comment.

    Returns
    -------
    str
        TOML: ``[motor]`` and ``[drive]`` with every default filled in (per
        phase dq values, SI), ``[controller.<method>]`` with the method's
        defaults filled in (the design method's ``cfg.to_spec``; as given
        when the method cannot render itself), ``[requirements]`` as given,
        and every ``[[scenario]]`` with all its keys; ``[campaign]`` as given.
    """
    notes = {c.key: _note(c) for c in spec.conversions}
    out = [f"# {_comment(source or spec.source or 'spec')}: ok (resolved spec, SI units)",
           f"# dq convention: {CONVENTION_TEXT[spec.motor.convention]}"]
    if spec.title:
        out.append(f"title = {toml_value(spec.title)}")
    motor = {f.name: getattr(spec.motor, f.name) for f in fields(spec.motor)}
    motor = {"catalog": motor.pop("catalog"), **motor}
    derived = []
    if motor.pop("magnetics") is not None:
        # a saturated motor: its magnetics as given; Ld, Lq, flux derive from
        # them (toolbox/ARCHITECTURE.md "Saturated motors") and are refused
        # next to them, so they are comments here
        derived = [f"# {key} = {toml_value(motor.pop(key))}  (from the magnetic model)"
                   for key in ("Ld", "Lq", "flux")]
        for key in ("flux_map", "saturation"):
            if key in spec.raw.get("motor", {}):
                motor[key] = spec.raw["motor"][key]
    out += ["", "[motor]"] + derived + list(_lines(motor, notes))
    drive = asdict(spec.drive)
    out += ["", "[drive]"] + list(_lines(drive, notes))
    out += _controller_lines(spec)
    if spec.requirements.given:
        drift = {name: list(r) for name, r in spec.requirements.parameter_drift.items()}
        out += ["", "[requirements]"] + list(_lines(
            {**spec.requirements.bounds, **({"parameter_drift": drift} if drift else {})}, {}))
    if spec.export_prefix != "cct_":
        out += ["", "[export]", f"prefix = {toml_value(spec.export_prefix)}"]
    for scenario in spec.scenarios:
        values = {f.name: getattr(scenario, f.name) for f in fields(scenario)}
        out += ["", "[[scenario]]"] + list(_lines(values, {}))
    campaign = spec.raw.get("campaign")
    if isinstance(campaign, Mapping):
        out += ["", "[campaign]", "# as given (README.md \"Campaigns\")"] + list(
            _lines(campaign, {}))
    return "\n".join(out) + "\n"
