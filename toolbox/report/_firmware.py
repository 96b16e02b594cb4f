"""The report's firmware card: the target figures of ``firmware.json``
(:mod:`toolbox.export.firmware`), or why they were not measured."""

from __future__ import annotations

from typing import Mapping


def _firmware_card(firmware: Mapping | None) -> dict:
    """The card's strings: ``value`` (instructions and share of the PWM period),
    ``detail`` (sizes, toolchain, clock), ``measured`` (bool).

    ``firmware`` is the ``firmware.json`` dict; ``None`` (no header was
    written) and ``measured = false`` both give a card that says "not
    measured" and why."""
    if firmware is None:
        return {"measured": False, "value": "not measured",
                "detail": "no firmware.json (no controller.h was written)"}
    if not firmware.get("measured"):
        reason = str(firmware.get("reason", "not measured"))
        return {"measured": False, "value": "not measured",
                "detail": reason.removeprefix("not measured: ")}
    ins, share = firmware["instructions"], firmware["period_share"]
    clock = float(firmware["clock_hz"]) / 1e6
    period = 1e6 / float(firmware["pwm_hz"])
    cpi = share.get("cpi", [1.0, 1.3])
    return {"measured": True,
            "value": (f"{ins['typical']}-{ins['worst']} instructions per step, "
                      f"{100 * share['low']:.1f}-{100 * share['high']:.1f} % of "
                      f"{period:g} us at {clock:g} MHz"),
            "detail": (f"Cortex-M4F (emulated): code {firmware['code_bytes']} B, data "
                       f"{firmware['data_bytes']} B, stack {firmware['stack_bytes']} B, "
                       f"libm {firmware['libm_bytes']} B; typical / worst path, "
                       f"{cpi[0]:g}-{cpi[1]:g} cycles per instruction; "
                       f"{firmware.get('toolchain', '')}")}
