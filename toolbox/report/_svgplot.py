"""A small deterministic SVG line-plot writer for the report figures.

Why not matplotlib: its layout engine and text measurement drew the 7 report
figures in about 3.5 s per design; the figures are line and marker plots on
linear or logarithmic axes, which this module writes directly as SVG in a few
milliseconds. What it supports is what the report draws: stacked axes
sharing x, linear and log scales with major ticks (1-2-2.5-5 steps, decades
on log axes, minor ticks 2..9 per decade), grid, polylines (dashed or not),
markers (``o``, ``x``, ``+``, filled or hollow), horizontal lines, vertical
segments, a horizontal band, text in axes coordinates, a legend box, titles,
axis labels and an equal-aspect option.

Determinism: the output depends only on the calls made (no ids from memory
addresses, no dates); coordinates are printed with two decimals (1/100 pt).
Non-finite values (NaN, +-inf, and values <= 0 on a log axis) break a line
instead of being drawn; points far outside the limits are clamped to a
bounded coordinate range and cut by the axes' clip path. Every text is XML
escaped. Text is SVG ``<text>`` in a sans-serif font (the browser's and
typst's), so its width is estimated (``_text_width``) for legend boxes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

__all__ = ["Axes", "Figure", "escape", "nice_ticks", "log_ticks"]

FONT = "DejaVu Sans, Arial, Helvetica, sans-serif"
#: Largest |coordinate| written (pt from the axes origin): far points are
#: clamped so that the path stays printable; the clip path cuts them anyway.
_CLAMP = 1e5


def escape(text: str) -> str:
    """``text`` escaped for SVG character data and attribute values."""
    return (str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;").replace("'", "&#39;"))


def _f(v: float) -> str:
    """A coordinate with two decimals, never ``-0.00``."""
    s = f"{v:.2f}"
    return "0.00" if s == "-0.00" else s


def _text_width(text: str, size: float) -> float:
    """Estimated width (pt) of ``text`` in a sans-serif font of ``size`` pt."""
    return 0.58 * size * len(text)


def nice_ticks(lo: float, hi: float, target: int = 6) -> list[float]:
    """Major ticks on a linear axis: multiples of 1, 2, 2.5 or 5 x 10^k within
    ``[lo, hi]``, about ``target`` of them."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return []
    raw = (hi - lo) / max(target - 1, 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1.0, 2.0, 2.5, 5.0, 10.0) if m * mag >= raw * 0.999)
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    # round to the step's decimals so labels read 0.3, not 0.30000000000000004
    digits = max(0, -math.floor(math.log10(step)) + 2)
    return [round(k * step, digits) + 0.0 for k in range(first, last + 1)]


def log_ticks(lo: float, hi: float) -> tuple[list[float], list[float]]:
    """Major ticks (decades 10^k) and minor ticks (2..9 x 10^k) within ``[lo, hi]``
    (both > 0); at most 12 labelled decades (every other one beyond)."""
    if not (lo > 0 and hi > lo and math.isfinite(hi)):
        return [], []
    k0, k1 = math.ceil(math.log10(lo) - 1e-9), math.floor(math.log10(hi) + 1e-9)
    every = max(1, math.ceil((k1 - k0 + 1) / 12))
    major = [10.0 ** k for k in range(k0, k1 + 1) if k % every == 0]
    minor = [m * 10.0 ** k for k in range(k0 - 1, k1 + 1) for m in range(2, 10)
             if lo <= m * 10.0 ** k <= hi]
    return major, minor


def _label(v: float) -> str:
    """Tick label of a linear axis."""
    s = f"{v:.6g}"
    return "0" if s in ("-0", "0") else s.replace("-", "\u2212")


@dataclass
class _Line:
    x: np.ndarray
    y: np.ndarray
    color: str
    width: float
    dash: str | None
    opacity: float
    label: str | None


@dataclass
class _Markers:
    x: np.ndarray
    y: np.ndarray
    shape: str
    color: str
    size: float
    filled: bool
    edge: str | None
    label: str | None
    tips: tuple[str, ...] | None = None


@dataclass
class Axes:
    """One plot area: data, scales, limits and labels."""

    xlog: bool = False
    ylog: bool = False
    title: str = ""
    title_size: float = 10.0
    xlabel: str = ""
    ylabel: str = ""
    ylabel_size: float = 9.0
    xlim: tuple[float, float] | None = None
    ylim: tuple[float, float] | None = None
    equal: bool = False
    legend_loc: str | None = None
    legend_size: float = 8.0
    legend_cols: int = 1
    items: list = field(default_factory=list)
    texts: list = field(default_factory=list)

    def line(self, x, y, color: str, *, width: float = 1.4, dash: str | None = None,
             opacity: float = 1.0, label: str | None = None) -> None:
        """A polyline through ``(x, y)``; ``dash`` is an SVG dash array ("4 2")."""
        self.items.append(_Line(np.asarray(x, float).ravel(), np.asarray(y, float).ravel(),
                                color, width, dash, opacity, label))

    def markers(self, x, y, color: str, *, shape: str = "o", size: float = 5.0,
                filled: bool = True, edge: str | None = None, label: str | None = None,
                tips: Sequence[str] | None = None) -> None:
        """Markers ``o`` (circle), ``x`` or ``+`` of diameter ``size`` pt;
        ``tips`` (one per marker): an SVG ``<title>`` each, shown on hover."""
        self.items.append(_Markers(np.asarray(x, float).ravel(), np.asarray(y, float).ravel(),
                                   shape, color, size, filled, edge, label,
                                   None if tips is None else tuple(str(t) for t in tips)))

    def hline(self, y: float, color: str = "#000000", width: float = 0.8) -> None:
        """A horizontal line across the axes at ``y``."""
        self.items.append(("hline", float(y), color, width))

    def vsegment(self, x: float, y0: float, y1: float, color: str, *, width: float = 2.2,
                 opacity: float = 0.7) -> None:
        """A vertical segment at ``x`` from ``y0`` to ``y1`` (data coordinates)."""
        self.line([x, x], [y0, y1], color, width=width, opacity=opacity)

    def hband(self, y0: float, y1: float, color: str, *, opacity: float = 0.5,
              label: str | None = None) -> None:
        """A band across the axes between ``y0`` and ``y1``."""
        self.items.append(("hband", float(y0), float(y1), color, opacity, label))

    def text(self, fx: float, fy: float, text: str, color: str, size: float = 8.0,
             box: bool = False) -> None:
        """Text at axes fractions ``(fx, fy)`` (0, 0 = bottom left), left aligned."""
        self.texts.append((fx, fy, text, color, size, box))

    # ------------------------------------------------------------- scales

    def _data(self, axis: int) -> np.ndarray:
        vals = []
        for it in self.items:
            if isinstance(it, (_Line, _Markers)):
                vals.append(it.x if axis == 0 else it.y)
        if not vals:
            return np.zeros(0)
        v = np.concatenate(vals)
        log = self.xlog if axis == 0 else self.ylog
        return v[np.isfinite(v) & ((v > 0) if log else True)]

    def limits(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Axis limits: the given ones, else the data range (+5 % on linear axes)."""
        out = []
        for axis, given, log in ((0, self.xlim, self.xlog), (1, self.ylim, self.ylog)):
            if given is not None:
                out.append((float(given[0]), float(given[1])))
                continue
            v = self._data(axis)
            if axis == 1:  # horizontal lines and bands belong to the y range
                extra = [it[1] for it in self.items if isinstance(it, tuple) and it[0] == "hline"]
                extra += [y for it in self.items if isinstance(it, tuple) and it[0] == "hband"
                          for y in it[1:3]]
                v = np.concatenate([v, np.asarray(extra, float)])
            if v.size == 0:
                out.append((1.0, 10.0) if log else (0.0, 1.0))
                continue
            lo, hi = float(v.min()), float(v.max())
            if log:
                lo, hi = (lo / 2, hi * 2) if lo == hi else (lo, hi)
                if axis == 1:
                    pad = (math.log10(hi) - math.log10(lo)) * 0.05
                    lo, hi = lo / 10 ** pad, hi * 10 ** pad
            else:
                if lo == hi:
                    lo, hi = lo - (abs(lo) or 1.0) * 0.5, hi + (abs(hi) or 1.0) * 0.5
                elif axis == 1 or not self.xlog:
                    pad = 0.05 * (hi - lo)
                    lo, hi = lo - pad, hi + pad
            out.append((lo, hi))
        return out[0], out[1]


def _transform(v: np.ndarray, lim: tuple[float, float], log: bool, p0: float,
               p1: float) -> np.ndarray:
    """Data -> pt (``lim[0]`` at ``p0``, ``lim[1]`` at ``p1``); NaN where not drawable."""
    v = np.asarray(v, float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if log:
            v = np.where(v > 0, np.log10(np.where(v > 0, v, 1.0)), np.nan)
            a, b = math.log10(lim[0]), math.log10(lim[1])
        else:
            a, b = lim
        out = p0 + (v - a) / (b - a) * (p1 - p0)
    out[~np.isfinite(out)] = np.nan
    return np.clip(out, p0 - _CLAMP, p0 + _CLAMP)


def _path(px: np.ndarray, py: np.ndarray) -> str:
    """SVG path data of a polyline, broken at NaN points."""
    ok = np.isfinite(px) & np.isfinite(py)
    parts, pen = [], False
    for x, y, good in zip(px, py, ok):
        if not good:
            pen = False
            continue
        parts.append(("L" if pen else "M") + _f(x) + " " + _f(y))
        pen = True
    return "".join(parts)


@dataclass
class Figure:
    """A figure of ``rows`` stacked axes sharing x, ``width`` x ``height`` in inches."""

    width: float
    height: float
    rows: int = 1
    axes: list[Axes] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not self.axes:
            self.axes = [Axes() for _ in range(self.rows)]

    def svg(self, prefix: str) -> str:
        """The figure as an SVG string; element ids start with ``prefix``."""
        W, H = 72.0 * self.width, 72.0 * self.height
        left, right, bottom, top_pad = 62.0, 14.0, 36.0, 8.0
        n = len(self.axes)
        titles = [14.0 + a.title_size if a.title else 0.0 for a in self.axes]
        gap = 10.0
        avail = H - bottom - top_pad - sum(titles) - gap * (n - 1)
        h = avail / n
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{_f(W)}pt" height="{_f(H)}pt" '
               f'viewBox="0 0 {_f(W)} {_f(H)}" version="1.1" font-family="{FONT}">',
               f'<rect width="{_f(W)}" height="{_f(H)}" fill="#ffffff"/>']
        y_top = top_pad
        xlims = [ax.limits()[0] for ax in self.axes]
        # shared x: the union of the axes' x ranges (given limits win)
        shared = (min(l[0] for l in xlims), max(l[1] for l in xlims))
        for k, ax in enumerate(self.axes):
            y_top += titles[k]
            x0, x1, y0, y1 = left, W - right, y_top, y_top + h
            xlim = shared if ax.xlim is None else ax.xlim
            ylim = ax.limits()[1]
            if ax.equal:
                # shrink the box so one data unit is as long on both axes
                sx = (x1 - x0) / (xlim[1] - xlim[0])
                sy = (y1 - y0) / (ylim[1] - ylim[0])
                if sx > sy:
                    w = (xlim[1] - xlim[0]) * sy
                    x0, x1 = x0 + 0.5 * (x1 - x0 - w), x0 + 0.5 * (x1 - x0 + w)
                else:
                    hh = (ylim[1] - ylim[0]) * sx
                    y0, y1 = y0 + 0.5 * (y1 - y0 - hh), y0 + 0.5 * (y1 - y0 + hh)
            out += self._axes_svg(ax, f"{prefix}-ax{k}", (x0, x1, y0, y1), xlim, ylim,
                                  last=(k == n - 1))
            y_top += h + gap
        out.append("</svg>")
        return "\n".join(out) + "\n"

    @staticmethod
    def _axes_svg(ax: Axes, cid: str, box, xlim, ylim, last: bool) -> list[str]:
        x0, x1, y0, y1 = box
        tx = lambda v: _transform(v, xlim, ax.xlog, x0, x1)  # noqa: E731
        ty = lambda v: _transform(v, ylim, ax.ylog, y1, y0)  # noqa: E731
        o = [f'<clipPath id="{cid}"><rect x="{_f(x0)}" y="{_f(y0)}" width="{_f(x1 - x0)}" '
             f'height="{_f(y1 - y0)}"/></clipPath>']
        # grid and ticks
        grid, ticks, labels = [], [], []
        for axis, lim, log in ((0, xlim, ax.xlog), (1, ylim, ax.ylog)):
            lo, hi = min(lim), max(lim)
            if log:
                major, minor = log_ticks(lo, hi)
                if len(major) < 2:  # less than two decades shown: linear ticks read better
                    major, minor = nice_ticks(lo, hi), []
                    texts = [_label(v) for v in major]
                else:
                    texts = [None] * len(major)
            else:
                major, minor = nice_ticks(lo, hi), []
                texts = [_label(v) for v in major]
            for v, is_major, text in ([(v, True, t) for v, t in zip(major, texts)]
                                      + [(v, False, None) for v in minor]):
                if axis == 0:
                    p = float(tx([v])[0])
                    if is_major:
                        grid.append(f"M{_f(p)} {_f(y0)}V{_f(y1)}")
                    ticks.append(f"M{_f(p)} {_f(y1)}v{3.5 if is_major else 2.0}")
                    if is_major and last:
                        labels.append(_tick_text(p, y1 + 13, "middle", v, text, log))
                else:
                    p = float(ty([v])[0])
                    if is_major:
                        grid.append(f"M{_f(x0)} {_f(p)}H{_f(x1)}")
                    ticks.append(f"M{_f(x0)} {_f(p)}h-{3.5 if is_major else 2.0}")
                    if is_major:
                        labels.append(_tick_text(x0 - 5, p + 3, "end", v, text, log))
        o.append(f'<path d="{"".join(grid)}" stroke="#b0b0b0" stroke-opacity="0.35" '
                 f'stroke-width="0.6" fill="none"/>')
        o.append(f'<g clip-path="url(#{cid})">')
        legend = []
        for it in ax.items:
            if isinstance(it, tuple) and it[0] == "hband":
                _, b0, b1, color, op, label = it
                p0, p1 = float(ty([b0])[0]), float(ty([b1])[0])
                o.append(f'<rect x="{_f(x0)}" y="{_f(min(p0, p1))}" width="{_f(x1 - x0)}" '
                         f'height="{_f(abs(p1 - p0))}" fill="{color}" fill-opacity="{op}"/>')
                if label:
                    legend.append(("band", color, None, op, label))
            elif isinstance(it, tuple) and it[0] == "hline":
                _, yv, color, width = it
                p = float(ty([yv])[0])
                o.append(f'<path d="M{_f(x0)} {_f(p)}H{_f(x1)}" stroke="{color}" '
                         f'stroke-width="{width}" fill="none"/>')
            elif isinstance(it, _Line):
                d = _path(tx(it.x), ty(it.y))
                dash = f' stroke-dasharray="{it.dash}"' if it.dash else ""
                op = f' stroke-opacity="{it.opacity}"' if it.opacity != 1.0 else ""
                if d:
                    o.append(f'<path d="{d}" stroke="{it.color}" stroke-width="{it.width}"'
                             f'{dash}{op} fill="none" stroke-linejoin="round"/>')
                if it.label:
                    legend.append(("line", it.color, it.dash, it.width, it.label))
            elif isinstance(it, _Markers):
                px, py = tx(it.x), ty(it.y)
                tips = it.tips or (None,) * len(px)
                o += [_marker(x, y, it) if tip is None else
                      f"<g><title>{escape(tip)}</title>{_marker(x, y, it)}</g>"
                      for x, y, tip in zip(px, py, tips)
                      if math.isfinite(x) and math.isfinite(y)]
                if it.label:
                    legend.append(("marker", it, None, None, it.label))
        o.append("</g>")
        o.append(f'<path d="{"".join(ticks)}" stroke="#000000" stroke-width="0.8" fill="none"/>')
        o.append(f'<rect x="{_f(x0)}" y="{_f(y0)}" width="{_f(x1 - x0)}" height="{_f(y1 - y0)}" '
                 f'stroke="#000000" stroke-width="0.8" fill="none"/>')
        o += labels
        if ax.title:
            o.append(f'<text x="{_f(0.5 * (x0 + x1))}" y="{_f(y0 - 6)}" text-anchor="middle" '
                     f'font-size="{ax.title_size}">{escape(ax.title)}</text>')
        if ax.ylabel:
            cy = 0.5 * (y0 + y1)
            o.append(f'<text x="{_f(x0 - 46)}" y="{_f(cy)}" text-anchor="middle" '
                     f'font-size="{ax.ylabel_size}" transform="rotate(-90 {_f(x0 - 46)} {_f(cy)})">'
                     f'{escape(ax.ylabel)}</text>')
        if ax.xlabel and last:
            o.append(f'<text x="{_f(0.5 * (x0 + x1))}" y="{_f(y1 + 29)}" text-anchor="middle" '
                     f'font-size="9">{escape(ax.xlabel)}</text>')
        for fx, fy, text, color, size, box in ax.texts:
            px, py = x0 + fx * (x1 - x0), y1 - fy * (y1 - y0)
            if box:
                o.append(f'<rect x="{_f(px - 1)}" y="{_f(py - size)}" '
                         f'width="{_f(_text_width(text, size) + 2)}" height="{_f(size + 3)}" '
                         f'fill="#ffffff" fill-opacity="0.8"/>')
            o.append(f'<text x="{_f(px)}" y="{_f(py)}" font-size="{size}" fill="{color}">'
                     f'{escape(text)}</text>')
        if legend and ax.legend_loc:
            o += _legend(legend, ax, (x0, x1, y0, y1))
        return o


def _tick_text(x: float, y: float, anchor: str, v: float, text: str | None, log: bool) -> str:
    """A tick label; decades of a log axis as 10 with a superscript exponent."""
    head = f'<text x="{_f(x)}" y="{_f(y)}" text-anchor="{anchor}" font-size="8">'
    if text is not None:
        return head + escape(text) + "</text>"
    k = round(math.log10(v))
    return head + f'10<tspan dy="-4" font-size="6">{escape(_label(k))}</tspan></text>'


def _marker(x: float, y: float, m: _Markers) -> str:
    r = 0.5 * m.size
    if m.shape == "x":
        return (f'<path d="M{_f(x - r)} {_f(y - r)}L{_f(x + r)} {_f(y + r)}M{_f(x - r)} '
                f'{_f(y + r)}L{_f(x + r)} {_f(y - r)}" stroke="{m.color}" stroke-width="1.6"/>')
    if m.shape == "+":
        return (f'<path d="M{_f(x - r)} {_f(y)}H{_f(x + r)}M{_f(x)} {_f(y - r)}V{_f(y + r)}" '
                f'stroke="{m.color}" stroke-width="2"/>')
    fill = m.color if m.filled else "none"
    stroke = m.edge or m.color
    return (f'<circle cx="{_f(x)}" cy="{_f(y)}" r="{_f(r)}" fill="{fill}" stroke="{stroke}" '
            f'stroke-width="1"/>')


def _legend(entries: Sequence[tuple], ax: Axes, box) -> list[str]:
    x0, x1, y0, y1 = box
    size = ax.legend_size
    row_h = size + 4.0
    sample = 18.0
    cols = max(1, ax.legend_cols)
    n_rows = math.ceil(len(entries) / cols)
    col_w = max(_text_width(e[4], size) for e in entries) + sample + 10.0
    w, h = cols * col_w + 4.0, n_rows * row_h + 4.0
    loc = ax.legend_loc
    lx = x1 - w - 4 if loc.endswith("right") else x0 + 4
    ly = y0 + 4 if loc.startswith("upper") else y1 - h - 4
    o = [f'<rect x="{_f(lx)}" y="{_f(ly)}" width="{_f(w)}" height="{_f(h)}" fill="#ffffff" '
         f'fill-opacity="0.8" stroke="#cccccc" stroke-width="0.6"/>']
    for k, (kind, a, b, c, label) in enumerate(entries):
        cx = lx + 4 + (k % cols) * col_w
        cy = ly + 2 + (k // cols) * row_h + 0.5 * row_h
        if kind == "line":
            dash = f' stroke-dasharray="{b}"' if b else ""
            o.append(f'<path d="M{_f(cx)} {_f(cy)}h{_f(sample)}" stroke="{a}" '
                     f'stroke-width="{c}"{dash} fill="none"/>')
        elif kind == "band":
            o.append(f'<rect x="{_f(cx)}" y="{_f(cy - 3)}" width="{_f(sample)}" height="6" '
                     f'fill="{a}" fill-opacity="{c}"/>')
        else:
            o.append(_marker(cx + 0.5 * sample, cy, a))
        o.append(f'<text x="{_f(cx + sample + 4)}" y="{_f(cy + 0.35 * size)}" '
                 f'font-size="{size}">{escape(label)}</text>')
    return o
