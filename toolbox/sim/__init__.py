"""The closed-loop simulator: compiled PMSM plant with sampling, delay and inverter.

Runs one :class:`toolbox.spec.Scenario` (or a batch) of a :class:`ControlLaw`
on a true plant (a :class:`toolbox.spec.Motor`) and returns its metrics
(:data:`METRIC_NAMES`, step metrics as defined in :mod:`toolbox.metrics`) and
optional traces. :func:`control_law`, :func:`drive_params` and
:func:`scenario_setup` make the simulator's inputs from a controller artifact
and a validated drive. Judging a run is verification's (``toolbox.verify``).
"""

from ._metrics import METRIC_NAMES
from ._setup import control_law, drive_params, scenario_setup
from ._simulate import (AxisLaw, BatchResult, ControlLaw, DriveParams, FcsWeights,
                        SimResult, SpeedLoop, discrete_pi, simulate, simulate_batch)

__all__ = ["METRIC_NAMES", "AxisLaw", "BatchResult", "ControlLaw", "DriveParams", "FcsWeights",
           "SimResult", "SpeedLoop", "discrete_pi", "simulate", "simulate_batch",
           "control_law", "drive_params", "scenario_setup"]
