"""The torque-speed grid in the report (verify.json ``envelope``): the
envelope figure draws the limit curves and one marker per point coloured by
status (pass green, fail red, unreachable grey x) with its reason as the
marker's SVG ``<title>`` (hover), the table repeats every reason, the summary
line is shown; a grid that was skipped says why; the figure parses as XML
and holds no user string (the reasons are the toolbox's own text)."""

from __future__ import annotations

import dataclasses
import re
import xml.etree.ElementTree as ET

from toolbox.report import build_context, write_html

NS = "{http://www.w3.org/2000/svg}"


def _point(sf, tf, status, reason=None, torque=5.0):
    unreachable = status == "unreachable"
    return {"speed_fraction": sf, "torque_fraction": tf, "speed": 100.0 * sf,
            "torque": None if unreachable else torque,
            "region": "unreachable" if unreachable else "mtpa", "status": status,
            "reason": reason}


ENVELOPE = {
    "passed": False, "counts": {"pass": 1, "fail": 1, "unreachable": 1},
    "summary": "torque-speed grid: 1 pass, 1 fail, 1 unreachable of 3 points (base speed 100 "
               "rad/s, torque limit 10 N m, radial voltage priority)",
    "failures": ["0.5 x torque limit at 1.5 x base speed (150 rad/s): peak current 30 A "
                 "after the step (bound 24 A)"],
    "base_speed_rad_s": 100.0, "torque_limit_nm": 10.0,
    "curves": {"speed_rad_s": [0.0, 100.0, 200.0], "torque_limit": [10.0, 10.0, None],
               "current_limit": [10.0, 10.0, 10.0], "voltage_limit": [None, 20.0, 8.0]},
    "points": [_point(0.0, 0.5, "pass"),
               _point(1.5, 0.5, "fail", "peak current 30 A after the step (bound 24 A)"),
               _point(2.0, 1.0, "unreachable", "no current fits at 200 rad/s: the back-EMF "
                      "exceeds the voltage limit (82.3 V) with the current limit (20 A) "
                      "reached")]}


def _data(full_data, envelope):
    ver = dict(full_data.verification or {})
    ver["envelope"] = envelope
    return dataclasses.replace(full_data, verification=ver)


def test_envelope_figure_and_table(full_data):
    ctx = build_context(_data(full_data, ENVELOPE))
    env = ctx["envelope"]
    assert env["status"] == "fail" and env["summary"] == ENVELOPE["summary"]
    root = ET.fromstring(env["svg"])
    tips = {}
    for g in root.iter(f"{NS}g"):
        title = g.find(f"{NS}title")
        if title is not None:
            shape = g.find(f"{NS}circle")
            if shape is None:
                shape = g.find(f"{NS}path")
            tips[title.text] = shape.get("fill") if shape.tag.endswith("circle") \
                else shape.get("stroke")
    assert len(tips) == 3
    by_status = {t.split(": ")[1].split(",")[0].split(":")[0]: c for t, c in tips.items()}
    assert by_status == {"pass": "#2a7f3f", "fail": "#c23b22", "unreachable": "#8a8f98"}
    assert any("peak current 30 A after the step (bound 24 A)" in t for t in tips)
    assert any("back-EMF exceeds the voltage limit" in t for t in tips)
    # the limit curves: three polylines, the legend names them
    text = env["svg"]
    for label in ("torque limit (current and voltage)", "current limit alone",
                  "voltage limit alone (MTPV)", "unreachable (not simulated)"):
        assert label in text
    html = write_html(_data(full_data, ENVELOPE))
    assert 'id="envelope-figure"' in html and 'id="envelope-table"' in html
    assert html.count("peak current 30 A after the step (bound 24 A)") >= 2  # hover + table
    assert re.search(r'<b class="status fail">torque-speed grid: 1 pass, 1 fail', html)


def test_envelope_skipped_and_absent(full_data):
    ctx = build_context(_data(full_data, {"passed": True,
                                          "skipped": "no operating envelope: no current limit"}))
    assert ctx["envelope"]["svg"] is None and "skipped" in ctx["envelope"]["summary"]
    ver = {k: v for k, v in (full_data.verification or {}).items() if k != "envelope"}
    assert build_context(dataclasses.replace(full_data, verification=ver))["envelope"] is None
