"""Design methods: each turns a validated spec into a ControllerArtifact.

One module per method (``pi``, ``total_comp``, ``ilq``, ``lq``, ``hinf``,
``fcs_mpc``), each with ``read_cfg`` (validates ``[controller.<method>]``),
``design(spec)`` and a plain API on python-control plants and numbers,
re-exported here. ``steady_state`` holds the symbolic steady-state analysis
of paper 000. ``_defaults`` derives the parameters a spec leaves out from
the sample time and the delay (``default_bandwidth``, ``current_scale``,
``speed_scale``, ``largest_stable_pi_bandwidth``).
"""

from ._defaults import (current_scale, default_bandwidth, largest_stable_pi_bandwidth,
                        speed_scale)
from ._registry import METHOD_MODULES, design, read_method_cfg
from .hinf import design_hinf_axis
from .ilq import design_ilq, inverse_lq, inverse_lq_sdp, sigma_bound
from .lq import bryson_weights, design_lq, lqi_continuous, lqi_discrete
from .pi import design_pi, gains_cancellation, gains_symmetric_optimum
from .steady_state import (pi_acceleration_steady_state, tc_speed_error_steady_state,
                           tci_acceleration_steady_state)
from .total_comp import design_total_compensation, gains_match_pi

__all__ = ["METHOD_MODULES", "design", "read_method_cfg", "design_hinf_axis", "design_ilq",
           "inverse_lq", "inverse_lq_sdp", "sigma_bound", "bryson_weights", "design_lq",
           "lqi_continuous", "lqi_discrete", "design_pi", "gains_cancellation",
           "gains_symmetric_optimum", "pi_acceleration_steady_state",
           "tc_speed_error_steady_state", "tci_acceleration_steady_state",
           "design_total_compensation", "gains_match_pi", "default_bandwidth",
           "largest_stable_pi_bandwidth", "current_scale", "speed_scale"]
