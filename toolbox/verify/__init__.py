"""Verification: a controller artifact run through the spec's scenarios and judged.

The stage after analysis (toolbox/ARCHITECTURE.md "Stages"): :func:`verify`
recomputes margins and stability from the executed law, gives the drift-box
verdict, simulates every scenario (``toolbox.sim``; the spec's
``[[scenario]]`` tables, else :func:`default_scenarios`) and checks each
against the spec's requirements and the default checks; the result
(:class:`VerifyResult`) is verify.json. :func:`torque_speed_grid` checks the
current loop at the operating envelope's references over the speed range.
"""

from ._checks import fcs_ripple
from ._default_scenarios import default_scenarios
from ._envelope_grid import DEFAULT_SPEEDS, DEFAULT_TORQUES, GridPoint, torque_speed_grid
from ._verify import (MAX_CHECK_TRACE_ROWS, NO_REQUIREMENTS, ROBUSTNESS_CHECKS, VERIFY_SCHEMA,
                      ScenarioOutcome, VerifyResult, verify)

__all__ = ["verify", "VerifyResult", "ScenarioOutcome", "VERIFY_SCHEMA", "NO_REQUIREMENTS",
           "ROBUSTNESS_CHECKS", "MAX_CHECK_TRACE_ROWS", "default_scenarios", "fcs_ripple",
           "DEFAULT_SPEEDS", "DEFAULT_TORQUES", "GridPoint", "torque_speed_grid"]
