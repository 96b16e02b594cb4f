"""The drift a drive's current loop must survive, and the verdict on it.

Every design is judged on a parameter box (toolbox/ARCHITECTURE.md "Spec
file", "Robustness verdict"): the spec's ``[requirements] parameter_drift``
when it states one, else :data:`DRIVE_DRIFT`, the drift a real drive sees
between a cold start and a hot, saturated motor. The verdict runs the
machinery the analysis already has, nothing new: the robustness sweep
(:func:`toolbox.analysis.robustness_sweep`: the executed coupled sampled loop
with ZOH, the design's delay and the decoupling with the controller's own
parameters, at electrical speeds up to the maximum, with the speed-sensor
errors in the measured speed) for stability, and the multiloop disk margin
of that loop over the R, Ld, Lq corners (:func:`toolbox.analysis.mimo_over_box`).

Sources of the default box (datasheet values taken as the 20 degC,
low-current point; winding and magnets from -20 degC, a cold start, to
+150 degC, the limit of class F insulation and of high-temperature NdFeB
grades):

* R: copper's temperature coefficient ``alpha_Cu = 0.00393 /K`` at 20 degC
  (annealed copper, IEC 60028): ``1 + alpha_Cu (T - 20)`` gives x0.843 at
  -20 degC and x1.511 at +150 degC.
* Ld, Lq: x0.8..x1.1. +-10 % is the usual manufacturing tolerance printed on
  servo and traction datasheets; below that, magnetic saturation lowers the
  inductances at peak current (Lq of an interior PM machine the most:
  Morimoto, Sanada, Takeda, "Effects and compensation of magnetic saturation
  in flux-weakening controlled permanent magnet synchronous motor drives",
  IEEE Trans. Ind. Appl. 30(6), 1994), taken here as another -10 %: x0.8. A
  strongly saturating IPM loses more; state it with ``parameter_drift``.
* flux: NdFeB remanence falls by about 0.12 %/K (the reversible temperature
  coefficient of Br printed by magnet makers for sintered N grades, -0.11 to
  -0.12 %/K); the PM flux linkage follows Br: ``1 - 0.0012 (T - 20)`` gives
  x1.048 at -20 degC and x0.844 at +150 degC.
* speed sensor: gain 0.98..1.02 and offset +-1 % of the maximum speed
  (mechanical): an engineering estimate of a resolver-to-digital or encoder
  speed estimate (clock and filter scale errors, estimator bias), far inside
  paper 000's +-10 % robustness test. Estimates, not a standard: say so.
* delay: the design's own (the executed law's ``delay_samples``); a spec that
  fears one period more states it by designing with it.
* speeds: 9 electrical speeds from -max to +max
  (:func:`toolbox.plant.max_electrical_speed`: ``drive.max_speed``, else the
  rated speed, else the back-EMF limit).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..artifact import json_ready
from ..plant import max_electrical_speed
from ._sampling import DEFAULT_RANGES
from ._mimo import mimo_over_box
from .robustness import robustness_sweep

__all__ = ["ALPHA_CU", "FLUX_TEMPERATURE_COEFF", "WINDING_TEMPERATURE_C", "DRIVE_DRIFT",
           "SPEED_OFFSET_FRACTION", "DEFAULT_DRIFT_SETS", "DRIFT_SETS", "DRIFT_SPEEDS",
           "DriftVerdict", "drift_ranges", "drift_verdict", "box_text"]

#: Copper's resistance temperature coefficient at 20 degC (1/K), IEC 60028.
ALPHA_CU = 0.00393
#: Reversible temperature coefficient of NdFeB remanence (1/K), magnet makers' N grades.
FLUX_TEMPERATURE_COEFF = -0.0012
#: Winding and magnet temperatures (degC): datasheet value, cold start, hot limit.
WINDING_TEMPERATURE_C = (20.0, -20.0, 150.0)


def _thermal(coeff: float) -> tuple[float, float]:
    ref, cold, hot = WINDING_TEMPERATURE_C
    a, b = 1.0 + coeff * (cold - ref), 1.0 + coeff * (hot - ref)
    return (round(min(a, b), 3), round(max(a, b), 3))


#: The default drift box (factors on the nominal value), module docstring:
#: R x0.843..x1.511, Ld and Lq x0.8..x1.1, flux x0.844..x1.048, speed gain 0.98..1.02.
DRIVE_DRIFT: dict[str, tuple[float, float]] = {
    "R": _thermal(ALPHA_CU),
    "Ld": (0.8, 1.1),
    "Lq": (0.8, 1.1),
    "flux": _thermal(FLUX_TEMPERATURE_COEFF),
    "speed_gain": (0.98, 1.02),
}
#: Speed-sensor offset of the default box: +- this fraction of the maximum speed.
SPEED_OFFSET_FRACTION = 0.01
#: Latin-hypercube sets of the default box (plus the nominal point and its 2^6
#: corners, where the drifts of the gallery and the corpus first lose stability) ...
#: 500: the verdict's eigenvalues are most of its cost in every ``cct design``.
DEFAULT_DRIFT_SETS = 500
#: ... and of a spec's ``parameter_drift`` box (plus nominal and 2^k corners, k <= 4) ...
DRIFT_SETS = 200
#: ... each at this many electrical speeds, -max..max (0 included).
DRIFT_SPEEDS = 9


def drift_ranges(motor, drive, parameter_drift: dict | None = None) -> tuple[str, dict]:
    """``(source, ranges)``: the box a design is judged on, as sweep ranges.

    ``source`` is ``"parameter_drift"`` (the spec's box: its parameters, the
    sweep's others held nominal) or ``"default"`` (:data:`DRIVE_DRIFT` and a
    speed offset of +-:data:`SPEED_OFFSET_FRACTION` of the maximum mechanical
    speed). ``ranges`` maps every name of
    :data:`toolbox.analysis.DEFAULT_RANGES` to ``[low, high]`` or None (held
    nominal; the delay is always the design's).

    Parameters
    ----------
    motor : Motor
        Nominal plant (pole pairs for the mechanical speed offset).
    drive : Drive
        Speed range (:func:`toolbox.plant.max_electrical_speed`).
    parameter_drift : dict, optional
        The spec's ``[requirements] parameter_drift``.
    """
    if parameter_drift:
        return "parameter_drift", {name: (list(parameter_drift[name])
                                          if name in parameter_drift else None)
                                   for name in DEFAULT_RANGES}
    ranges = {name: (list(DRIVE_DRIFT[name]) if name in DRIVE_DRIFT else None)
              for name in DEFAULT_RANGES}
    offset = SPEED_OFFSET_FRACTION * max_electrical_speed(motor, drive) / motor.pole_pairs
    ranges["speed_offset"] = [-offset, offset] if offset > 0 else None
    return "default", ranges


def box_text(source: str, ranges: dict, max_speed_rad_s: float) -> str:
    """One-line description of a box, e.g. ``default drift box: R x0.843..1.511, ...``."""
    parts = []
    r = {k: v for k, v in ranges.items() if v is not None}
    if "R" in r:
        parts.append(f"R x{r['R'][0]:.4g}..{r['R'][1]:.4g}")
    if "Ld" in r and "Lq" in r and list(r["Ld"]) == list(r["Lq"]):
        parts.append(f"Ld/Lq x{r['Ld'][0]:.4g}..{r['Ld'][1]:.4g}")
    else:
        parts += [f"{k} x{r[k][0]:.4g}..{r[k][1]:.4g}" for k in ("Ld", "Lq") if k in r]
    if "flux" in r:
        parts.append(f"flux x{r['flux'][0]:.4g}..{r['flux'][1]:.4g}")
    if "speed_gain" in r:
        lo, hi = r["speed_gain"]
        gain = max(1 - lo, hi - 1) * 100
        parts.append(f"speed sensor +-{gain:.3g} %")
    if "speed_offset" in r:
        parts.append(f"+-{SPEED_OFFSET_FRACTION * 100:.3g} % offset"
                     if source == "default" else
                     f"offset +-{max(abs(v) for v in r['speed_offset']):.3g} rad/s")
    parts.append(f"0..{max_speed_rad_s:.4g} rad/s electrical")
    name = "default drift box" if source == "default" else "parameter_drift box"
    return f"{name}: " + ", ".join(parts)


@dataclass(frozen=True)
class DriftVerdict:
    """Stability and worst multiloop disk margin of a design over its drift box.

    Attributes
    ----------
    source : str
        ``"default"`` (:data:`DRIVE_DRIFT`) or ``"parameter_drift"`` (the spec's).
    box : dict
        ``name -> [low, high]`` of the evaluated parameters (factors;
        ``speed_offset`` in mechanical rad/s).
    box_text : str
        The same in one line (:func:`box_text`).
    max_speed_rad_s : float
        Highest electrical speed evaluated (rad/s).
    delay_samples : int
        The computation delay of every set (the design's).
    n_sets, n_unstable : int
        Parameter sets evaluated (nominal, corners, Latin hypercube) and those
        whose coupled sampled loop is unstable at some speed.
    first_unstable : dict or None
        The first unstable set in that order: its factors, speed-sensor
        offset, ``speed_rad_s`` (electrical speed of its largest pole
        modulus) and ``spectral_radius``.
    worst_spectral_radius : float
    worst_disk_margin : float
        Smallest balanced multiloop disk margin over the nominal plant and the
        corners of the R, Ld, Lq box at 9 speeds 0..max (0: unstable).
    worst_disk_margin_at : dict
        Its plant factors and ``speed_rad_s``.
    """

    source: str
    box: dict
    box_text: str
    max_speed_rad_s: float
    delay_samples: int
    n_sets: int
    n_unstable: int
    first_unstable: dict | None
    worst_spectral_radius: float
    worst_disk_margin: float
    worst_disk_margin_at: dict

    @property
    def passed(self) -> bool:
        """No evaluated set unstable, and no corner of the multiloop disk-margin
        check either (a zero margin is an unstable (plant, speed) pair)."""
        return self.n_unstable == 0 and self.worst_disk_margin > 0.0

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready(asdict(self))

    def summary(self) -> str:
        """The CLI's robustness line."""
        return (f"robustness ({self.box_text}): worst multiloop disk margin "
                f"{self.worst_disk_margin:.2f}, unstable {self.n_unstable} / {self.n_sets} sets")

    def failure(self) -> str | None:
        """Why the design fails on the box, naming the first failing set (None: it passes)."""
        if self.first_unstable is None:
            if self.passed:
                return None
            at = self.worst_disk_margin_at
            where = ", ".join(f"{k} x{at[k]:.3g}" for k in ("R", "Ld", "Lq") if k in at)
            return (f"the coupled sampled loop is unstable on the corner {where} of the "
                    f"{self.box_text.split(':')[0]} at {at.get('speed_rad_s', 0.0):.4g} rad/s "
                    "electrical with an exact speed sensor (multiloop disk margin 0)")
        f = self.first_unstable
        where = ", ".join(f"{k} x{f[k]:.3g}" for k in ("R", "Ld", "Lq", "flux", "speed_gain")
                          if k in f)
        if "speed_offset" in f:
            where += f", speed offset {f['speed_offset']:+.3g} rad/s"
        return (f"the coupled sampled loop is unstable for {self.n_unstable} of {self.n_sets} "
                f"parameter sets of the {self.box_text.split(':')[0]} at electrical speeds "
                f"up to {self.max_speed_rad_s:.4g} rad/s; first: {where} at "
                f"{f['speed_rad_s']:.4g} rad/s electrical (largest closed-loop pole "
                f"{f['spectral_radius']:.4g})")


def drift_verdict(artifact, motor, drive, parameter_drift: dict | None = None, *,
                  seed: int = 0) -> DriftVerdict:
    """Judge ``artifact`` on its drift box (module docstring).

    Parameters
    ----------
    artifact : ControllerArtifact
    motor : Motor
        Nominal plant.
    drive : Drive
        Speed range (:func:`toolbox.plant.max_electrical_speed`).
    parameter_drift : dict, optional
        The spec's ``[requirements] parameter_drift``; empty or None: :data:`DRIVE_DRIFT`.
    seed : int
        Latin-hypercube seed.

    Returns
    -------
    DriftVerdict
    """
    source, ranges = drift_ranges(motor, drive, parameter_drift)
    n = DEFAULT_DRIFT_SETS if source == "default" else DRIFT_SETS
    # the verdict reads stability only: a coarse grid for the sweep's per-axis margins
    sweep = robustness_sweep(artifact, motor, ranges, n=n, drive=drive, n_speeds=DRIFT_SPEEDS,
                             n_grid=100, seed=seed)
    wmax = max(abs(s) for s in sweep.speeds_rad_s)
    box = {k: tuple(ranges[k]) if ranges.get(k) else (1.0, 1.0) for k in ("R", "Ld", "Lq")}
    mimo = mimo_over_box(artifact, motor, drive, box=box, n_speeds=DRIFT_SPEEDS,
                         max_speed_rad_s=wmax)
    first = None
    if sweep.unstable_examples:
        ex = sweep.unstable_examples[0]
        first = {k: v for k, v in ex.items() if k != "delay_samples"}
    worst = float(mimo.worst_disk_margin)
    return DriftVerdict(
        source=source, box={k: [float(x) for x in v] for k, v in ranges.items() if v is not None},
        box_text=box_text(source, ranges, wmax), max_speed_rad_s=float(wmax),
        delay_samples=int(artifact.delay_samples), n_sets=sweep.n_sets,
        n_unstable=sweep.n_unstable, first_unstable=first,
        worst_spectral_radius=float(sweep.worst_spectral_radius),
        worst_disk_margin=worst if math.isfinite(worst) else 0.0,
        worst_disk_margin_at={**mimo.worst_params, "speed_rad_s": mimo.worst_speed_rad_s})
