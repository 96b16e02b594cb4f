"""Current Control Toolbox: robust current controllers for PMSM drives.

The pipeline as function calls::

    spec = toolbox.load_spec("designs/003_azaiz2007_hinf.toml")
    artifact = toolbox.design_spec(spec)              # ControllerArtifact
    artifact, analysis = toolbox.analyse(artifact, spec)
    result = toolbox.run_verification(artifact, spec)
    outputs = toolbox.build_outputs(spec)              # everything cct design writes
"""

from __future__ import annotations

from ._lazy import lazy_attributes
from .errors import ArtifactError, CctError, DesignInfeasible, ExportRefused, SpecError
from .spec import Spec, load_spec, spec_from_dict
from . import design as _design  # noqa: F401  registers the methods' parameter readers with spec

#: public name -> defining module, imported on first access (PEP 562): the
#: artifact and pipeline import scipy (its linear algebra, for toolbox.lti);
#: ``import toolbox`` and ``cct --help`` must not pay for it.
_LAZY = {
    "ControllerArtifact": "artifact",
    "analyse": "pipeline", "build_outputs": "pipeline", "design_spec": "pipeline",
    "run_verification": "pipeline", "write_outputs": "pipeline",
}


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, globals())

__all__ = ["ArtifactError", "CctError", "ControllerArtifact", "DesignInfeasible",
           "ExportRefused", "SpecError", "analyse", "build_outputs", "design_spec",
           "run_verification", "write_outputs", "Spec", "load_spec", "spec_from_dict"]
