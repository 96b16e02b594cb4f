"""Setting up a simulation of a controller artifact: the executed law and the drive.

The simulator's inputs made from the spec's and the artifact's plain data:
:func:`drive_params` (the validated ``Drive`` as :class:`DriveParams`),
:func:`control_law` (the artifact's executed discrete laws, decoupling and
predictive weights as a :class:`ControlLaw`) and :func:`scenario_setup`
(both for one :class:`toolbox.spec.Scenario`). Verification
(``toolbox.verify``) and the campaign (``toolbox.campaign``) set up their
runs through them; nothing is re-designed here.
"""

from __future__ import annotations

import math

from toolbox.spec import Scenario

from ._simulate import AxisLaw, ControlLaw, DriveParams, SpeedLoop

__all__ = ["drive_params", "control_law", "scenario_setup"]


def drive_params(drive, inverter: str = "average") -> DriveParams:
    """Simulator drive settings.

    Parameters
    ----------
    drive : Drive
        Validated drive.
    inverter : {"average", "svm", "fcs_mpc"}
        Inverter model.
    """
    return DriveParams(vdc=drive.vdc, sample_time=drive.sample_time,
                       delay_samples=drive.delay_samples, v_limit=drive.voltage_limit,
                       inverter=inverter, switching_frequency=drive.switching_frequency,
                       hold_frame=drive.hold_frame,
                       voltage_priority=drive.voltage_priority)


def _axis_law(axis) -> AxisLaw:
    aw = None if axis.antiwindup is None else axis.antiwindup.reshape(-1)
    law = axis.law
    return AxisLaw(law.A, law.B, law.C, law.D, aw)


def control_law(artifact, speed_loop: SpeedLoop | None = None) -> ControlLaw:
    """The simulator's :class:`ControlLaw` executing ``artifact``.

    The executed law of each axis is the artifact's ``axes.<axis>.law``; the
    predictive law of ``fcs_mpc`` reads the typed ``artifact.fcs`` weights, and
    method ``cv`` executes its complex-vector law ``artifact.cv``.

    Parameters
    ----------
    artifact : ControllerArtifact
        The design.
    speed_loop : SpeedLoop, optional
        Outer speed loop of the scenario.
    """
    return ControlLaw(d=_axis_law(artifact.axes["d"]), q=_axis_law(artifact.axes["q"]),
                      sample_time=artifact.sample_time, decoupling=artifact.decoupling,
                      speed_loop=speed_loop, fcs=artifact.fcs, cv=artifact.cv)


def _speed_loop(scenario: Scenario, sample_time: float) -> SpeedLoop | None:
    sl = dict(scenario.speed_loop)
    if not sl:
        return None
    ts = sl.get("sample_time", sample_time)  # a whole multiple of Ts (checked at spec load)
    return SpeedLoop(kp=sl["kp"], ki=sl.get("ki", 0.0), kd=sl.get("kd", 0.0),
                     sample_time=ts, iq_limit=sl.get("iq_limit", math.inf))


def scenario_setup(artifact, scenario: Scenario, drive) -> tuple[ControlLaw, DriveParams]:
    """The simulator's law and drive for one scenario of ``artifact``.

    The law executes the artifact (:func:`control_law`) under the scenario's
    speed loop, if any; the inverter is the scenario's, else the predictive
    switching law for ``fcs_mpc`` and the ideal average inverter otherwise.
    Verification and the campaign (``toolbox.campaign``) both set up their
    runs through it.

    Parameters
    ----------
    artifact : ControllerArtifact
    scenario : Scenario
    drive : Drive
        The spec's validated drive.
    """
    inverter = scenario.inverter or ("fcs_mpc" if artifact.method == "fcs_mpc" else "average")
    return (control_law(artifact, _speed_loop(scenario, artifact.sample_time)),
            drive_params(drive, inverter))
