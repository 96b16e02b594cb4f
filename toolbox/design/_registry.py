"""Which module designs which method, and how its parameters are read.

Each method module exposes ``read_cfg(method, table, motor, drive) -> Cfg``
(validating ``[controller.<method>]``) and ``design(spec) -> ControllerArtifact``.
Importing this package registers every method's ``read_cfg`` with the spec
stage (:func:`toolbox.spec.register_method_reader`), so that ``toolbox.spec``
validates method parameters without importing ``toolbox.design``.
"""

from __future__ import annotations

import importlib
from typing import Any

from ..errors import SpecError
from ..spec import read_method_cfg, register_method_reader  # re-exported: one route

__all__ = ["METHOD_MODULES", "read_method_cfg", "design"]

METHOD_MODULES = {
    "pi": "pi", "ip": "pi", "pi_lag": "pi",
    "tc": "total_comp", "tci": "total_comp",
    "ilq": "ilq", "lq": "lq", "hinf": "hinf", "fcs_mpc": "fcs_mpc",
    "robust_pi": "robust_pi", "tune": "tune", "cv": "cv_discrete",
}


def _module(method: str):
    if method not in METHOD_MODULES:
        raise SpecError("controller.method", f"one of {sorted(METHOD_MODULES)}", method)
    return importlib.import_module(f"{__package__}.{METHOD_MODULES[method]}")


def design(spec) -> Any:
    """Run the design method a validated spec asks for.

    Returns
    -------
    ControllerArtifact
    """
    return _module(spec.controller.method).design(spec)


class _LazyReader:
    """A method's ``read_cfg`` that imports its module on first call.

    Importing every method module at registration would pull scipy into every
    ``import toolbox``, ``cct --help`` and ``cct check``; only the
    method a spec names is imported, when the spec is read.
    """

    def __init__(self, method: str) -> None:
        self.method = method

    def __call__(self, method: str, table, motor, drive) -> Any:
        return _module(self.method).read_cfg(method, table, motor, drive)

    def __repr__(self) -> str:
        return f"<lazy read_cfg of toolbox.design.{METHOD_MODULES[self.method]}>"


def _register_readers() -> None:
    """Register every method's ``read_cfg`` (imported lazily) with the spec stage."""
    for method in METHOD_MODULES:
        register_method_reader(method, _LazyReader(method))


_register_readers()
