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

Datasheet spellings (normalised before parsing, :func:`normalise_unit`):
``kg·cm²``, ``kg*cm^2``, ``N·m/A``, ``Nm/A``, ``mNm``, ``Ohm``/``Ω``,
``1/min``/``min⁻¹``/``U/min``/``r/min`` (revolutions per minute, as
datasheets print rpm), ``Arms``/``A rms``/``A_rms`` and ``Vrms`` (rms
values). An rms current is converted to the model's dq magnitude: the
model's dq frame is amplitude-invariant (toolbox/spec/_datasheet.py
"Convention"), where |i_dq| is the peak phase current, so ``"10 Arms"`` is
``10 sqrt(2) = 14.14 A`` (sqrt(3) x in the power-invariant convention); an
rms voltage ``"Vrms"`` is sqrt(2) x its peak. A key whose name ends in
``_rms`` (``kt_rms``, ``rated_current_rms``) already means rms: the marker
is accepted there and nothing is scaled. A value given as a speed per volt
(a hobby motor's KV, ``"380 rpm/V"``) where a back-EMF or torque constant
is expected is refused with the constant it stands for (ke = 1/KV in V s/rad).

Bandwidths and other angular rates (``rad/s``) accept ``Hz``: ``"2 kHz"`` is
the angular frequency 2 pi 2000 = 12566 rad/s. Speeds (``rad/s
mechanical``) refuse ``Hz`` (electrical or mechanical cycles?) and take
``rpm``.
"""

from __future__ import annotations

import functools
import math
import re
import warnings
from dataclasses import dataclass
from typing import Any

from ..errors import SpecError

__all__ = ["Kind", "KINDS", "UNIT_LABELS", "kind_for_unit", "normalise_unit", "parse_quantity",
           "looks_like_quantity"]

#: Longest accepted quantity string (a datasheet value is short).
MAX_QUANTITY_CHARS = 64

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d{1,3})?"
_UNIT_NAME = r"(?:[A-Za-zµμΩ_]+|1)(?:\s*(?:\^|\*\*)\s*-?[1-4])?"
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
    # design parameters and requirements (toolbox.spec.Table.number's ``unit``)
    "angular_rate": Kind("an angular rate", "rad/s", "rad/s, or Hz (x 2 pi)",
                         refuse=("revolutions_per_minute", "revolution")),
    "rate": Kind("a rate", "1/s", "1/s", refuse=("hertz", "revolutions_per_minute",
                                                  "revolution")),
    "angle": Kind("an angle", "deg", "deg"),
    "level": Kind("a level in decibels", "dB", "dB"),
    "gain_ohm": Kind("a proportional gain", "V/A", "V/A"),
    "gain_integral": Kind("an integral gain", "V/(A*s)", "V/(A s)"),
    "per_current": Kind("a gain per ampere", "1/A", "1/A"),
    "per_voltage_sq": Kind("a weight per volt squared", "1/V^2", "1/V^2"),
    "speed_gain": Kind("a speed-loop proportional gain", "A*s/rad", "A s/rad"),
    "speed_gain_integral": Kind("a speed-loop integral gain", "A/rad", "A/rad"),
    "torque": Kind("a torque", "N*m", "N m"),
    "acceleration": Kind("an angular acceleration", "rad/s^2", "rad/s^2, or rpm/s",
                         refuse=("hertz",)),
}

#: ``unit`` labels of :meth:`toolbox.spec.Table.number` (and of
#: ``REQUIREMENT_KEYS``) -> the kind a quantity string is converted to.
#: A label not listed here (``"1"``, ``"%"``, ``"(N m)^2"``) takes plain
#: numbers only.
UNIT_LABELS: dict[str, str] = {
    "ohm": "resistance", "H": "inductance", "Wb": "flux", "A": "current", "V": "voltage",
    "s": "time", "Hz": "frequency", "rad/s": "angular_rate", "1/s": "rate",
    "rad/s mechanical": "speed", "deg": "angle", "dB": "level", "V/A": "gain_ohm",
    "V/(A s)": "gain_integral", "1/A": "per_current", "1/V^2": "per_voltage_sq",
    "kg m^2": "inertia", "N m s/rad": "friction", "N m/A": "torque_constant",
    "A s/rad": "speed_gain", "A/rad": "speed_gain_integral", "N m": "torque",
    "rad/s^2": "acceleration",
}


def kind_for_unit(label: str) -> str | None:
    """The kind (a key of :data:`KINDS`) of a ``unit`` label, or None."""
    return UNIT_LABELS.get(label)

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
        ureg = pint.UnitRegistry()
        # rms values of a sinusoid in peak units (rms -> peak: x sqrt(2)); the
        # power-invariant dq magnitude of a phase current is sqrt(3) x its rms
        ureg.define("cct_rms_ampere = 1.4142135623730951 * ampere")
        ureg.define("cct_rms_volt = 1.4142135623730951 * volt")
        ureg.define("cct_rms_ampere_power = 1.7320508075688772 * ampere")
        ureg.define("cct_marked_rms_ampere = ampere")
        ureg.define("cct_marked_rms_volt = volt")
        return ureg


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


#: Unicode and datasheet spellings -> pint syntax (applied in order).
_SPELLINGS = (
    (re.compile(r"[·⋅•×]"), "*"), (re.compile("²"), "^2"), (re.compile("³"), "^3"),
    (re.compile("⁻¹"), "^-1"), (re.compile("[µμ]"), "u"), (re.compile("Ω"), "ohm"),
    (re.compile(r"(?<![A-Za-z_])([mkMu]?)Ohms?(?![A-Za-z_])"), r"\1ohm"),
    # revolutions per minute as datasheets print them
    (re.compile(r"(?<![A-Za-z_0-9])(?:1\s*/\s*min|min\s*\^\s*-1|[Ur]\s*/\s*min)"
                r"(?![A-Za-z_])"), "rpm"),
)

#: An rms marker after A or V: "Arms", "A rms", "A_rms", "Vrms" (and peak
#: markers "Apk", "A peak", "A_peak": peak is what the model uses).
_RMS_MARK = re.compile(r"(?<![A-Za-z_])([mkuM]?)([AV])(?:\s*_?\s*)(rms|pk|peak)(?![A-Za-z_])")


def normalise_unit(unit_text: str, rms: str = "peak") -> str:
    """Datasheet spelling -> pint syntax.

    Parameters
    ----------
    unit_text : str
        The unit as written (``"kg·cm²"``, ``"A rms"``, ``"N·m/Arms"``).
    rms : str
        What an rms marker does: ``"peak"`` converts the rms value to peak
        (x sqrt(2): the amplitude-invariant dq magnitude of a phase
        current), ``"power"`` converts an rms current to the power-invariant
        dq magnitude (x sqrt(3)), ``"rms"`` accepts the marker and keeps the
        value (keys whose name says rms).

    Examples
    --------
    >>> normalise_unit("kg·cm²")
    'kg*cm^2'
    >>> normalise_unit("1/min")
    'rpm'
    >>> normalise_unit("A rms")
    'cct_rms_ampere'
    """
    for pattern, repl in _SPELLINGS:
        unit_text = pattern.sub(repl, unit_text)

    def mark(m: re.Match) -> str:
        prefix, base, which = m.groups()
        if which != "rms" or rms == "rms":
            name = "cct_marked_rms_ampere" if base == "A" else "cct_marked_rms_volt"
        elif base == "A":
            name = "cct_rms_ampere_power" if rms == "power" else "cct_rms_ampere"
        else:
            name = "cct_rms_volt"
        return f"{prefix}{name}" if prefix else name

    unit_text = _RMS_MARK.sub(mark, unit_text)
    return _datasheet_spelling(unit_text)


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
    if quantity.dimensionality == (1 / ureg.parse_units("V*s")).dimensionality:
        return "a rate per volt (1/(V s), as a motor's KV in rpm/V)"
    if quantity.dimensionless:
        return "a dimensionless number"
    return f"a quantity of dimension {quantity.dimensionality}"


def _kv_hint(quantity: Any, kind: str, key: str) -> str | None:
    """For a speed per volt where a back-EMF/torque constant or a flux is
    expected: the constant it stands for (ke = 1/KV, V s/rad)."""
    if kind not in ("emf_constant", "torque_constant", "flux"):
        return None
    ureg = _registry()
    if quantity.dimensionality != (1 / ureg.parse_units("V*s")).dimensionality:
        return None
    try:
        ke = 1.0 / float(quantity.to("rad/s/V").magnitude)
    except (ZeroDivisionError, OverflowError):
        return None
    return (f"this is a KV (speed per volt); ke = 1/KV = {ke:.4g} V s/rad: write "
            f'motor.ke_ll_peak = "{ke:.4g} V s/rad" when the KV is per line-to-line peak '
            "volt (the usual rating of hobby motors: no-load speed per DC-link volt), "
            "motor.ke_ll_rms when it is per rms volt")


def parse_quantity(value: str, key: str, kind: str, rms: str = "peak") -> float:
    """Convert ``"<number> <unit>"`` to the SI value of ``kind``.

    Parameters
    ----------
    value : str
        For example ``"0.2 mH"``, ``"49.8 V/krpm"``, ``"20 mohm"``.
    key : str
        Dotted key path (for messages).
    kind : str
        A key of :data:`KINDS`.
    rms : str
        What an rms marker (``"Arms"``) does (:func:`normalise_unit`).

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
    >>> round(parse_quantity("2 kHz", "controller.pi.bandwidth", "angular_rate"), 1)
    12566.4
    >>> round(parse_quantity("10 Arms", "motor.rated_current", "current"), 4)
    14.1421
    """
    k = KINDS[kind]
    expected = f"{k.name} ({k.shown})"
    if len(value) > MAX_QUANTITY_CHARS:
        match = None
    else:
        pre = _LEADING_NUMBER.match(value)
        unit_written = value[pre.end():] if pre else ""
        match = _QUANTITY.match(value[:pre.end()] + " " + normalise_unit(unit_written, rms)
                                if pre else value)
    if match is None:
        raise SpecError(key, expected, value,
                        hint='write a number and a unit, e.g. "0.2 mH", "49.8 V/krpm"')
    import pint

    ureg = _registry()
    number, unit_text = match.groups()
    if kind == "level":  # decibels are logarithmic: only "dB" itself
        if unit_text.strip() != "dB":
            raise SpecError(key, expected, value, hint='write the level in dB, e.g. "6 dB"')
        return float(number)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a pint warning is an error here, never leaked
            unit = ureg.parse_units(unit_text)
    except (pint.errors.PintError, AttributeError, ValueError, TypeError,
            SyntaxError, Warning) as err:
        raise SpecError(key, expected, value, hint=f"unknown unit: {err}") from None
    quantity = ureg.Quantity(float(number), unit)
    used = [name for name, _ in quantity.unit_items()]
    refused = [name for name in k.refuse
               if any((name in u) if name != "minute" else u == "minute" for u in used)]
    if kind == "angle" and not all(u in ("degree", "radian", "arcminute", "arcsecond",
                                         "turn", "revolution") for u in used):
        raise SpecError(key, expected, value, hint='write an angle, e.g. "45 deg"')
    if refused and refused[0] == "minute":
        raise SpecError(key, expected, value,
                        hint='a speed "per minute" (min^-1, 1/min) on a datasheet means '
                             f'revolutions per minute: write "{number} rpm"')
    if refused:
        raise SpecError(key, expected, value,
                        hint=f"{refused[0]} is not {k.name}: give {k.shown}")
    if kind == "angular_rate" and any("hertz" in u for u in used):
        quantity = quantity * (2 * math.pi) * ureg.radian  # f in Hz -> omega = 2 pi f
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            out = float(quantity.to(k.si).magnitude)
    except pint.errors.DimensionalityError:
        raise SpecError(key, expected, _Shown(f'{_describe(quantity)} ("{value}")'),
                        hint=_kv_hint(quantity, kind, key)) from None
    except (OverflowError, ZeroDivisionError, Warning) as err:
        raise SpecError(key, expected, value, hint=str(err)) from None
    if not math.isfinite(out):
        raise SpecError(key, f"a finite {k.name[2:] if k.name.startswith('a ') else k.name}"
                        f" ({k.shown})", value)
    return out
