"""Spec files: TOML -> validated frozen dataclasses."""

from ._catalog import CATALOG, CATALOG_NOTES
from ._fields import Collector, SpecErrors, Table, check_keys
from ._load import load_spec, spec_from_dict
from ._model import (METHODS, REQUIREMENT_KEYS, ControllerChoice, Drive, Motor, inverter_radii,
                     Requirements, Spec)

__all__ = ["CATALOG", "CATALOG_NOTES", "Collector", "SpecErrors", "Table", "check_keys", "load_spec",
           "spec_from_dict", "METHODS", "REQUIREMENT_KEYS", "ControllerChoice",
           "Drive", "Motor", "Requirements", "Spec", "inverter_radii"]
