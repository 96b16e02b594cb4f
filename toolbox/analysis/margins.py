"""Stability margins of the current loops: the public face of the margin modules.

The implementation lives in private modules, one concept each:

* :mod:`._siso` - the one margins API (:func:`frequency_margins`,
  :func:`lti_loop_margins`, :func:`grid_margins`, disk margins);
* :mod:`._laws` - loops from the executed laws (:func:`axis_law`);
* :mod:`._statespace` - state-space algebra and ZOH discretisations;
* :mod:`._axis` - per-axis loops, :class:`MarginsResult`, :func:`compute_margins`;
* :mod:`._steps` - linear step responses and their figures;
* :mod:`._coupled` - the coupled dq loop at speed;
* :mod:`._mimo` - multiloop disk margins over speed;

and re-exports :func:`toolbox.artifact.json_ready` (the one JSON encoder).

Import from here (or from :mod:`toolbox.analysis`), never from the private
modules (toolbox/ARCHITECTURE.md "Privacy rule").
"""

from __future__ import annotations

from ._axis import AxisLoop, MarginsResult, axis_margins, compute_margins, make_axis_loop
from ._coupled import CoupledLoop, coupled_closed_loop, coupled_plant, decoupling_matrix
from ..artifact import json_ready
from ._laws import AXES, Law, axis_law, law_to_continuous
from ._mimo import (MimoBoxResult, MimoMarginsResult, MultiModelLoops, mimo_disk_margins,
                    mimo_loop_response, mimo_over_box, mu_upper_2x2, multimodel_disk_margins,
                    sigma_max_2x2)
from ._siso import (MARGIN_KEYS, FrequencyMargins, disk_variations, frequency_margins,
                    grid_margins, lti_loop_margins, log_grid)
from ._statespace import (closed_loop, freqresp, is_stable, pade, plant_chain, series,
                          zoh_2x2, zoh_axis, zoh_coupled)
from ._steps import step_figures, step_response

__all__ = ["MARGIN_KEYS", "MarginsResult", "MimoMarginsResult", "AxisLoop", "CoupledLoop",
           "compute_margins", "make_axis_loop", "axis_margins", "mimo_disk_margins",
           "mimo_loop_response", "MultiModelLoops", "multimodel_disk_margins",
           "MimoBoxResult", "mimo_over_box",
           "coupled_closed_loop", "coupled_plant", "decoupling_matrix",
           "disk_variations", "law_to_continuous", "mu_upper_2x2", "sigma_max_2x2",
           "zoh_2x2", "json_ready",
           # the one margins API
           "FrequencyMargins", "frequency_margins", "lti_loop_margins", "grid_margins",
           "log_grid",
           # loop building blocks (used by robustness, certificate and the tests)
           "AXES", "Law", "axis_law", "freqresp", "zoh_axis", "plant_chain", "pade", "series",
           "closed_loop", "is_stable", "zoh_coupled", "step_response", "step_figures"]
