"""Registry of the design methods' parameter readers.

The spec stage validates ``[controller.<method>]`` without knowing the
methods: each design method registers a reader here when its package is
imported (:mod:`toolbox.design` does it for all of them; ``import toolbox``
imports it). ``toolbox.spec`` therefore never imports ``toolbox.design``
(checked by ``tests/test_architecture.py``; toolbox/ARCHITECTURE.md "Layers").

A reader has the signature ``reader(method, table, motor, drive) -> cfg``:
``table`` is the :class:`~toolbox.spec.Table` of ``[controller.<method>]``,
``motor``/``drive`` the validated :class:`Motor`/:class:`Drive`; it raises
:class:`~toolbox.errors.SpecError` naming the key path and returns the
method's frozen ``*Cfg`` object stored in ``ControllerChoice.cfg``.

Every error of the table in one run: a reader may stop at its first error
(or raise :class:`~toolbox.spec.SpecErrors` for a group it reads together);
:func:`read_method_cfg` then reads the table again without the offending
key, so that the reader takes that key's default and goes on to the next
mistake, until the table reads or no key is left to take out
(:func:`read_collecting`). An error that may be a consequence of a key taken
out (the key itself reported missing, an error on the table or a key above
it, one naming a taken-out key, a key missing that a taken-out key's error
names, or one outside the table) is not reported.
"""

from __future__ import annotations

import re
import warnings
from typing import Any, Callable, Mapping, Sequence

from ..errors import SpecError
from ._fields import Collector, Table

__all__ = ["MethodReader", "register_method_reader", "read_method_cfg", "registered_methods",
           "read_collecting", "MAX_METHOD_ERRORS"]

#: ``reader(method, table, motor, drive) -> cfg``
MethodReader = Callable[[str, Any, Any, Any], Any]

_READERS: dict[str, MethodReader] = {}


def register_method_reader(name: str, reader: MethodReader) -> None:
    """Register (or replace) the parameter reader of design method ``name``.

    Parameters
    ----------
    name : str
        Method name as written in ``controller.method``.
    reader : callable
        ``reader(method, table, motor, drive) -> cfg`` (module docstring).
    """
    if not callable(reader):
        raise TypeError(f"register_method_reader: reader for {name!r} is not callable")
    _READERS[name] = reader


def registered_methods() -> tuple[str, ...]:
    """Names of the methods with a registered reader, sorted."""
    return tuple(sorted(_READERS))


def read_method_cfg(method: str, table, motor, drive,
                    prior: Sequence[SpecError] = ()) -> Any:
    """Validate ``[controller.<method>]`` with the method's registered reader.

    Parameters
    ----------
    method : str
        Design method name.
    table : Table
        The ``[controller.<method>]`` table.
    motor : Motor
        Validated motor (gains may derive from it).
    drive : Drive
        Validated drive (sample time, delay).
    prior : sequence of SpecError, optional
        Errors already found in the table (a unit string that does not
        convert): reported first, their keys taken out before reading.

    Raises
    ------
    SpecError
        ``controller.method`` when no reader is registered for ``method``;
        every error of the table otherwise (one, or
        :class:`~toolbox.spec.SpecErrors` for several).
    """
    reader = _READERS.get(method)
    if reader is None:
        raise SpecError("controller.method",
                        f"a method with a registered parameter reader "
                        f"({', '.join(registered_methods()) or 'none registered'})", method,
                        hint="import toolbox.design (import toolbox does) to register the "
                             "design methods")
    return read_collecting(lambda t: reader(method, t, motor, drive), table, prior)


#: Readings of one table at most (each takes one key out): a table with
#: 10,000 unknown keys is reported by its first errors, not read 10,000 times.
MAX_METHOD_ERRORS = 20


def read_collecting(read: Callable[[Table], Any], table: Table,
                    prior: Sequence[SpecError] = ()) -> Any:
    """``read(table)``, with every independent error of ``table`` raised together.

    Parameters
    ----------
    read : callable
        ``read(Table) -> cfg``; raises :class:`SpecError` (or ``SpecErrors``).
    table : Table
        The method's table (not modified).
    prior : sequence of SpecError
        Errors found before (module docstring).

    Returns
    -------
    object
        What ``read`` returns when the table has no error.

    Raises
    ------
    SpecError
        The one error, or ``SpecErrors`` in the order found (``prior`` first);
        past :data:`MAX_METHOD_ERRORS` readings the list ends with an error on
        the table saying that more may follow.
    """
    prefix = table.prefix
    if not prior:
        try:
            return read(table)
        except SpecError as err:
            first = _errors_of(err)
    else:
        first = list(prior)
    data: Any = table.data  # taken apart by copies (_without), never changed
    found = Collector()
    removed: list[str] = []
    named: set[str] = set()  # the names in the errors whose keys were taken out
    batch = first
    with warnings.catch_warnings():  # a re-reading's warnings are no news
        warnings.simplefilter("ignore")
        for _ in range(MAX_METHOD_ERRORS):
            progress = False
            before = list(removed)  # errors of one reading are independent of each other
            named_before = set(named)
            for err in batch:
                if not _consequence(err, prefix, before, named_before):
                    found.add(err)
                path = _path_in(data, err.key, prefix)
                if path:
                    named.update(_WORD.findall(f"{err.expected} {err.hint or ''}"))
                    data = _without(data, path)
                    removed.append(".".join([prefix, *path]) if prefix else ".".join(path))
                    progress = True
            if not progress:
                break
            try:
                read(Table(data, prefix))
            except SpecError as err:
                batch = _errors_of(err)
            else:
                break
        else:
            found.add(SpecError(prefix, f"at most {MAX_METHOD_ERRORS} errors (the first are "
                                "listed above; more may follow)",
                                hint="correct them and check again"))
    if not found.failed:  # every error a consequence of another: report the first
        found.add(first[0])
    found.raise_if_any()
    raise AssertionError("unreachable")  # pragma: no cover


def _errors_of(err: SpecError) -> list[SpecError]:
    return list(getattr(err, "errors", None) or [err])


def _consequence(err: SpecError, prefix: str, removed: list[str], named: set[str]) -> bool:
    """``err`` may follow from a key taken out (module docstring): also a key
    reported missing that the error of a key taken out names (``Kp`` and
    ``Kp_normalised`` both given: with ``Kp_normalised`` out, ``Ki`` is not
    reported missing)."""
    if not removed:
        return False
    key = str(err.key)
    if not (key == prefix or key.startswith(prefix + ".")):
        return True
    if str(err.expected).endswith("(missing)") and key.rsplit(".", 1)[-1] in named:
        return True
    for gone in removed:
        if key == gone or gone.startswith(key + ".") or gone.startswith(key + "["):
            return True  # the key itself, or a table above it
        if key.startswith(gone + ".") or key.startswith(gone + "["):
            return True
        words = _WORD.findall(f"{err.expected} {err.hint or ''}")
        if gone.rsplit(".", 1)[-1] in words:  # "Kp_normalised and Ki_normalised alongside it"
            return True
    return False


_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _path_in(data: Any, key: str, prefix: str) -> list[str]:
    """The names leading from ``data`` to the deepest entry that ``key``
    (dotted, ``[i]`` indices, under ``prefix``) reaches; [] for none."""
    key = str(key)
    if prefix:
        if not key.startswith(prefix + "."):
            return []
        key = key[len(prefix) + 1:]
    path: list[str] = []
    node = data
    while key and isinstance(node, Mapping):
        # the longest name that the rest of the key starts with (a name may hold a dot)
        match = max((str(n) for n in node if key == str(n) or key.startswith(f"{n}.")
                     or key.startswith(f"{n}[")), key=len, default=None)
        if match is None:
            break
        path.append(match)
        node = node[match]
        key = key[len(match):]
        if key.startswith("["):  # an entry of a list: the list is what is taken out
            break
        key = key[1:]
    return path


def _without(data: Mapping, path: list[str]) -> dict:
    """``data`` with the entry at ``path`` taken out (copies along the path)."""
    out = dict(data)
    if len(path) == 1:
        out.pop(path[0], None)
    else:
        out[path[0]] = _without(out[path[0]], path[1:])
    return out
