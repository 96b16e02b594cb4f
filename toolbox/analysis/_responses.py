"""Response data of the executed current loops, stored in ``analysis.json``.

The report draws its figures from these numbers only, so every curve it shows
is the loop whose margins are tabled: the artifact's **executed** two-input
law ``v = K_r i_ref + K_m i_meas`` (sampled, with the computation delay
``z^-d``) on the zero-order-hold plant ``1/(R + s L)`` (paper 003 eq
(33)-(34)), assembled by :func:`toolbox.analysis.margins.make_axis_loop`.

Per axis, on ``n_points`` log-spaced frequencies up to 0.999 times the
Nyquist frequency ``pi/T_s``:

* ``loop``: ``L = K G z^-d`` with ``K = -K_m`` (loop broken at the plant
  input), magnitude (dB), unwrapped phase (deg), real and imaginary parts
  (Bode and Nyquist plots);
* ``S``, ``T``, ``KS``: ``|1/(1 + L)|``, ``|L/(1 + L)|``, ``|K/(1 + L)|`` in dB
  (``KS`` in dB V/A);
* ``weight_bounds``: for an H-infinity design, ``gamma/|W_i|`` (dB) of the
  typed weights ``artifact.weights`` (paper 003 eq (41)-(43): the design
  guarantees ``|W_1 S|, |W_2 K S|, |W_3 T| < gamma``);
* ``step``: the reference step ``i_ref -> i`` of the executed law (a
  two-degree-of-freedom law's reference channel included), with the
  intersample current, the same response whose figures (overshoot, 5 % time)
  ``margins.discrete`` holds;
* ``pz``: closed-loop poles and zeros of ``i_ref -> i`` in the z-plane.

Numbers are rounded to 6 significant digits so that ``analysis.json`` is
stable across platforms (last-bit differences of LAPACK builds vanish) and
small; 6 digits resolve a 0.001 dB or 0.001 deg feature, far below what a
figure shows.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..lti import invariant_zeros as _zeros
from ..artifact import AxisWeights
# step_response is the step helper whose figures the discrete margins report:
# one step computation.
from .margins import AxisLoop, freqresp, json_ready, make_axis_loop, step_response

__all__ = ["RESPONSES_SCHEMA", "N_POINTS", "W_END_FRACTION", "round_sig", "axis_responses",
           "loop_responses"]

#: Version of the ``responses`` block layout inside analysis.json.
RESPONSES_SCHEMA = "cct.responses/1"
#: Default number of frequency points per axis.
N_POINTS = 300
#: Most step-response samples stored per axis (peak kept; see :func:`_decimate`).
STEP_POINTS = 400
#: Lowest frequency of the grid (rad/s): a decade or more below every current
#: loop's crossover (hundreds to thousands of rad/s).
W_MIN = 1.0
#: Last grid frequency as a fraction of the Nyquist frequency (see axis_responses).
W_END_FRACTION = 0.999
AXES = ("d", "q")
WEIGHT_FUNCTIONS = (("w1", "S"), ("w2", "KS"), ("w3", "T"))


def round_sig(values: Any, digits: int = 6) -> Any:
    """Round to ``digits`` significant digits (arrays become lists).

    Parameters
    ----------
    values : float or array_like
    digits : int

    Returns
    -------
    float or list
        Non-finite values pass through unchanged (``json_ready`` turns them
        into the strings ``"inf"``/``"nan"`` later).
    """
    arr = np.asarray(values, float)
    # Python floats: formatting a numpy scalar costs several times more
    flat = [float(f"{v:.{digits}g}") if math.isfinite(v) else v for v in arr.ravel().tolist()]
    if arr.ndim == 0:
        return flat[0]
    return np.asarray(flat).reshape(arr.shape).tolist()


def _db(x: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(np.abs(x))


def _pairs(roots: np.ndarray) -> list[list[float]]:
    """Roots as sorted ``[re, im]`` pairs (deterministic order)."""
    roots = np.asarray(roots, complex)
    roots = roots[np.lexsort((roots.imag, roots.real))]
    return [[round_sig(r.real), round_sig(r.imag)] for r in roots]


def _decimate(t: np.ndarray, y: np.ndarray, n_max: int) -> tuple[np.ndarray, np.ndarray]:
    """At most about ``n_max`` samples, always keeping the first, last and peak ones.

    Keeping the peak sample makes the stored curve show the overshoot that
    ``margins.discrete`` reports, whatever the decimation.
    """
    if t.size <= n_max:
        return t, y
    keep = np.unique(np.r_[np.linspace(0, t.size - 1, n_max).round().astype(int),
                           int(np.argmax(y)), t.size - 1])
    return t[keep], y[keep]


def _step(loop: AxisLoop) -> dict:
    """Reference step ``i_ref -> i`` of the executed loop, trimmed and decimated.

    Shown until three times the 2 % settling instant (at least 40 periods),
    which is where the report's time axis ends.
    """
    cl = loop.reference_loop()
    t, y = step_response(loop, *cl)
    outside = np.nonzero(np.abs(y - 1.0) > 0.02)[0]
    t_settle = float(t[outside[-1] + 1]) if outside.size and outside[-1] + 1 < t.size else (
        float(t[-1]) if outside.size else 0.0)
    t_end = max(40 * loop.sample_time, 3.0 * t_settle)
    keep = t <= t_end
    td, yd = _decimate(t[keep], y[keep], STEP_POINTS)
    return {"t": round_sig(td), "y": round_sig(yd)}


def _pole_zero(loop: AxisLoop) -> dict:
    A, B, C, D = loop.reference_loop()
    return {"domain": "z" if loop.discrete else "s",
            "poles": _pairs(np.linalg.eigvals(A)) if A.size else [],
            "zeros": _pairs(_zeros(A, B, C, D)) if A.size else []}


def _weight_bounds(weights: AxisWeights | None, w: np.ndarray) -> dict | None:
    """``gamma/|W_i(j w)|`` (dB) of one axis' typed H-infinity weights (003 eq (41)-(43))."""
    if weights is None:
        return None
    out: dict[str, Any] = {"gamma": float(weights.gamma)}
    s = 1j * w
    for wkey, fn in WEIGHT_FUNCTIONS:
        wt = getattr(weights, wkey)
        out[fn] = None if wt is None else round_sig(_db(weights.gamma / np.abs(wt(s))))
    return out


def axis_responses(loop: AxisLoop, *, weights: AxisWeights | None = None,
                   n_points: int = N_POINTS, w_min: float = W_MIN) -> dict:
    """Response data of one assembled loop (see the module docstring).

    Parameters
    ----------
    loop : AxisLoop
        From :func:`toolbox.analysis.margins.make_axis_loop` (discrete: the
        executed law with ZOH plant and delay).
    weights : AxisWeights, optional
        The H-infinity weights of this axis and the level ``gamma`` the
        design reached (``artifact.weights[axis]``).
    n_points : int
        Frequency points, log-spaced from ``w_min`` to ``loop.w_max`` (times
        ``W_END_FRACTION`` in discrete time).
    w_min : float
        Lowest frequency (rad/s).

    Returns
    -------
    dict
        ``{"omega", "loop": {"mag_db", "phase_deg", "re", "im"}, "S_db",
        "T_db", "KS_db", "weight_bounds", "step": {"t", "y"}, "pz"}``,
        numbers rounded to 6 significant digits.
    """
    # evaluate at the rounded frequencies that are stored, so that each stored
    # value is the response at its stored frequency. The grid stops at
    # W_END_FRACTION of Nyquist: Tustin controllers have a zero at z = -1, so
    # |L| -> 0 (-inf dB) exactly at pi/Ts and would flatten every plot's scale.
    w_hi = loop.w_max * (W_END_FRACTION if loop.discrete else 1.0)
    w = np.asarray(round_sig(np.logspace(math.log10(w_min), math.log10(w_hi), n_points)))
    x = np.exp(1j * w * loop.sample_time) if loop.discrete else 1j * w
    K = freqresp(*loop.law.error_controller(), x)[:, 0, 0]
    L = loop.loop(w)
    S = 1.0 / (1.0 + L)
    phase = np.degrees(np.unwrap(np.angle(L)))
    # start the unwrapped phase in [-270, 90): a loop with integral action then
    # starts near -90 deg and -180 deg is the critical line, as in the margins
    phase -= 360.0 * math.floor((float(phase[0]) + 270.0) / 360.0)
    return {
        "omega": w.tolist(),
        "loop": {"mag_db": round_sig(_db(L)), "phase_deg": round_sig(phase),
                 "re": round_sig(L.real), "im": round_sig(L.imag)},
        "S_db": round_sig(_db(S)), "T_db": round_sig(_db(L * S)), "KS_db": round_sig(_db(K * S)),
        "weight_bounds": _weight_bounds(weights, w),
        "step": _step(loop),
        "pz": _pole_zero(loop),
    }


def loop_responses(artifact, motor, *, n_points: int = N_POINTS) -> dict:
    """Response data of both current loops of an artifact (``analysis.json["responses"]``).

    Parameters
    ----------
    artifact : ControllerArtifact
        The design: executed laws, sample time, delay; H-infinity weights
        and levels from the typed ``artifact.weights`` (None for other methods).
    motor : Motor
        Nominal plant (R in ohm, Ld/Lq in H).
    n_points : int
        Frequency points per axis.

    Returns
    -------
    dict
        ``{"schema": "cct.responses/1", "domain": "discrete", "d": {...},
        "q": {...}}`` (JSON-ready), each axis as :func:`axis_responses`.
    """
    out: dict[str, Any] = {"schema": RESPONSES_SCHEMA, "domain": "discrete"}
    for name, L in (("d", motor.Ld), ("q", motor.Lq)):
        loop = make_axis_loop(artifact.axes[name], motor.R, L, artifact.sample_time,
                              artifact.delay_samples, discrete=True)
        aw = None if artifact.weights is None else artifact.weights[name]
        with np.errstate(divide="ignore", invalid="ignore"):
            out[name] = axis_responses(loop, weights=aw, n_points=n_points)
    return json_ready(out)
