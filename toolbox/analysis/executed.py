"""Margins and stability of the law a controller.json actually executes,
recomputed on demand (never trust stored numbers).

``cct verify`` and ``cct report`` read a controller.json that may have been
edited by hand or by a tool. The ``margins`` stored in it are a cache of the
analysis; the verdict must come from the executed law itself
(``axes.<axis>.law``, the one executed law of the axis), analysed on the spec's nominal plant with ZOH and the
computation delay, exactly as :func:`toolbox.analysis.compute_margins` does at
design time.

For ``fcs_mpc`` the executed law is the predictive switching of paper 002
(criterion (23)), which has no linear loop: the stored axes hold only the
SVM baseline PI (eq (19)-(20)). Its margins are informational and no
stability verdict is computed from them; the simulation's ``default.bounded_*``
checks judge the predictive loop.
"""

from __future__ import annotations

import math

import numpy as np

from .margins import MARGIN_KEYS, make_axis_loop

__all__ = ["INFORMATIONAL_METHODS", "loop_stability", "settling_horizon", "HORIZON_TAUS",
           "margin_disagreements", "MARGIN_RTOL"]

#: Methods whose stored axes are not what runs (their margins are informational).
INFORMATIONAL_METHODS = {
    "fcs_mpc": "the predictive switching law (paper 002 criterion (23)) does not run the "
               "baseline PI of eq (19)-(20) whose margins are shown",
}

#: Relative tolerance between stored and recomputed margins. The same code on the
#: same law gives bit-identical numbers up to JSON's 17 significant digits; 1e-6
#: leaves room for a different BLAS while any edit of the law shows (a changed
#: pole moves the margins by far more).
MARGIN_RTOL = 1e-6


def loop_stability(artifact, motor) -> dict:
    """Is the executed sampled loop of each axis stable?

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant.

    Returns
    -------
    dict
        Per axis ``{"stable": bool or None, "spectral_radius": float or None,
        "basis": str}``: the largest closed-loop pole magnitude of the
        reference -> current loop (law, ZOH plant, ``z^-delay``); ``None``
        (not decided here) for methods whose stored axes do not run.
    """
    if artifact.method in INFORMATIONAL_METHODS:
        return {ax: {"stable": None, "spectral_radius": None,
                     "basis": f"not analysed: {INFORMATIONAL_METHODS[artifact.method]}; "
                              "judged by the simulation's bounded checks"}
                for ax in ("d", "q")}
    out = {}
    for ax, L in (("d", motor.Ld), ("q", motor.Lq)):
        loop = make_axis_loop(artifact.axes[ax], motor.R, L, artifact.sample_time,
                              artifact.delay_samples)
        A_cl = loop.reference_loop()[0]
        rho = float(np.max(np.abs(np.linalg.eigvals(A_cl)))) if A_cl.size else 0.0
        out[ax] = {"stable": bool(rho < 1.0 - 1e-9), "spectral_radius": rho,
                   "basis": f"executed sampled loop (axes.{ax}.law, ZOH plant, "
                            f"{artifact.delay_samples} period(s) of delay)"}
    return out


def _number(value) -> float | None:
    if isinstance(value, str) and value in ("inf", "-inf", "nan"):
        return float(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


def _same(a: float, b: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= MARGIN_RTOL * max(abs(a), abs(b)) + 1e-12


def margin_disagreements(stored: dict, recomputed: dict, file: str | None = None) -> list[str]:
    """Warnings for stored MARGINS that differ from the recomputed ones.

    Parameters
    ----------
    stored : dict
        ``margins`` of controller.json (``{"d": {...}, "q": {...}}``, may be empty).
    recomputed : dict
        ``{"d": MarginsResult, "q": MarginsResult}``.
    file : str, optional
        The controller.json path, named in the messages.

    Returns
    -------
    list of str
        One message per disagreeing entry (empty when they agree).
    """
    where = f"{file}: " if file else ""
    out = []
    for ax, res in recomputed.items():
        fresh = res.to_json(extras=False)
        old = (stored or {}).get(ax)
        if not isinstance(old, dict):
            continue
        for key in MARGIN_KEYS:
            a, b = _number(old.get(key)), _number(fresh.get(key))
            if a is None or b is None or _same(a, b):
                continue
            fresh_txt = f"{b:.4g}" if math.isfinite(b) else "no finite value"
            out.append(f"{where}margins.{ax}.{key}: stored {a:.4g} disagrees with "
                       f"{fresh_txt} recomputed from the executed law (axes.{ax}.law); "
                       f"the recomputed value is used")
        if old.get("stable") is not None and bool(old.get("stable")) != res.stable:
            out.append(f"{where}margins.{ax}.stable: stored {old.get('stable')} disagrees "
                       f"with {res.stable} recomputed from the executed law (axes.{ax}.law)")
    return out


#: Default scenario horizon rule (toolbox/ARCHITECTURE.md "Default scenarios"):
#: HORIZON_TAUS time constants of the slowest closed-loop mode that shows in
#: the step response. A mode of step amplitude ``a`` (fraction of the final
#: value) enters the 2 % settling band after ``tau ln(a / 0.02)``: 4.6 tau for
#: a = 2 (twice the step), so 10 tau leaves the settling time measurable with
#: room for the overlap of modes.
HORIZON_TAUS = 10.0
#: A mode smaller than the 2 % settling band never leaves it: it cannot delay
#: any metric (response, rise or settling time) and sets no horizon.
HORIZON_BAND = 0.02
#: Horizon clamp (s): at least the previous default span, at most 1 s (a
#: current loop slower than 0.1 s is judged by its margins; 1 s at the default
#: 1 us plant step is 1e6 RK4 steps per scenario).
HORIZON_RANGE = (0.02, 1.0)


def settling_horizon(artifact, motor) -> float | None:
    """Simulated span a default step scenario needs to measure the settling
    of the executed sampled loop: :data:`HORIZON_TAUS` time constants of the
    slowest closed-loop pole (over both axes) whose mode amplitude in the
    reference step response is at least :data:`HORIZON_BAND` of the final
    value, clamped to :data:`HORIZON_RANGE`.

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant.

    Returns
    -------
    float or None
        Seconds; None for laws whose stored axes do not run (fcs_mpc) or an
        unstable loop (no settling to measure: the default span stays).

    Notes
    -----
    Modal decomposition of the reference -> current loop ``(A, B, C)``
    (discrete, ``A = V diag(lambda) V^-1``): the step response is
    ``sum_i r_i (1 - lambda_i^(k+1)) / (1 - lambda_i)`` with ``r_i = (C V)_i
    (V^-1 B)_i``; mode ``i`` has amplitude ``|r_i / (1 - lambda_i)|`` and time
    constant ``-Ts / ln |lambda_i|``. A pole almost cancelled by a zero (paper
    003's near-integrator, eq 70) has a tiny amplitude and is ignored. A
    defective pole set (repeated placed poles: ``V`` singular) has no modal
    split: every mode counts then.
    """
    if artifact.method in INFORMATIONAL_METHODS:
        return None
    ts = artifact.sample_time
    slowest = 0.0
    for ax, L in (("d", motor.Ld), ("q", motor.Lq)):
        A, B, C, D = make_axis_loop(artifact.axes[ax], motor.R, L, ts,
                                    artifact.delay_samples).reference_loop()
        if not A.size:
            continue
        with np.errstate(all="ignore"):
            lam, V = np.linalg.eig(A)
            if np.any(np.abs(lam) >= 1.0):
                return None
            tau = -ts / np.log(np.maximum(np.abs(lam), 1e-300))
            final = abs(float((C @ np.linalg.solve(np.eye(A.shape[0]) - A, B) + D)[0, 0]))
            if np.linalg.cond(V) < 1e12:
                r = (C @ V).ravel() * np.linalg.solve(V, B).ravel()
                amp = np.abs(r / (1.0 - lam))
            else:  # repeated, defective poles (a placed law): no modal split, every mode counts
                amp = np.full(lam.shape, np.inf)
        shown = ~np.isnan(amp) & (amp >= HORIZON_BAND * max(final, 1e-12))
        if np.any(shown):
            slowest = max(slowest, float(np.max(tau[shown])))
    low, high = HORIZON_RANGE
    return min(max(HORIZON_TAUS * slowest, low), high)
