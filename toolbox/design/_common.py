"""Pieces every design method shares: the artifact assembly and plant access."""

from __future__ import annotations

from datetime import datetime, timezone
from typing import Any

from .._version import toolbox_version
from ..artifact import AxisController, ControllerArtifact, Decoupling, spec_sha256

__all__ = ["make_artifact", "decoupling_from_motor"]


def decoupling_from_motor(motor, *, cross: bool = True, emf: bool = True) -> Decoupling:
    """Compensation terms using the motor's own (nominal) parameters."""
    return Decoupling(cross=cross, emf=emf, R_c=motor.R, Ld_c=motor.Ld, Lq_c=motor.Lq,
                      flux_c=motor.flux, pole_pairs=motor.pole_pairs)


def make_artifact(spec, axes: dict[str, AxisController], decoupling: Decoupling,
                  gains: dict[str, Any], equations: list[str]) -> ControllerArtifact:
    """Assemble the artifact of a design made from ``spec``.

    ``equations`` lists the source equations used (e.g. ``"000 eq (11)"``),
    recorded in the provenance.
    """
    return ControllerArtifact(
        method=spec.controller.method,
        spec=spec.raw,
        sample_time=spec.drive.sample_time,
        delay_samples=spec.drive.delay_samples,
        axes=axes,
        decoupling=decoupling,
        gains=gains,
        provenance={
            "version": toolbox_version(),
            "spec_sha256": spec_sha256(spec.raw),
            "created": datetime.now(timezone.utc).replace(microsecond=0).isoformat(),
            "equations": list(equations),
        },
    )
