"""The one exception users see for bad input.

Every input problem (spec file, method parameter, unreachable requirement) raises
:class:`SpecError`; the CLI turns it into exit code 2 and writes nothing. Any other
exception escaping the toolbox is a bug and keeps its traceback.
"""

from __future__ import annotations

from typing import Any

__all__ = ["SpecError"]


def _show(value: Any) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    return repr(value)


class SpecError(ValueError):
    """Bad user input, located by file and dotted key path.

    Parameters
    ----------
    key : str
        Dotted key path inside the spec, e.g. ``controller.hinf.gamma``
        (empty for the whole file).
    expected : str
        What was expected, in words ("a number > 0").
    got : object, optional
        The offending value, shown with ``repr``.
    file : str, optional
        The spec file; ``None`` for specs given as dicts.
    hint : str, optional
        A remedy or did-you-mean suggestion appended to the message.

    Examples
    --------
    >>> str(SpecError("motor.R", "a number > 0", -1, file="designs/x.toml"))
    'designs/x.toml: motor.R: expected a number > 0, got -1'
    """

    _MISSING = object()

    def __init__(self, key: str, expected: str, got: Any = _MISSING, *,
                 file: str | None = None, hint: str | None = None) -> None:
        self.key = key
        self.expected = expected
        self.got = None if got is SpecError._MISSING else got
        self.has_got = got is not SpecError._MISSING
        self.file = file
        self.hint = hint
        super().__init__(self._text())

    def _text(self) -> str:
        where = f"{self.file}: " if self.file else ""
        key = f"{self.key}: " if self.key else ""
        text = f"{where}{key}expected {self.expected}"
        if self.has_got:
            text += f", got {_show(self.got)}"
        if self.hint:
            text += f" ({self.hint})"
        return text

    def with_file(self, file: str) -> "SpecError":
        """Return the same error located in ``file``."""
        err = SpecError(self.key, self.expected,
                        self.got if self.has_got else SpecError._MISSING,
                        file=file, hint=self.hint)
        return err

    def under(self, prefix: str) -> "SpecError":
        """Return the same error with ``prefix`` prepended to the key path."""
        key = f"{prefix}.{self.key}" if self.key else prefix
        return SpecError(key, self.expected,
                         self.got if self.has_got else SpecError._MISSING,
                         file=self.file, hint=self.hint)
