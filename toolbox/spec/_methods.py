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
"""

from __future__ import annotations

from typing import Any, Callable

from ..errors import SpecError

__all__ = ["MethodReader", "register_method_reader", "read_method_cfg", "registered_methods"]

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


def read_method_cfg(method: str, table, motor, drive) -> Any:
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

    Raises
    ------
    SpecError
        ``controller.method`` when no reader is registered for ``method``.
    """
    reader = _READERS.get(method)
    if reader is None:
        raise SpecError("controller.method",
                        f"a method with a registered parameter reader "
                        f"({', '.join(registered_methods()) or 'none registered'})", method,
                        hint="import toolbox.design (import toolbox does) to register the "
                             "design methods")
    return reader(method, table, motor, drive)
