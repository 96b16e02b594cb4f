"""The Python reference of the header's law in double precision:
:class:`ReferenceLaw` (one period at a time), :func:`reference_law` (a whole
input sequence) and the d-axis priority voltage limit
(:func:`d_priority_limit`)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ExportRefused
from ._check import AXES, PRIORITIES


# ---------------------------------------------------------------------------
# Python reference of the executed law (double precision)
# ---------------------------------------------------------------------------
class ReferenceLaw:
    """The executed law in double precision, one period at a time.

    Uses the artifact's own state-space law (not the exported realisation),
    so it is an independent route to the header's input-output map: per axis
    ``v = C x + D u``, decoupling, the voltage limit, then
    ``x <- A x + B u + aw (v_sat - v_unsat)``. The simulator kernel
    (:mod:`toolbox.sim._kernel`) runs the same law; tests/export compare the
    three (kernel, this class, the C header).

    Voltage limit, as the simulator:

    * ``"circle"``: radial scaling onto ``|v| <= v_max``;
    * ``"hexagon"``: the SVM hexagon of apothem ``v_max`` (vertex radius
      ``2 v_max / sqrt(3)``, vertices at 0, 60, ... deg in the stationary frame),
      seen at the placement angle ``theta_e + t_c w_e`` (``t_c`` the
      decoupling's ``delay_compensation_time``, toolbox/ARCHITECTURE.md "The
      digital loop"); radial scaling onto its edge.

    Priority (``drive.voltage_priority``): ``"radial"`` as above; ``"d_axis"``
    keeps ``v_d`` (clamped to the limit's d extent and to the guard
    :func:`d_priority_cap` of the speed voltage ``w (Ld_c i_d + psi_c)``) and clips ``v_q`` into
    what is left: ``|v_q| <= sqrt(v_max^2 - v_d^2)`` on the circle, the
    hexagon's chord at that ``v_d`` in the placement frame
    (:func:`d_priority_limit`).

    Faults, as the header: a non-finite input returns the last good output
    with ``status = 1`` and leaves the state unchanged; a non-finite result
    (overflow) does the same with ``status = 2``; ``status = 0`` otherwise.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller.
    v_max : float
        Voltage-limit radius (V): the circle's radius or the hexagon's apothem.
    limit : {"circle", "hexagon"}
        Voltage-limit shape.
    priority : {"radial", "d_axis"}
        Voltage-limit priority.
    """

    def __init__(self, artifact, v_max: float, limit: str = "circle",
                 priority: str = "radial") -> None:
        if limit not in ("circle", "hexagon"):
            raise ExportRefused("drive.voltage_limit", '"circle" or "hexagon"', limit)
        if priority not in PRIORITIES:
            raise ExportRefused("drive.voltage_priority", '"radial" or "d_axis"', priority)
        self.priority = priority
        self.dec = artifact.decoupling
        self.v_max = float(v_max)
        self.limit = limit
        self.t_comp = float(artifact.decoupling.delay_compensation_time)
        self.laws = [artifact.axes[ax].law for ax in AXES]
        self.aws = [np.zeros(l.order) if artifact.axes[ax].antiwindup is None
                    else artifact.axes[ax].antiwindup.ravel()
                    for l, ax in zip(self.laws, AXES)]
        self.xs = [np.zeros(l.order) for l in self.laws]
        self.hold = (0.0, 0.0)
        self.status = 0

    def _limit(self, vd: float, vq: float, w: float, theta_e: float) -> float:
        """Scale factor k <= 1 applied to (vd, vq) (radial priority)."""
        if self.limit == "circle":
            mag = math.hypot(vd, vq)
            return self.v_max / mag if mag > self.v_max else 1.0
        th = theta_e + w * self.t_comp
        c, sn = math.cos(th), math.sin(th)
        va, vb = vd * c - vq * sn, vd * sn + vq * c
        # largest projection on the edge normals at 30, 90 and 150 deg
        h = math.sqrt(3.0) / 2.0
        pm = max(abs(h * va + 0.5 * vb), abs(vb), abs(-h * va + 0.5 * vb))
        return self.v_max / pm if pm > self.v_max else 1.0

    def step(self, i_d_ref: float, i_q_ref: float, i_d: float, i_q: float,
             omega_m: float, theta_e: float = 0.0) -> tuple[float, float, int]:
        """One period: currents (A), mechanical speed (rad/s), electrical angle
        (rad, hexagon only) -> (v_d, v_q (V), saturated); sets ``self.status``."""
        args = (i_d_ref, i_q_ref, i_d, i_q, omega_m) + ((theta_e,) if self.limit == "hexagon" else ())
        if not all(math.isfinite(a) for a in args):
            self.status = 1
            return self.hold[0], self.hold[1], 0
        dec = self.dec
        u = [np.array([i_d_ref, i_d]), np.array([i_q_ref, i_q])]
        with np.errstate(all="ignore"):
            v_lin = [float((l.C @ x + l.D @ uu)[0]) for l, x, uu in zip(self.laws, self.xs, u)]
            w = dec.pole_pairs * omega_m
            vd = v_lin[0] - dec.cross * w * dec.Lq_c * i_q
            vq = v_lin[1] + dec.cross * w * dec.Ld_c * i_d + dec.emf * w * dec.flux_c
            if not (math.isfinite(vd) and math.isfinite(vq)):
                vds = vqs = math.nan
                sat = 0
            elif self.priority == "d_axis":
                vds, vqs = d_priority_limit(vd, vq, self.v_max, self.limit,
                                            theta_e + w * self.t_comp,
                                            w * (dec.Ld_c * i_d + dec.flux_c))
                sat = int(vds != vd or vqs != vq)
            else:
                k = self._limit(vd, vq, w, theta_e)
                vds, vqs, sat = (vd * k, vq * k, 1) if k < 1.0 else (vd, vq, 0)
            dv = (vds - vd, vqs - vq)
            xs = [l.A @ x + l.B @ uu + a * d
                  for l, x, uu, a, d in zip(self.laws, self.xs, u, self.aws, dv)]
        if not (math.isfinite(vds) and math.isfinite(vqs)
                and all(np.all(np.isfinite(x)) for x in xs)):
            self.status = 2
            return self.hold[0], self.hold[1], 0
        self.xs, self.hold, self.status = xs, (vds, vqs), 0
        return vds, vqs, sat


def d_priority_cap(v_in: float, e_q: float) -> float:
    """The d-axis priority guard, a fraction of the limit's d extent:
    ``sqrt(1 - min(|e_q| / v_in, 1)^2)``; on the circle (``v_in`` its radius)
    the largest ``|v_d|`` that leaves ``v_q`` the speed voltage ``e_q = w
    (Ld_c i_d + psi_c)`` (the controller's model at the measured current and
    speed); the hexagon (``v_in`` its apothem) scales its d extent alike. Without it the d loop's
    ``-w Lq i_q`` takes the voltage in a flying start above base speed and
    ``v_q`` falls below the back-EMF (toolbox/ARCHITECTURE.md "Operating
    envelope"); the simulator's ``toolbox.sim._kernel.d_priority_cap`` is the
    same formula."""
    e = min(abs(e_q) / v_in, 1.0)
    return math.sqrt(max(1.0 - e * e, 0.0))


def d_priority_limit(vd: float, vq: float, v_max: float, limit: str = "circle",
                     theta: float = 0.0, e_q: float = 0.0) -> tuple[float, float]:
    """d-axis priority voltage limit (the limiter of field-weakening drives,
    Briz et al., IEEE Trans. Ind. Appl. 37(1) 2001): ``v_d`` clamped to the
    limit's d extent times :func:`d_priority_cap` ``(v_max, e_q)`` (``e_q``
    the speed voltage the guard keeps for ``v_q``; 0: no guard), then ``v_q``
    clipped into the chord at that ``v_d``.

    Circle of radius ``v_max``: ``|v_d| <= v_max``, ``|v_q| <= sqrt(v_max^2 -
    v_d^2)``. Hexagon of apothem ``v_max`` (vertex radius ``r = 2 v_max /
    sqrt(3)``) seen from the dq frame at ``theta``: the edge normal at ``alpha``
    (30, 90, 150 deg) is ``(cos(alpha - theta), sin(alpha - theta))`` in dq, each
    edge pair bounds ``|c v_d + s v_q| <= v_max``; the d extent is the support
    function ``r max_j |cos(theta - 60 j deg)|``.
    """
    cap = d_priority_cap(v_max, e_q)
    if limit == "circle":
        vds = min(max(vd, -cap * v_max), cap * v_max)
        q = math.sqrt(max(v_max * v_max - vds * vds, 0.0))
        return vds, min(max(vq, -q), q)
    h = math.sqrt(3.0) / 2.0
    r_hex = v_max / h
    c0, s0 = math.cos(theta), math.sin(theta)
    d_max = cap * r_hex * max(abs(c0), abs(0.5 * c0 + h * s0), abs(-0.5 * c0 + h * s0))
    vds = min(max(vd, -d_max), d_max)
    lo, hi = -math.inf, math.inf
    for ca, sa in ((h, 0.5), (0.0, 1.0), (-h, 0.5)):
        ck, sk = ca * c0 + sa * s0, sa * c0 - ca * s0
        if abs(sk) > 1e-12:
            b1, b2 = sorted(((v_max - ck * vds) / sk, (-v_max - ck * vds) / sk))
            lo, hi = max(lo, b1), min(hi, b2)
    if lo > hi:  # v_d on a vertex, rounding: the chord is one point
        lo = hi = 0.5 * (lo + hi)
    return vds, min(max(vq, lo), hi)


def reference_law(artifact, inputs: np.ndarray, v_max: float, limit: str = "circle",
                  priority: str = "radial") -> tuple[np.ndarray, np.ndarray]:
    """Run :class:`ReferenceLaw` over an input sequence.

    Parameters
    ----------
    artifact : ControllerArtifact
        Controller.
    inputs : ndarray
        (N, 5): ``i_d_ref, i_q_ref, i_d, i_q`` (A), ``Omega_m`` (rad/s); (N, 6)
        with the electrical angle ``theta_e`` (rad) for the hexagon.
    v_max : float
        Voltage-limit radius (V).
    limit : {"circle", "hexagon"}
        Voltage-limit shape.
    priority : {"radial", "d_axis"}
        Voltage-limit priority.

    Returns
    -------
    (ndarray, ndarray)
        (N, 2) voltages ``v_d, v_q`` (V) and (N,) saturation flags.
    """
    law = ReferenceLaw(artifact, v_max, limit, priority)
    out = np.zeros((len(inputs), 2))
    sat = np.zeros(len(inputs), dtype=int)
    for k, row in enumerate(np.asarray(inputs, float)):
        out[k, 0], out[k, 1], sat[k] = law.step(*row)
    return out, sat
