"""Closed-loop verification: compiled PMSM simulation with sampling, delay and inverter."""

from ._metrics import METRIC_NAMES, step_metrics
from ._scenario import INVERTER_KINDS, SCENARIO_KINDS, Scenario
from ._simulate import (AxisLaw, BatchResult, ControlLaw, DriveParams, FcsWeights,
                        SimResult, SpeedLoop, discrete_pi, simulate, simulate_batch)

__all__ = ["METRIC_NAMES", "step_metrics", "INVERTER_KINDS", "SCENARIO_KINDS", "Scenario",
           "AxisLaw", "BatchResult", "ControlLaw", "DriveParams", "FcsWeights",
           "SimResult", "SpeedLoop", "discrete_pi", "simulate", "simulate_batch"]

from ._verify import (NO_REQUIREMENTS, ROBUSTNESS_CHECKS, VERIFY_SCHEMA, ScenarioOutcome, VerifyResult, control_law,
                      default_scenarios, drive_params, scenario_setup, verify)

__all__ += ["NO_REQUIREMENTS", "ROBUSTNESS_CHECKS", "VERIFY_SCHEMA", "ScenarioOutcome", "VerifyResult", "control_law",
            "default_scenarios", "drive_params", "scenario_setup", "verify"]

from ._envelope_grid import DEFAULT_SPEEDS, DEFAULT_TORQUES, GridPoint, torque_speed_grid

__all__ += ["DEFAULT_SPEEDS", "DEFAULT_TORQUES", "GridPoint", "torque_speed_grid"]
