"""Default S/KS weights of the H-infinity design, from requirements and the drive.

Paper 003 (Azaiz 2007) chooses its weights by hand, eq (44)-(49). Without
weights in the spec they are built here like MATLAB's ``makeweight``
(:func:`toolbox.design._weights.makeweight`), per axis of inductance ``L``:

``w1`` (on S, eq (35)-(36))
    ``makeweight(dc_gain = 1000, crossover = w_b, crossover_gain = 1,
    hf_gain = M_m)``: ``|S| <= gamma/|w1|`` keeps the low-frequency error
    below 0.1 % (integral-like action), S back at 1 no earlier than ``w_b``
    and the peak ``||S||inf <= gamma/M_m``, i.e. a modulus margin of at
    least ``M_m`` for ``gamma <= 1``.
    ``w_b``: ``requirements.min_bandwidth_rad_s`` when given, else the
    crossover of :func:`toolbox.design._defaults.default_bandwidth` with the
    integral zero counted (the weight's low-frequency slope puts one near
    crossover, as the second-order defaults); ``M_m``:
    ``requirements.min_stability_margin`` when given, else 0.5.
``w2`` (on KS, control-effort roll-off; the solver's assumption A2 needs
its high-frequency gain non-zero)
    ``makeweight(dc_gain = h/100, crossover = w_c, crossover_gain = h/10,
    hf_gain = h)``, ``h = 1/(L w_c)``, ``w_c`` the PI default crossover
    (no zero): above ``w_c`` the controller gain is held to
    ``|K| <= gamma L w_c``, the proportional gain of the cancellation PI
    that the delay allows, so the loop cannot cross over faster than the
    sampling allows.
``w3``
    none (the delay is handled by the crossover choice, not by a T weight).

``gamma`` defaults to ``"optimal"`` (with the back-off) when the weights are
defaults. On the three motors of ``tests/design/test_defaults.py`` this gives
a sampled phase margin of 65 deg, gain margin 14.7 dB, M_m 0.71.
"""

from __future__ import annotations

import math

from ._defaults import default_bandwidth
from ._weights import makeweight

__all__ = ["W1_DC_GAIN", "DEFAULT_MODULUS_MARGIN", "w1_params", "w2_params",
           "w2_toml"]

#: low-frequency gain of w1: steady-state error <= 1/1000 of the reference
W1_DC_GAIN = 1000.0
#: modulus margin M_m = 1/||S||inf asked when the requirements give none
DEFAULT_MODULUS_MARGIN = 0.5


def w1_params(drive, requirements=None) -> tuple[dict, str]:
    """makeweight parameters of the default ``w1`` and where they came from."""
    bounds = getattr(requirements, "bounds", {}) or {}
    if bounds.get("min_bandwidth_rad_s"):
        w_b = float(bounds["min_bandwidth_rad_s"])
        src = "w_b = requirements.min_bandwidth_rad_s"
    else:
        bw = default_bandwidth(drive, zero=True)
        w_b = bw.value
        src = f"w_b: {bw.rule}"
    m_m = float(bounds.get("min_stability_margin") or DEFAULT_MODULUS_MARGIN)
    m_src = ("M_m = requirements.min_stability_margin" if bounds.get("min_stability_margin")
             else f"M_m = {DEFAULT_MODULUS_MARGIN:g} (modulus margin, ||S||inf <= 2)")
    params = {"dc_gain": W1_DC_GAIN, "crossover": w_b, "crossover_gain": 1.0, "hf_gain": m_m}
    return params, f"{src}; {m_src}"


def w2_params(L: float, drive) -> tuple[dict, str]:
    """makeweight parameters of the default ``w2`` for an axis of inductance
    ``L`` (H) and the rule that gave them."""
    w_c = default_bandwidth(drive).value
    h = 1.0 / (L * w_c)
    params = {"dc_gain": h / 100.0, "crossover": w_c, "crossover_gain": h / 10.0, "hf_gain": h}
    return params, (f"h = 1/(L w_c) = 1/({L:.4g} x {w_c:.5g}) = {h:.4g} A/V: |K| <= gamma L w_c "
                    "above w_c (w_c = PI default crossover)")


def default_w2(L: float, drive, key: str = "controller.hinf.weights.w2"):
    """The default ``w2`` transfer function alone (see :func:`w2_params`)."""
    return _make(w2_params(L, drive)[0], key)


def w2_toml(L: float, drive) -> str:
    """The default ``w2`` as the TOML inline table a user can paste."""
    p = w2_params(L, drive)[0]
    return ("w2 = { " + ", ".join(f"{k} = {_num(v)}" for k, v in p.items()) + " }")


def _num(v: float) -> str:
    return f"{v:.4g}" if math.isfinite(v) else str(v)


def _make(p: dict, key: str):
    return makeweight(p["dc_gain"], p["crossover"], p["crossover_gain"], p["hf_gain"], key=key)
