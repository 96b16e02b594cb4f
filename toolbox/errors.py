"""The exceptions users see, under one base.

:class:`CctError` is the base of every error the toolbox raises on purpose; the
CLI turns any of them into exit code 2 and writes nothing. Any other exception
escaping the toolbox is a bug and keeps its traceback.

- :class:`SpecError`: bad input in a spec file or a method parameter.
- :class:`DesignInfeasible`: the spec is valid but the method cannot meet it
  (e.g. no H-infinity controller for the requested weights); a ``SpecError``
  because the remedy is a change of the spec.
- :class:`ArtifactError`: a ``controller.json`` (or ``analysis.json``) that is
  malformed, tampered with or from an incompatible version.
- :class:`ExportRefused`: a sound artifact that the requested firmware format
  cannot represent (range, precision, unsupported law).

:class:`InfrastructureError` is not a ``CctError``: the input is sound but
the machinery to run it is not (a Dask scheduler that cannot be reached or
does not answer, no workers, workers without the toolbox or with another
build of it, a full or read-only output disk). ``cct campaign`` turns it into
exit code 4 so that a release gate can tell "retry on a working cluster"
from "the design fails" (1) and "the input is wrong" (2).
"""

from __future__ import annotations

from typing import Any

__all__ = ["ArtifactError", "CctError", "DesignInfeasible", "ExportRefused",
           "InfrastructureError", "SpecError"]


#: Echo of a found value or a key path cut to this many characters (a
#: 500,000-character key or string must not make a 1 MB message) when it is
#: longer than :data:`MAX_WHOLE` (a long file path is still shown whole).
MAX_SHOWN = 80
MAX_WHOLE = 256


def _clip(text: str, limit: int = MAX_SHOWN, whole: int = MAX_WHOLE) -> str:
    """``text`` with control characters escaped (a message is one line per
    error: ``"m\\n"`` shows as ``m\\n``); longer than ``whole``, cut to
    ``limit`` characters with the length said."""
    if not text.isprintable():
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    if len(text) <= max(limit, whole):
        return text
    return f"{text[:limit - 3]}... ({len(text)} characters)"


def _show(value: Any) -> str:
    if isinstance(value, str):
        return f'"{_clip(value)}"'
    try:
        text = repr(value)
    except ValueError:  # an int beyond the interpreter's digit limit
        return f"an integer of about {int(value.bit_length() * 0.30103) + 1} digits"
    if isinstance(value, int) and len(text) > MAX_SHOWN:  # digits are never worth reading
        return f"{text[:20]}... (an integer of {len(text.lstrip('-'))} digits)"
    return _clip(text)


class CctError(ValueError):
    """An error the user can act on, located by file and dotted key path.

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
    >>> str(CctError("motor.R", "a number > 0", -1, file="designs/x.toml"))
    'designs/x.toml: motor.R: expected a number > 0, got -1'
    """

    _MISSING = object()

    def __init__(self, key: str, expected: str, got: Any = _MISSING, *,
                 file: str | None = None, hint: str | None = None) -> None:
        self.key = key
        self.expected = expected
        self.got = None if got is CctError._MISSING else got
        self.has_got = got is not CctError._MISSING
        self.file = file
        self.hint = hint
        super().__init__(self._text())

    def _text(self) -> str:
        where = f"{self.file}: " if self.file else ""
        key = f"{_clip(str(self.key))}: " if self.key else ""
        text = f"{where}{key}expected {_clip(str(self.expected), 1000, 1000)}"
        if self.has_got:
            text += f", got {_show(self.got)}"
        if self.hint:
            text += f" ({_clip(str(self.hint), 1000, 1000)})"
        return text

    def _copy(self, key: str, file: str | None) -> "CctError":
        return type(self)(key, self.expected,
                          self.got if self.has_got else CctError._MISSING,
                          file=file, hint=self.hint)

    def with_file(self, file: str) -> "CctError":
        """Return the same error (same class) located in ``file``."""
        return self._copy(self.key, file)

    def under(self, prefix: str) -> "CctError":
        """Return the same error (same class) with ``prefix`` prepended to the key path."""
        return self._copy(f"{prefix}.{self.key}" if self.key else prefix, self.file)


class SpecError(CctError):
    """Bad input in a spec file or a method parameter."""


class DesignInfeasible(SpecError):
    """A valid spec that the method cannot meet; the remedy is a spec change."""


class ArtifactError(CctError):
    """A malformed, tampered or incompatible controller.json / analysis.json."""


class ExportRefused(CctError):
    """A sound artifact that the requested firmware format cannot represent."""


class InfrastructureError(RuntimeError):
    """The run cannot proceed for a reason outside the input (exit code 4).

    Parameters
    ----------
    message : str
        What failed, in one line (names the address, worker or path).
    hint : str, optional
        What to do about it.

    Examples
    --------
    >>> str(InfrastructureError("no Dask worker joined tcp://127.0.0.1:8786 within 30 s",
    ...                         hint="start workers: dask worker tcp://127.0.0.1:8786"))
    'no Dask worker joined tcp://127.0.0.1:8786 within 30 s (start workers: dask worker tcp://127.0.0.1:8786)'
    """

    def __init__(self, message: str, *, hint: str | None = None) -> None:
        self.message = message
        self.hint = hint
        super().__init__(f"{message} ({hint})" if hint else message)
