"""The plant: symbolic dq derivation and the numeric models made from it."""

from ._describe import describe_model
from ._limits import max_electrical_speed
from ._numeric import ElectricalPlant, axis_plants, linearise, numeric_plant
from ._symbolic import SYMBOLS, DqModel, derive_dq_model, park_matrix

__all__ = ["describe_model", "max_electrical_speed", "ElectricalPlant", "axis_plants", "linearise", "numeric_plant", "SYMBOLS",
           "DqModel", "derive_dq_model", "park_matrix"]
