"""firmware.json (:mod:`toolbox.export.firmware`): the target figures of a
header as data, the report's firmware card and the README's table.

* Without the cross toolchain (simulated by making ``_m4.available`` report
  it missing) the data says ``measured: false`` with the reason (the
  report's card: ``tests/report/test_firmware_card.py``).
* With it, the figures of a gallery header equal ``reports/<name>/firmware.json``
  (deterministic, and the gallery's file is fresh), the share of the PWM
  period is the stated formula of the worst path, and the README's table is
  the one :func:`firmware_table` writes from the gallery's files.
* ``tests/export/test_target.py`` checks the figures against an independent
  route: the instruction counts along a closed-loop trajectory stay within
  the measured worst path, and the sizes are the same build's.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from toolbox.export import _m4
from toolbox.export.firmware import (CPI, SLOW_EXTRA, firmware_table, load_firmware,
                                     measure_firmware)

import target_m4 as T

ROOT = Path(__file__).resolve().parents[2]


def test_not_measured_without_toolchain(monkeypatch):
    monkeypatch.setattr(_m4, "available", lambda: "arm-none-eabi-gcc, unicorn (PyPI)")
    header = (ROOT / "reports" / "003_azaiz2007_pi" / "controller.h").read_text()
    data = measure_firmware(header)
    assert data["measured"] is False
    assert data["reason"] == "not measured: toolchain absent (arm-none-eabi-gcc, unicorn (PyPI))"


def test_gallery_figures_are_fresh_and_consistent():
    T.require()
    d = ROOT / "reports" / "003_azaiz2007_pi"
    stored = load_firmware(d)
    assert stored is not None and stored["measured"]
    data = json.loads(json.dumps(measure_firmware((d / "controller.h").read_text())))
    assert data == stored, "reports/003_azaiz2007_pi/firmware.json is not the header's"
    ins = data["instructions"]
    assert 0 < ins["typical"] <= ins["worst"]
    assert data["saturated"] > 0                       # the worst path includes the limit
    for key, cpi in (("low", CPI[0]), ("high", CPI[1])):
        assert data["period_share"][key] == pytest.approx(
            (ins["worst"] * cpi + SLOW_EXTRA * data["div_sqrt"]) / (170e6 / 20e3), rel=1e-12)


def test_readme_table_is_the_gallery_data():
    table = firmware_table(ROOT / "reports")
    assert table.count("\n") >= 3
    readme = (ROOT / "README.md").read_text()
    indented = "\n".join("  " + ln for ln in table.splitlines())
    assert indented in readme, "README's firmware table differs from reports/*/firmware.json"
