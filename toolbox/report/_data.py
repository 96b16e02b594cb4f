"""The report's input bundle :class:`ReportData` (plain data of the earlier stages)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence


@dataclass
class ReportData:
    """Everything a report shows (plain data; only the first three are required).

    The report draws and tabulates what these hold and computes no loop,
    margin or response itself: ``analysis`` is ``analysis.json`` and
    ``verification`` is ``verify.json``, as written by ``cct design``.

    Attributes
    ----------
    title : str
        Report title (free user text; escaped in every output).
    spec : toolbox.spec.Spec
        The validated spec (motor, drive, requirements).
    artifact : toolbox.artifact.ControllerArtifact
        The designed controller (axes, typed fields, design parameters, provenance).
    analysis : dict or None
        ``analysis.json``: ``margins.discrete`` (the MARGINS table, margin
        markers and step figures), ``responses`` (every loop figure, see
        :mod:`toolbox.analysis._responses`), ``requirements`` (margin checks),
        ``sweep``, ``mimo_at_speed`` and ``certificate``. ``None``: margins
        from ``artifact.margins`` when non-empty, everything else "not
        computed".
    verification : dict or None
        ``verify.json``: per scenario ``name``, ``kind``, ``passed``,
        ``metrics`` and ``requirements``; ``margin_requirements`` are used
        when ``analysis`` is absent.
    traces : list or None
        Simulated traces per scenario of ``verification``, in its order
        (``{"t": s, "id", "iq", "id_ref", "iq_ref": A, "vd", "vq": V, ...}``,
        a :class:`toolbox.sim.SimResult`, or ``None``); they are not part of
        verify.json, so a report without them shows no trace figure.
    equations : list or None
        The derived dq model as ``{"label", "latex", "text"}`` rows;
        ``None`` derives it from ``spec.motor.convention`` (paper 000 eq
        (1)-(2), 003 eq (3)-(7)).
    generated : str or None
        Report time stamp to print (ISO 8601); ``None`` prints none, which keeps
        the output byte-identical for identical inputs.
    notice : str or None
        One line shown above the checks, e.g. "no requirements given; default
        checks only".
    warnings : list of str or None
        Lines shown with the notice (stored numbers that disagree with the
        recomputed ones, a refused header).
    firmware : dict or None
        ``firmware.json`` (:func:`toolbox.export.firmware.measure_firmware`):
        the firmware card's figures, or why they were not measured; ``None``
        when no header was written.
    """

    title: str
    spec: Any
    artifact: Any
    analysis: Mapping | None = None
    verification: Mapping | None = None
    traces: Sequence | None = None
    equations: list | None = None
    generated: str | None = None
    notice: str | None = None
    warnings: list | None = None
    firmware: Mapping | None = None
