"""The report's firmware card (toolbox/report/_firmware.py) from firmware.json:
the measured figures, or "not measured" and why (no toolchain, no header)."""

from __future__ import annotations

from toolbox.report._firmware import _firmware_card

MEASURED = {"schema": "cct.firmware/1", "measured": True, "clock_hz": 170e6, "pwm_hz": 20e3,
            "code_bytes": 1300, "data_bytes": 116, "stack_bytes": 136, "libm_bytes": 4360,
            "instructions": {"typical": 282, "worst": 288},
            "period_share": {"cpi": [1.0, 1.3], "low": 0.036941, "high": 0.047106},
            "toolchain": "arm-none-eabi-gcc 12.2"}


def test_card_shows_the_measured_figures():
    card = _firmware_card(MEASURED)
    assert card["measured"]
    assert card["value"] == "282-288 instructions per step, 3.7-4.7 % of 50 us at 170 MHz"
    assert "code 1300 B, data 116 B, stack 136 B, libm 4360 B" in card["detail"]


def test_card_says_not_measured_and_why():
    card = _firmware_card({"schema": "cct.firmware/1", "measured": False,
                           "reason": "not measured: toolchain absent (arm-none-eabi-gcc)"})
    assert (card["measured"], card["value"]) == (False, "not measured")
    assert card["detail"] == "toolchain absent (arm-none-eabi-gcc)"
    none = _firmware_card(None)
    assert none["value"] == "not measured" and "no controller.h" in none["detail"]
