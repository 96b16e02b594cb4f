"""Current Control Toolbox: robust current controllers for PMSM drives.

The pipeline as function calls::

    spec = toolbox.load_spec("designs/003_azaiz2007_hinf.toml")
    artifact = toolbox.design_spec(spec)              # ControllerArtifact
    artifact, analysis = toolbox.analyse(artifact, spec)
    result = toolbox.run_verification(artifact, spec)
    outputs = toolbox.build_outputs(spec)              # everything cct design writes
"""

from .artifact import ControllerArtifact
from .errors import ArtifactError, CctError, DesignInfeasible, ExportRefused, SpecError
from .pipeline import analyse, build_outputs, design_spec, run_verification, write_outputs
from .spec import Spec, load_spec, spec_from_dict
from . import design as _design  # noqa: F401  registers the methods' parameter readers with spec

__all__ = ["ArtifactError", "CctError", "ControllerArtifact", "DesignInfeasible",
           "ExportRefused", "SpecError", "analyse", "build_outputs", "design_spec",
           "run_verification", "write_outputs", "Spec", "load_spec", "spec_from_dict"]
