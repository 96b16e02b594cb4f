"""The plant: symbolic dq derivation and the numeric models made from it.

The symbolic names (the derivation, its symbols, :func:`describe_model`) are
imported on first access (PEP 562): they import sympy (about 0.7 s with the
units module its ``simplify`` pulls in), which a design whose numeric model
comes from the on-disk cache does not need.
"""

from __future__ import annotations

from .._lazy import lazy_attributes
from ._limits import max_electrical_speed
from ._linear import (axis_coefficients, dq_matrices, steady_state_voltage,
                      voltage_limited_speed, zoh_first_order)
from ._numeric import ElectricalPlant, axis_plant_models, axis_plants, linearise, numeric_plant
from ._saturation import at_operating_point, incremental_dq_matrices

#: public name -> defining private module, imported on first use
_LAZY = {"describe_model": "_describe", "SYMBOLS": "_symbolic", "DqModel": "_symbolic",
         "derive_dq_model": "_symbolic", "park_matrix": "_symbolic",
         "FluxLinkageModel": "_symbolic_flux",
         "derive_flux_linkage_model": "_symbolic_flux",
         # the operating envelopes (the saturated one imports scipy.optimize)
         "OperatingEnvelope": "_envelope", "OperatingPoint": "_envelope",
         "mtpa_d_current": "_envelope", "SaturatedEnvelope": "_envelope_saturated",
         "envelope_of": "_envelope"}


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, globals())


__all__ = ["at_operating_point", "incremental_dq_matrices", "OperatingEnvelope", "OperatingPoint", "mtpa_d_current",
           "SaturatedEnvelope", "envelope_of", "describe_model", "max_electrical_speed", "axis_coefficients", "dq_matrices",
           "zoh_first_order", "steady_state_voltage", "voltage_limited_speed",
           "ElectricalPlant", "axis_plant_models", "axis_plants", "linearise", "numeric_plant",
           "SYMBOLS", "DqModel", "derive_dq_model", "park_matrix", "FluxLinkageModel",
           "derive_flux_linkage_model"]
