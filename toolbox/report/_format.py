"""Number and text formatting of the report: :func:`fmt`, :func:`fmt_q` (with
the display resolution of each unit), the units of the simulated metrics
(:func:`sim_metric_unit`), zero-pole-gain text (:func:`zpk_text`) and the
"not computed" placeholder."""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np


NOT_COMPUTED = "not computed"


# ----------------------------------------------------------------- formatting

def fmt(value: Any, digits: int = 4) -> str:
    """Format a value for a table: numbers to ``digits`` significant digits.

    ``None`` and NaN (a quantity that has no value, e.g. the bandwidth of an
    unstable loop) become "not computed"; infinities "inf"; booleans "yes"/"no".
    """
    if value is None:
        return NOT_COMPUTED
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return NOT_COMPUTED
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return f"{v:.{digits}g}"
    if isinstance(value, complex):
        return f"{value.real:.{digits}g}{value.imag:+.{digits}g}j"
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value, dtype=object)
        if arr.ndim <= 1:
            return "[" + ", ".join(fmt(v, digits) for v in arr.tolist()) + "]"
        return "[" + "; ".join(", ".join(fmt(v, digits) for v in row) for row in arr.tolist()) + "]"
    if isinstance(value, Mapping):
        return ", ".join(f"{k}: {fmt(v, digits)}" for k, v in value.items())
    return str(value)


#: Display resolution of each unit: a value whose magnitude is below it is
#: round-off (e.g. a static error of 4.4e-14) and is shown as 0 (stated in the
#: report under the tables, :data:`RESOLUTION_NOTE`).
RESOLUTION = {"s": 1e-7, "A": 1e-6, "V": 1e-6, "%": 1e-3, "dB": 1e-3, "deg": 1e-3,
              "rad/s": 1e-3, "rad": 1e-6, "Hz": 1e-3, "1/s": 1e-3, "1": 1e-9,
              "A^2": 1e-12, "(N m)^2": 1e-12}
RESOLUTION_NOTE = ("Numbers to 4 significant digits; values below the resolution of their "
                   "unit are shown as 0 (s: 0.1 us, A and V: 1 uA and 1 uV, %, dB, deg, "
                   "rad/s and 1/s: 0.001, dimensionless: 1e-9, A^2 and (N m)^2: 1e-12).")


def fmt_q(value: Any, unit: str, digits: int = 4) -> str:
    """:func:`fmt` of a quantity in ``unit``: below :data:`RESOLUTION` it is 0.

    Parameters
    ----------
    value : float, int, str or None
        The quantity (a string is shown as it is).
    unit : str
        Its unit, a key of :data:`RESOLUTION` (others: no resolution).
    digits : int
        Significant digits.
    """
    v = _as_float(value) if not isinstance(value, str) else None
    res = RESOLUTION.get(unit)
    if v is not None and res is not None and math.isfinite(v) and abs(v) < res:
        return "0"
    return fmt(value if not isinstance(value, (int, float, np.number)) or v is None else v,
               digits)


#: Units of the simulated metrics (:mod:`toolbox.sim._metrics`); ``signal``:
#: the stepped signal's unit (A, or rad/s for a speed scenario).
SIM_METRIC_UNITS = {
    "response_time_5pct": "s", "rise_time_10_90": "s", "settling_time_2pct": "s",
    "overshoot_pct": "%", "static_error": "signal", "final_value": "signal",
    "static_error_abs": "A", "static_speed_error_abs": "rad/s",
    "mse_torque": "(N m)^2", "mse_id": "A^2", "mse_iq": "A^2",
    "commutations_per_s": "1/s", "cell_transitions_per_s": "1/s",
    "saturation_time": "s", "final_speed": "rad/s",
    "E_torque": "(N m)^2", "E_id": "A^2",
}

SPEED_KINDS = ("speed_step", "load_step")


def sim_metric_unit(name: str, kind: str = "") -> str:
    """Unit of a simulated metric of a scenario of ``kind`` ("" when unknown).

    Parameters
    ----------
    name : str
        Metric name (:mod:`toolbox.sim._metrics`).
    kind : str
        Scenario kind: the static error and final value of a speed scenario are rad/s.
    """
    unit = SIM_METRIC_UNITS.get(name, "")
    if unit == "signal":
        return "rad/s" if kind in SPEED_KINDS else "A"
    return unit


def _poly_factors(roots: np.ndarray, var: str = "s") -> str:
    """``(s + a)(s^2 + b s + c)`` text for real / complex-pair roots (rad/s)."""
    parts: list[str] = []
    scale = max(1.0, float(np.max(np.abs(roots)))) if len(roots) else 1.0
    # a root within round-off of the origin is an integrator (e.g. 003 eq (71)-(72))
    roots = np.where(np.abs(roots) < 1e-12 * scale, 0.0, roots)
    done = np.zeros(len(roots), bool)
    for k, r in enumerate(roots):
        if done[k]:
            continue
        done[k] = True
        if abs(r.imag) <= 1e-9 * max(1.0, abs(r)):
            a = -r.real
            parts.append(var if a == 0 else f"({var} {'+' if a > 0 else '-'} {abs(a):.4g})")
        else:
            for j in range(k + 1, len(roots)):  # its conjugate
                if not done[j] and abs(roots[j] - np.conj(r)) <= 1e-6 * abs(r):
                    done[j] = True
                    break
            b, c = -2 * r.real, abs(r) ** 2
            parts.append(f"({var}^2 {'+' if b >= 0 else '-'} {abs(b):.4g} {var} + {c:.4g})")
    return "".join(parts) if parts else "1"


def zpk_text(zpk, var: str = "s") -> str:
    """``k (s + z1)... / ((s + p1)...)`` of a :class:`toolbox.artifact.Zpk`.

    Parameters
    ----------
    zpk : Zpk
        Zeros and poles (rad/s, or z-plane for a discrete-only design), gain.
    var : str
        ``"s"`` or ``"z"``.
    """
    num = _poly_factors(np.asarray(zpk.zeros, complex), var)
    den = _poly_factors(np.asarray(zpk.poles, complex), var)
    head = f"{zpk.gain:.4g}" if num == "1" else f"{zpk.gain:.4g} {num}"
    return head if den == "1" else f"{head} / {den}"


def _flatten(prefix: str, value: Any, out: list) -> None:
    if isinstance(value, Mapping):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    else:
        out.append((prefix, fmt(value)))


def _as_float(v: Any) -> float | None:
    if v is None or isinstance(v, bool):
        return None
    if isinstance(v, str):  # artifact JSON writes "inf"
        try:
            return float(v)
        except ValueError:
            return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None
