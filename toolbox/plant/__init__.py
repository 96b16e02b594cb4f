"""The plant: symbolic dq derivation and the numeric models made from it."""

from ._describe import describe_model
from ._limits import max_electrical_speed
from ._linear import (axis_coefficients, dq_matrices, steady_state_voltage,
                      voltage_limited_speed, zoh_first_order)
from ._numeric import ElectricalPlant, axis_plants, linearise, numeric_plant
from ._symbolic import SYMBOLS, DqModel, derive_dq_model, park_matrix

__all__ = ["describe_model", "max_electrical_speed", "axis_coefficients", "dq_matrices",
           "zoh_first_order", "steady_state_voltage", "voltage_limited_speed",
           "ElectricalPlant", "axis_plants", "linearise", "numeric_plant",
           "SYMBOLS", "DqModel", "derive_dq_model", "park_matrix"]
