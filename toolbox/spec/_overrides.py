"""Command-line overrides of a spec: ``--set key.path=value`` and ``--method``.

An override replaces (or adds) one value of the parsed TOML before
validation (``--method M`` sets ``controller.method`` and drops the parameter
tables of the other methods), so the validated spec, its errors and its provenance are those of
the file with the override applied. The value is read as a TOML value
(scalar or array: ``1e-4``, ``true``, ``"hexagon"``, ``[0.5, 2]``); a bare
word that is not TOML (``hexagon``) is taken as a string. Nothing is
evaluated as code. A validation error on an overridden key (or below it)
names the override it came from.
"""

from __future__ import annotations

import copy
import re
import tomllib
from typing import Any, Mapping, Sequence

from ..errors import SpecError
from ._fields import SpecErrors
from ._model import METHODS

__all__ = ["parse_override", "apply_overrides", "blame_overrides"]

_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]*$")
_BARE_WORD = re.compile(r"^[A-Za-z_][A-Za-z0-9_.+-]*$")


def parse_override(text: str, option: str = "--set") -> tuple[list[str], Any]:
    """``"controller.pi.bandwidth=1500"`` -> ``(["controller", "pi", "bandwidth"], 1500)``.

    Path parts are TOML bare keys or array indices (``scenario.0.duration``).
    """
    if "=" not in text:
        raise SpecError(option, "key.path=value (e.g. controller.pi.bandwidth=1500)", text)
    key, _, raw = text.partition("=")
    key, raw = key.strip(), raw.strip()
    parts = key.split(".")
    if not key or not all(_KEY.match(p) or p.isdigit() for p in parts):
        raise SpecError(option, "a dotted key path of TOML bare keys (letters, digits, _ and -)"
                        " before the =", key)
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        if not _BARE_WORD.match(raw):
            raise SpecError(f"{option} {key}", "a TOML scalar or array after the = (strings "
                            'in double quotes: "text")', raw) from None
        value = raw
    if isinstance(value, dict) or (isinstance(value, list)
                                    and any(isinstance(v, (dict, list)) for v in value)):
        raise SpecError(f"{option} {key}", "a scalar or an array of scalars", raw)
    return parts, value


def apply_overrides(data: Mapping[str, Any], overrides: Sequence[tuple[str, str]]) -> dict:
    """A copy of ``data`` with each ``(option, "key.path=value")`` applied in order."""
    out = copy.deepcopy(dict(data))
    for option, text in overrides:
        parts, value = parse_override(text, option)
        if option == "--method" and isinstance(out.get("controller"), dict):
            # another method: the parameter tables of the others no longer apply

            out["controller"] = {k: v for k, v in out["controller"].items()
                                 if k not in METHODS or k == value}
        node: Any = out
        for depth, part in enumerate(parts[:-1]):
            here = ".".join(parts[:depth + 1])
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise SpecError(here, f"an index below {len(node)} (the array's length)",
                                    part, hint=f"from {option} {text}")
                node = node[int(part)]
            elif isinstance(node, dict):
                node = node.setdefault(part, {})
            if not isinstance(node, (dict, list)):
                raise SpecError(here, "a table to set a key in", node,
                                hint=f"from {option} {text}")
        last = parts[-1]
        if isinstance(node, list):
            if not last.isdigit() or int(last) >= len(node):
                raise SpecError(".".join(parts), f"an index below {len(node)}", last,
                                hint=f"from {option} {text}")
            node[int(last)] = value
        else:
            node[last] = value
    return out


def blame_overrides(err: SpecError, overrides: Sequence[tuple[str, str]]) -> SpecError:
    """``err`` with each error on an overridden key (or below it) naming the override."""
    def one(e: SpecError) -> SpecError:
        for option, text in reversed(overrides):
            key = text.partition("=")[0].strip()
            if option == "--method":
                key = "controller.method"
            if e.key and (e.key == key or e.key.startswith(key + ".")
                          or key.startswith(e.key + ".")):
                shown = f"{option} {text.partition('=')[2]}" if option == "--method" \
                    else f"{option} {text}"
                hint = f"from {shown}" + (f"; {e.hint}" if e.hint else "")
                return type(e)(e.key, e.expected, e.got if e.has_got else SpecError._MISSING,
                               file=e.file, hint=hint)
        return e

    if isinstance(err, SpecErrors):
        return SpecErrors([one(e) for e in err.errors], file=err.file)
    return one(err)
