"""Controller artifact (controller.json) and its state-space views (toolbox.lti)."""

from ._artifact import SCHEMA, ControllerArtifact, json_ready, spec_sha256
from ._axis import AxisController, StateSpaceData, Zpk
from ._decoupling import Decoupling
from ._cv import CvGains, CvLaw, cv_gains
from ._fields import WEIGHT_NAMES, AxisWeights, FcsWeights, TransferFunctionData

__all__ = ["SCHEMA", "AxisController", "AxisWeights", "ControllerArtifact", "CvGains", "CvLaw",
           "cv_gains", "Decoupling", "FcsWeights", "StateSpaceData", "TransferFunctionData", "WEIGHT_NAMES", "Zpk",
           "json_ready", "spec_sha256"]
