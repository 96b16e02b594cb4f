"""Design methods: each turns a validated spec into a ControllerArtifact.

One module per method (``pi``, ``total_comp``, ``ilq``, ``lq``, ``hinf``,
``fcs_mpc``, ``robust_pi``, ``tune``, ``cv_discrete``), each with ``read_cfg`` (validates
``[controller.<method>]``), ``design(spec)`` and a plain API on toolbox.lti or python-control
plants and numbers,
re-exported here. ``steady_state`` holds the symbolic steady-state analysis
of paper 000. ``_defaults`` derives the parameters a spec leaves out from
the sample time and the delay (``default_bandwidth``, ``current_scale``,
``speed_scale``, ``largest_stable_pi_bandwidth``). ``cv_discrete`` is method
``cv``, the direct discrete-time complex-vector design (Hinkkanen et al.
2016) with its exact closed-loop analysis; its artifact carries the law
(``toolbox.artifact.CvLaw``), whose speed-dependent gains every later stage
computes at the measured speed (toolbox/ARCHITECTURE.md "Direct
discrete-time complex-vector control").
"""

from __future__ import annotations

from .._lazy import lazy_attributes
# light (math only): imported eagerly, toolbox.sim's default scenarios use it
from ._defaults import (current_scale, default_bandwidth, largest_stable_pi_bandwidth,
                        speed_scale)
from ._registry import METHOD_MODULES, design, read_method_cfg

#: public name -> defining submodule. The method modules import scipy (and
#: steady_state sympy): they are loaded on first attribute access (PEP 562)
#: so that ``import toolbox`` stays light.
_LAZY = {
    "design_hinf_axis": "hinf",
    "design_ilq": "ilq", "inverse_lq": "ilq", "inverse_lq_sdp": "ilq", "sigma_bound": "ilq",
    "bryson_weights": "lq", "design_lq": "lq", "lqi_continuous": "lq", "lqi_discrete": "lq",
    "design_pi": "pi", "gains_cancellation": "pi", "gains_symmetric_optimum": "pi",
    "pi_acceleration_steady_state": "steady_state",
    "tc_speed_error_steady_state": "steady_state",
    "tci_acceleration_steady_state": "steady_state",
    "design_total_compensation": "total_comp", "gains_match_pi": "total_comp",
    "design_cv_discrete": "cv_discrete", "CvDiscreteLaw": "cv_discrete",
}


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, globals())


__all__ = ["METHOD_MODULES", "design", "read_method_cfg", "design_hinf_axis", "design_ilq",
           "inverse_lq", "inverse_lq_sdp", "sigma_bound", "bryson_weights", "design_lq",
           "lqi_continuous", "lqi_discrete", "design_pi", "gains_cancellation",
           "gains_symmetric_optimum", "pi_acceleration_steady_state",
           "tc_speed_error_steady_state", "tci_acceleration_steady_state",
           "design_total_compensation", "gains_match_pi", "design_cv_discrete",
           "CvDiscreteLaw", "default_bandwidth",
           "largest_stable_pi_bandwidth", "current_scale", "speed_scale"]
