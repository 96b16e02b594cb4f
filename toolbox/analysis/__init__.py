"""Analysis stage: margins, robustness sweeps, stability certificates.

* :mod:`.margins` - per-axis margins (continuous and sampled with delay) and
  the multiloop disk margin of the coupled dq loop over speed;
* :mod:`.robustness` - vectorised sweeps over parameter drift, speed-sensor
  errors and delay; :func:`drift_verdict` judges a design on the drift box of
  a drive (:data:`DRIVE_DRIFT`, its sources cited in ``_drift``) or the
  spec's ``parameter_drift``;
* :mod:`.certificate` - common quadratic Lyapunov function over a parameter
  box (vertex LMIs solved by Clarabel, called directly), continuous loop;
* :func:`largest_certified_sampled_scale` - the same question for the sampled
  coupled dq loop as executed (ZOH, delay, decoupling with the controller's
  parameters and the measured speed; ``_sampled_certificate``; opt-in: tens
  of seconds).

:func:`analysis_report` assembles what the CLI writes to ``analysis.json``
and :func:`compare_designs` the rows of ``cct compare``. The one margins API
(:func:`lti_loop_margins`, :func:`frequency_margins`, :func:`grid_margins`)
is what every other stage calls for a margin.
"""

from __future__ import annotations

from ._responses import loop_responses
from .certificate import (CertificateResult, ParameterBox, certify,
                          largest_certified_scale)
from ._statespace import FreqResponse
from .margins import (MARGIN_KEYS, FrequencyMargins, MarginsResult, MimoBoxResult,
                      MimoMarginsResult, compute_margins, disk_variations, frequency_margins,
                      grid_margins, json_ready, lti_loop_margins, mimo_disk_margins,
                      mimo_over_box)
from .robustness import DEFAULT_RANGES, SweepResult, robustness_sweep
from ._drift import DRIVE_DRIFT, DriftVerdict, drift_ranges, drift_verdict
from ._sampled_certificate import (SampledBox, SampledCertificate, certify_sampled,
                                   largest_certified_sampled_scale)

__all__ = ["MARGIN_KEYS", "MarginsResult", "MimoMarginsResult", "compute_margins",
           "disk_variations", "mimo_disk_margins", "MimoBoxResult", "mimo_over_box",
           "DEFAULT_RANGES", "SweepResult",
           "robustness_sweep", "DRIVE_DRIFT", "DriftVerdict", "drift_ranges", "drift_verdict",
           "CertificateResult", "ParameterBox", "certify",
           "largest_certified_scale", "SampledBox", "SampledCertificate", "certify_sampled",
           "largest_certified_sampled_scale", "analysis_report", "compare_designs", "ANALYSIS_SCHEMA",
           "FrequencyMargins", "frequency_margins", "grid_margins", "lti_loop_margins",
           "FreqResponse"]

ANALYSIS_SCHEMA = "cct.analysis/1"
#: Bisection tolerance of the sampled certificate in analysis.json and compare: 1/8
#: of the scale (four steps after the end points, about 15 s for paper 003's
#: third-order H-infinity laws; the LMI solves dominate, 0.05 costs three times more)
SAMPLED_CERTIFICATE_TOL = 0.125
STEP_KEYS = ("response_time_5pct", "rise_time_10_90", "settling_time_2pct", "overshoot_pct")


#: Latin-hypercube sets of the stress sweep (plus nominal and corners) of
#: ``analysis.json`` and of ``cct compare``: one number, so the two count the
#: same sets (compare used 500, 629 sets, against design's 1000, 1129).
SWEEP_SETS = 1000


def analysis_report(artifact, motor, drive=None, *, sweep_sets: int = SWEEP_SETS,
                    certificate: bool = True, certificate_delay: bool = False,
                    sampled_certificate: bool = False, seed: int = 0) -> dict:
    """Everything ``analysis.json`` holds (JSON-ready dict).

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant.
    drive : Drive, optional
        Speed range (``max_speed``, mechanical rad/s).
    sweep_sets : int
        Latin-hypercube sets of the robustness sweep.
    certificate : bool
        Run the quadratic-stability certificate of the continuous loop: largest
        certified scale of the box R, L x0.5..x2, |omega| <= max speed (about
        a second).
    certificate_delay : bool
        Certificate with the Pade delay model (512 vertices, slower).
    sampled_certificate : bool
        Also certify the sampled coupled loop as executed (speed sensor gain
        0.9..1.1 and offset +/-10 rad/s too): up to about a second, so opt-in
        (``cct design --sampled-certificate``); ``None`` in the output otherwise.
    seed : int
        Sweep seed (deterministic output).

    Returns
    -------
    dict
        ``{"schema": "cct.analysis/1", "method", "sample_time", "delay_samples",
        "margins": {"discrete": {d, q}, "continuous": {d, q},
        "continuous_delay": {d, q}}, "responses": {...} (figure data of
        the executed loops, :func:`toolbox.analysis._responses.loop_responses`),
        "mimo_at_speed": {...}, "mimo_over_box": {...} (worst multiloop disk
        margin over the nominal plant and the corners of R, Ld, Lq x0.5..x2 at
        speeds 0..max, :func:`mimo_over_box`),
        "sweep": {...}, "certificate": {...} or None,
        "sampled_certificate": {...} or None}`` (:class:`SampledCertificate`:
        certified scale, box and speed range, first uncertified corner); each
        margins entry is
        :meth:`MarginsResult.to_json`.
    """
    # every block below is JSON-ready already (its to_json / json_ready): walking
    # the whole document again cost ~30 ms, so only the header is
    out = {
        **json_ready({"schema": ANALYSIS_SCHEMA, "method": artifact.method,
                      "sample_time": artifact.sample_time,
                      "delay_samples": artifact.delay_samples}),
        "margins": {
            "discrete": {k: v.to_json() for k, v in compute_margins(artifact, motor).items()},
            "continuous": {k: v.to_json() for k, v in
                           compute_margins(artifact, motor, discrete=False).items()},
            "continuous_delay": {k: v.to_json() for k, v in
                                 compute_margins(artifact, motor, discrete=False,
                                                 delay="exact").items()},
        },
        "responses": loop_responses(artifact, motor),
        "mimo_at_speed": mimo_disk_margins(artifact, motor, drive).to_json(),
        "mimo_over_box": mimo_over_box(artifact, motor, drive).to_json(),
        "sweep": robustness_sweep(artifact, motor, n=sweep_sets, drive=drive,
                                  seed=seed).to_json(),
        "certificate": (largest_certified_scale(artifact, motor, drive,
                                                delay=certificate_delay).to_json()
                        if certificate and artifact.cv is None else None),
        "sampled_certificate": (largest_certified_sampled_scale(
            artifact, motor, drive, tol=SAMPLED_CERTIFICATE_TOL).to_json()
                                if sampled_certificate and artifact.cv is None else None),
    }
    return out


def compare_designs(artifacts: list, motor, drive=None, *, sweep_sets: int = SWEEP_SETS,
                    certificate: bool = True, sampled_certificate: bool = False) -> list[dict]:
    """Side-by-side rows for ``cct compare``.

    Each row: ``method``, ``margins`` (per axis, the nine MARGINS keys of the
    sampled loop), ``response_times`` (per axis, the four step figures, s and
    %), ``worst_case`` (per axis, the smallest gain/phase/stability/disk
    margins over the robustness sweep), ``n_unstable`` (sweep sets that lose
    stability), ``mimo_worst_disk_margin``, ``mimo_box`` (worst multiloop
    disk margin over the parameter box and the speeds, with its speed and
    parameters, :func:`mimo_over_box`), ``certificate``
    (``{"certified_scale", "certified"}`` or None) and ``sampled_certificate``
    (the same for the sampled coupled loop, with ``speed_range_rad_s``, electrical,
    and ``speed_range_mech_rad_s``, mechanical, or None).

    Parameters
    ----------
    artifacts : list of ControllerArtifact
        The designs to compare (one motor).
    motor : Motor
        Nominal plant of all designs.
    drive : Drive, optional
        Speed range of the sweeps (``max_speed``).
    sweep_sets : int
        Parameter sets per robustness sweep.
    certificate : bool
        Also search the largest certified parameter box (slower).
    sampled_certificate : bool
        Also certify the sampled coupled loop (up to about a second per design).
    """
    rows = []
    for art in artifacts:
        m = compute_margins(art, motor)
        sw = robustness_sweep(art, motor, n=sweep_sets, drive=drive).to_json()
        mimo = mimo_disk_margins(art, motor, drive)
        box = mimo_over_box(art, motor, drive)
        # the certificates' polytopes rest on a law affine in the measured speed: not
        # the cv law's gains (null, as when not asked for)
        cert = largest_certified_scale(art, motor, drive) if certificate and art.cv is None \
            else None
        scert = (largest_certified_sampled_scale(art, motor, drive, tol=SAMPLED_CERTIFICATE_TOL)
                 if sampled_certificate and art.cv is None else None)
        rows.append(json_ready({
            "method": art.method,
            "margins": {ax: r.to_json(extras=False) for ax, r in m.items()},
            "response_times": {ax: {k: getattr(r, k) for k in STEP_KEYS} for ax, r in m.items()},
            "worst_case": {ax: {k: v["value"] for k, v in sw["worst"][ax].items()}
                           for ax in ("d", "q")},
            "n_unstable": sw["n_unstable"],
            "n_sets": sw["n_sets"],
            "mimo_worst_disk_margin": mimo.worst_disk_margin,
            "mimo_box": {"worst_disk_margin": box.worst_disk_margin,
                         "worst_speed_rad_s": box.worst_speed_rad_s,
                         "worst_params": box.worst_params, "n_unstable": box.n_unstable},
            "certificate": (None if cert is None else
                            {"certified_scale": cert.scale, "certified": cert.certified}),
            "sampled_certificate": (None if scert is None else
                                    {"certified_scale": scert.scale,
                                     "certified": scert.certified,
                                     "speed_range_rad_s": scert.speed_range_rad_s,
                                     "speed_range_mech_rad_s":
                                         scert.speed_range_mech_rad_s}),
        }))
    return rows
