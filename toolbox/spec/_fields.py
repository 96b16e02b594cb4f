"""Typed readers for plain-data spec tables.

Each reader takes the table, the field name and the dotted key path of the
table, and either returns a validated value or raises :class:`SpecError`
naming the key, what was expected and what was found. Nothing is evaluated
as code: values are taken only as TOML/JSON gives them.
"""

from __future__ import annotations

import difflib
import math
from contextlib import contextmanager
from typing import Any, Iterable, Iterator, Mapping, Sequence

from ..errors import SpecError
from ._units import kind_for_unit, looks_like_quantity, parse_quantity

__all__ = [
    "Table",
    "check_keys",
    "did_you_mean",
    "as_table",
    "SpecErrors",
    "Collector",
    "MAX_INTEGER",
    "is_finite_number",
]

_MISSING = object()


def _path(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def did_you_mean(word: str, choices: Iterable[str]) -> str | None:
    """``'did you mean "x"?'`` for the choice closest to ``word`` (difflib's
    similarity ratio >= 0.6), else None.

    A word more than 7/3 times longer than every choice is refused before
    difflib sees it: the ratio ``2 M / (len(a) + len(b))`` with ``M <= len(b)``
    is then below 0.6, and difflib's set-up on the word costs time linear
    in its length (tens of ms on a 500 k-character value)."""
    choices = [str(c) for c in choices]
    word = str(word)
    if not choices or 3 * len(word) > 7 * max(len(c) for c in choices):
        return None
    close = difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    return f'did you mean "{close[0]}"?' if close else None


def check_keys(table: Mapping, allowed: Iterable[str], prefix: str) -> None:
    """Refuse unknown keys, with a did-you-mean among ``allowed``.

    Parameters
    ----------
    table : Mapping
        The table read from the spec.
    allowed : iterable of str
        Known keys.
    prefix : str
        Dotted key path of the table (for the message).
    """
    allowed = list(allowed)
    for name in table:
        if name not in allowed:
            hint = (did_you_mean(str(name), allowed)
                    or f"allowed keys: {', '.join(sorted(allowed))}")
            where = f"a known key of [{prefix}]" if prefix else "a known top-level key"
            raise SpecError(_path(prefix, str(name)), where, hint=hint)


def as_table(value: Any, key: str) -> Mapping:
    if not isinstance(value, Mapping):
        raise SpecError(key, "a table", value)
    return value


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def is_finite_number(value: Any) -> bool:
    """An int or float (not a bool) that is a finite double: an integer of
    400 digits is not (``math.isfinite`` raises ``OverflowError`` on it).

    Parameters
    ----------
    value : object
        Any value read from a spec or JSON.
    """
    if not _is_number(value):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


#: Largest magnitude of an integer key without its own maximum (2**53: every
#: integer up to it is exact as a double, which the numerics use).
MAX_INTEGER = 2 ** 53


class Table:
    """A spec table being read; remembers its key path and refuses unknown keys.

    Examples
    --------
    >>> t = Table({"R": 0.6}, "motor")
    >>> t.number("R", positive=True)
    0.6
    """

    def __init__(self, data: Any, prefix: str, allowed: Sequence[str] | None = None):
        self.data = as_table(data if data is not None else {}, prefix)
        self.prefix = prefix
        if allowed is not None:
            check_keys(self.data, allowed, prefix)

    def key(self, name: str) -> str:
        return _path(self.prefix, name)

    def has(self, name: str) -> bool:
        return name in self.data

    def raw(self, name: str, default: Any = None) -> Any:
        return self.data.get(name, default)

    def _get(self, name: str, default: Any, expected: str) -> Any:
        if name in self.data:
            return self.data[name]
        if default is _MISSING:
            raise SpecError(self.key(name), f"{expected} (missing)")
        return default

    def number(self, name: str, default: Any = _MISSING, *, positive: bool = False,
               nonnegative: bool = False, minimum: float | None = None,
               maximum: float | None = None, negative: bool = False,
               unit: str = "", kind: str | None = None) -> Any:
        """A finite real number with optional bounds.

        A string with a unit (``"12566 rad/s"``, ``"2 kHz"``, ``"45 deg"``)
        is accepted when ``unit`` names a physical quantity
        (:data:`toolbox.spec._units.UNIT_LABELS`; ``kind`` overrides the
        label's kind, e.g. ``"speed"`` for a ``rad/s`` that is a speed) and
        converted to ``unit`` before the bounds are checked.
        """
        cond = []
        if positive:
            cond.append("> 0")
        if nonnegative:
            cond.append(">= 0")
        if negative:
            cond.append("< 0")
        if minimum is not None:
            cond.append(f">= {minimum:g}")
        if maximum is not None:
            cond.append(f"<= {maximum:g}")
        expected = "a number" + (" " + " and ".join(cond) if cond else "") + (
            f" ({unit})" if unit else "")
        value = self._get(name, default, expected)
        if value is default and name not in self.data:
            return value
        value = self._quantity(value, self.key(name), unit, kind)
        if not is_finite_number(value):
            raise SpecError(self.key(name), expected, value)
        bad = ((positive and not value > 0) or (nonnegative and value < 0)
               or (negative and not value < 0)
               or (minimum is not None and value < minimum)
               or (maximum is not None and value > maximum))
        if bad:
            raise SpecError(self.key(name), expected, value)
        return float(value)

    @staticmethod
    def _quantity(value: Any, key: str, unit: str, kind: str | None) -> Any:
        """``value`` converted to ``unit`` when it is a string with a unit and
        ``unit`` (or ``kind``) names a physical quantity; else as given."""
        kind = kind or kind_for_unit(unit)
        if kind is not None and looks_like_quantity(value):
            return parse_quantity(value, key, kind)
        return value

    def integer(self, name: str, default: Any = _MISSING, *, minimum: int | None = None,
                maximum: int | None = None) -> Any:
        """An integer with optional bounds (a float such as 4.5 or 1e6 is refused)."""
        cond = ([f">= {minimum}"] if minimum is not None else []) + (
            [f"<= {maximum}"] if maximum is not None else [])
        expected = "an integer" + (" " + " and ".join(cond) if cond else "")
        value = self._get(name, default, expected)
        if value is default and name not in self.data:
            return value
        if not isinstance(value, int) or isinstance(value, bool) or (
                minimum is not None and value < minimum) or (
                maximum is not None and value > maximum):
            raise SpecError(self.key(name), expected, value)
        if abs(value) > MAX_INTEGER:  # 400 digits: no integer the numerics can use
            raise SpecError(self.key(name), f"{expected} of magnitude at most 2**53", value)
        return value

    def boolean(self, name: str, default: Any = _MISSING) -> Any:
        value = self._get(name, default, "true or false")
        if not isinstance(value, bool):
            raise SpecError(self.key(name), "true or false", value)
        return value

    def string(self, name: str, default: Any = _MISSING, *,
               choices: Sequence[str] | None = None) -> Any:
        expected = ("one of " + ", ".join(f'"{c}"' for c in choices)) if choices else "a string"
        value = self._get(name, default, expected)
        if value is default and name not in self.data:
            return value
        if not isinstance(value, str) or (choices is not None and value not in choices):
            hint = did_you_mean(value, choices) if isinstance(value, str) and choices else None
            raise SpecError(self.key(name), expected, value, hint=hint)
        return value

    def numbers(self, name: str, default: Any = _MISSING, *, length: int | None = None,
                min_length: int = 0, max_length: int | None = None, unit: str = "",
                kind: str | None = None) -> Any:
        """A list of finite numbers (at most ``max_length`` of them); entries
        may carry units as in :meth:`number`."""
        expected = (f"a list of {length} numbers" if length is not None
                    else "a list of numbers") + (f" ({unit})" if unit else "")
        value = self._get(name, default, expected)
        if value is default and name not in self.data:
            return value
        if (max_length is not None and isinstance(value, (list, tuple))
                and len(value) > max_length):  # before looking at each entry
            raise SpecError(self.key(name), f"a list of at most {max_length} numbers"
                            + (f" ({unit})" if unit else ""), f"{len(value)} numbers")
        if isinstance(value, (list, tuple)):
            value = [self._quantity(v, f"{self.key(name)}[{i}]", unit, kind)
                     for i, v in enumerate(value)]
        if (not isinstance(value, (list, tuple))
                or not all(is_finite_number(v) for v in value)
                or (length is not None and len(value) != length)
                or len(value) < min_length):
            raise SpecError(self.key(name), expected, value)
        return tuple(float(v) for v in value)

    def per_axis(self, name: str, default: Any = _MISSING, **bounds: Any) -> Any:
        """A number for both axes or a table ``{d = .., q = ..}``; returns ``(d, q)``."""
        value = self._get(name, default, "a number or a table {d = .., q = ..}")
        if value is default and name not in self.data:
            return value
        if isinstance(value, Mapping):
            sub = Table(value, self.key(name), ("d", "q"))
            errors = Collector()  # a bad d and a bad q: both reported
            d = q = None
            with errors.check():
                d = sub.number("d", **bounds)
            with errors.check():
                q = sub.number("q", **bounds)
            errors.raise_if_any()
            return (d, q)
        v = self.number(name, **bounds)
        return (v, v)

    def table(self, name: str, allowed: Sequence[str] | None = None,
              required: bool = False) -> "Table":
        if name not in self.data and required:
            raise SpecError(self.key(name), "a table (missing)")
        return Table(self.data.get(name, {}), self.key(name), allowed)


class SpecErrors(SpecError):
    """Several spec errors reported at once (one line each).

    The first error gives ``key``, ``expected`` and ``got`` (so code that
    reads one error still works); ``errors`` holds all of them.

    Examples
    --------
    >>> err = SpecErrors([SpecError("motor.R", "a number > 0", -1),
    ...                   SpecError("drive.vdc", "a number > 0", 0)], file="x.toml")
    >>> print(err)
    x.toml: 2 errors:
      motor.R: expected a number > 0, got -1
      drive.vdc: expected a number > 0, got 0
    """

    def __init__(self, errors: Sequence[SpecError], file: str | None = None) -> None:
        if not errors:
            raise ValueError("SpecErrors needs at least one error")
        self.errors = [e.with_file(file) if file else e for e in errors]
        first = self.errors[0]
        super().__init__(first.key, first.expected,
                         first.got if first.has_got else SpecError._MISSING,
                         file=file, hint=first.hint)

    def _text(self) -> str:
        where = f"{self.file}: " if self.file else ""
        lines = [f"{where}{len(self.errors)} errors:"]
        for err in self.errors:
            located = err.with_file("") if err.file else err  # the file is named once
            lines.append(f"  {located}")
        return "\n".join(lines)

    def with_file(self, file: str) -> "SpecErrors":
        return SpecErrors([e.with_file(file) for e in self.errors], file=file)

    def under(self, prefix: str) -> "SpecErrors":
        return SpecErrors([e.under(prefix) for e in self.errors], file=self.file)


class Collector:
    """Gather the spec errors of independent checks and raise them together.

    Examples
    --------
    >>> c = Collector()
    >>> with c.check():
    ...     raise SpecError("motor.R", "a number > 0", -1)
    >>> c.failed
    True
    >>> c.raise_if_any()
    Traceback (most recent call last):
    ...
    toolbox.errors.SpecError: motor.R: expected a number > 0, got -1
    """

    def __init__(self) -> None:
        self.errors: list[SpecError] = []

    @property
    def failed(self) -> bool:
        return bool(self.errors)

    def add(self, err: SpecError) -> None:
        self.errors.extend(err.errors if isinstance(err, SpecErrors) else [err])

    @contextmanager
    def check(self) -> Iterator[None]:
        """Run a block; a :class:`SpecError` in it is recorded, not raised."""
        try:
            yield
        except SpecError as err:
            self.add(err)

    def raise_if_any(self) -> None:
        """Raise the one error as it is, or :class:`SpecErrors` for several."""
        if len(self.errors) == 1:
            raise self.errors[0]
        if self.errors:
            raise SpecErrors(self.errors)
