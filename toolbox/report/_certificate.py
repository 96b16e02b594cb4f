"""The certificate section of the content model: the stored robustness
certificate and the sampled certificate's box in words."""

from __future__ import annotations

from typing import Any, Mapping

from ._format import _as_float, fmt


def _certificate_of(analysis: Mapping | None) -> dict | None:
    """Named facts of ``analysis.certificate``, ``analysis.sampled_certificate``,
    ``analysis.mimo_at_speed`` and ``analysis.mimo_over_box``."""
    facts: dict[str, Any] = {}
    cert = (analysis or {}).get("certificate")
    if cert:
        facts["quadratic stability (continuous loop, no delay)"] = (
            "certified" if cert.get("certified") else "not certified")
        facts["largest certified box scale"] = cert.get("scale")
        for name, (lo, hi) in (cert.get("box") or {}).items():
            facts[f"box {name}"] = f"{lo:.4g} .. {hi:.4g}"
    facts.update(_sampled_certificate_of((analysis or {}).get("sampled_certificate")))
    mimo = (analysis or {}).get("mimo_at_speed") or {}
    if mimo:
        facts["MIMO disk margin, worst electrical speed (rad/s)"] = mimo.get("worst_speed_rad_s")
        facts["MIMO disk margin, worst value"] = mimo.get("worst_disk_margin")
    box = (analysis or {}).get("mimo_over_box") or {}
    if box:
        facts["MIMO disk margin over the parameter box and speeds, worst value"] = (
            box.get("worst_disk_margin"))
        facts["MIMO disk margin over the box, worst electrical speed (rad/s)"] = (
            box.get("worst_speed_rad_s"))
        facts["MIMO disk margin over the box, worst parameters (scale factors)"] = ", ".join(
            f"{k} x{v:g}" for k, v in (box.get("worst_params") or {}).items())
        facts["MIMO over the box: unstable (plant, speed) pairs"] = (
            f"{box.get('n_unstable')} of {box.get('n_models')} plants x "
            f"{len(box.get('speeds_rad_s') or [])} speeds")
    return facts or None


#: units of the sampled certificate's box entries other than the speeds
_SAMPLED_BOX_UNITS = {"R": " ohm", "Ld": " H", "Lq": " H"}
#: labels of its speed entries (electrical rad/s in the JSON)
_SAMPLED_BOX_SPEEDS = {"omega": "speed", "speed_offset": "speed-sensor offset"}
#: labels of the other box entries
_SAMPLED_BOX_LABELS = {"speed_gain": "speed-sensor gain"}


def _speed_text(lo: Any, hi: Any, pole_pairs: Any) -> str:
    """An electrical speed range (rad/s) as mechanical rad/s with electrical in
    brackets (the spec's ``max_speed`` is mechanical); electrical alone when
    the pole pairs are unknown (an analysis.json written before they were)."""
    elec = f"{fmt(lo)} .. {fmt(hi)} rad/s electrical"
    lo, hi, pp = _as_float(lo), _as_float(hi), _as_float(pole_pairs)
    if lo is None or hi is None or not pp:
        return elec
    return f"{fmt(lo / pp)} .. {fmt(hi / pp)} rad/s mechanical ({elec})"


def _sampled_certificate_of(cert: Mapping | None) -> dict[str, Any]:
    """Named facts of ``analysis.sampled_certificate`` (empty when absent); its
    speeds (electrical in the JSON) are stated in mechanical rad/s with
    electrical in brackets."""
    if not isinstance(cert, Mapping):
        return {}
    where = "sampled coupled loop as executed (ZOH, delay, decoupling, voltage placement)"
    pp = cert.get("pole_pairs")
    facts: dict[str, Any] = {
        f"stability certificate, {where}": "certified" if cert.get("certified")
        else "not certified, not even the nominal point",
        "sampled loop: largest certified box scale": cert.get("scale"),
        "sampled loop: what the scale means": "scale k shrinks every range of the "
        "sweep's box towards the nominal point by the factor k, the speed range "
        "included (k = 1: the whole box and speeds up to the maximum); the box "
        "certified is listed below in the spec's units"}
    speed = cert.get("speed_range_rad_s")
    if isinstance(speed, (list, tuple)) and len(speed) == 2:
        facts["sampled loop: speed range covered"] = _speed_text(*speed, pp)
    for name, (lo, hi) in (cert.get("box") or {}).items():
        if name == "omega" and "sampled loop: speed range covered" in facts:
            continue            # the same range
        if name in _SAMPLED_BOX_SPEEDS:
            facts[f"sampled loop: box {_SAMPLED_BOX_SPEEDS[name]}"] = _speed_text(lo, hi, pp)
        else:
            unit = _SAMPLED_BOX_UNITS.get(name, "")
            label = _SAMPLED_BOX_LABELS.get(name, name)
            facts[f"sampled loop: box {label}"] = f"{lo:.4g} .. {hi:.4g}{unit}"
    first = cert.get("first_uncertified")
    if isinstance(first, Mapping):
        c = first.get("corner") or {}
        state = ("unstable" if c.get("unstable") else "stable there, not proven on its cell")

        def speed_at(v):
            w, p = _as_float(v), _as_float(pp)
            if w is None or not p:
                return f"{fmt(v)} rad/s electrical"
            return f"{fmt(w / p)} rad/s mechanical ({fmt(w)} rad/s electrical)"

        facts["sampled loop: first uncertified corner"] = (
            f"scale {fmt(first.get('scale'))}: R x{fmt(c.get('R'))}, Ld x{fmt(c.get('Ld'))}, "
            f"Lq x{fmt(c.get('Lq'))}, w {speed_at(c.get('omega_rad_s'))}, speed gain "
            f"{fmt(c.get('speed_gain'))}, offset {speed_at(c.get('speed_offset_rad_s'))}; "
            f"spectral radius {fmt(c.get('spectral_radius'))} ({state}); {first.get('reason')}")
    return facts
