"""Typed method fields of controller.json (schema ``cct.controller/2``).

Before schema 2 every method-specific number lived in one untyped ``gains``
dict and later stages guessed keys (``alpha``, ``weights``, ``gamma``,
``executed``, ``delay_compensation``). What a later stage *executes or draws*
now has a typed, validated home:

* :class:`FcsWeights` - the weights of paper 002's criterion (23) that the
  predictive switching law executes (method ``fcs_mpc`` only);
* :class:`toolbox.artifact.CvLaw` (module ``_cv``) - the poles of the
  direct discrete-time complex-vector law (Hinkkanen et al. 2016; method
  ``cv`` only), whose speed-dependent gains every executor computes from
  them each period;
* :class:`AxisWeights` - the validated H-infinity weights ``W1``, ``W2``,
  ``W3`` and the level ``gamma`` of one axis (paper 003 eq (41)-(43):
  ``|W1 S|, |W2 K S|, |W3 T| < gamma``), from which analysis draws the
  bounds (method ``hinf`` only).

The nonlinear compensation the law executes (cross-coupling, back-EMF and
the delay-compensation rotation) is :class:`toolbox.artifact.Decoupling`.
Everything else a design computes is informational
(``ControllerArtifact.design_parameters``): shown in the report, never
branched on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ..errors import ArtifactError

__all__ = ["FcsWeights", "TransferFunctionData", "AxisWeights", "WEIGHT_NAMES",
           "finite_number"]

#: H-infinity weight names of one axis: w1 on S, w2 on K S, w3 on T (003 eq (41)-(43)).
WEIGHT_NAMES = ("w1", "w2", "w3")


def finite_number(value: Any) -> bool:
    """A JSON number (not a bool) that is a finite double: an integer of 400
    digits is not (``math.isfinite`` raises ``OverflowError`` on it)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _number(value: Any, key: str, what: str = "a finite number",
            minimum: float | None = None, strict: bool = False) -> float:
    """A JSON number (not a bool), finite, optionally bounded below."""
    ok = finite_number(value)
    if ok and minimum is not None:
        ok = value > minimum if strict else value >= minimum
    if not ok:
        raise ArtifactError(key, what, value)
    return float(value)


def _only(data: Mapping, allowed: tuple[str, ...], key: str) -> None:
    for name in data:
        if name not in allowed:
            raise ArtifactError(f"{key}.{name}", f"one of {sorted(allowed)}", "unknown key")


def _no_unknown(data: Mapping, allowed: set[str], key: str) -> None:
    for name in data:
        if name not in allowed:
            raise ArtifactError(f"{key}.{name}" if key else name,
                            f"one of {sorted(allowed)}", "unknown key")


@dataclass(frozen=True)
class FcsWeights:
    """Weights of paper 002 criterion (23), executed by the predictive switching.

    Attributes
    ----------
    alpha : float
        Weight of the i_q error (torque error over ``p flux``), >= 0.
    beta : float
        Weight of the i_d error, >= 0 (``alpha + beta > 0``).
    gamma : float
        Weight of the commutations, >= 0.
    """

    alpha: float = 1.0
    beta: float = 1.0
    gamma: float = 0.0

    def to_json(self) -> dict:
        return {"alpha": self.alpha, "beta": self.beta, "gamma": self.gamma}

    @classmethod
    def from_json(cls, data: Any, key: str = "fcs") -> "FcsWeights":
        """Validate ``{"alpha", "beta", "gamma"}`` (all finite and >= 0, alpha + beta > 0)."""
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object with alpha, beta, gamma", data)
        names = ("alpha", "beta", "gamma")
        _only(data, names, key)
        values = {}
        for name in names:
            if name not in data:
                raise ArtifactError(f"{key}.{name}", "a finite number >= 0 (the fcs_mpc law "
                                    "reads it)", "nothing (missing)")
            values[name] = _number(data[name], f"{key}.{name}",
                                   "a finite number >= 0 (the fcs_mpc law reads it)", 0.0)
        if values["alpha"] + values["beta"] <= 0.0:
            # criterion (23) would ignore the currents entirely
            raise ArtifactError(f"{key}.alpha", "alpha + beta > 0",
                                [values["alpha"], values["beta"]])
        return cls(**values)


@dataclass(frozen=True, eq=False)
class TransferFunctionData:
    """A continuous SISO transfer function ``num(s)/den(s)``.

    Attributes
    ----------
    num, den : ndarray
        Coefficients in ``s``, highest power first (``den[0] != 0``).
    """

    num: np.ndarray
    den: np.ndarray

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """Frequency response at the complex points ``s``."""
        return np.polyval(self.num, s) / np.polyval(self.den, s)

    def to_json(self) -> dict:
        return {"num": [float(c) for c in self.num], "den": [float(c) for c in self.den]}

    @classmethod
    def from_json(cls, data: Any, key: str) -> "TransferFunctionData":
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object {num, den}", data)
        _only(data, ("num", "den"), key)
        coeffs = {}
        for name in ("num", "den"):
            v = data.get(name)
            if not isinstance(v, list) or not v:
                raise ArtifactError(f"{key}.{name}", "a non-empty list of numbers "
                                    "(highest power of s first)",
                                    v if name in data else "nothing (missing)")
            coeffs[name] = np.array([_number(c, f"{key}.{name}[{i}]") for i, c in enumerate(v)])
        if coeffs["den"][0] == 0.0:
            raise ArtifactError(f"{key}.den[0]", "a non-zero leading coefficient", 0.0)
        return cls(coeffs["num"], coeffs["den"])


@dataclass(frozen=True)
class AxisWeights:
    """Validated H-infinity weights of one axis and the level they bound.

    Attributes
    ----------
    gamma : float
        Level of the synthesis on this axis (> 0): the design guarantees
        ``|W1 S|, |W2 K S|, |W3 T| < gamma`` (003 eq (41)-(43)).
    w1, w2, w3 : TransferFunctionData or None
        Weights on ``S``, ``K S`` and ``T`` (continuous, whatever their spec
        form: constant, num/den, zpk or makeweight); ``None`` when absent.
    """

    gamma: float
    w1: TransferFunctionData | None = None
    w2: TransferFunctionData | None = None
    w3: TransferFunctionData | None = None

    def to_json(self) -> dict:
        out: dict[str, Any] = {"gamma": self.gamma}
        for name in WEIGHT_NAMES:
            w = getattr(self, name)
            out[name] = None if w is None else w.to_json()
        return out

    @classmethod
    def from_json(cls, data: Any, key: str) -> "AxisWeights":
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object {gamma, w1, w2, w3}", data)
        _only(data, ("gamma",) + WEIGHT_NAMES, key)
        if "gamma" not in data:
            raise ArtifactError(f"{key}.gamma", "a number > 0", "nothing (missing)")
        gamma = _number(data["gamma"], f"{key}.gamma", "a number > 0", 0.0, strict=True)
        ws = {name: (None if data.get(name) is None
                     else TransferFunctionData.from_json(data[name], f"{key}.{name}"))
              for name in WEIGHT_NAMES}
        if ws["w1"] is None:
            # W1 on S is what makes the design an S/KS/T one (003 eq (41))
            raise ArtifactError(f"{key}.w1", "a weight {num, den} (W1 is required)",
                                "nothing (missing or null)")
        return cls(gamma, **ws)
