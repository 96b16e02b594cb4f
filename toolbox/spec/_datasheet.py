"""Datasheet values -> per-phase dq model parameters, converted and recorded.

Datasheets print line-to-line values and back-EMF or torque constants; the
model (toolbox.plant) needs per-phase dq parameters. This module converts
one into the other and keeps a log of what was given and what was derived.

Convention
----------
The dq model is amplitude-invariant (2/3 Park transform, as in motulator,
whose space vectors are peak-value scaled, and Krishnan, *Permanent Magnet
Synchronous and Brushless DC Motor Drives*, CRC 2010, ch. 3): a balanced
phase current of peak I gives |i_dq| = I, and ``flux`` is the peak phase PM
flux linkage psi_f, so the phase back-EMF has peak ``p omega_m psi_f`` and
the torque is ``T = 3/2 p (psi_f i_q + (Ld - Lq) i_d i_q)``. For
``convention = "power"`` (sqrt(2/3) Park, torque factor 1) the flux is
sqrt(3/2) psi_f; resistance and inductances are the same in both.

Derivations (star connection, sinusoidal EMF; tests/spec/test_datasheet.py
re-derives each with sympy from the three phase waveforms):

* ``R = R_ll / 2``: a line-to-line measurement spans two phase windings in
  series.
* ``Ld = Lq = L_ll / 2`` (surface PM machines only): between two terminals
  with the third open the measured inductance is 2 (L_self - M) = 2 L_s,
  and the synchronous inductance L_s is the dq inductance. Interior PM
  machines: give ``Ld`` and ``Lq``.
* back-EMF constant, line-to-line peak, per mechanical speed (V s/rad):
  e_ab = e_a - e_b has peak sqrt(3) p omega_m psi_f, so
  ``psi_f = ke_ll_peak / (sqrt(3) p)``; for an rms value ke_ll_peak =
  sqrt(2) ke_ll_rms. ``"V/krpm"`` is converted with 1 krpm = 2 pi 1000/60 rad/s.
* torque constant at i_d = 0: power balance sum(e_k i_k) = T omega_m with
  phase currents of peak I in phase with the EMFs gives T = 3/2 p psi_f I,
  so ``psi_f = kt_peak / (1.5 p)`` (N m per A peak) and
  ``psi_f = kt_rms / (1.5 sqrt(2) p)`` (N m per A rms). Check:
  kt_rms = sqrt(3) ke_ll_rms (both SI), the usual datasheet identity.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from ..errors import SpecError
from ._fields import Collector, is_finite_number
from ._units import KINDS, _Shown, looks_like_quantity, parse_quantity

__all__ = ["Conversion", "GROUPS", "MOTOR_KINDS", "DRIVE_KINDS", "CONVENTION_TEXT",
           "SCENARIO_KINDS", "SPEED_LOOP_KINDS", "rms_rule", "convert_scenario",
           "resolve_motor", "resolve_drive", "convert_units", "catalog_kept",
           "reported_keys", "relocate"]

CONVENTION_TEXT = {
    "amplitude": ("amplitude-invariant dq (2/3 Park): |i_dq| = peak phase current, "
                  "flux = peak phase PM flux linkage, T = 3/2 p (flux i_q + (Ld - Lq) i_d i_q)"),
    "power": ("power-invariant dq (sqrt(2/3) Park): |i_dq| = sqrt(3/2) peak phase current, "
              "flux = sqrt(3/2) peak phase PM flux linkage, T = p (flux i_q + (Ld - Lq) i_d i_q)"),
}

#: Motor keys holding a physical quantity: key -> kind (see _units.KINDS).
MOTOR_KINDS = {
    "R": "resistance", "R_ll": "resistance",
    "Ld": "inductance", "Lq": "inductance", "L_ll": "inductance",
    "flux": "flux", "ke_ll_peak": "emf_constant", "ke_ll_rms": "emf_constant",
    "kt_peak": "torque_constant", "kt_rms": "torque_constant",
    "J": "inertia", "friction": "friction",
    "rated_current": "current", "max_current": "current", "rated_speed": "speed",
    "rated_current_rms": "current", "max_current_rms": "current",
}

#: Drive keys holding a physical quantity.
DRIVE_KINDS = {
    "vdc": "voltage", "sample_time": "time", "sample_frequency": "frequency",
    "switching_frequency": "frequency", "max_speed": "speed",
}

#: Equivalent ways to give one model quantity: (what, model keys, alternatives).
#: At most one way may be used; giving any of them replaces the catalog's.
GROUPS = (
    ("the phase resistance", ("R",), ("R_ll",)),
    ("the dq inductances", ("Ld", "Lq"), ("L_ll",)),
    ("the PM flux linkage", ("flux",), ("ke_ll_peak", "ke_ll_rms", "kt_peak", "kt_rms")),
    ("the rated current", ("rated_current",), ("rated_current_rms",)),
    ("the largest current", ("max_current",), ("max_current_rms",)),
)

#: Datasheet rms phase currents -> the model's dq current magnitude.
RMS_CURRENTS = {"rated_current_rms": "rated_current", "max_current_rms": "max_current"}


@dataclass(frozen=True)
class Conversion:
    """One derived model value and how it was obtained.

    Attributes
    ----------
    key : str
        Model key (``R``, ``Ld``, ``Lq``, ``flux``, or a key given with a unit).
    value : float
        The SI value used by the model.
    unit : str
        Its SI unit.
    given : dict
        The spec keys and values it came from, as written.
    formula : str
        The formula, in words a drive engineer can check.
    """

    key: str
    value: float
    unit: str
    given: dict = field(default_factory=dict)
    formula: str = ""

    def as_dict(self) -> dict:
        return {"key": self.key, "value": self.value, "unit": self.unit,
                "given": dict(self.given), "formula": self.formula}


def _flux_amplitude(key: str, value: float, p: int) -> tuple[float, str]:
    """Peak phase PM flux (amplitude-invariant) from one datasheet constant."""
    rules: dict[str, tuple[Callable[[float], float], str]] = {
        "ke_ll_peak": (lambda k: k / (math.sqrt(3) * p),
                       "flux = ke_ll_peak / (sqrt(3) p), ke in V s/rad (mechanical)"),
        "ke_ll_rms": (lambda k: math.sqrt(2) * k / (math.sqrt(3) * p),
                      "flux = sqrt(2) ke_ll_rms / (sqrt(3) p), ke in V s/rad (mechanical)"),
        "kt_peak": (lambda k: k / (1.5 * p),
                    "flux = kt_peak / (1.5 p), kt in N m per A peak phase current"),
        "kt_rms": (lambda k: k / (1.5 * math.sqrt(2) * p),
                   "flux = kt_rms / (1.5 sqrt(2) p), kt in N m per A rms phase current"),
    }
    rule, text = rules[key]
    return rule(value), text


def _dq_current_per_rms(convention: str) -> tuple[float, str]:
    """|i_dq| per A rms of balanced sinusoidal phase currents: the peak phase
    current sqrt(2) I_rms (amplitude-invariant dq), sqrt(3/2) times more in the
    power-invariant dq."""
    if convention == "power":
        return math.sqrt(3.0), "sqrt(3) (power-invariant dq: sqrt(3/2) x the peak sqrt(2) I_rms)"
    return math.sqrt(2.0), "sqrt(2) (amplitude-invariant dq: the peak phase current)"


#: ``[[scenario]]`` keys holding a physical quantity (toolbox.sim.Scenario's
#: units); ``plant_values`` takes the motor's kinds, ``speed_loop`` these.
SCENARIO_KINDS = {
    "duration": "time", "step_time": "time", "load_time": "time", "plant_step": "time",
    "trace_step": "time",
    "id_ref": "current", "iq_ref": "current", "id_ref0": "current", "iq_ref0": "current",
    "current_noise": "current", "current_quantum": "current",
    "torque_ref": "torque", "load_torque": "torque", "torque_amplitude": "torque",
    "torque_frequency": "frequency",
    "speed_ref": "speed", "speed_ref0": "speed", "initial_speed": "speed",
    "speed_offset": "speed", "speed_noise": "speed", "acceleration": "acceleration",
}
SPEED_LOOP_KINDS = {"kp": "speed_gain", "ki": "speed_gain_integral",
                    "sample_time": "time", "iq_limit": "current"}


def rms_rule(key: str, kind: str, convention: str) -> str:
    """What an rms marker means for ``key`` (:func:`toolbox.spec._units.normalise_unit`):
    nothing for keys named rms, the dq magnitude of the convention for a
    current, rms -> peak (x sqrt(2)) inside other units (``"N m/Arms"``)."""
    if key.endswith("_rms"):
        return "rms"
    if kind == "current" and convention == "power":
        return "power"
    return "peak"


def convert_units(table: Mapping[str, Any], kinds: Mapping[str, str], prefix: str,
                  errors: Collector, convention: str = "amplitude"
                  ) -> tuple[dict, list[Conversion]]:
    """Replace ``"<number> <unit>"`` strings by SI floats, recording each.

    Other values are left as they are for the type checks (``"0.6"`` stays a
    string and is refused there as "expected a number"). An rms current
    (``"10 Arms"``) becomes the dq magnitude of ``convention``
    (:func:`rms_rule`).
    """
    out = dict(table)
    log: list[Conversion] = []
    for key, kind in kinds.items():
        value = table.get(key)
        if not looks_like_quantity(value):
            continue
        with errors.check():
            out[key] = parse_quantity(value, f"{prefix}.{key}", kind,
                                      rms_rule(key, kind, convention))
            log.append(Conversion(key, out[key], KINDS[kind].si.replace("*", " "),
                                  {key: value}, f"{value} in SI units"))
    return out, log


def _as_written(value: Any) -> str:
    """A spec value as TOML writes it (double-quoted strings)."""
    return json.dumps(value) if isinstance(value, str) else repr(value)


def _check_groups(given: Mapping[str, Any], errors: Collector) -> None:
    """At most one way to give each model quantity."""
    for what, model, alternatives in GROUPS:
        used = [k for k in model if k in given][:1] + [k for k in alternatives if k in given]
        if len(used) > 1:
            with errors.check():
                both = ", ".join(f"{k} = {_as_written(given[k])}" for k in used)
                raise SpecError(f"motor.{used[1]}",
                                f"only one of motor.{used[0]}, motor.{used[1]} "
                                f"(equivalent ways to give {what})",
                                _Shown(f"both ({both})"), hint="remove one of them")


def catalog_kept(catalog: Mapping[str, Any], user: Mapping[str, Any]) -> dict:
    """The catalog values the user's table does not replace: a datasheet form
    (``R_ll``) replaces the catalog's model keys for it (``R``); a model key
    replaces only itself (``Ld`` alone keeps the catalog's ``Lq``)."""
    kept = dict(catalog)
    for _, model, alternatives in GROUPS:
        if any(k in user for k in alternatives):
            for k in model:
                kept.pop(k, None)
    return kept


def resolve_motor(user: Mapping[str, Any], catalog: Mapping[str, Any],
                  errors: Collector) -> tuple[dict, list[Conversion]]:
    """The ``[motor]`` table with datasheet keys replaced by model keys.

    Parameters
    ----------
    user : mapping
        The ``[motor]`` table as written (keys already checked).
    catalog : mapping
        The catalog entry's values (empty without ``catalog``).
    errors : Collector
        Receives every error (unit, dimension, two equivalents).

    Returns
    -------
    merged : dict
        Model keys (``R``, ``Ld``, ``Lq``, ``flux`` ...) with SI values where
        they could be converted; offending values are left for the type
        checks to report.
    log : list of Conversion
        What was given and what was derived from it.
    """
    _check_groups(user, errors)
    base = {**catalog_kept(catalog, user), **user}
    merged, log = convert_units(base, MOTOR_KINDS, "motor", errors,
                                str(base.get("convention", "amplitude")))
    if "R_ll" in merged and "R" not in user:
        r_ll = _positive(merged.pop("R_ll"), user["R_ll"], "motor.R_ll", "ohm", errors)
        if r_ll is not None:
            merged["R"] = r_ll / 2
            log.append(Conversion("R", r_ll / 2, "ohm", {"R_ll": user["R_ll"]},
                                  "R = R_ll / 2 (star: the line-to-line value spans two "
                                  "phases)"))
    if "L_ll" in merged and not ({"Ld", "Lq"} & set(user)):
        l_ll = _positive(merged.pop("L_ll"), user["L_ll"], "motor.L_ll", "H", errors)
        if l_ll is not None:
            merged["Ld"] = merged["Lq"] = l_ll / 2
            for k in ("Ld", "Lq"):
                log.append(Conversion(k, l_ll / 2, "H", {"L_ll": user["L_ll"]},
                                      f"{k} = L_ll / 2 (star, surface PM: Ld = Lq = the "
                                      "synchronous inductance; give Ld, Lq for an IPM)"))
    flux_keys = [k for k in GROUPS[2][2] if k in merged and "flux" not in user]
    if flux_keys:
        key = flux_keys[0]  # two of them are already an error (_check_groups)
        values = {k: merged.pop(k) for k in flux_keys}
        unit = "V s/rad" if key.startswith("ke") else "N m/A"
        constant = _positive(values[key], user[key], f"motor.{key}", unit, errors)
        p = merged.get("pole_pairs")
        if constant is not None and isinstance(p, int) and not isinstance(p, bool) and p >= 1:
            psi, text = _flux_amplitude(key, constant, p)
            if merged.get("convention", "amplitude") == "power":
                psi *= math.sqrt(1.5)
                text = text.replace("flux = ", "flux = sqrt(3/2) x ") + " (power-invariant dq)"
            merged["flux"] = psi
            log.append(Conversion("flux", psi, "Wb", {key: user[key], "pole_pairs": p}, text))
        else:  # the constant's or pole_pairs' own error says why; no second message
            merged["flux"] = _NOT_DERIVED
    for key, model in RMS_CURRENTS.items():
        if key in merged and model not in user:
            i_rms = _positive(merged.pop(key), user[key], f"motor.{key}", "A", errors)
            if i_rms is None:
                merged[model] = _NOT_DERIVED
                continue
            factor, text = _dq_current_per_rms(merged.get("convention", "amplitude"))
            merged[model] = factor * i_rms
            log.append(Conversion(model, factor * i_rms, "A", {key: user[key]},
                                  f"{model} = {text} x {key}"))
    consumed = {"R_ll", "L_ll", "ke_ll_peak", "ke_ll_rms", "kt_peak", "kt_rms",
                *RMS_CURRENTS}
    return merged, [c for c in log if c.key not in consumed or c.formula.startswith(c.key)]


def convert_scenario(item: Any, key: str, convention: str,
                     errors: Collector) -> Any:
    """A ``[[scenario]]`` table with its unit strings in SI (the scenario's
    own keys, ``plant_values`` and ``speed_loop``); each failed conversion is
    recorded in ``errors`` and its value left for the type check."""
    if not isinstance(item, Mapping):
        return item
    out, _ = convert_units(item, SCENARIO_KINDS, key, errors, convention)
    for sub, kinds in (("plant_values", MOTOR_KINDS), ("speed_loop", SPEED_LOOP_KINDS)):
        if isinstance(item.get(sub), Mapping):
            out[sub], _ = convert_units(item[sub], kinds, f"{key}.{sub}", errors, convention)
    return out


def reported_keys(errors: Collector, prefix: str) -> set[str]:
    """Keys of ``[prefix]`` that already have an error, with the model keys
    their datasheet form stands for (``R_ll`` -> ``R``), so that the type
    checks do not report them a second time (or as missing)."""
    keys = {e.key[len(prefix) + 1:] for e in errors.errors if e.key.startswith(prefix + ".")}
    for _, model, alternatives in GROUPS:
        if keys & set(alternatives):
            keys |= set(model)
    if prefix == "drive" and "sample_frequency" in keys:
        keys.add("sample_time")
    return keys


#: Placeholder for a model value that could not be derived (its source's
#: error is already recorded, so the model key is not reported missing).
_NOT_DERIVED = 1.0


def _positive(value: Any, written: Any, key: str, unit: str,
              errors: Collector) -> float | None:
    """``value`` if a finite number > 0; else record why (once) and return None."""
    if is_finite_number(value) and value > 0:  # a 400-digit integer is not
        return float(value)
    if not looks_like_quantity(written):  # a unit string was already reported
        errors.add(SpecError(key, f"a number > 0 ({unit}) or a string with a unit", written))
    return None


def resolve_drive(user: Mapping[str, Any], errors: Collector) -> tuple[dict, list[Conversion]]:
    """The ``[drive]`` table in SI, ``sample_frequency`` turned into ``sample_time``."""
    if "sample_time" in user and "sample_frequency" in user:
        errors.add(SpecError("drive.sample_frequency",
                             "only one of drive.sample_time, drive.sample_frequency "
                             "(equivalent ways to give the controller period)",
                             _Shown(f"both (sample_time = {user['sample_time']!r}, "
                                    f"sample_frequency = {user['sample_frequency']!r})"),
                             hint="remove one of them"))
    merged, log = convert_units(user, DRIVE_KINDS, "drive", errors)
    if "sample_frequency" in merged and "sample_time" not in user:
        fs = merged.pop("sample_frequency")
        if is_finite_number(fs) and fs > 0:
            merged["sample_time"] = 1.0 / fs
            log.append(Conversion("sample_time", 1.0 / fs, "s",
                                  {"sample_frequency": user["sample_frequency"]},
                                  "sample_time = 1 / sample_frequency"))
        else:
            errors.add(SpecError("drive.sample_frequency", "a number > 0 (Hz)",
                                 user["sample_frequency"]))
    merged.pop("sample_frequency", None)
    return merged, [c for c in log if c.key != "sample_frequency"]


def relocate(err: SpecError, conversions: list[Conversion]) -> SpecError:
    """Point an error on a derived model key at the key the user wrote.

    A range check on ``motor.R`` is about ``R_ll`` when R was derived from it;
    the message then names ``motor.R_ll`` (a key in the spec) and says how R
    was obtained.

    Parameters
    ----------
    err : SpecError
        An error of a later check (ranges, time constants).
    conversions : list of Conversion
        The spec's conversion log.

    Returns
    -------
    SpecError
        ``err`` itself, or a copy naming the given key.
    """
    section, _, name = err.key.partition(".")
    for conv in conversions:
        sources = [k for k in conv.given if k != "pole_pairs"]
        if conv.key != name or sources == [name] or not sources:
            continue
        shown = ", ".join(f"{k} = {_as_written(v)}" for k, v in conv.given.items())
        return SpecError(f"{section}.{sources[0]}",
                         f"{err.expected} for {name} (derived: {conv.formula})",
                         _Shown(f"{name} = {conv.value:.6g} from {shown}"), hint=err.hint)
    return err
