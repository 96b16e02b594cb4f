"""The speed ramp through base speed in the report (verify.json
``envelope.speed_ramp``): the envelope table's last row, its line in the
section's summary, and a failing ramp makes the section fail."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

from toolbox.report import build_context

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "verify"))
from test_speed_ramp import ENVELOPE, RAMP  # noqa: E402


def test_report_ramp_row(full_data):
    ver = dict(full_data.verification or {})
    ver["envelope"] = ENVELOPE
    ctx = build_context(dataclasses.replace(full_data, verification=ver))
    row = ctx["envelope"]["rows"][-1]
    assert row[0].startswith("speed ramp") and row[4] == "fail" and "peak current" in row[5]
    assert RAMP["summary"] in ctx["envelope"]["summary"]
    assert ctx["envelope"]["status"] == "fail"
    assert len(ctx["envelope"]["rows"]) == len(ENVELOPE["points"]) + 1
