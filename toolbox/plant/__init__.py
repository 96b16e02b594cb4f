"""The plant: symbolic dq derivation and the numeric models made from it."""

from ._describe import describe_model
from ._numeric import ElectricalPlant, axis_plants, linearise, numeric_plant
from ._symbolic import SYMBOLS, DqModel, derive_dq_model, park_matrix

__all__ = ["describe_model", "ElectricalPlant", "axis_plants", "linearise", "numeric_plant", "SYMBOLS",
           "DqModel", "derive_dq_model", "park_matrix"]
