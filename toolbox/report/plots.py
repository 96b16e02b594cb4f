"""Report figures as deterministic, self-contained SVG strings.

All figures use matplotlib's object API (no pyplot state) with
``svg.fonttype = "path"`` (glyphs as paths: no font needed by the viewer or by
typst), a fixed ``svg.hashsalt`` and no date metadata, so equal inputs give
byte-identical SVG. The XML prologue, DOCTYPE and metadata block are removed
(the SVG is inlined in HTML and holds no external reference), and element ids
are prefixed per figure so several SVGs can share one HTML document.

The loop analysed is the sampled one the controller runs: ``L(z) = K_d(z)
G_zoh(z) z^{-n_d}`` per axis, with ``G(s) = 1/(R + s L)`` (paper 003 eq
(33)-(34), :func:`toolbox.plant.axis_plants`) sampled with a zero-order hold and
``n_d`` periods of computation delay. Frequencies are shown up to the Nyquist
frequency ``pi/T_s`` (rad/s). Figures never contain user-supplied text.
"""

from __future__ import annotations

import io
import math
import re
from typing import Any, Mapping, Sequence

import control
import matplotlib
import numpy as np
from matplotlib.figure import Figure

__all__ = ["loop_data", "figures", "equation_svg", "scenario_svg", "robustness_svg",
           "traces_dict", "svg_from_figure", "crossings"]

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


def svg_from_figure(fig: Figure, prefix: str, tight: bool = False) -> str:
    """Serialise ``fig`` to a cleaned, deterministic SVG string.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    prefix : str
        Prefix for every element id (unique per figure in a document).
    tight : bool
        Crop to the drawn content (used for equations).
    """
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


def _figure(width_in: float, height_in: float) -> Figure:
    with matplotlib.rc_context(RC):
        return Figure(figsize=(width_in, height_in), layout="constrained")


# ------------------------------------------------------------------ loop data

def _delay(n: int, dt: float) -> control.TransferFunction:
    return control.tf([1.0], [1.0] + [0.0] * n, dt)


def loop_data(artifact, motor, n_freq: int = 500) -> dict:
    """Sampled loop of each axis and its closed-loop functions on a frequency grid.

    Parameters
    ----------
    artifact : ControllerArtifact
        Supplies ``K_d(z)`` per axis, the sample time (s) and delay (periods).
    motor : Motor
        Supplies ``G(s) = 1/(R + s L_{d,q})`` (A/V).
    n_freq : int
        Number of grid points, log-spaced from 1 rad/s (or lower, to include
        a decade below the crossover) to the Nyquist frequency.

    Returns
    -------
    dict
        ``{axis: {"omega": rad/s, "L", "S", "T", "KS": complex arrays,
        "closed": closed-loop T(z) (python-control), "dt": s}}``.
    """
    from ..plant import axis_plants

    dt = float(artifact.sample_time)
    plants = axis_plants(motor)
    w_nyq = math.pi / dt
    out = {}
    for name in ("d", "q"):
        K = control.ss(artifact.axes[name].to_statespace(discrete=True))
        G = control.sample_system(control.ss(plants[name]), dt, method="zoh")
        L = control.series(K, G, control.ss(_delay(artifact.delay_samples, dt)))
        omega = np.logspace(0.0, math.log10(w_nyq * 0.999), n_freq)
        z = np.exp(1j * omega * dt)
        Lw = np.asarray(L(z), complex).reshape(-1)
        Kw = np.asarray(K(z), complex).reshape(-1)
        S = 1.0 / (1.0 + Lw)
        out[name] = {"omega": omega, "L": Lw, "S": S, "T": Lw * S, "KS": Kw * S,
                     "closed": control.feedback(L, 1), "dt": dt}
    return out


def crossings(omega: np.ndarray, L: np.ndarray) -> dict:
    """Margins read off a sampled frequency response (for figure markers).

    Returns
    -------
    dict
        ``pm_deg``/``w_pm`` at the first |L| = 1 crossing and ``gm_db``/``w_gm``
        at the first crossing of the negative real axis (``None`` if absent).
        Linear interpolation between grid points (log frequency).
    """
    out: dict[str, float | None] = {"pm_deg": None, "w_pm": None, "gm_db": None, "w_gm": None}
    mag = np.abs(L)
    idx = np.nonzero((mag[:-1] >= 1.0) & (mag[1:] < 1.0))[0]
    if idx.size:
        k = idx[0]
        f = (math.log(mag[k])) / (math.log(mag[k]) - math.log(mag[k + 1]))
        w = math.exp(math.log(omega[k]) + f * (math.log(omega[k + 1]) - math.log(omega[k])))
        ph = np.degrees(np.angle(L[k] + f * (L[k + 1] - L[k])))
        out["pm_deg"], out["w_pm"] = float(ph % 360.0 - 180.0), w
    im = L.imag
    idx = np.nonzero((np.sign(im[:-1]) != np.sign(im[1:])) & (L.real[:-1] < 0))[0]
    if idx.size:
        k = idx[0]
        f = im[k] / (im[k] - im[k + 1])
        re_ = L.real[k] + f * (L.real[k + 1] - L.real[k])
        if re_ < 0:
            w = math.exp(math.log(omega[k]) + f * (math.log(omega[k + 1]) - math.log(omega[k])))
            out["gm_db"], out["w_gm"] = float(-20 * math.log10(-re_)), w
    return out


# -------------------------------------------------------------------- figures

def bode_svg(loops: dict, prefix: str = "bode") -> str:
    """Bode diagram of ``L`` per axis, with the margins read off the curve marked."""
    fig = _figure(7.2, 4.6)
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    lines: list[tuple[str, str]] = []
    for name, lp in loops.items():
        w, L = lp["omega"], lp["L"]
        c = AXIS_COLORS[name]
        ax_m.semilogx(w, 20 * np.log10(np.abs(L)), color=c, label=f"{name} axis")
        phase = np.degrees(np.unwrap(np.angle(L)))
        phase -= 360.0 * round(float(phase[0]) / 360.0 + 0.5) if phase[0] > 0 else 0.0
        ax_p.semilogx(w, phase, color=c, label=f"{name} axis")
        cr = crossings(w, L)
        lines.append((c, f"{name} axis: " + (f"PM {cr['pm_deg']:.1f} deg at {cr['w_pm']:.3g} rad/s"
                                            if cr["w_pm"] else "no gain crossover")
                      + ("; " + f"GM {cr['gm_db']:.1f} dB at {cr['w_gm']:.3g} rad/s"
                         if cr["w_gm"] else "; no phase crossover")))
        if cr["w_pm"]:
            ax_m.plot([cr["w_pm"]], [0.0], "o", color=c, ms=5)
            ph_at = np.interp(math.log(cr["w_pm"]), np.log(w), phase)
            ax_p.vlines(cr["w_pm"], -180.0, ph_at, color=c, lw=2.2, alpha=0.7)
        if cr["w_gm"]:
            ax_m.vlines(cr["w_gm"], -cr["gm_db"], 0.0, color=c, lw=2.2, alpha=0.7)
    for k, (c, text) in enumerate(lines):
        ax_m.text(0.02, 0.05 + 0.11 * (len(lines) - 1 - k), text, transform=ax_m.transAxes,
                  color=c, fontsize=8, bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1})
    ax_m.axhline(0.0, color="k", lw=0.8)
    ax_p.axhline(-180.0, color="k", lw=0.8)
    ax_m.set_ylabel("|L| (dB)")
    ax_p.set_ylabel("phase of L (deg)")
    ax_p.set_xlabel("frequency (rad/s)")
    ax_m.legend(loc="upper right")
    ax_m.set_title("Open loop L = K G (sampled, ZOH and computation delay)")
    return svg_from_figure(fig, prefix)


def nyquist_svg(loops: dict, prefix: str = "nyq") -> str:
    """Nyquist plot of ``L`` near the critical point, with the ``1/max|S|`` circle."""
    fig = _figure(5.6, 4.8)
    ax = fig.subplots()
    th = np.linspace(0, 2 * math.pi, 361)
    for name, lp in loops.items():
        L, c = lp["L"], AXIS_COLORS[name]
        ax.plot(L.real, L.imag, color=c, label=f"{name} axis (w > 0)")
        ax.plot(L.real, -L.imag, color=c, ls="--", lw=0.9)
        r = 1.0 / float(np.max(np.abs(lp["S"])))
        ax.plot(-1 + r * np.cos(th), r * np.sin(th), color=c, lw=0.8, ls=":",
                label=f"{name}: 1/max|S| = {r:.2f}")
    ax.plot([-1], [0], "k+", ms=12, mew=2)
    ax.set_xlim(-3.0, 1.5)
    ax.set_ylim(-2.5, 2.5)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("Re L (1)")
    ax.set_ylabel("Im L (1)")
    ax.set_title("Nyquist plot (zoom on the critical point -1)")
    ax.legend(loc="lower right")
    return svg_from_figure(fig, prefix)


def _weight_response(W: Any, omega: np.ndarray) -> np.ndarray | None:
    s = 1j * omega
    if W is None:
        return None
    if isinstance(W, Mapping):
        num = np.atleast_1d(np.asarray(W["num"], float))
        den = np.atleast_1d(np.asarray(W["den"], float))
        return np.polyval(num, s) / np.polyval(den, s)
    if isinstance(W, (control.TransferFunction, control.StateSpace)):
        return np.asarray(W(s), complex).reshape(-1)
    return np.full(omega.shape, complex(float(W)))


def sensitivity_svg(loops: dict, weights: dict | None, prefix: str = "sens") -> str:
    """|S|, |KS|, |T| per axis, with ``gamma/|W_i|`` bounds when weights are given."""
    fig = _figure(7.2, 6.4)
    axs = fig.subplots(3, 1, sharex=True)
    keys = (("S", "w1", "|S| (dB)", "sensitivity S = 1/(1+L)"),
            ("KS", "w2", "|KS| (dB, V/A)", "control sensitivity KS"),
            ("T", "w3", "|T| (dB)", "complementary sensitivity T = L/(1+L)"))
    for ax, (fn, wkey, ylabel, title) in zip(axs, keys):
        for name, lp in loops.items():
            c = AXIS_COLORS[name]
            ax.semilogx(lp["omega"], 20 * np.log10(np.abs(lp[fn])), color=c, label=f"{name} axis")
            wt = (weights or {}).get(name) or {}
            resp = _weight_response(wt.get(wkey), lp["omega"])
            if resp is not None:
                gamma = float(wt.get("gamma", 1.0))
                ax.semilogx(lp["omega"], 20 * np.log10(gamma / np.abs(resp)), color=c, ls="--",
                            lw=1.0, label=f"{name}: gamma/|{wkey.upper()}|")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=9)
        ax.legend(loc="best", ncol=2)
    axs[-1].set_xlabel("frequency (rad/s)")
    return svg_from_figure(fig, prefix)


def _step(closed: control.StateSpace, dt: float, n_max: int = 20000) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n_max) * dt
    y = np.asarray(control.step_response(closed, T=t).outputs).reshape(-1)
    final = y[-1]
    band = 0.02 * max(abs(final), 1e-12)
    outside = np.nonzero(np.abs(y - final) > band)[0]
    k_settle = int(outside[-1]) + 1 if outside.size else 1
    n = int(min(n_max, max(40, 3 * k_settle)))
    return t[:n], y[:n]


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


def step_svg(loops: dict, traces: Sequence[dict] | None = None, prefix: str = "step") -> str:
    """Linear unit-step response of the sampled closed loop T(z) per axis.

    Simulated step responses (verification traces, normalised by the
    reference) are overlaid, dashed, when given.
    """
    fig = _figure(7.2, 3.4)
    ax = fig.subplots()
    t_end = 0.0
    for name, lp in loops.items():
        t, y = _step(lp["closed"], lp["dt"])
        t_end = max(t_end, float(t[-1]))
        ax.step(t * 1e3, y, where="post", color=AXIS_COLORS[name], label=f"{name} axis, linear")
    for axis, k, t, y in _simulated_steps(traces):
        keep = t <= t_end
        ax.plot(t[keep] * 1e3, y[keep], color=AXIS_COLORS[axis], ls="--", lw=1.0,
                label=f"{axis} axis, simulated (scenario {k})")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhspan(0.95, 1.05, color="0.85", alpha=0.5, lw=0, label="+/- 5 % band")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("current / reference (A/A)")
    ax.set_title("Linear step response of the sampled loop (unit reference step)")
    ax.legend(loc="lower right")
    return svg_from_figure(fig, prefix)


def pzmap_svg(loops: dict, prefix: str = "pz") -> str:
    """Closed-loop poles (x) and zeros (o) of T(z) per axis, with the unit circle."""
    fig = _figure(5.6, 5.0)
    ax = fig.subplots()
    th = np.linspace(0, 2 * math.pi, 361)
    ax.plot(np.cos(th), np.sin(th), color="0.4", lw=0.8)
    for name, lp in loops.items():
        c = AXIS_COLORS[name]
        p = control.poles(lp["closed"])
        z = control.zeros(lp["closed"])
        ax.plot(p.real, p.imag, "x", color=c, ms=8, mew=1.6, label=f"{name} poles")
        if z.size:
            ax.plot(z.real, z.imag, "o", color=c, mfc="none", ms=8, label=f"{name} zeros")
    ax.set_xlim(-1.2, 1.2)
    ax.set_ylim(-1.2, 1.2)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("Re z (1)")
    ax.set_ylabel("Im z (1)")
    ax.set_title("Closed-loop pole-zero map (z-plane)")
    ax.legend(loc="lower left", fontsize=7)
    return svg_from_figure(fig, prefix)


def figures(loops: dict, weights: dict | None = None,
            traces: Sequence[dict] | None = None) -> list[dict]:
    """The loop figures of a report: ``[{"id", "title", "caption", "svg"}]``.

    ``traces`` are the verification scenarios' traces (``traces_dict`` form,
    ``None`` entries allowed), in scenario order; single reference steps are
    overlaid on the linear step response.
    """
    sim = _simulated_steps(traces)
    has_w = bool(weights) and any((weights or {}).get(a) for a in ("d", "q"))
    return [
        {"id": "bode", "title": "Bode diagram of the loop",
         "caption": "L = K G per axis (sampled loop with ZOH and computation delay, up to the "
                    "Nyquist frequency). Dots: gain crossover; bars: phase and gain margins "
                    "read off the plotted curves.",
         "svg": bode_svg(loops)},
        {"id": "nyquist", "title": "Nyquist plot",
         "caption": "Solid: positive frequencies; dashed: mirror image. Dotted circles around "
                    "-1 have radius 1/max|S| (the stability margin).",
         "svg": nyquist_svg(loops)},
        {"id": "sensitivity", "title": "Closed-loop functions",
         "caption": ("Dashed: bounds gamma/|W_i| from the H-infinity weights." if has_w else
                     "Weight bounds: not computed (no H-infinity weights given)."),
         "svg": sensitivity_svg(loops, weights)},
        {"id": "step", "title": "Step response (linear)",
         "caption": "Unit step of the sampled linear closed loop T(z) = L/(1+L)"
                    + ("; dashed: simulated responses of the verification scenarios "
                       "(numbered as in the verification section), divided by the reference."
                       if sim else "; simulated step responses: not computed."),
         "svg": step_svg(loops, traces)},
        {"id": "pzmap", "title": "Pole-zero map",
         "caption": "Closed-loop poles and zeros of T(z); all poles inside the unit circle "
                    "means the sampled loop is stable.",
         "svg": pzmap_svg(loops)},
    ]


def equation_svg(tex: str, prefix: str | None = None) -> str | None:
    """Render a LaTeX equation with matplotlib mathtext; ``None`` if unsupported."""
    prefix = prefix or "eq" + format(abs(hash_text(tex)) % 10**8, "08d")
    fig = _figure(9.0, 0.6)
    fig.set_layout_engine(None)
    fig.text(0.01, 0.5, f"${tex}$", fontsize=17, va="center")
    try:
        return svg_from_figure(fig, prefix, tight=True)
    except ValueError:  # mathtext parse error
        return None


def hash_text(text: str) -> int:
    """A stable (not salted per process) hash for element-id prefixes."""
    import hashlib

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
    fig = _figure(7.2, 4.8 if has_v else 3.0)
    axs = fig.subplots(2 if has_v else 1, 1, sharex=True, squeeze=False)[:, 0]
    t = traces["t"] * 1e3
    for key, c, ls in (("id", AXIS_COLORS["d"], "-"), ("iq", AXIS_COLORS["q"], "-"),
                       ("id_ref", AXIS_COLORS["d"], ":"), ("iq_ref", AXIS_COLORS["q"], ":")):
        if key in traces:
            axs[0].plot(t, traces[key], color=c, ls=ls, label=key.replace("_ref", " reference"))
    axs[0].set_ylabel("current (A)")
    axs[0].legend(loc="best", ncol=2)
    if has_v:
        for key, c in (("vd", AXIS_COLORS["d"]), ("vq", AXIS_COLORS["q"])):
            if key in traces:
                axs[1].plot(t, traces[key], color=c, label=key)
        axs[1].set_ylabel("voltage (V)")
        axs[1].legend(loc="best")
    axs[-1].set_xlabel("time (ms)")
    return svg_from_figure(fig, prefix)


def robustness_svg(cases: Sequence[Mapping], worst: Sequence[str], prefix: str = "rob") -> str:
    """Metric values over the sweep cases; failing cases red, worst cases ringed."""
    names: list[str] = []
    for c in cases:
        for m in (c.get("metrics") or {}):
            if m not in names:
                names.append(m)
    names = names[:3] or ["(none)"]
    fig = _figure(7.2, 1.2 + 1.9 * len(names))
    axs = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    idx = np.arange(len(cases))
    ok = np.array([c.get("pass") is not False for c in cases])
    is_worst = np.array([str(c.get("label")) in set(worst) for c in cases])
    for ax, m in zip(axs, names):
        vals = np.array([float((c.get("metrics") or {}).get(m, np.nan)) for c in cases])
        ax.plot(idx[ok], vals[ok], "o", color="#2a7f3f", ms=4, label="pass")
        if (~ok).any():
            ax.plot(idx[~ok], vals[~ok], "o", color="#c23b22", ms=4, label="fail")
        if is_worst.any():
            ax.plot(idx[is_worst], vals[is_worst], "o", mfc="none", mec="k", ms=10, label="worst")
        ax.set_ylabel(f"{m} ({METRIC_UNITS.get(m, '1')})", fontsize=8)
        ax.legend(loc="best", fontsize=7)
    axs[-1].set_xlabel("sweep case (index in the sweep)")
    axs[0].set_title("Robustness sweep")
    return svg_from_figure(fig, prefix)
