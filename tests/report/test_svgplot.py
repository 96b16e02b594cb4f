"""The report's SVG plotter (toolbox/report/_svgplot.py, no matplotlib: toolbox/ARCHITECTURE.md
"Caches and lazy imports").

Checks are on the SVG written: tick values and positions, the path data of
lines with NaN/inf, escaping, byte-for-byte determinism, and that every
output parses as XML with unique ids.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from toolbox.report._svgplot import Axes, Figure, escape, log_ticks, nice_ticks

NS = "{http://www.w3.org/2000/svg}"


def _texts(svg: str) -> list[str]:
    return ["".join(e.itertext()) for e in ET.fromstring(svg).iter(f"{NS}text")]


def _paths(svg: str) -> list[str]:
    return [e.get("d") for e in ET.fromstring(svg).iter(f"{NS}path")]


def test_nice_ticks():
    """Linear ticks are 1/2/2.5/5 x 10^k multiples inside the range, labels exact."""
    assert nice_ticks(0.0, 1.0) == [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    assert nice_ticks(-183.0, 12.0) == [-150.0, -100.0, -50.0, 0.0]
    assert nice_ticks(0.0, 0.3, target=4) == [0.0, 0.1, 0.2, 0.3]  # not 0.30000000000000004
    assert nice_ticks(0.69, 0.72) == [0.69, 0.7, 0.71, 0.72]  # step 0.01 >= 0.03/5
    assert nice_ticks(1.0, 1.0) == [] and nice_ticks(0.0, math.inf) == []


def test_log_ticks():
    """Decades are the major ticks, 2..9 x 10^k the minor ones, inside the range."""
    major, minor = log_ticks(1.0, 31415.9)
    assert major == [1.0, 10.0, 100.0, 1000.0, 10000.0]
    assert minor[:3] == [2.0, 3.0, 4.0] and minor[-1] == 30000.0
    assert all(1.0 <= v <= 31415.9 for v in minor) and len(minor) == 4 * 8 + 2
    major, _ = log_ticks(0.5, 900.0)
    assert major == [1.0, 10.0, 100.0]
    # very wide ranges label every other decade (at most 12 labels)
    major, _ = log_ticks(1e-20, 1e20)
    assert len(major) <= 12 and all(math.log10(v) % 2 == 0 for v in major)
    assert log_ticks(-1.0, 10.0) == ([], [])


def _log_figure() -> str:
    fig = Figure(4.0, 3.0)
    ax = fig.axes[0]
    ax.xlog = True
    ax.line([1.0, 10.0, 100.0, 1000.0], [0.0, 1.0, 2.0, 3.0], "#ff0000", label="a")
    ax.xlabel = "x"
    return fig.svg("t")


def test_log_axis_tick_positions_are_evenly_spaced():
    """On a log axis the decades 1, 10, 100, 1000 are equally spaced and labelled
    10^k (exponent as superscript), and the line maps decades linearly."""
    svg = _log_figure()
    labels = [t for t in _texts(svg) if t.startswith("10")]
    assert labels == ["100", "101", "102", "103"]  # "10" + superscript k
    xs = [float(x) for x in re.findall(r'<text x="([0-9.]+)" y="[0-9.]+" text-anchor="middle" '
                                       r'font-size="8">10<tspan', svg)]
    steps = np.diff(xs)
    assert len(xs) == 4 and np.allclose(steps, steps[0], atol=0.011)  # printed to 0.01 pt
    line = next(d for d in _paths(svg) if d.count("L") == 3)
    px = [float(v) for v in re.findall(r"[ML]([0-9.]+) ", line)]
    assert np.allclose(px, xs, atol=0.011)  # the data sit on their decade ticks


def test_nan_and_inf_break_lines():
    """NaN and inf points are not drawn: the line restarts after them (M, not L);
    non-positive values are not drawable on a log axis either."""
    fig = Figure(4.0, 3.0)
    ax = fig.axes[0]
    ax.line([0, 1, 2, 3, 4, 5], [0, 1, math.nan, 3, math.inf, 5], "#000000")
    svg = fig.svg("n")
    d = next(p for p in _paths(svg) if p.startswith("M") and "L" in p and "V" not in p
             and "H" not in p)
    assert d.count("M") == 3 and d.count("L") == 1  # (0,1) joined, 3 and 5 alone
    assert "nan" not in svg.lower() and "inf" not in svg.lower()
    fig = Figure(4.0, 3.0)
    ax = fig.axes[0]
    ax.ylog = True
    ax.line([0, 1, 2, 3], [1.0, -1.0, 0.0, 10.0], "#000000")
    d = [p for p in _paths(fig.svg("m")) if p.startswith("M") and p.count("M") == 2]
    assert d  # the points 1 and 10 are each alone, the two non-positive ones dropped


def test_limits_ignore_non_finite_and_far_points_are_clamped():
    """Autoscaling uses the finite data only; a huge value within given limits
    is clamped to a printable coordinate and cut by the clip path."""
    fig = Figure(4.0, 3.0)
    ax = fig.axes[0]
    ax.line([0, 1, 2], [0, math.inf, 1], "#000000")
    assert ax.limits()[1] == pytest.approx((-0.05, 1.05))
    ax.line([0, 1], [0, 1e300], "#000000")
    ax.ylim = (0.0, 1.0)
    svg = fig.svg("c")
    assert "e+" not in svg and max(len(n) for n in re.findall(r"[0-9.]+", svg)) < 12
    assert 'clip-path="url(#c-ax0)"' in svg and 'clipPath id="c-ax0"' in svg


def test_text_is_escaped():
    """Every text written goes through XML escaping (the SVG still parses)."""
    assert escape('<a & "b" \'c\'>') == "&lt;a &amp; &quot;b&quot; &#39;c&#39;&gt;"
    fig = Figure(4.0, 3.0)
    ax = fig.axes[0]
    ax.line([0, 1], [0, 1], "#000000", label="</text><script>x</script> & 'q'")
    ax.title, ax.xlabel, ax.ylabel = "a < b", "c & d", '"e"'
    ax.legend_loc = "upper right"
    ax.text(0.1, 0.1, "f > g", "#000000", box=True)
    svg = fig.svg("e")
    assert "<script>" not in svg
    texts = _texts(svg)
    for t in ("</text><script>x</script> & 'q'", "a < b", "c & d", '"e"', "f > g"):
        assert t in texts


def test_deterministic_and_ids_unique():
    """Same calls, same bytes; ids carry the prefix and are unique per figure."""
    def make(prefix):
        fig = Figure(7.2, 6.4, rows=3)
        for k, ax in enumerate(fig.axes):
            ax.xlog = True
            w = np.logspace(0, 4, 50)
            ax.line(w, np.sin(np.log(w)) * (k + 1), "#1f5fa8", label="d axis")
            ax.markers([10.0], [0.0], "#c23b22", shape="x")
            ax.legend_loc = "lower right"
        return fig.svg(prefix)

    a, b = make("p"), make("p")
    assert a == b
    ids = re.findall(r'\bid="([^"]+)"', a)
    assert ids == ["p-ax0", "p-ax1", "p-ax2"]
    root = ET.fromstring(a)
    assert root.get("width") == "518.40pt" and root.get("height") == "460.80pt"


def test_equal_aspect_keeps_unit_lengths():
    """With ``equal`` one data unit is as long on x as on y (the box shrinks)."""
    fig = Figure(5.6, 4.8)
    ax = fig.axes[0]
    ax.line([-3, 1.5], [-2.5, 2.5], "#000000")
    ax.xlim, ax.ylim, ax.equal = (-3.0, 1.5), (-2.5, 2.5), True
    rect = next(e for e in ET.fromstring(fig.svg("q")).iter(f"{NS}rect")
                if e.get("stroke") == "#000000")
    w, h = float(rect.get("width")), float(rect.get("height"))
    assert w / 4.5 == pytest.approx(h / 5.0, abs=0.01)


def test_axes_api_defaults():
    """An empty axes still draws (limits 0..1), so a figure never fails on no data."""
    ax = Axes()
    assert ax.limits() == ((0.0, 1.0), (0.0, 1.0))
    ET.fromstring(Figure(3.0, 2.0).svg("z"))
