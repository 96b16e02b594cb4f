"""The controller artifact: the hinge between design and everything after it.

A :class:`ControllerArtifact` holds, per current axis, one executed law: the
two-input law ``[i_ref, i_meas] -> v`` that simulation and firmware run (it
differs from the error controller for IP, ILQ and total-compensation
structures, whose proportional action acts on the measurement), its
continuous-time twin (same order) and the views derived from it (the error
-> voltage ``discrete`` controller, the zpk form). Decoupling, back-EMF and
delay compensation are nonlinear terms kept apart in :class:`Decoupling`;
method fields later stages execute or draw are typed (:class:`FcsWeights`,
:class:`AxisWeights`); everything else is informational
(``design_parameters``).

The JSON form (``controller.json``, schema ``cct.controller/2``) round-trips
exactly: floats are written with ``repr`` precision and read back unchanged.
Files of schema ``cct.controller/1`` (untyped ``gains``) are refused with
"re-run cct design".

This module holds the artifact and its JSON I/O; the axis law and its views
are in ``_axis``, :class:`Decoupling` in ``_decoupling``, the typed method
fields in ``_fields`` (all re-exported here and by :mod:`toolbox.artifact`).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field, replace
from typing import Any, Mapping

import numpy as np

from .._io import check_data_depth, check_text_depth
from ..errors import ArtifactError
# _antiwindup_gain: re-exported for the tests (tests/sim/test_saturation.py)
from ._axis import AxisController, StateSpaceData, Zpk, _antiwindup_gain  # noqa: F401
from ._decoupling import Decoupling
from ._cv import CvLaw
from ._fields import (AxisWeights, FcsWeights, TransferFunctionData, _no_unknown,
                      finite_number)
from ..spec import METHODS

__all__ = [
    "SCHEMA",
    "StateSpaceData",
    "Zpk",
    "AxisController",
    "Decoupling",
    "FcsWeights",
    "CvLaw",
    "AxisWeights",
    "TransferFunctionData",
    "ControllerArtifact",
    "spec_sha256",
    "json_ready",
]

SCHEMA = "cct.controller/2"
#: Schemas of older toolboxes: refused with "re-run cct design".
OLD_SCHEMAS = ("cct.controller/1",)
AXES = ("d", "q")

#: The MARGINS keys (toolbox/ARCHITECTURE.md "controller.json"): numbers (non-finite ones as the strings
#: "inf", "-inf", "nan") or null. Other keys (lists of crossings, skewed disk
#: margins, "domain") are free-form analysis details.
MARGIN_NUMBERS = ("gain_margin_db", "gain_crossover_rad_s", "phase_margin_deg",
                  "phase_crossover_rad_s", "disk_margin", "stability_margin",
                  "sensitivity_peak", "bandwidth_rad_s", "static_error")


def _check_margins(margins: Mapping) -> None:
    """``{"d": MARGINS, "q": MARGINS}``: objects whose MARGINS keys are numbers."""
    for axis, values in margins.items():
        if axis not in AXES:
            raise ArtifactError(f"margins.{axis}", 'one of the axes "d", "q"', "unknown key")
        if not isinstance(values, Mapping):
            raise ArtifactError(f"margins.{axis}", "an object (MARGINS)", values)
        for name in MARGIN_NUMBERS:
            v = values.get(name)
            ok = (v is None or (isinstance(v, (int, float)) and not isinstance(v, bool)
                                and not (isinstance(v, int) and abs(v) >= 2 ** 1024))
                  or v in ("inf", "-inf", "nan"))  # 2**1024: no double holds it
            if not ok:
                raise ArtifactError(f"margins.{axis}.{name}",
                                    'a number, "inf", "-inf", "nan" or null', v)
        if "stable" in values and not isinstance(values["stable"], (bool, type(None))):
            raise ArtifactError(f"margins.{axis}.stable", "true, false or null",
                                values["stable"])


def json_ready(value: Any) -> Any:
    """Plain-JSON copy, the one encoder of every JSON the toolbox writes
    (controller.json, analysis.json): mappings to dicts, arrays and tuples to
    lists, numpy scalars to Python, complex to ``[re, im]``, non-finite floats
    to the strings ``"inf"``, ``"-inf"``, ``"nan"``.

    Parameters
    ----------
    value : Any
        Nested mappings, sequences, arrays and scalars.

    Returns
    -------
    Any
        The same structure in plain JSON types.
    """
    # exact plain types first: analysis.json holds tens of thousands of floats, and
    # the ABC check isinstance(x, Mapping) on each cost most of its encoding
    kind = type(value)
    if kind is float:
        return value if math.isfinite(value) else _non_finite(value)
    if kind in _PLAIN:
        return value
    if kind is list or kind is tuple:
        return [v if type(v) is float and math.isfinite(v) else json_ready(v) for v in value]
    if kind is dict or isinstance(value, Mapping):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (complex, np.complexfloating)):
        return [float(value.real), float(value.imag)]
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else _non_finite(v)
    return value


#: Exact types :func:`json_ready` returns unchanged.
_PLAIN = frozenset({int, str, bool, type(None)})


def _non_finite(v: float) -> str:
    """The JSON string of a non-finite float."""
    return "inf" if v > 0 else "-inf" if v < 0 else "nan"


def spec_sha256(spec: Mapping) -> str:
    """SHA-256 of the canonical JSON form of a validated spec."""
    text = json.dumps(json_ready(spec), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _check_schema(schema: Any) -> None:
    """The current schema, with a remedy for files of an older toolbox."""
    if schema == SCHEMA:
        return
    if schema in OLD_SCHEMAS:
        raise ArtifactError("schema", f'"{SCHEMA}"', schema,
                            hint="written by an older toolbox whose gains dict later stages "
                            "had to guess keys from; re-run cct design on the spec")
    raise ArtifactError("schema", f'"{SCHEMA}"', schema,
                        hint="written by another version of the toolbox?")


def _weights_from_json(data: Any) -> dict[str, AxisWeights] | None:
    """``{"d": AxisWeights, "q": AxisWeights}`` or ``None`` (JSON null or absent)."""
    if data is None:
        return None
    if not isinstance(data, Mapping) or set(data) != set(AXES):
        raise ArtifactError("weights", 'null or an object with the axes "d" and "q"',
                            sorted(data) if isinstance(data, Mapping) else data)
    return {ax: AxisWeights.from_json(data[ax], f"weights.{ax}") for ax in AXES}


@dataclass(frozen=True, eq=False)
class ControllerArtifact:
    """Everything after design reads this; nothing after design re-runs design.

    Attributes
    ----------
    method : str
        Design method (``pi``, ``ip``, ``pi_lag``, ``tc``, ``tci``, ``ilq``,
        ``lq``, ``hinf``, ``fcs_mpc``).
    spec : dict
        The validated spec (plain data) the design came from.
    sample_time : float
        Controller period (s).
    delay_samples : int
        Computation delay the design assumes (periods).
    axes : dict
        ``{"d": AxisController, "q": AxisController}``; each axis' ``law`` is
        the one executed.
    decoupling : Decoupling
        Nonlinear compensation terms the law executes (cross-coupling,
        back-EMF, delay-compensation rotation) and the controller-side model.
    fcs : FcsWeights or None
        Criterion (23) weights of the predictive law (``fcs_mpc`` only).
    cv : CvLaw or None
        The direct discrete-time complex-vector law (method ``cv`` only, then
        required): the simulator and the header execute it instead of the
        axes' laws, which hold its standstill law (exact at zero speed, where
        it decouples) for the per-axis views.
    weights : dict or None
        ``{"d": AxisWeights, "q": AxisWeights}``: validated H-infinity
        weights and levels (required for ``hinf``; optional for other
        methods, whose report then draws the bounds too).
    design_parameters : dict
        Informational method-specific numbers (plain JSON data) shown in the
        report; no later stage branches on them.
    margins : dict
        ``{"d": MARGINS, "q": MARGINS}`` of the sampled executed loop once
        analysis ran (else empty).
    provenance : dict
        ``version``, ``spec_sha256``, ``created``, ``equations`` used.
    """

    method: str
    spec: dict
    sample_time: float
    delay_samples: int
    axes: dict[str, AxisController]
    decoupling: Decoupling
    fcs: FcsWeights | None = None
    weights: dict[str, AxisWeights] | None = None
    design_parameters: dict = field(default_factory=dict)
    margins: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)
    cv: CvLaw | None = None

    def __post_init__(self) -> None:
        if set(self.axes) != set(AXES):
            raise ArtifactError("axes", 'exactly the axes "d" and "q"', sorted(self.axes))
        for name, axis in self.axes.items():
            if not math.isclose(axis.law.dt, self.sample_time, rel_tol=1e-12):
                raise ArtifactError(f"axes.{name}.law.dt",
                                    f"dt equal to sample_time {self.sample_time}", axis.law.dt)
        if self.weights is not None and set(self.weights) != set(AXES):
            raise ArtifactError("weights", 'exactly the axes "d" and "q"', sorted(self.weights))
        if self.method == "fcs_mpc" and self.fcs is None:
            raise ArtifactError("fcs", "an object {alpha, beta, gamma} (the fcs_mpc law "
                                "executes criterion (23) with it)", "nothing (missing or null)")
        if self.method != "fcs_mpc" and self.fcs is not None:
            # a linear law would silently ignore them
            raise ArtifactError("fcs", "null (only method fcs_mpc executes criterion (23) "
                                "weights)", f"weights for method {self.method}")
        if (self.method == "cv") != (self.cv is not None):
            raise ArtifactError("cv", "an object {bandwidth, integral_bandwidth, delay_pole} "
                                "for method cv, null for every other method (a linear law "
                                "would silently ignore it)",
                                "nothing (missing or null)" if self.cv is None
                                else f"a cv law for method {self.method}")
        if self.cv is not None and self.decoupling.cross:
            # the cv law holds the cross-coupling in its gains: the static terms twice
            raise ArtifactError("decoupling.cross", "false for method cv (its gains hold "
                                "the dq coupling)", True)
        if self.method == "hinf" and self.weights is None:
            raise ArtifactError("weights", 'an object with the axes "d" and "q" (the '
                                "H-infinity weights the bounds of 003 eq (41)-(43) are drawn "
                                "from)", "nothing (missing or null)")

    def with_margins(self, margins: dict) -> "ControllerArtifact":
        """A copy carrying analysis results."""
        return replace(self, margins=json_ready(margins))

    def to_json(self) -> dict:
        return {
            "schema": SCHEMA,
            "method": self.method,
            "spec": json_ready(self.spec),
            "sample_time": self.sample_time,
            "delay_samples": self.delay_samples,
            "axes": {name: self.axes[name].to_json() for name in AXES},
            "decoupling": self.decoupling.to_json(),
            "fcs": None if self.fcs is None else self.fcs.to_json(),
            "weights": (None if self.weights is None
                        else {ax: self.weights[ax].to_json() for ax in AXES}),
            "design_parameters": json_ready(self.design_parameters),
            "margins": json_ready(self.margins),
            "provenance": json_ready(self.provenance),
        } | ({} if self.cv is None else {"cv": self.cv.to_json()})   # method cv only

    def law_sha256(self) -> str:
        """SHA-256 of what the executed law is made of (method, spec, sample time,
        delay, axes, decoupling, predictive weights), not of the stored margins or
        provenance: controller.h carries it, and ``cct verify`` compares it with the
        controller.json it verifies (ARCHITECTURE.md, "Artifacts")."""
        data = self.to_json()
        law = {k: data[k] for k in ("schema", "method", "spec", "sample_time",
                                    "delay_samples", "axes", "decoupling", "fcs")}
        if self.cv is not None:      # only then: every other law's digest is unchanged
            law["cv"] = data["cv"]
        text = json.dumps(law, sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()

    def dumps(self) -> str:
        """Deterministic JSON text (sorted keys are not used: field order is fixed)."""
        return json.dumps(self.to_json(), indent=1, allow_nan=False) + "\n"

    @classmethod
    def from_json(cls, data: Any, file: str | None = None) -> "ControllerArtifact":
        """Validate and load a controller.json document.

        Raises
        ------
        ArtifactError
            Wrong or old schema, missing or unknown keys, malformed matrices or
            typed fields, sample times that disagree; the message names
            ``file`` and the key path.
        """
        try:
            check_data_depth(data, ArtifactError)  # copies and readers below recurse
            return cls._from_json(data)
        except ArtifactError as err:
            raise err.with_file(file) if file else err from None

    @classmethod
    def _from_json(cls, data: Any) -> "ControllerArtifact":
        if not isinstance(data, Mapping):
            raise ArtifactError("", "a JSON object", type(data).__name__)
        _check_schema(data.get("schema"))
        allowed = {"schema", "method", "spec", "sample_time", "delay_samples", "axes",
                   "decoupling", "fcs", "cv", "weights", "design_parameters", "margins",
                   "provenance"}
        _no_unknown(data, allowed, "")
        for name in ("method", "sample_time", "axes", "decoupling"):
            if name not in data:
                raise ArtifactError(name, "a value (missing)")
        if not isinstance(data["method"], str):
            raise ArtifactError("method", "a method name", data["method"])

        if data["method"] not in METHODS:
            raise ArtifactError("method", "one of " + ", ".join(METHODS), data["method"])
        ts = data["sample_time"]
        if not finite_number(ts) or not ts > 0:  # Infinity parses as a JSON float
            raise ArtifactError("sample_time", "a finite number > 0 (s)", ts)
        delay = data.get("delay_samples", 0)
        if not isinstance(delay, int) or isinstance(delay, bool) or delay < 0:
            raise ArtifactError("delay_samples", "an integer >= 0", delay)
        if delay > 10:  # as drive.delay_samples of a spec
            raise ArtifactError("delay_samples", "an integer from 0 to 10", delay)
        axes_data = data["axes"]
        if not isinstance(axes_data, Mapping) or set(axes_data) != set(AXES):
            raise ArtifactError("axes", 'an object with the axes "d" and "q"',
                            sorted(axes_data) if isinstance(axes_data, Mapping) else axes_data)
        axes = {name: AxisController.from_json(axes_data[name], f"axes.{name}") for name in AXES}
        for name in ("spec", "design_parameters", "margins", "provenance"):
            if not isinstance(data.get(name, {}), Mapping):
                raise ArtifactError(name, "an object", data.get(name))
        _check_margins(data.get("margins", {}))
        fcs = None if data.get("fcs") is None else FcsWeights.from_json(data["fcs"], "fcs")
        cv = None if data.get("cv") is None else CvLaw.from_json(data["cv"], "cv")
        return cls(method=data["method"], spec=dict(data.get("spec", {})),
                   sample_time=float(ts), delay_samples=delay, axes=axes,
                   decoupling=Decoupling.from_json(data["decoupling"]),
                   fcs=fcs, cv=cv, weights=_weights_from_json(data.get("weights")),
                   design_parameters=dict(data.get("design_parameters", {})),
                   margins=dict(data.get("margins", {})),
                   provenance=dict(data.get("provenance", {})))

    @classmethod
    def loads(cls, text: str, file: str | None = None) -> "ControllerArtifact":
        """Parse controller.json text (see :meth:`from_json`)."""
        check_text_depth(text, ArtifactError, file=file)  # json recurses: bound depth first
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise ArtifactError("", "valid JSON", f"{err.msg} at line {err.lineno}",
                            file=file) from None
        return cls.from_json(data, file)
