"""Robustness sweeps: margins and stability over thousands of parameter sets.

The plant parameters drift, the speed sensor lies and the computation delay
may be longer than designed; the controller (its laws and decoupling model
parameters) stays as designed. Each parameter set is evaluated with stacked
numpy arrays, not a Python loop per set:

* per-axis loop frequency responses ``L = K(z) b/(z - a) z^-d`` on a common
  grid (``K`` is evaluated once; ``a, b`` from each set's ``R, L``), giving
  gain, phase, stability (``min |1 + L|``) and balanced disk margins;
* closed-loop poles of the coupled dq loop (decoupling with measured speed
  ``w_m = g w + p Omega_offset``, paper 000 sect. 3 "robustness to speed
  error") at the speeds of the grid, from ``numpy.linalg.eigvals`` on stacked
  matrices (:func:`toolbox.analysis.margins.coupled_closed_loop`);
* static currents at the highest speed for the rated q reference, solving the
  stacked steady-state systems: without integrators a speed or flux error
  leaves a static error (paper 000 eq (14)-(17)), with integrators it does not.

Ranges default to R x0.5..x2, Ld and Lq x0.5..x2 (paper 001 sect. 4 uses 0.5x
and 2x inductance), flux x0.8..x1.2 (paper 001), speed-sensor gain 0.9..1.1
and offset +/-10 rad/s (paper 000), delay 1..2 periods. Sets are a Latin
hypercube (log-uniform for scale factors) plus the nominal point and all
corners of the box, so extreme combinations are always included.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from ..plant import max_electrical_speed
from ._laws import executed_laws
from ._sampling import DEFAULT_BOX, DEFAULT_RANGES, sample_parameters
from ._statespace import FreqResponse
from .margins import (AXES, axis_law, axis_margins, coupled_closed_loop,
                      grid_margins, json_ready, make_axis_loop, zoh_axis)

__all__ = ["DEFAULT_BOX", "DEFAULT_RANGES", "SweepResult", "sample_parameters", "robustness_sweep",
           "batch_axis_margins", "batch_loop_margins"]

#: Parameter sets per block of :func:`batch_axis_margins`.
BLOCK_ROWS = 64


def batch_axis_margins(K_fr: np.ndarray, z: np.ndarray, w: np.ndarray, R: np.ndarray,
                       L: np.ndarray, Ts: float, d: np.ndarray) -> dict[str, np.ndarray]:
    """Grid margins of ``L = K b/(z - a) z^-d`` for N plants at once.

    Parameters
    ----------
    K_fr : ndarray
        Controller response on the grid (Nw,).
    z, w : ndarray
        ``exp(j w Ts)`` and the frequencies (rad/s), (Nw,).
    R, L : ndarray
        Plant resistance (ohm) and inductance (H), (N,).
    Ts : float
        Sample time (s).
    d : ndarray
        Delay (periods), (N,).

    Returns
    -------
    dict
        ``gain_margin_db``, ``phase_margin_deg``, ``stability_margin``,
        ``disk_margin`` (N,) with linear interpolation between grid points
        (:func:`toolbox.analysis.margins.grid_margins`; the worst set is
        recomputed exactly afterwards).
    """
    # the loop depends on (R, L, d) only: the box corners of a sweep repeat those
    # triples (a tenth of the sets of the default sweep), so each is evaluated once,
    # grouped by delay; the rows are independent, the numbers the same
    keys, inverse = np.unique(np.column_stack([d, R, L]), axis=0, return_inverse=True)
    d_u, R_u, L_u = keys.T
    a, b = zoh_axis(R_u, L_u, Ts)
    delays, starts = np.unique(d_u, return_index=True)
    Kz = K_fr[None, :] * z[None, :] ** (-delays[:, None])
    parts = []
    for k, rows in enumerate(np.split(np.arange(d_u.size), starts[1:])):
        # blocks of sets: each temporary then stays in the cache (1.5x faster than
        # whole (N, Nw) arrays, the same numbers: the rows are independent)
        for block in np.array_split(rows, max(1, -(-rows.size // BLOCK_ROWS))):
            # the last grid point is the Nyquist frequency (robustness_sweep builds it so)
            parts.append(grid_margins(w, _loop_block(Kz[k], z.real, z.imag, a[block], b[block]),
                                      nyquist=True))
    return {k: np.concatenate([p[k] for p in parts])[inverse.reshape(-1)] for k in parts[0]}


def _loop_block(Kz: np.ndarray, zr: np.ndarray, qi: np.ndarray, a: np.ndarray,
                b: np.ndarray) -> np.ndarray:
    """``L = K z^-d b/(z - a)`` (n, Nw) for one delay (``Kz``, (Nw,)) and plants ``a, b`` (n,).

    ``b/(z - a) = b conj(z - a)/|z - a|^2`` in real arithmetic: numpy's complex
    division of (n, Nw) arrays cost 4x. The real factors come from one
    compiled pass (:func:`toolbox.analysis._grid_kernel.plant_factors`); the
    complex product stays numpy's, operand order kept (its fused multiply-add
    kernels make the order matter): the numbers of
    ``Kz * (qr - 1j qi) * (b/|q|^2)`` bit for bit.
    """
    from ._grid_kernel import plant_factors  # lazy: numba + JIT kernel, 211 modules

    L, scale = plant_factors(zr, qi, a, b)
    np.multiply(Kz, L, out=L)
    L *= scale
    return L


def batch_loop_margins(artifact, R: np.ndarray, Ld: np.ndarray, Lq: np.ndarray,
                       d: np.ndarray, n_grid: int) -> dict[str, dict[str, np.ndarray]]:
    """Grid margins of both axes' sampled executed loops for N plants at once.

    The grid is ``n_grid`` log-spaced frequencies from 1 rad/s to the Nyquist
    frequency (its last point exactly); each axis's error controller is that
    of its executed law (:func:`toolbox.analysis.margins.axis_law`). The
    robustness sweep and the campaign both call it.

    Parameters
    ----------
    artifact : ControllerArtifact
        The controller (its laws and sample time).
    R, Ld, Lq : ndarray
        Plant resistance (ohm) and inductances (H), (N,).
    d : ndarray
        Delay (periods), (N,).
    n_grid : int
        Number of grid frequencies.

    Returns
    -------
    dict
        ``{"d": ..., "q": ...}``, each the dict of :func:`batch_axis_margins`.
    """
    Ts = artifact.sample_time
    w = np.logspace(0, math.log10(math.pi / Ts), n_grid)
    w[-1] = math.pi / Ts
    z = np.exp(1j * w * Ts)
    margins = {}
    for name, L in (("d", Ld), ("q", Lq)):
        K_fr = FreqResponse(*axis_law(artifact.axes[name], True).error_controller())(z)[:, 0, 0]
        margins[name] = batch_axis_margins(K_fr, z, w, R, L, Ts, d)
    return margins


@dataclass(frozen=True)
class SweepResult:
    """Worst cases of a robustness sweep.

    Attributes
    ----------
    n_sets : int
        Parameter sets evaluated (nominal + corners + Latin hypercube).
    ranges : dict
        ``name -> [low, high, kind]``.
    speeds_rad_s : list
        Electrical speeds of the coupled-loop checks (rad/s).
    n_unstable : int
        Sets whose coupled closed loop is unstable at some speed.
    unstable_examples : list of dict
        Up to five unstable sets, in the order evaluated (nominal, corners,
        samples): parameters, ``spectral_radius`` (largest closed-loop pole
        modulus over the speeds) and ``speed_rad_s`` (the electrical speed
        where it occurs).
    worst_spectral_radius : float
        Largest closed-loop pole modulus over all sets and speeds.
    worst : dict
        Per axis and margin (``gain_margin_db``, ``phase_margin_deg``,
        ``stability_margin``, ``disk_margin``), ``{"value", "grid_value",
        "params"}``: the smallest single-axis margin (sampled loop with the
        set's R, L and delay; speed-independent) over the sets whose coupled
        loop is stable at every speed, recomputed exactly by
        :func:`~toolbox.analysis.margins.axis_margins` (``value``) next to the
        batch grid value; ``params`` are the set's parameters (factors,
        offset in rad/s mechanical, delay in periods).
    static_error : dict
        ``{"reference_A", "worst_A", "params"}``: the largest static current
        error (A, vector norm) at the highest speed for the reference
        ``(0, rated_current)`` over stable sets.
    nominal : dict
        Per axis grid margins of the nominal set.
    """

    n_sets: int
    ranges: dict
    speeds_rad_s: list
    n_unstable: int
    unstable_examples: list
    worst_spectral_radius: float
    worst: dict
    static_error: dict
    nominal: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready({f.name: getattr(self, f.name) for f in fields(self)})


def _spectral_radii(laws: dict, decoupling, Ts: float, d: int, R: np.ndarray, Ld: np.ndarray,
                    Lq: np.ndarray, omega: float, omega_meas: np.ndarray) -> np.ndarray:
    """Largest pole modulus of each set's coupled closed loop at one speed (N,).

    The state matrix depends on neither the flux (the back-EMF enters the
    constant term only) nor, at zero speed, the speed-sensor gain: the box
    corners repeat matrices, and each distinct one is analysed once (
    the eigenvalues of a matrix do not depend on the others in the stack).
    """
    _, first, inverse = np.unique(np.column_stack([R, Ld, Lq, omega_meas]), axis=0,
                                  return_index=True, return_inverse=True)
    loop = coupled_closed_loop(laws, decoupling, Ts, d, R=R[first], Ld=Ld[first],
                               Lq=Lq[first], omega=omega, omega_meas=omega_meas[first])
    return loop.spectral_radius()[inverse.reshape(-1)]


def _params_of(P: dict, i: int) -> dict:
    return {k: (int(v[i]) if v.dtype.kind == "i" else float(v[i])) for k, v in P.items()}


def robustness_sweep(artifact, motor, ranges: dict | None = None, n: int = 2000, *,
                     drive=None, n_speeds: int = 3, n_grid: int = 1200, seed: int = 0,
                     i_ref: tuple | None = None) -> SweepResult:
    """Worst margins and stability of a design over parameter drift.

    Parameters
    ----------
    artifact : ControllerArtifact
        The design (controller unchanged across sets).
    motor : Motor
        Nominal plant; set values are ``scale * nominal``.
    ranges : dict, optional
        Overrides of :data:`DEFAULT_RANGES` (same layout; a name mapped to
        None is dropped and held at its nominal value).
    n : int
        Latin-hypercube sets (plus nominal and 2^k corners).
    drive : Drive, optional
        Speed range (see :func:`toolbox.analysis.margins.mimo_disk_margins`).
    n_speeds : int
        Electrical speeds ``linspace(-w_max, w_max)`` for the coupled loop
        (1: zero speed only).
    n_grid : int
        Frequency points of the per-axis grid (1 rad/s .. Nyquist).
    seed : int
        Latin-hypercube seed (results are deterministic).
    i_ref : tuple, optional
        dq reference (A) for the static error; default ``(0, rated_current)``
        or ``(0, 10)``.

    Returns
    -------
    SweepResult
    """
    rng = dict(DEFAULT_RANGES)
    lo, hi, kind = rng["delay_samples"]  # default: the design's delay and one period more
    rng["delay_samples"] = (artifact.delay_samples + lo, artifact.delay_samples + hi, kind)
    for k, v in (ranges or {}).items():
        if k not in DEFAULT_RANGES:
            raise ValueError(f"ranges: unknown parameter {k!r}; expected one of {list(DEFAULT_RANGES)}")
        if v is None:
            rng.pop(k)
        else:
            rng[k] = (v[0], v[1], DEFAULT_RANGES[k][2])
    P = sample_parameters(rng, n, seed)
    N = len(next(iter(P.values())))
    one = np.ones(N)
    R = motor.R * P.get("R", one)
    Ld = motor.Ld * P.get("Ld", one)
    Lq = motor.Lq * P.get("Lq", one)
    flux = motor.flux * P.get("flux", one)
    g = P.get("speed_gain", one)
    off = P.get("speed_offset", 0 * one) * motor.pole_pairs
    d = P.get("delay_samples", np.full(N, artifact.delay_samples, int)).astype(int)
    Ts = artifact.sample_time

    # per-axis loops at zero speed (vectorised over sets)
    margins = batch_loop_margins(artifact, R, Ld, Lq, d, n_grid)

    # coupled closed loops at speed (vectorised per delay value)
    wmax = max_electrical_speed(motor, drive)
    speeds = np.linspace(-wmax, wmax, n_speeds) if (wmax > 0 and n_speeds > 1) else np.zeros(1)
    laws = executed_laws(artifact)
    rho = np.zeros(N)
    rho_speed = np.zeros(N)  # the speed of each set's largest pole modulus
    i_ref = i_ref or (0.0, motor.rated_current or 10.0)
    err = np.full(N, np.nan)
    for dv in np.unique(d):
        sel = np.nonzero(d == dv)[0]
        for om in speeds:
            r = _spectral_radii(laws, artifact.decoupling, Ts, int(dv), R[sel], Ld[sel],
                                Lq[sel], om, g[sel] * om + off[sel])
            rho_speed[sel] = np.where(r > rho[sel], om, rho_speed[sel])
            rho[sel] = np.maximum(rho[sel], r)
            if om == speeds[-1]:
                ok = r < 1 - 1e-9
                iss = np.full((sel.size, 2), np.nan)
                if ok.any():
                    sub = coupled_closed_loop(laws, artifact.decoupling, Ts, int(dv),
                                              R=R[sel][ok], Ld=Ld[sel][ok], Lq=Lq[sel][ok],
                                              omega=om, omega_meas=g[sel][ok] * om + off[sel][ok],
                                              flux=flux[sel][ok])
                    iss[ok] = sub.steady_currents(i_ref)
                err[sel] = np.linalg.norm(iss - np.asarray(i_ref), axis=1)
    stable = rho < 1 - 1e-9
    unstable = np.nonzero(~stable)[0]

    worst = {}
    for name, L in (("d", Ld), ("q", Lq)):
        worst[name] = {}
        exact = {}     # one set is often the worst of several margins: analysed once
        for key, mg in margins[name].items():
            vals = np.where(stable, np.abs(mg) if key != "phase_margin_deg" else mg, np.inf)
            if key == "gain_margin_db":
                vals = np.where(stable, mg, np.inf)
            i = int(np.argmin(vals))
            if i not in exact:
                exact[i] = axis_margins(make_axis_loop(artifact.axes[name], float(R[i]),
                                                       float(L[i]), Ts, int(d[i])), step=False)
            worst[name][key] = {"value": float(getattr(exact[i], key)), "grid_value": float(mg[i]),
                                "params": _params_of(P, i)}
    j = int(np.nanargmax(np.where(stable, err, -np.inf))) if stable.any() else 0
    return SweepResult(
        n_sets=N, ranges={k: list(v) for k, v in rng.items()},
        speeds_rad_s=[float(s) for s in speeds], n_unstable=int(unstable.size),
        unstable_examples=[dict(_params_of(P, int(i)), spectral_radius=float(rho[i]),
                                speed_rad_s=float(rho_speed[i])) for i in unstable[:5]],
        worst_spectral_radius=float(np.max(rho)), worst=worst,
        static_error={"reference_A": list(i_ref), "speed_rad_s": float(speeds[-1]),
                      "worst_A": float(err[j]), "params": _params_of(P, j)},
        nominal={ax: {k: float(v[0]) for k, v in margins[ax].items()} for ax in AXES})
