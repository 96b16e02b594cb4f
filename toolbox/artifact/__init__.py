"""Controller artifact (controller.json) and its python-control conversions."""

from ._artifact import (SCHEMA, AxisController, ControllerArtifact, Decoupling,
                        StateSpaceData, Zpk, spec_sha256)

__all__ = ["SCHEMA", "AxisController", "ControllerArtifact", "Decoupling",
           "StateSpaceData", "Zpk", "spec_sha256"]
