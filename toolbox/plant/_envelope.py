"""Operating envelope of a PMSM on a drive: MTPA, field weakening and MTPV
current references for constant ``Ld``, ``Lq``, ``flux``.

Model (the steady state of paper 003 eq (3)-(7), :func:`steady_state_voltage`),
``w = p Omega`` the electrical speed, ``k = motor.torque_factor`` (3/2
amplitude-invariant, 1 power-invariant: currents, voltages and flux are in the
motor's own convention)::

    T   = k p (psi i_q + (Ld - Lq) i_d i_q)
    v_d = R i_d - w Lq i_q,   v_q = R i_q + w (Ld i_d + psi)

Limits: ``|v| <= V`` (``drive.max_voltage(convention)``, the circle inscribed
in the SVM hexagon, or ``v_max``) and ``|i| <= I`` (``motor.max_current``, else
2 x ``motor.rated_current``, or ``i_max``).

* **MTPA** (Morimoto et al., IEEE Trans. Ind. Appl. 26(5) 1990; motulator's
  ``TorqueCharacteristics.mtpa``): with ``i_d = i_s cos b``, ``i_q = i_s sin b``,
  ``dT/db = 0`` gives ``psi i_d + (Ld - Lq)(2 i_d^2 - i_s^2) = 0``, whose root
  of maximum torque is, with ``dL = Lq - Ld``,
  ``i_d = (psi - sqrt(psi^2 + 8 dL^2 i_s^2)) / (4 dL)
  = -2 dL i_s^2 / (psi + sqrt(psi^2 + 8 dL^2 i_s^2))`` (the second form holds
  for either sign of ``dL`` and for ``dL = 0``). ``k`` scales the torque only,
  so the locus is the same in both conventions.
* **Field weakening**: on the constant-torque curve
  ``i_q = T / (k p (psi + (Ld - Lq) i_d))``, ``|i|`` grows monotonically away
  from the MTPA point; the reference is the point of that curve nearest MTPA
  on the voltage limit ``|v(i)| = V`` (the voltage "ellipse", here with ``R``,
  a shifted ellipse; ``resistive=False`` drops ``R`` for the textbook one).
* **MTPV / maximum torque**: the torque is bilinear, its only stationary point
  a saddle, so the largest torque at a speed lies on the boundary of the
  convex set ``|i| <= I, |v(i)| <= V``: on the current circle
  (``i = I (cos b, sin b)``) or on the voltage boundary, parametrised exactly
  as ``i = Z^{-1} (V (cos f, sin f) - e)`` with ``Z = [[R, -w Lq], [w Ld, R]]``,
  ``e = (0, w psi)``. The voltage boundary's torque maximum is the MTPV point
  (with ``R = 0``: the flux angle of motulator's ``mtpv``).

Speeds are mechanical (rad/s) as everywhere in the toolbox; torques in N m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from ..errors import SpecError

__all__ = ["OperatingEnvelope", "OperatingPoint", "mtpa_d_current"]

#: Samples of a boundary curve before local refinement.
_N_BOUNDARY = 2048


def mtpa_d_current(i_s, Ld: float, Lq: float, flux: float):
    """MTPA d-axis current (A) for a current amplitude ``i_s`` (A):
    ``-2 (Lq - Ld) i_s^2 / (flux + sqrt(flux^2 + 8 (Lq - Ld)^2 i_s^2))``
    (module docstring; either convention, either saliency)."""
    i_s = np.asarray(i_s, float)
    dL = Lq - Ld
    root = np.sqrt(flux ** 2 + 8.0 * dL ** 2 * i_s ** 2)
    den = flux + root
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 0, -2.0 * dL * i_s ** 2 / np.where(den > 0, den, 1.0), 0.0)
    return out if out.ndim else float(out)


@dataclass(frozen=True)
class OperatingPoint:
    """A current reference of the envelope.

    Attributes
    ----------
    i_d, i_q : float
        Current reference (A).
    torque : float
        Torque it produces (N m): the request, or the limit when the request
        exceeds it.
    region : str
        ``"mtpa"`` (no limit active), ``"field_weakening"`` (on the voltage
        limit, below the torque limit), ``"current_limit"``, ``"voltage_limit"``
        (the MTPV point) or ``"current_and_voltage_limit"`` (the torque was
        limited to the largest the drive can give at that speed).
    """

    i_d: float
    i_q: float
    torque: float
    region: str


class OperatingEnvelope:
    """MTPA, field-weakening and MTPV references of a motor on a drive.

    :attr:`HEADROOM` (5 %) is the voltage fraction the verification grid and
    the exported reference table keep out of the envelope for the current
    loop's transients (``v_max = (1 - HEADROOM)`` x the drive's circle).

    Parameters
    ----------
    motor : Motor
        ``R``, ``Ld``, ``Lq``, ``flux``, ``pole_pairs``, ``torque_factor``;
        ``max_current`` or ``rated_current`` unless ``i_max`` is given.
    drive : Drive, optional
        ``drive.max_voltage(motor.convention)`` is the voltage limit unless
        ``v_max`` is given.
    v_max : float, optional
        Steady-state voltage limit (V), e.g. the drive's minus a headroom the
        current loop keeps for its transients.
    i_max : float, optional
        Current amplitude limit (A).
    resistive : bool
        Keep ``R`` in the voltage (default); False: the textbook ellipse.
    """

    #: Voltage fraction kept for the loop's transients (verification grid, header table).
    HEADROOM = 0.05

    def __init__(self, motor, drive=None, *, v_max: float | None = None,
                 i_max: float | None = None, resistive: bool = True) -> None:
        if v_max is None:
            if drive is None:
                raise SpecError("drive", "a drive (or v_max) for the voltage limit", None)
            v_max = drive.max_voltage(motor.convention)
        if i_max is None:
            i_max = motor.max_current or (2.0 * motor.rated_current
                                          if motor.rated_current else None)
            if i_max is None:
                raise SpecError("motor.max_current", "a current limit (max_current or "
                                "rated_current, or i_max=) for the envelope", None)
        if not (v_max > 0 and math.isfinite(v_max)):
            raise SpecError("drive.vdc", "a positive voltage limit (V)", v_max)
        if not (i_max > 0 and math.isfinite(i_max)):
            raise SpecError("motor.max_current", "a positive current limit (A)", i_max)
        self.motor = motor
        self.V = float(v_max)
        self.I = float(i_max)
        self.R = float(motor.R) if resistive else 0.0
        self.Ld, self.Lq, self.flux = float(motor.Ld), float(motor.Lq), float(motor.flux)
        self.p = motor.pole_pairs
        self.kt = float(motor.torque_factor) * motor.pole_pairs

    # ------------------------------------------------------------------ model
    def torque(self, i_d, i_q):
        """Torque (N m) of the currents (A)."""
        return self.kt * (self.flux * np.asarray(i_q) + (self.Ld - self.Lq)
                          * np.asarray(i_d) * np.asarray(i_q))

    def voltage(self, i_d, i_q, speed):
        """Steady-state ``(v_d, v_q)`` (V) at the mechanical speed (rad/s)."""
        w = self.p * speed
        return (self.R * np.asarray(i_d) - w * self.Lq * np.asarray(i_q),
                self.R * np.asarray(i_q) + w * (self.Ld * np.asarray(i_d) + self.flux))

    def _vmag(self, i_d, i_q, speed):
        return np.hypot(*self.voltage(i_d, i_q, speed))

    # ------------------------------------------------------------------- MTPA
    def mtpa(self, torque: float) -> tuple[float, float]:
        """MTPA currents ``(i_d, i_q)`` (A) for a torque (N m), no limits."""
        if torque == 0:
            return 0.0, 0.0
        sgn = math.copysign(1.0, torque)

        def tq(i_s):
            i_d = mtpa_d_current(i_s, self.Ld, self.Lq, self.flux)
            return float(self.torque(i_d, math.sqrt(max(i_s * i_s - i_d * i_d, 0.0))))

        hi = max(abs(torque) / (self.kt * max(self.flux, 1e-12)), 1e-6)
        while tq(hi) < abs(torque):
            hi *= 2.0
        i_s = brentq(lambda s: tq(s) - abs(torque), 0.0, hi, xtol=1e-14, rtol=1e-14)
        i_d = float(mtpa_d_current(i_s, self.Ld, self.Lq, self.flux))
        return i_d, sgn * math.sqrt(max(i_s * i_s - i_d * i_d, 0.0))

    # ------------------------------------------------------- boundary curves
    def _voltage_boundary(self, speed, f):
        """Currents on ``|v| = V`` at the angles ``f`` of the voltage vector."""
        w = self.p * speed
        Z = np.array([[self.R, -w * self.Lq], [w * self.Ld, self.R]])
        rhs = np.vstack([self.V * np.cos(f), self.V * np.sin(f) - w * self.flux])
        i = np.linalg.solve(Z, rhs)
        return i[0], i[1]

    def _current_boundary(self, speed, b):
        return self.I * np.cos(b), self.I * np.sin(b)

    def _boundary_max(self, curve, feasible, sign):
        """Largest ``sign x torque`` on a closed curve ``curve(t)``, t in
        [0, 2 pi), where ``feasible(i_d, i_q) <= 0``: sampled, then refined
        (a local maximum by bounded search, a feasibility end by brentq)."""
        t = np.linspace(0.0, 2.0 * math.pi, _N_BOUNDARY, endpoint=False)
        dt = t[1]
        i_d, i_q = curve(t)
        g = feasible(i_d, i_q)
        ok = g <= 0
        if not ok.any():
            return None
        f = sign * self.torque(i_d, i_q)
        f = np.where(ok, f, -np.inf)
        k = int(np.argmax(f))
        fun = lambda s: -sign * float(self.torque(*curve(np.array([s])))[0])  # noqa: E731
        gfun = lambda s: float(feasible(*curve(np.array([s])))[0])  # noqa: E731
        cands = [t[k]]
        res = minimize_scalar(fun, bounds=(t[k] - dt, t[k] + dt), method="bounded",
                              options={"xatol": 1e-13})
        if gfun(res.x) <= 0:
            cands.append(res.x)
        for nb in (t[k] - dt, t[k] + dt):        # an infeasible neighbour: the end between
            if gfun(nb) > 0:
                cands.append(brentq(gfun, min(nb, t[k]), max(nb, t[k]), xtol=1e-15))
        cands = [c for c in cands if gfun(c) <= 1e-9 * max(self.V, self.I) ** 2]
        best = min(cands, key=fun)
        bd, bq = curve(np.array([best]))
        return float(bd[0]), float(bq[0])

    def max_torque_point(self, speed: float, sign: float = 1.0) -> OperatingPoint:
        """The largest torque (``sign = 1``; the most negative with -1) the
        limits allow at a mechanical speed (rad/s), and its currents."""
        V2, I2 = self.V ** 2, self.I ** 2
        # without R at standstill no current reaches the voltage limit (Z = 0)
        on_v = None if self.R == 0.0 and speed == 0.0 else self._boundary_max(
            lambda f: self._voltage_boundary(speed, f), lambda d, q: d * d + q * q - I2, sign)
        on_i = self._boundary_max(lambda b: self._current_boundary(speed, b),
                                  lambda d, q: self._vmag(d, q, speed) ** 2 - V2, sign)
        pts = [p for p in (on_v, on_i) if p is not None]
        if not pts:
            raise SpecError("drive.vdc", f"a voltage limit the back-EMF at {speed:g} rad/s "
                            "leaves room for within the current limit", self.V)
        d, q = max(pts, key=lambda pq: sign * float(self.torque(*pq)))
        return OperatingPoint(d, q, float(self.torque(d, q)), self._region(d, q, speed))

    def mtpv(self, speed: float, sign: float = 1.0) -> tuple[float, float]:
        """The MTPV currents (A): the largest torque on the voltage limit at a
        mechanical speed (rad/s), the current limit ignored."""
        return self._boundary_max(lambda f: self._voltage_boundary(speed, f),
                                  lambda d, q: np.zeros_like(d) - 1.0, sign)

    def _region(self, d, q, speed, tol=1e-7):
        on_i = math.hypot(d, q) >= self.I * (1 - tol)
        on_v = self._vmag(d, q, speed) >= self.V * (1 - tol)
        return {(True, True): "current_and_voltage_limit", (True, False): "current_limit",
                (False, True): "voltage_limit", (False, False): "mtpa"}[(on_i, on_v)]

    def base_speed(self) -> float:
        """Highest mechanical speed (rad/s) at which the MTPA point of the
        current limit is within the voltage limit (the corner of the
        constant-torque region)."""
        i_d = float(mtpa_d_current(self.I, self.Ld, self.Lq, self.flux))
        i_q = math.sqrt(self.I ** 2 - i_d ** 2)
        if self._vmag(i_d, i_q, 0.0) >= self.V:
            return 0.0
        hi = 1.0
        while self._vmag(i_d, i_q, hi) < self.V:
            hi *= 2.0
        return brentq(lambda s: self._vmag(i_d, i_q, s) - self.V, 0.0, hi, xtol=1e-12)

    # --------------------------------------------------------- the reference
    def operating_point(self, torque: float, speed: float,
                        limit: OperatingPoint | None = None) -> OperatingPoint:
        """Current reference of least amplitude for a torque (N m) at a
        mechanical speed (rad/s) within both limits: MTPA when it fits, else
        the field-weakening point of the torque curve on the voltage limit,
        else (torque beyond the limit at that speed) the largest torque point
        of that sign. ``limit``: :meth:`max_torque_point` of that speed and
        sign when the caller has it (a table over torque at one speed)."""
        sign = 1.0 if torque >= 0 else -1.0
        d, q = self.mtpa(torque)
        if math.hypot(d, q) <= self.I and self._vmag(d, q, speed) <= self.V:
            return OperatingPoint(d, q, float(torque), "mtpa")
        lim = limit if limit is not None else self.max_torque_point(speed, sign)
        if sign * torque >= sign * lim.torque:
            return lim
        # along the torque curve i_q(i_d): the point of least |v| (feasible as
        # |torque| < the limit), then the root of |v| = V between it and MTPA
        dL = self.Lq - self.Ld

        def iq_of(i_d):
            return torque / (self.kt * (self.flux - dL * i_d))

        def vexcess(i_d):
            return float(self._vmag(i_d, iq_of(i_d), speed)) - self.V

        lo_b, hi_b = -self.I, self.I   # |i_d| <= I, and psi - dL i_d > 0 (the torque's sign)
        if dL > 0:
            hi_b = min(hi_b, self.flux / dL * (1 - 1e-9))
        elif dL < 0:
            lo_b = max(lo_b, self.flux / dL * (1 - 1e-9))
        grid = np.linspace(lo_b, hi_b, 4001)
        vg = self._vmag(grid, iq_of(grid), speed) - self.V
        k = int(np.argmin(vg))
        span = grid[1] - grid[0]
        res = minimize_scalar(vexcess, bounds=(grid[max(k - 1, 0)], grid[min(k + 1, 4000)]),
                              method="bounded", options={"xatol": 1e-12})
        seed = res.x if res.fun <= vg[k] else grid[k]
        if vexcess(seed) > 0 or span <= 0:
            return lim
        if vexcess(d) <= 0:   # MTPA within the voltage limit but beyond the current limit
            return lim
        i_d = brentq(vexcess, min(seed, d), max(seed, d), xtol=1e-13, rtol=1e-15)
        i_q = iq_of(i_d)
        if math.hypot(i_d, i_q) > self.I * (1 + 1e-9):
            return lim
        return OperatingPoint(float(i_d), float(i_q), float(torque), "field_weakening")

    def current_reference(self, torque: float, speed: float) -> tuple[float, float]:
        """``(i_d, i_q)`` (A) of :meth:`operating_point`."""
        op = self.operating_point(torque, speed)
        return op.i_d, op.i_q
