"""The designed controller's linear loop at each operating point of the envelope.

One controller covers the torque-speed envelope (toolbox/ARCHITECTURE.md
"Operating envelope", "One controller, proved per point"): a saturated motor's
law is designed at the nominal incremental inductances (the rated MTPA point,
:meth:`toolbox.spec.MagneticModel.nominal`) while the plant's incremental
inductances vary with the current, and the dq coupling with the speed. This
module proves the one controller at each operating point instead of
scheduling it: the **executed** sampled loop (the same model as the nominal
analyses: ZOH of the plant at the point's electrical speed, the computation
delay line, the law's decoupling with its own model parameters and the
measured speed, the voltage placement ``Gamma R(eps)``; :mod:`._coupled`,
:mod:`._mimo`) closed around the **tangent plant** at ``(i_d, i_q, omega)``::

    L di/dt = dv - R di - omega J L di,   L = L_inc(i_d, i_q)   (cross term kept)

(:func:`toolbox.plant.incremental_dq_matrices`). Linearising the law is the
law itself: its decoupling ``W(omega_meas) i`` and back-EMF term are affine
in the current with the controller's constant parameters. Per point:

* ``spectral_radius`` of the coupled closed loop (:func:`coupled_state_matrix`)
  and ``stable`` (``< 1 - 1e-9``, the threshold of every other verdict);
* ``margins`` - the per-axis margins of the executed sampled axis loops on the
  tangent axis plants ``1/(R + s L_inc,dd)``, ``1/(R + s L_inc,qq)`` (those
  of :func:`toolbox.plant.at_operating_point`; :func:`make_axis_loop`,
  :func:`axis_margins`, as :func:`compute_margins` assembles them): the
  numbers the spec's margin requirements judge at the design point, judged
  here at every point by the same :meth:`Requirements.check_margins`;
* ``mimo_disk_margin`` - the balanced multiloop input disk margin of the
  coupled loop at the point's speed on the tangent plant (the quantity of
  ``mimo_at_speed``, :func:`mimo_disk_margins`), reported, not judged (no
  requirement names it).

A point fails when its tangent loop is unstable or a margin requirement fails
there; the reason says which. The predictive switching law (``fcs_mpc``) has
no linear loop: its points are not analysed (the simulation judges them).
Small-signal only: what the voltage and current limits do to a large step is
the grid's simulation's to show.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterable

import numpy as np

from ..artifact import json_ready
from ..plant import incremental_dq_matrices
from ..spec import REQUIREMENT_KEYS
from ._axis import axis_margins, compute_margins, make_axis_loop
from ._coupled import coupled_state_matrix, placement_error, rotation
from ._laws import executed_laws
from ._mimo import _controllers, _grid_point, _loop_response, inv_2x2, mu_upper_2x2
from ._siso import disk_variations, log_grid
from ._statespace import zoh_2x2
from .executed import INFORMATIONAL_METHODS

__all__ = ["TangentLoop", "tangent_loops", "STABLE_RADIUS", "MIMO_GRID"]

#: A discrete closed loop is stable when its spectral radius is below this (the
#: threshold of ``default.stable``, the drift verdict and the MIMO margins).
STABLE_RADIUS = 1.0 - 1e-9
#: Frequency points of each point's multiloop disk margin (log grid 1e-2 rad/s
#: to Nyquist), as :func:`toolbox.analysis.mimo_disk_margins` uses.
MIMO_GRID = 1500
#: Frequency points of the per-axis margins at a saturated motor's tangent points:
#: the crossings and peaks are refined off the grid (:func:`frequency_margins`), so
#: the grid only has to bracket them; on paper 000, 001 and 003's laws at 0.5, 1
#: and 3 x the nominal inductance 600 points gave the 6000-point numbers to 4e-13
#: (relative) at a third to a tenth of the cost.
AXIS_GRID = 1000
#: The margins reported per axis (a subset of the MARGINS keys, each judged by
#: a requirement when the spec names one).
POINT_MARGIN_KEYS = ("gain_margin_db", "phase_margin_deg", "disk_margin",
                     "stability_margin", "sensitivity_peak", "bandwidth_rad_s",
                     "static_error")


@dataclass(frozen=True)
class TangentLoop:
    """The executed loop at the tangent plant of one operating point.

    Attributes
    ----------
    speed_rad_s : float
        Mechanical speed (rad/s); ``omega_e_rad_s`` the electrical one.
    i_d, i_q : float
        Operating currents (A).
    L_inc : tuple
        Incremental inductance ``((L_dd, L_dq), (L_qd, L_qq))`` (H) there.
    analysed : bool
        False for a law without a linear loop (``basis`` says why).
    stable : bool or None
        Coupled tangent loop stable (``spectral_radius < STABLE_RADIUS``).
    spectral_radius : float
        Largest closed-loop pole modulus of the coupled tangent loop.
    margins : dict or None
        ``{"d": {...}, "q": {...}}`` per-axis margins on the tangent axis
        plants (:data:`POINT_MARGIN_KEYS`); None when not computed
        (``axis_loops``).
    mimo_disk_margin : float
        Balanced multiloop input disk margin at this speed (0 when unstable).
    mimo_gain_margin, mimo_phase_margin_deg : tuple, float
        The simultaneous gain factors ``(low, high)`` and phase variation
        (deg) in both channels the disk margin guarantees.
    checks : dict
        The spec's margin requirements at this point
        (:meth:`toolbox.spec.Requirements.check_margins` records).
    passed : bool
    reason : str or None
        Why the point fails (None when it passes).
    basis : str
        What was analysed.
    """

    speed_rad_s: float
    omega_e_rad_s: float
    i_d: float
    i_q: float
    L_inc: tuple
    analysed: bool
    stable: bool | None
    spectral_radius: float
    margins: dict | None = None
    mimo_disk_margin: float = math.nan
    mimo_gain_margin: tuple = (math.nan, math.nan)
    mimo_phase_margin_deg: float = math.nan
    checks: dict = field(default_factory=dict)
    passed: bool = True
    reason: str | None = None
    basis: str = ""

    def to_json(self) -> dict:
        """JSON-ready dict of all attributes (non-finite floats as strings)."""
        return json_ready({k: getattr(self, k) for k in self.__dataclass_fields__})


def _bounds_margins(requirements) -> bool:
    """Whether ``requirements`` bound a margin (a ``margins``-stage key)."""
    return requirements is not None and any(
        REQUIREMENT_KEYS[k][0] == "margins" for k in getattr(requirements, "bounds", {}))


def tangent_loops(artifact, motor, points: Iterable, *, requirements=None,
                  axis_loops: bool | None = None,
                  n_grid: int = MIMO_GRID) -> list[TangentLoop]:
    """The executed loop at the tangent plant of each operating point (module docstring).

    Parameters
    ----------
    artifact : ControllerArtifact
        The one designed controller (its executed laws, decoupling, delay).
    motor : Motor
        The true plant: constant parameters or saturated (``motor.magnetics``).
    points : iterable of (speed, i_d, i_q)
        Mechanical speed (rad/s) and the operating currents (A).
    requirements : Requirements, optional
        The spec's ``[requirements]``: its margin bounds are checked at every
        point (none: stability alone is judged).
    axis_loops : bool, optional
        Compute the per-axis margins at each point (tens of ms per distinct
        current and axis for a saturated motor); default: for a
        constant-parameter motor (the nominal ones, already computed) and
        whenever ``requirements`` bound a margin (what is judged).
    n_grid : int
        Frequency points of the multiloop disk margin.

    Returns
    -------
    list of TangentLoop
        One per point, in order.
    """
    pts = [(float(s), float(a), float(b)) for s, a, b in points]
    if not pts:
        return []
    omega = np.array([motor.pole_pairs * s for s, _, _ in pts])
    AB = [incremental_dq_matrices(motor, a, b, w) for (_, a, b), w in zip(pts, omega)]
    Ac = np.stack([A for A, _ in AB])
    Bc = np.stack([B for _, B in AB])
    L = np.linalg.inv(Bc)            # B = L_inc^-1
    L_inc = [tuple(tuple(float(v) for v in row) for row in Lk) for Lk in L]
    if artifact.method in INFORMATIONAL_METHODS:
        basis = f"not analysed: {INFORMATIONAL_METHODS[artifact.method]}; judged by simulation"
        return [TangentLoop(s, float(w), a, b, Lk, False, None, math.nan, basis=basis)
                for (s, a, b), w, Lk in zip(pts, omega, L_inc)]
    Ts, d, dec = artifact.sample_time, int(artifact.delay_samples), artifact.decoupling
    # the coupled executed loop, exactly as coupled_closed_loop closes it (exact speed sensor)
    Phi, Gam = zoh_2x2(Ac, Bc, Ts)
    Gam_v = Gam @ rotation(placement_error(dec, Ts, d, omega, omega))
    A_cl = coupled_state_matrix(executed_laws(artifact), dec, d, Phi, Gam_v, omega)
    rho = np.max(np.abs(np.linalg.eigvals(A_cl)), axis=-1)
    w = log_grid(1e-2, math.pi / Ts, n_grid, True)[:-1]   # z = -1 excluded, as mimo_disk_margins
    x = _grid_point(artifact, w, True)
    C = _controllers(artifact, x, True)
    basis = (f"executed sampled loop at the tangent plant (ZOH at the point's speed, "
             f"{d} period(s) of delay, the law's decoupling and voltage placement)")
    if axis_loops is None:
        axis_loops = motor.magnetics is None or _bounds_margins(requirements)
    axis_memo: dict = {}

    def axis_margins_at(k: int) -> dict | None:
        """Per-axis margins on the tangent axis plants of point ``k`` (None when
        not asked); a constant-parameter motor: the nominal axis loops (the
        verdict's own :func:`compute_margins` call, cached); memoised by the
        axis inductances (they do not change with speed)."""
        if not axis_loops:
            return None
        key = (float(L[k, 0, 0]), float(L[k, 1, 1]))
        if key not in axis_memo:
            res = (compute_margins(artifact, motor) if motor.magnetics is None else
                   {ax: axis_margins(make_axis_loop(artifact.axes[ax], motor.R, key[j], Ts, d),
                                     n_grid=AXIS_GRID, step=False)
                    for j, ax in enumerate(("d", "q"))})
            axis_memo[key] = {ax: {m: r.to_json(extras=False)[m] for m in POINT_MARGIN_KEYS}
                              for ax, r in res.items()}
        return axis_memo[key]

    out = []
    for k, (s, a, b) in enumerate(pts):
        stable = bool(rho[k] < STABLE_RADIUS)
        mimo = 0.0
        if stable:
            Li = _loop_response(artifact, motor, float(omega[k]), w, x, C, True,
                                float(omega[k]), zoh=(Phi[k:k + 1], Gam[k:k + 1]))
            M = inv_2x2(np.eye(2) + Li) - 0.5 * np.eye(2)
            mimo = 1.0 / float(np.max(mu_upper_2x2(M)))
        mj = axis_margins_at(k)
        checks = (requirements.check_margins(mj) if requirements is not None and mj else {})
        reasons = []
        if not stable:
            reasons.append(f"tangent loop unstable (spectral radius {rho[k]:.4g} >= 1 at "
                           f"L_inc d {L[k, 0, 0] * 1e3:.3g} mH, q {L[k, 1, 1] * 1e3:.3g} mH)")
        for key, c in checks.items():
            if not c["pass"]:
                v = c["value"]
                reasons.append(f"tangent loop {c['quantity']} "
                               f"{'none' if v is None else format(v, '.3g')} {c['unit']} "
                               f"against {key} {c['bound']:g}")
        lo, hi, ph = disk_variations(mimo, 0.0)
        out.append(TangentLoop(s, float(omega[k]), a, b, L_inc[k], True, stable,
                               float(rho[k]), mj, mimo, (lo, hi), ph, checks, not reasons,
                               "; ".join(reasons) or None, basis))
    return out
