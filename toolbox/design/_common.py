"""Pieces every design method shares: the artifact assembly and plant access."""

from __future__ import annotations

from dataclasses import replace
from datetime import datetime, timezone
from typing import Any

from .._version import toolbox_version
from ..artifact import (AxisController, AxisWeights, ControllerArtifact, CvLaw, Decoupling,
                        FcsWeights, spec_sha256)

__all__ = ["make_artifact", "decoupling_from_motor"]


def decoupling_from_motor(motor, *, cross: bool = True, emf: bool = True) -> Decoupling:
    """Compensation terms using the motor's own (nominal) parameters (the
    voltage placement is the drive's, set by :func:`make_artifact`)."""
    return Decoupling.from_motor(motor, cross=cross, emf=emf)


def make_artifact(spec, axes: dict[str, AxisController], decoupling: Decoupling,
                  design_parameters: dict[str, Any], equations: list[str], *,
                  fcs: FcsWeights | None = None,
                  weights: dict[str, AxisWeights] | None = None,
                  cv: CvLaw | None = None) -> ControllerArtifact:
    """Assemble the artifact of a design made from ``spec``.

    ``design_parameters`` are informational (shown in the report, never
    branched on); what a later stage executes or draws goes in the typed
    fields (``decoupling``, ``fcs``, ``weights``, ``cv``). ``equations`` lists the
    source equations used (e.g. ``"000 eq (11)"``), recorded in the provenance.

    The decoupling's ``delay_compensation_time`` is the drive's voltage
    placement (``drive.angle_compensation``, toolbox/ARCHITECTURE.md "The
    digital loop"), the same for every method; the predictive law (``fcs``)
    switches inverter states in the stationary frame and places no voltage.
    """
    t_comp = 0.0 if fcs is not None else spec.drive.angle_compensation_time
    decoupling = replace(decoupling, delay_compensation_time=t_comp)
    return ControllerArtifact(
        method=spec.controller.method,
        spec=spec.raw,
        sample_time=spec.drive.sample_time,
        delay_samples=spec.drive.delay_samples,
        axes=axes,
        decoupling=decoupling,
        fcs=fcs,
        weights=weights,
        cv=cv,
        design_parameters=design_parameters,
        provenance={
            "version": toolbox_version(),
            "spec_sha256": spec_sha256(spec.raw),
            "created": datetime.now(timezone.utc).replace(microsecond=0).isoformat(),
            "equations": list(equations),
            # the magnetic data of a saturated motor (its flux-map file or saturation
            # parameters): toolbox/ARCHITECTURE.md "controller.json"
            **({"magnetics_sha256": spec.motor.magnetics.data_sha256()}
               if spec.motor.magnetics is not None else {}),
        },
    )
