"""Report figures as deterministic, self-contained SVG strings.

The loop, scenario and robustness figures are written by the small SVG
plotter :mod:`toolbox.report._svgplot` (matplotlib's layout and
text measurement took about 3.5 s per report); its output depends only on
the numbers drawn, so equal inputs give byte-identical SVG, and element ids
are prefixed per figure so several SVGs can share one HTML document.

Equations are typeset by matplotlib's mathtext (:func:`equation_svg`,
imported only there) with ``svg.fonttype = "path"`` (glyphs as paths), a
fixed ``svg.hashsalt`` and no date metadata; :func:`svg_from_figure` is also
what the campaign report uses for its matplotlib figures.

The loop figures draw the numbers of ``analysis.json["responses"]``
(:mod:`toolbox.analysis._responses`: the executed law, sampled, with the
computation delay, on the ZOH plant) and mark the margins of
``analysis.json["margins"]["discrete"]``: nothing here computes a loop, so
every curve is the loop whose margins are tabled. Figures never contain
user-supplied text.
"""

from __future__ import annotations

import io
import math
import re
from typing import Any, Mapping, Sequence
import hashlib

import numpy as np

from ._svgplot import Figure

__all__ = ["figures", "equation_svg", "scenario_svg", "robustness_svg", "traces_dict",
           "svg_from_figure", "STEP_FIGURES"]

AXIS_COLORS = {"d": "#1f5fa8", "q": "#c23b22"}
RC = {
    "svg.fonttype": "path",
    "svg.hashsalt": "cct-report",
    "font.family": "DejaVu Sans",
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "grid.linewidth": 0.6,
    "axes.titlesize": 10,
    "legend.fontsize": 8,
    "lines.linewidth": 1.4,
    "figure.dpi": 72,
    "savefig.dpi": 72,
}

METRIC_UNITS = {
    "gain_margin_db": "dB", "phase_margin_deg": "deg", "gain_crossover_rad_s": "rad/s",
    "phase_crossover_rad_s": "rad/s", "disk_margin": "1", "stability_margin": "1",
    "sensitivity_peak": "1", "bandwidth_rad_s": "rad/s", "static_error": "1",
    "response_time_5pct": "s", "rise_time": "s", "settling_time": "s",
    "overshoot_pct": "%", "torque_mse": "(N m)^2", "id_mse": "A^2",
    "commutations_per_s": "1/s", "saturation_time": "s",
}

_FIG_COUNTER_ATTR = "_cct_fig_counter"


# -------------------------------------------------------------------- SVG out

_ID_RE = re.compile(r'\bid="([^"]+)"')


def svg_from_figure(fig, prefix: str, tight: bool = False) -> str:
    """Serialise ``fig`` to a cleaned, deterministic SVG string.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    prefix : str
        Prefix for every element id (unique per figure in a document).
    tight : bool
        Crop to the drawn content (used for equations).
    """
    import matplotlib  # lazy: matplotlib, ~100 modules

    buf = io.StringIO()
    with matplotlib.rc_context(RC):
        fig.savefig(buf, format="svg", metadata={"Date": None},
                    bbox_inches="tight" if tight else None, pad_inches=0.04)
    svg = buf.getvalue()
    svg = re.sub(r"<\?xml[^>]*\?>\s*", "", svg)
    svg = re.sub(r"<!DOCTYPE[^>]*>\s*", "", svg)
    svg = re.sub(r"<metadata>.*?</metadata>\s*", "", svg, flags=re.S)
    ids = set(_ID_RE.findall(svg))
    if ids:
        def ref(m: re.Match) -> str:
            name = m.group(2)
            return f"{m.group(1)}{prefix}-{name}" if name in ids else m.group(0)
        svg = _ID_RE.sub(lambda m: f'id="{prefix}-{m.group(1)}"', svg)
        svg = re.sub(r'(href="#)([^"]+)', lambda m: ref(m) , svg)
        svg = re.sub(r"(url\(#)([^)]+)", lambda m: ref(m), svg)
    return svg.strip() + "\n"


def _mpl_figure(width_in: float, height_in: float):
    """A matplotlib figure with the report's style (equations only)."""
    import matplotlib  # lazy: matplotlib, ~100 modules
    from matplotlib.figure import Figure as MplFigure  # lazy: ~220 modules

    with matplotlib.rc_context(RC):
        return MplFigure(figsize=(width_in, height_in))


# --------------------------------------------------------------- stored data

#: Step figures of ``margins.discrete`` shown with the step response: key -> (label, unit, scale).
STEP_FIGURES = {
    "overshoot_pct": ("overshoot", "%", 1.0),
    "response_time_5pct": ("5 % time", "ms", 1e3),
    "settling_time_2pct": ("2 % settling", "ms", 1e3),
}


def _arr(values: Any) -> np.ndarray:
    """Float array from stored JSON numbers (``"inf"``/``"nan"`` strings included)."""
    return np.array([float(v) for v in values], float)


def _num(value: Any) -> float | None:
    """A stored scalar as float; ``None`` when absent or not finite."""
    if value is None or isinstance(value, bool):
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _axes(responses: Mapping) -> list[str]:
    return [a for a in ("d", "q") if isinstance(responses.get(a), Mapping)]


# -------------------------------------------------------------------- figures

DASH, DOT = "5 2.2", "1.2 2"


def bode_svg(responses: Mapping, margins: Mapping | None, prefix: str = "bode") -> str:
    """Bode diagram of the stored loop ``L`` per axis, margins marked.

    The markers and the text are the analysis' margins (gain margin at the
    phase crossover, phase margin at the gain crossover), not a reading of
    the plotted grid.
    """
    fig = Figure(7.2, 4.6, rows=2)
    ax_m, ax_p = fig.axes
    ax_m.xlog = ax_p.xlog = True
    lines: list[tuple[str, str]] = []
    for name in _axes(responses):
        r = responses[name]
        w, mag, phase = _arr(r["omega"]), _arr(r["loop"]["mag_db"]), _arr(r["loop"]["phase_deg"])
        c = AXIS_COLORS[name]
        ax_m.line(w, mag, c, label=f"{name} axis")
        ax_p.line(w, phase, c)
        m = (margins or {}).get(name) or {}
        pm, w_pm = _num(m.get("phase_margin_deg")), _num(m.get("gain_crossover_rad_s"))
        gm, w_gm = _num(m.get("gain_margin_db")), _num(m.get("phase_crossover_rad_s"))
        text = f"{name} axis: " + (f"PM {pm:.1f} deg at {w_pm:.3g} rad/s"
                                   if pm is not None and w_pm else "no gain crossover")
        text += (f"; GM {gm:.1f} dB at {w_gm:.3g} rad/s" if gm is not None and w_gm
                 else "; no phase crossover")
        lines.append((c, text))
        if pm is not None and w_pm:
            ax_m.markers([w_pm], [0.0], c, size=5)
            ph_at = float(np.interp(math.log(w_pm), np.log(w), phase))
            # the margin is the distance to the nearest odd multiple of -180 deg
            ax_p.vsegment(w_pm, ph_at - pm, ph_at, c)
        if gm is not None and w_gm:
            ax_m.vsegment(w_gm, -gm, 0.0, c)
    for k, (c, text) in enumerate(lines):
        ax_m.text(0.02, 0.05 + 0.11 * (len(lines) - 1 - k), text, c, size=8, box=True)
    ax_m.hline(0.0)
    ax_p.hline(-180.0)
    ax_m.ylabel = "|L| (dB)"
    ax_p.ylabel = "phase of L (deg)"
    ax_p.xlabel = "frequency (rad/s)"
    ax_m.legend_loc = "upper right"
    ax_m.title = "Open loop L = K G (executed law, sampled, ZOH and computation delay)"
    return fig.svg(prefix)


def nyquist_svg(responses: Mapping, margins: Mapping | None, prefix: str = "nyq") -> str:
    """Nyquist plot of the stored ``L`` near -1, with the circle of radius ``1/max|S|``."""
    fig = Figure(5.6, 4.8)
    ax = fig.axes[0]
    th = np.linspace(0, 2 * math.pi, 361)
    for name in _axes(responses):
        r, c = responses[name], AXIS_COLORS[name]
        re_, im = _arr(r["loop"]["re"]), _arr(r["loop"]["im"])
        ax.line(re_, im, c, label=f"{name} axis (w > 0)")
        ax.line(re_, -im, c, dash=DASH, width=0.9)
        rad = _num(((margins or {}).get(name) or {}).get("stability_margin"))
        if rad is None:  # no margins given: the stored |S| peak
            rad = float(10 ** (-np.nanmax(_arr(r["S_db"])) / 20))
        ax.line(-1 + rad * np.cos(th), rad * np.sin(th), c, width=0.8, dash=DOT,
                label=f"{name}: 1/max|S| = {rad:.2f}")
    ax.markers([-1], [0], "#000000", shape="+", size=12)
    ax.xlim, ax.ylim, ax.equal = (-3.0, 1.5), (-2.5, 2.5), True
    ax.xlabel, ax.ylabel = "Re L (1)", "Im L (1)"
    ax.title = "Nyquist plot (zoom on the critical point -1)"
    ax.legend_loc = "lower right"
    return fig.svg(prefix)


def has_weight_bounds(responses: Mapping | None) -> bool:
    """Whether any axis of the stored responses carries H-infinity weight bounds."""
    return any((responses or {}).get(a, {}).get("weight_bounds") for a in _axes(responses or {}))


def sensitivity_svg(responses: Mapping, prefix: str = "sens") -> str:
    """Stored |S|, |KS|, |T| per axis, with the stored ``gamma/|W_i|`` bounds when present."""
    fig = Figure(7.2, 6.4, rows=3)
    keys = (("S", "w1", "|S| (dB)", "sensitivity S = 1/(1+L)"),
            ("KS", "w2", "|KS| (dB, V/A)", "control sensitivity KS"),
            ("T", "w3", "|T| (dB)", "complementary sensitivity T = L/(1+L)"))
    for ax, (fn, wkey, ylabel, title) in zip(fig.axes, keys):
        ax.xlog = True
        for name in _axes(responses):
            r, c = responses[name], AXIS_COLORS[name]
            w = _arr(r["omega"])
            ax.line(w, _arr(r[f"{fn}_db"]), c, label=f"{name} axis")
            bound = (r.get("weight_bounds") or {}).get(fn)
            if bound is not None:
                ax.line(w, _arr(bound), c, dash=DASH, width=1.0,
                        label=f"{name}: gamma/|{wkey.upper()}|")
        ax.ylabel, ax.title, ax.title_size = ylabel, title, 9.0
        ax.legend_loc, ax.legend_cols = "lower right", 2
    fig.axes[-1].xlabel = "frequency (rad/s)"
    return fig.svg(prefix)


def _simulated_steps(traces: Sequence[dict] | None) -> list[tuple[str, int, np.ndarray, np.ndarray]]:
    """Normalised simulated responses of scenarios whose reference is one step.

    A trace qualifies on an axis when its reference goes from 0 to a constant
    non-zero value once; the response is divided by that value and its time
    is shifted to the step instant.
    """
    out = []
    for k, tr in enumerate(traces or []):
        if not tr:
            continue
        for axis in ("d", "q"):
            ref, cur = tr.get(f"i{axis}_ref"), tr.get(f"i{axis}")
            if ref is None or cur is None or ref.size < 3:
                continue
            final = float(ref[-1])
            if final == 0.0:
                continue
            changes = np.nonzero(np.diff(ref) != 0)[0]
            if changes.size > 1 or (changes.size == 0 and ref[0] != final):
                continue
            k0 = int(changes[0]) + 1 if changes.size else 0
            if changes.size and ref[changes[0]] != 0.0:
                continue
            out.append((axis, k + 1, tr["t"][k0:] - tr["t"][k0], cur[k0:] / final))
    return out


def step_text(margins: Mapping | None, axis: str) -> str:
    """``overshoot 0.004 %, 5 % time 2.21 ms, ...`` of one axis from the analysis' margins."""
    m = (margins or {}).get(axis) or {}
    parts = []
    for key, (label, unit, scale) in STEP_FIGURES.items():
        v = _num(m.get(key))
        parts.append(f"{label} {v * scale:.3g} {unit}" if v is not None else f"{label} n/a")
    return ", ".join(parts)


def step_svg(responses: Mapping, traces: Sequence[dict] | None = None,
             prefix: str = "step") -> str:
    """Stored reference step ``i_ref -> i`` of the executed loop per axis.

    Simulated step responses (verification traces,
    normalised by the reference) are overlaid, dashed, when given.
    """
    fig = Figure(7.2, 3.4)
    ax = fig.axes[0]
    t_end = 0.0
    for name in _axes(responses):
        st = responses[name]["step"]
        t, y = _arr(st["t"]), _arr(st["y"])
        t_end = max(t_end, float(t[-1]))
        ax.line(t * 1e3, y, AXIS_COLORS[name], label=f"{name} axis, linear")
    for axis, k, t, y in _simulated_steps(traces):
        keep = t <= t_end
        ax.line(t[keep] * 1e3, y[keep], AXIS_COLORS[axis], dash=DASH, width=1.0,
                label=f"{axis} axis, simulated (scenario {k})")
    ax.hline(1.0)
    ax.hband(0.95, 1.05, "#d9d9d9", opacity=0.5, label="+/- 5 % band")
    ax.xlabel, ax.ylabel = "time (ms)", "current / reference (A/A)"
    ax.title = "Linear reference step response of the executed loop (unit step)"
    ax.legend_loc, ax.legend_size = "lower right", 7.0
    return fig.svg(prefix)


def pzmap_svg(responses: Mapping, prefix: str = "pz") -> str:
    """Stored closed-loop poles (x) and zeros (o) of ``i_ref -> i`` per axis, unit circle."""
    fig = Figure(5.6, 5.0)
    ax = fig.axes[0]
    th = np.linspace(0, 2 * math.pi, 361)
    ax.line(np.cos(th), np.sin(th), "#666666", width=0.8)
    for name in _axes(responses):
        c, pz = AXIS_COLORS[name], responses[name]["pz"]
        p = np.array(pz["poles"], float).reshape(-1, 2)
        z = np.array(pz["zeros"], float).reshape(-1, 2)
        ax.markers(p[:, 0], p[:, 1], c, shape="x", size=8, label=f"{name} poles")
        if z.size:
            ax.markers(z[:, 0], z[:, 1], c, shape="o", size=8, filled=False,
                       label=f"{name} zeros")
    ax.xlim, ax.ylim, ax.equal = (-1.2, 1.2), (-1.2, 1.2), True
    ax.xlabel, ax.ylabel = "Re z (1)", "Im z (1)"
    ax.title = "Closed-loop pole-zero map (z-plane, reference to current)"
    ax.legend_loc, ax.legend_size = "lower left", 7.0
    return fig.svg(prefix)


def figures(responses: Mapping | None, margins: Mapping | None = None,
            traces: Sequence[dict] | None = None) -> list[dict]:
    """The loop figures of a report: ``[{"id", "title", "caption", "svg"}]``.

    Parameters
    ----------
    responses : mapping or None
        ``analysis.json["responses"]``; ``None`` gives no figure (the
        templates then say "not computed").
    margins : mapping, optional
        ``analysis.json["margins"]["discrete"]``: margin markers and step figures.
    traces : sequence of dict, optional
        Verification traces (``traces_dict`` form, ``None`` entries allowed)
        in scenario order; single reference steps are overlaid on the step.
    """
    if not responses:
        return []
    sim = _simulated_steps(traces)
    has_w = has_weight_bounds(responses)
    return [
        {"id": "bode", "title": "Bode diagram of the loop",
         "caption": "L = K G per axis (the executed law's feedback channel, sampled loop with "
                    "ZOH and computation delay, up to the Nyquist frequency). Dots: gain "
                    "crossover; bars: phase and gain margins of the margin table.",
         "svg": bode_svg(responses, margins)},
        {"id": "nyquist", "title": "Nyquist plot",
         "caption": "Solid: positive frequencies; dashed: mirror image. Dotted circles around "
                    "-1 have radius 1/max|S| (the stability margin).",
         "svg": nyquist_svg(responses, margins)},
        {"id": "sensitivity", "title": "Closed-loop functions",
         "caption": ("Dashed: bounds gamma/|W_i| from the H-infinity weights recorded in the "
                     "design (paper 003 eq (41)-(43))." if has_w else
                     "Weight bounds: not computed (no H-infinity weights in the design)."),
         "svg": sensitivity_svg(responses)},
        {"id": "step", "title": "Step response (linear)",
         "caption": "Unit reference step i_ref -> i of the executed law (two-degree-of-freedom "
                    "reference channel included, current between samples shown)"
                    + "".join(f"; {a} axis: {step_text(margins, a)}" for a in _axes(responses)
                              if margins)
                    + ("; dashed: simulated responses of the verification scenarios "
                       "(numbered as in the verification section), divided by the reference."
                       if sim else "; simulated step responses: not computed."),
         "svg": step_svg(responses, traces)},
        {"id": "pzmap", "title": "Pole-zero map",
         "caption": "Closed-loop poles and zeros of i_ref -> i; all poles inside the unit "
                    "circle means the sampled loop is stable.",
         "svg": pzmap_svg(responses)},
    ]


def equation_svg(tex: str, prefix: str | None = None) -> str | None:
    """Render a LaTeX equation with matplotlib mathtext; ``None`` if unsupported."""
    prefix = prefix or "eq" + format(abs(hash_text(tex)) % 10**8, "08d")
    fig = _mpl_figure(9.0, 0.6)
    fig.text(0.01, 0.5, f"${tex}$", fontsize=17, va="center")
    try:
        return svg_from_figure(fig, prefix, tight=True)
    except ValueError:  # mathtext parse error
        return None


def hash_text(text: str) -> int:
    """A stable (not salted per process) hash for element-id prefixes."""
    return int(hashlib.sha256(text.encode()).hexdigest()[:12], 16)


# ---------------------------------------------------------------- simulations

TRACE_NAMES = ("t", "id", "iq", "id_ref", "iq_ref", "vd", "vq", "speed", "speed_measured",
               "torque")


def traces_dict(traces: Any) -> dict | None:
    """Plain ``{name: ndarray}`` from a mapping or a :class:`toolbox.sim.SimResult`."""
    if traces is None:
        return None
    out = {}
    for name in TRACE_NAMES:
        v = traces.get(name) if isinstance(traces, Mapping) else getattr(traces, name, None)
        if v is not None:
            out[name] = np.asarray(v, float).reshape(-1)
    return out if "t" in out and len(out) > 1 else None


def scenario_svg(traces: dict, prefix: str | None = None) -> str:
    """Currents (and voltages, when present) of one simulated scenario versus time."""
    prefix = prefix or "sc" + format(hash_text(repr(sorted(traces)) + repr(traces["t"][:3].tolist())
                                               + str(len(traces["t"]))) % 10**8, "08d")
    has_v = "vd" in traces or "vq" in traces
    fig = Figure(7.2, 4.8 if has_v else 3.0, rows=2 if has_v else 1)
    axs = fig.axes
    t = traces["t"] * 1e3
    for key, c, dash in (("id", AXIS_COLORS["d"], None), ("iq", AXIS_COLORS["q"], None),
                         ("id_ref", AXIS_COLORS["d"], DOT), ("iq_ref", AXIS_COLORS["q"], DOT)):
        if key in traces:
            axs[0].line(t, traces[key], c, dash=dash, label=key.replace("_ref", " reference"))
    axs[0].ylabel = "current (A)"
    axs[0].legend_loc, axs[0].legend_cols = "lower right", 2
    if has_v:
        for key, c in (("vd", AXIS_COLORS["d"]), ("vq", AXIS_COLORS["q"])):
            if key in traces:
                axs[1].line(t, traces[key], c, label=key)
        axs[1].ylabel = "voltage (V)"
        axs[1].legend_loc = "lower right"
    axs[-1].xlabel = "time (ms)"
    return fig.svg(prefix)


#: Panel titles of the robustness figure.
ROBUSTNESS_PANELS = {"spectral_radius": "largest pole modulus",
                     "gain_margin_db": "gain margin", "phase_margin_deg": "phase margin",
                     "stability_margin": "1/max|S|", "disk_margin": "disk margin"}


def robustness_svg(cases: Sequence[Mapping], worst: Sequence[str], prefix: str = "rob") -> str:
    """Sweep cases per metric: failing (unstable) sets red, passing green,
    worst cases ringed.

    A panel holds the cases that carry its metric (a case's ``metrics``);
    the failing sets' panel (``spectral_radius``, the largest closed-loop
    pole modulus, with the stability limit 1) comes first, so every set the
    legend calls "fail" is drawn.
    """
    names: list[str] = []
    failing = [c for c in cases if c.get("pass") is False]
    for c in failing + [c for c in cases if c.get("pass") is not False]:
        for m in (c.get("metrics") or {}):
            if m not in names:
                names.append(m)
    names = names[:3] or ["(none)"]
    fig = Figure(7.2, 1.2 + 1.9 * len(names), rows=len(names))
    axs = fig.axes
    worst_set = set(worst)
    for ax, m in zip(axs, names):
        idx = np.array([k for k, c in enumerate(cases) if m in (c.get("metrics") or {})], int)
        vals = np.array([float(cases[k]["metrics"][m]) if cases[k]["metrics"][m] is not None
                         else np.nan for k in idx])
        ok = np.array([cases[k].get("pass") is not False for k in idx], bool)
        is_worst = np.array([str(cases[k].get("label")) in worst_set for k in idx], bool)
        if ok.any():
            ax.markers(idx[ok], vals[ok], "#2a7f3f", size=4, label="pass")
        if (~ok).any():
            ax.markers(idx[~ok], vals[~ok], "#c23b22", size=6, label="fail (unstable set)")
        if m == "spectral_radius":
            ax.hline(1.0, "#5b6472", 0.8)
        if is_worst.any():
            ax.markers(idx[is_worst], vals[is_worst], "#000000", size=10, filled=False,
                       label="worst")
        ax.ylabel = f"{ROBUSTNESS_PANELS.get(m, m)} ({METRIC_UNITS.get(m, '1')})"
        ax.ylabel_size = 8.0
        ax.legend_loc, ax.legend_size = "upper right", 7.0
    axs[-1].xlabel = "case (row of the table below)"
    axs[0].title = "Robustness stress sweep"
    return fig.svg(prefix)


#: Colours and markers of the torque-speed grid's point statuses.
ENVELOPE_STYLE = {"pass": ("#2a7f3f", "o", "pass"), "fail": ("#c23b22", "o", "fail"),
                  "unreachable": ("#8a8f98", "x", "unreachable (not simulated)")}


def envelope_point_text(p: Mapping) -> str:
    """The hover text (and table line) of a grid point of verify.json's ``envelope``."""
    head = (f"{p['torque_fraction']:g} x torque limit at {p['speed_fraction']:g} x base speed "
            f"({p['speed']:.4g} rad/s): {p['status']}")
    if p.get("region") and p["region"] != "unreachable":
        head += f", {p['region']}, {_num(p.get('torque')):.4g} N m"
    linear = envelope_linear_text(p.get("linear"))
    return (head + (f": {p['reason']}" if p.get("reason") else "")
            + (f" (tangent loop: {linear})" if linear else ""))


def envelope_linear_text(linear: Mapping | None) -> str:
    """A grid point's linear result (verify.json ``envelope.points[].linear``,
    :class:`toolbox.analysis.envelope_points.TangentLoop`) in one line: stable
    or not with the spectral radius, the worst per-axis gain and phase
    margins when computed, the multiloop disk margin and the phase it
    guarantees; empty without one."""
    if not linear:
        return ""
    if not linear.get("analysed"):
        return "not analysed (no linear loop)"

    def fmt(v: Any, spec: str) -> str:
        x = _num(v)
        return "inf" if x is None and v in ("inf", float("inf")) else (
            "-" if x is None else format(x, spec))

    text = (f"{'stable' if linear.get('stable') else 'UNSTABLE'}, spectral radius "
            f"{fmt(linear.get('spectral_radius'), '.4f')}")
    margins = linear.get("margins") or {}
    if margins:
        def worst(key):
            vals = [v for v in (_num(m.get(key)) for m in margins.values()) if v is not None]
            return min(vals) if vals else None
        text += (f"; axis GM {fmt(worst('gain_margin_db'), '.3g')} dB, "
                 f"PM {fmt(worst('phase_margin_deg'), '.3g')} deg")
    if linear.get("stable"):
        text += (f"; MIMO disk margin {fmt(linear.get('mimo_disk_margin'), '.3g')} "
                 f"(+-{fmt(linear.get('mimo_phase_margin_deg'), '.3g')} deg)")
    return text


def envelope_svg(env: Mapping, prefix: str = "env") -> str:
    """The operating envelope in the torque-speed plane (verify.json
    ``envelope``): the torque limit of both limits, the current limit alone
    and the voltage limit alone (MTPV) over speed, and the grid points
    coloured by status, each with its reason as hover text."""
    fig = Figure(7.2, 3.6)
    ax = fig.axes[0]
    c = env.get("curves") or {}
    curve = lambda k: np.array([np.nan if v is None else float(v)  # noqa: E731
                                for v in c.get(k, [])], float)
    w = curve("speed_rad_s")
    t_max = _num(env.get("torque_limit_nm")) or 1.0
    if w.size:
        ax.line(w, curve("torque_limit"), "#1f4e9c", width=2.0,
                label="torque limit (current and voltage)")
        ax.line(w, curve("current_limit"), "#7a5195", dash="5 3", width=1.0,
                label="current limit alone")
        ax.line(w, curve("voltage_limit"), "#ef8c1a", dash="2 2", width=1.0,
                label="voltage limit alone (MTPV)")
    base = _num(env.get("base_speed_rad_s"))
    for status, (color, shape, label) in ENVELOPE_STYLE.items():
        pts = [p for p in env.get("points", []) if p.get("status") == status]
        if not pts:
            continue
        # an unreachable point sits at its requested torque
        y = [(_num(p.get("torque")) if p.get("torque") is not None
              else p["torque_fraction"] * t_max) for p in pts]
        ax.markers([p["speed"] for p in pts], y, color, shape=shape,
                   size=7 if status == "fail" else 6, label=label,
                   tips=[envelope_point_text(p) for p in pts])
    ax.ylim = (-0.1 * t_max, 1.7 * t_max)  # the legend above the points
    ax.xlabel = "mechanical speed (rad/s)" + (f"; base speed {base:.4g} rad/s" if base else "")
    ax.ylabel = "torque (N m)"
    ax.title = "Operating envelope and torque-speed grid"
    ax.legend_loc, ax.legend_size = "upper right", 7.0
    return fig.svg(prefix)
