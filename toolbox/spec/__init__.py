"""Spec files: TOML -> validated frozen dataclasses."""

from .._lazy import lazy_attributes

from ._bounds import (RATE_TS, SCALE_RANGE, check_gain, check_rate, check_scale,
                      check_time_constant)
from ._campaign import (CAMPAIGN_PARAMETERS, DISTRIBUTIONS, OPERATING_POINT_KEYS, CampaignCfg,
                        ParameterDist)
from ._catalog import CATALOG, CATALOG_NOTES
from ._fields import Collector, SpecErrors, Table, check_keys, is_finite_number
from ._load import drive_from_dict, load_spec, motor_from_dict, spec_from_dict
from ._methods import read_method_cfg, register_method_reader, registered_methods
from ._render import spec_to_toml
from ._scenario import INVERTER_KINDS, SCENARIO_KINDS, Scenario
from ._model import (METHODS, MOTOR_PARAMETER_KEYS, REQUIREMENT_KEYS, ControllerChoice, Drive, Motor, inverter_radii,
                     Requirements, Spec)

__all__ = ["CATALOG", "CATALOG_NOTES", "Collector", "SpecErrors", "Table", "check_keys", "is_finite_number", "load_spec",
           "spec_from_dict", "METHODS", "MOTOR_PARAMETER_KEYS", "REQUIREMENT_KEYS", "ControllerChoice",
           "Drive", "Motor", "Requirements", "Spec", "inverter_radii",
           "motor_from_dict", "drive_from_dict", "read_method_cfg",
           "register_method_reader", "registered_methods", "spec_to_toml",
           "CAMPAIGN_PARAMETERS", "DISTRIBUTIONS", "OPERATING_POINT_KEYS", "CampaignCfg",
           "ParameterDist", "RATE_TS", "SCALE_RANGE", "check_gain", "check_rate", "check_scale",
           "check_time_constant", "INVERTER_KINDS", "SCENARIO_KINDS", "Scenario",
           "AlgebraicSaturation", "FluxMapData", "MagneticModel"]

# lazy: the magnetic models compute with numpy, which `cct` must not load
# before it has set the BLAS thread count (toolbox.cli); a constant-parameter
# spec never needs them
_LAZY = {"AlgebraicSaturation": "_magnetics", "FluxMapData": "_magnetics",
         "MagneticModel": "_magnetics"}
__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, globals())
