"""Quantities with units in spec files: ``"0.2 mH"``, ``"49.8 V/krpm"``, ``"40 kHz"``.

A spec value may be a plain number (SI, as before) or a string ``"<number>
<unit>"``. The unit is parsed by pint (``UnitRegistry.parse_units``) and the
value converted to the SI unit of the key. Nothing is evaluated as code: the
string must match :data:`_QUANTITY` first (a decimal number, then unit names
joined by ``*``, ``/``, spaces and small integer powers), so pint never sees
an arbitrary expression (pint's own expression parser accepts ``**`` on
numbers, e.g. ``"9**9**9"``, which would hang).

A dimension mismatch names both sides: ``"0.2 mH"`` for a resistance gives
``expected a resistance (ohm), got an inductance (0.2 mH)``.
"""

from __future__ import annotations

import functools
import math
import re
import warnings
from dataclasses import dataclass
from typing import Any

from ..errors import SpecError

__all__ = ["Kind", "KINDS", "parse_quantity", "looks_like_quantity"]

#: Longest accepted quantity string (a datasheet value is short).
MAX_QUANTITY_CHARS = 64

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d{1,3})?"
_UNIT_NAME = r"[A-Za-zµμΩ_]+(?:\s*(?:\^|\*\*)\s*-?[1-4])?"
_UNIT = rf"{_UNIT_NAME}(?:\s*[*/ ]\s*{_UNIT_NAME})*"
_QUANTITY = re.compile(rf"^\s*({_NUMBER})\s*({_UNIT})\s*$")
_LEADING_NUMBER = re.compile(rf"^\s*{_NUMBER}")


@dataclass(frozen=True)
class Kind:
    """A physical quantity a spec key holds.

    Attributes
    ----------
    name : str
        What it is, for messages ("a resistance").
    si : str
        The SI unit values are converted to (pint syntax).
    shown : str
        The unit as the README writes it.
    refuse : tuple of str
        pint unit names refused although dimensionally equal: pint's hertz
        is 1/s, so ``"50 Hz"`` would silently become 50 rad/s for a speed,
        and ``"3000 rpm"`` 314 Hz for a frequency.
    """

    name: str
    si: str
    shown: str
    refuse: tuple[str, ...] = ()


KINDS: dict[str, Kind] = {
    "resistance": Kind("a resistance", "ohm", "ohm"),
    "inductance": Kind("an inductance", "H", "H"),
    "flux": Kind("a flux linkage", "Wb", "Wb"),
    "emf_constant": Kind("a back-EMF constant", "V*s/rad", "V s/rad, or V/krpm"),
    "torque_constant": Kind("a torque constant", "N*m/A", "N m/A"),
    "speed": Kind("a speed", "rad/s", "rad/s, or rpm", refuse=("hertz", "minute")),
    "frequency": Kind("a frequency", "Hz", "Hz",
                      refuse=("revolutions_per_minute", "radian", "revolution")),
    "time": Kind("a time", "s", "s"),
    "current": Kind("a current", "A", "A"),
    "voltage": Kind("a voltage", "V", "V"),
    "inertia": Kind("an inertia", "kg*m^2", "kg m^2"),
    "friction": Kind("a viscous friction", "N*m*s/rad", "N m s/rad"),
}

#: Names for the dimension of a value that does not fit (first match wins;
#: flux, EMF and torque constants share one dimension, as do speed and
#: frequency).
_GOT_NAMES = (("resistance", "a resistance"), ("inductance", "an inductance"),
              ("flux", "a flux linkage, EMF or torque constant"),
              ("frequency", "a frequency or speed"), ("time", "a time"),
              ("current", "a current"), ("voltage", "a voltage"),
              ("inertia", "an inertia"))


@functools.lru_cache(maxsize=1)
def _registry() -> Any:
    """pint's default registry, built once on first use (about 0.3 s)."""
    import pint

    with warnings.catch_warnings():  # registry construction must not leak warnings
        warnings.simplefilter("ignore")
        return pint.UnitRegistry()


#: Datasheet spellings of newton metres: "Nm", "mNm", "Ncm", "Nms" (pint reads
#: "Nm" as its "number meter" and gives a nonsense dimension).
_NEWTON_METRE = re.compile(r"(?<![A-Za-z_])([munµμck]?)N([cm])m(s?)(?![A-Za-z_])|"
                           r"(?<![A-Za-z_])([munµμck]?)Nm(s?)(?![A-Za-z_])")


def _datasheet_spelling(unit_text: str) -> str:
    """``"mNm/A"`` -> ``"mN*m/A"``, ``"Nms"`` -> ``"N*m*s"``, ``"Ncm"`` -> ``"N*cm"``."""
    def sub(m: re.Match) -> str:
        if m.group(2) is not None:  # N cm / N mm
            return f"{m.group(1)}N*{m.group(2)}m" + ("*s" if m.group(3) else "")
        return f"{m.group(4)}N*m" + ("*s" if m.group(5) else "")
    return _NEWTON_METRE.sub(sub, unit_text)


def looks_like_quantity(value: Any) -> bool:
    """True for a string that starts with a number and has more after it.

    ``"0.6"`` (a number as a string) and ``"__import__(...)"`` are left to
    the type check, which refuses them as "expected a number".
    """
    if not isinstance(value, str) or len(value) > MAX_QUANTITY_CHARS:
        return False
    match = _LEADING_NUMBER.match(value)
    return bool(match) and value[match.end():].strip() != ""


class _Shown:
    """Text shown as is after "got" (SpecError quotes plain strings)."""

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__


def _describe(quantity: Any) -> str:
    ureg = _registry()
    for kind, text in _GOT_NAMES:
        if quantity.dimensionality == ureg.parse_units(KINDS[kind].si).dimensionality:
            return text
    if quantity.dimensionless:
        return "a dimensionless number"
    return f"a quantity of dimension {quantity.dimensionality}"


def parse_quantity(value: str, key: str, kind: str) -> float:
    """Convert ``"<number> <unit>"`` to the SI value of ``kind``.

    Parameters
    ----------
    value : str
        For example ``"0.2 mH"``, ``"49.8 V/krpm"``, ``"20 mohm"``.
    key : str
        Dotted key path (for messages).
    kind : str
        A key of :data:`KINDS`.

    Returns
    -------
    float
        The value in the SI unit ``KINDS[kind].si``.

    Raises
    ------
    SpecError
        Unknown unit, wrong dimension, or a refused unit, naming the key,
        the expected quantity and unit, and what was found.

    Examples
    --------
    >>> parse_quantity("0.2 mH", "motor.Ld", "inductance")
    0.0002
    >>> round(parse_quantity("3000 rpm", "motor.rated_speed", "speed"), 4)
    314.1593
    """
    k = KINDS[kind]
    expected = f"{k.name} ({k.shown})"
    match = _QUANTITY.match(value) if len(value) <= MAX_QUANTITY_CHARS else None
    if match is None:
        raise SpecError(key, expected, value,
                        hint='write a number and a unit, e.g. "0.2 mH", "49.8 V/krpm"')
    import pint

    ureg = _registry()
    number, unit_text = match.groups()
    unit_text = _datasheet_spelling(unit_text)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a pint warning is an error here, never leaked
            unit = ureg.parse_units(unit_text.replace("µ", "u").replace("μ", "u")
                                    .replace("Ω", "ohm"))
    except (pint.errors.PintError, AttributeError, ValueError, TypeError,
            SyntaxError, Warning) as err:
        raise SpecError(key, expected, value, hint=f"unknown unit: {err}") from None
    quantity = ureg.Quantity(float(number), unit)
    used = [name for name, _ in quantity.unit_items()]
    refused = [name for name in k.refuse
               if any((name in u) if name != "minute" else u == "minute" for u in used)]
    if refused and refused[0] == "minute":
        raise SpecError(key, expected, value,
                        hint='a speed "per minute" (min^-1, 1/min) on a datasheet means '
                             f'revolutions per minute: write "{number} rpm"')
    if refused:
        raise SpecError(key, expected, value,
                        hint=f"{refused[0]} is not {k.name}: give {k.shown}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            out = float(quantity.to(k.si).magnitude)
    except pint.errors.DimensionalityError:
        raise SpecError(key, expected,
                        _Shown(f'{_describe(quantity)} ("{value}")')) from None
    except (OverflowError, ZeroDivisionError, Warning) as err:
        raise SpecError(key, expected, value, hint=str(err)) from None
    if not math.isfinite(out):
        raise SpecError(key, f"a finite {k.name[2:] if k.name.startswith('a ') else k.name}"
                        f" ({k.shown})", value)
    return out
