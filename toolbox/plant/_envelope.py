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
  a shifted ellipse; ``resistive=False`` drops ``R`` for the textbook one):
  multiplied by the curve's denominator squared, ``|v|^2 = V^2`` is a quartic
  in ``i_d``, ``R`` included (:meth:`OperatingEnvelope.operating_point`).
* **MTPV / maximum torque**: the torque is bilinear, its only stationary point
  a saddle, so the largest torque at a speed lies on the boundary of the
  convex set ``|i| <= I, |v(i)| <= V``: on the current circle
  (``i = I (cos b, sin b)``) or on the voltage boundary, parametrised exactly
  as ``i = Z^{-1} (V (cos f, sin f) - e)`` with ``Z = [[R, -w Lq], [w Ld, R]]``,
  ``e = (0, w psi)``. The voltage boundary's torque maximum is the MTPV point
  (with ``R = 0``: the flux angle of motulator's ``mtpv``). On either curve
  the torque, and ``|i|^2`` on the voltage boundary, are trigonometric
  polynomials of degree 2 in the angle: the candidates (the torque's
  stationary points on each curve within the other limit, and the crossings
  of the two curves) are roots of quartics (:func:`_trig2_roots`), with
  ``R`` and without a search.

The quartics' roots are companion-matrix eigenvalues (``numpy.linalg.eigvals``,
as ``numpy.roots``), polished by two Newton steps.

Speeds are mechanical (rad/s) as everywhere in the toolbox; torques in N m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SpecError

__all__ = ["OperatingEnvelope", "OperatingPoint", "envelope_of", "mtpa_d_current"]


def _poly_roots(coef) -> list[complex]:
    """Roots of the polynomial ``coef`` (highest power first, real or complex;
    leading zeros dropped): the eigenvalues of its companion matrix (as
    ``numpy.roots``, without its per-call overhead)."""
    coef = list(coef)
    while coef and coef[0] == 0:
        coef.pop(0)
    n = len(coef) - 1
    if n < 1:
        return []
    C = np.eye(n, n, -1, dtype=complex)
    C[0, :] = [-c / coef[0] for c in coef[1:]]
    return np.linalg.eigvals(C).tolist()


def _trig2_roots(c0: float, c1: float, s1: float, c2: float, s2: float) -> list[float]:
    """Angles ``f`` (rad) where ``g(f) = c0 + c1 cos f + s1 sin f + c2 cos 2f +
    s2 sin 2f = 0``: with ``z = exp(i f)``, ``z^2 g`` is the quartic
    ``(c2 - i s2)/2 z^4 + (c1 - i s1)/2 z^3 + c0 z^2 + (c1 + i s1)/2 z +
    (c2 + i s2)/2`` (:func:`_poly_roots`), whose roots on the unit circle
    (to 1e-6: a double root, a tangency, splits off it by ~sqrt(eps)) are the
    real angles; each polished by two Newton steps on ``g``."""
    out = []
    for z in _poly_roots([0.5 * (c2 - 1j * s2), 0.5 * (c1 - 1j * s1), c0,
                          0.5 * (c1 + 1j * s1), 0.5 * (c2 + 1j * s2)]):
        if abs(abs(z) - 1.0) > 1e-6:
            continue
        f = math.atan2(z.imag, z.real)
        for _ in range(2):
            c, s, c_2, s_2 = math.cos(f), math.sin(f), math.cos(2 * f), math.sin(2 * f)
            dg = -c1 * s + s1 * c - 2.0 * c2 * s_2 + 2.0 * s2 * c_2
            if dg == 0:
                break
            step = (c0 + c1 * c + s1 * s + c2 * c_2 + s2 * s_2) / dg
            if not abs(step) < 1e-4:
                break
            f -= step
        out.append(f)
    return out


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
        self._circle = None   # the torque's stationary points on the current circle

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
        """MTPA currents ``(i_d, i_q)`` (A) for a torque (N m), no limits.

        With ``a = Ld - Lq``, ``tau = T / k p`` and ``x = a i_d / psi``, the
        MTPA condition ``psi i_d + a (i_d^2 - i_q^2) = 0`` and the torque give
        ``x (1 + x)^3 = (a tau / psi^2)^2`` (module docstring), whose root
        ``x >= 0`` is unique (the left side increases from 0): Newton's
        iteration from the upper bound ``min(c, c^(1/4))`` descends on the
        convex left side to it without overshooting. Then
        ``i_d = a tau^2 / (psi^3 (1 + x)^3)``, ``i_q = tau / (psi (1 + x))``
        (either saliency; ``a = 0`` gives ``i_d = 0``)."""
        if torque == 0:
            return 0.0, 0.0
        tau, psi, a = torque / self.kt, self.flux, self.Ld - self.Lq
        c = (a * tau / (psi * psi)) ** 2
        x = min(c, c ** 0.25)
        for _ in range(100):
            step = (x * (1.0 + x) ** 3 - c) / ((1.0 + x) ** 2 * (1.0 + 4.0 * x))
            if not step > 4e-16 * x:
                break
            x -= step
        return a * tau * tau / (psi ** 3 * (1.0 + x) ** 3), tau / (psi * (1.0 + x))

    # ------------------------------------------------------- boundary curves
    def _t(self, d: float, q: float) -> float:
        return self.kt * q * (self.flux + (self.Ld - self.Lq) * d)

    def _v2(self, d: float, q: float, w: float) -> float:
        """``|v|^2`` at the electrical speed ``w`` (scalars)."""
        vd, vq = self.R * d - w * self.Lq * q, self.R * q + w * (self.Ld * d + self.flux)
        return vd * vd + vq * vq

    def _voltage_boundary(self, w: float) -> tuple[float, ...] | None:
        """``(al, be, d0, ga, de, q0)``: the currents on ``|v| = V`` at the
        voltage angle ``f`` are ``(al cos f + be sin f + d0, ga cos f + de sin f
        + q0)`` (module docstring, ``i = Z^{-1} (V (cos f, sin f) - e)``),
        electrical speed ``w`` (rad/s); None when ``Z`` is singular (``R = 0``
        at standstill: no current reaches the voltage limit)."""
        R, Ld, Lq, V = self.R, self.Ld, self.Lq, self.V
        det = R * R + w * w * Ld * Lq
        if det == 0.0:
            return None
        return (V * R / det, V * w * Lq / det, -w * w * Lq * self.flux / det,
                -V * w * Ld / det, V * R / det, -R * w * self.flux / det)

    @staticmethod
    def _on_curve(cv: tuple[float, ...], fs: list[float]) -> list[tuple[float, float]]:
        al, be, d0, ga, de, q0 = cv
        return [(al * math.cos(f) + be * math.sin(f) + d0, ga * math.cos(f) + de * math.sin(f)
                 + q0) for f in fs]

    def _voltage_stationary(self, cv: tuple[float, ...]) -> list[tuple[float, float]]:
        """The stationary points of the torque on the voltage boundary ``cv``:
        with ``i(f)`` affine in ``(cos f, sin f)`` the bilinear torque is a
        trigonometric polynomial of degree 2 in ``f``, ``T / k p = const + c1
        cos f + s1 sin f + c2 cos 2f + s2 sin 2f``, so is ``dT/df``
        (:func:`_trig2_roots`)."""
        al, be, d0, ga, de, q0 = cv
        psi, a = self.flux, self.Ld - self.Lq
        c1 = psi * ga + a * (al * q0 + ga * d0)
        s1 = psi * de + a * (be * q0 + de * d0)
        c2 = 0.5 * a * (al * ga - be * de)
        s2 = 0.5 * a * (al * de + be * ga)
        return self._on_curve(cv, _trig2_roots(0.0, s1, -c1, 2.0 * s2, -2.0 * c2))

    def _corners(self, cv: tuple[float, ...]) -> list[tuple[float, float]]:
        """Where the voltage boundary ``cv`` crosses the current circle:
        ``|i(f)|^2 - I^2`` is a trigonometric polynomial of degree 2."""
        al, be, d0, ga, de, q0 = cv
        return self._on_curve(cv, _trig2_roots(
            0.5 * (al * al + be * be + ga * ga + de * de) + d0 * d0 + q0 * q0 - self.I ** 2,
            2.0 * (al * d0 + ga * q0), 2.0 * (be * d0 + de * q0),
            0.5 * (al * al + ga * ga - be * be - de * de), al * be + ga * de))

    def _circle_stationary(self) -> list[tuple[float, float]]:
        """The stationary points of the torque on the current circle:
        ``dT/db = 0`` is ``2 a I c^2 + psi c - a I = 0`` in ``c = cos b``
        (``a = Ld - Lq``); its root of the MTPA (:func:`mtpa_d_current` / I)
        and, the roots' product being -1/2, ``-1 / (2 c)`` when in [-1, 1];
        each at ``+-sin b``."""
        if self._circle is None:
            c = float(mtpa_d_current(self.I, self.Ld, self.Lq, self.flux)) / self.I
            pts = []
            for cb in [c] + ([-0.5 / c] if abs(c) >= 0.5 else []):
                cb = min(max(cb, -1.0), 1.0)
                sb = math.sqrt(1.0 - cb * cb)
                pts += [(self.I * cb, self.I * sb), (self.I * cb, -self.I * sb)]
            self._circle = pts
        return self._circle

    def max_torque_point(self, speed: float, sign: float = 1.0) -> OperatingPoint:
        """The largest torque (``sign = 1``; the most negative with -1) the
        limits allow at a mechanical speed (rad/s), and its currents: the best
        of the torque's stationary points on the current circle within the
        voltage limit, its stationary points on the voltage boundary within
        the current limit, and the corners where the two boundaries cross
        (module docstring: the maximum lies on the boundary; each candidate
        within the other limit to 1e-10 of its square, rounding)."""
        w, tol = self.p * speed, 1.0 + 1e-10
        V2, I2 = self.V ** 2 * tol, self.I ** 2 * tol
        pts = [pq for pq in self._circle_stationary() if self._v2(*pq, w) <= V2]
        cv = self._voltage_boundary(w)
        if cv is not None:
            pts += [(d, q) for d, q in self._voltage_stationary(cv) if d * d + q * q <= I2]
            pts += self._corners(cv)
        if not pts:
            raise SpecError("drive.vdc", f"a voltage limit the back-EMF at {speed:g} rad/s "
                            "leaves room for within the current limit", self.V)
        d, q = max(pts, key=lambda pq: sign * self._t(*pq))
        return OperatingPoint(d, q, self._t(d, q), self._region(d, q, speed))

    def mtpv(self, speed: float, sign: float = 1.0) -> tuple[float, float]:
        """The MTPV currents (A): the largest torque on the voltage limit at a
        mechanical speed (rad/s), the current limit ignored."""
        cv = self._voltage_boundary(self.p * speed)
        if cv is None:
            raise SpecError("speed", "a speed > 0 for the MTPV point without R (no current "
                            "reaches the voltage limit at standstill)", speed)
        return max(self._voltage_stationary(cv), key=lambda pq: sign * self._t(*pq))

    def _region(self, d, q, speed, tol=1e-7):
        on_i = math.hypot(d, q) >= self.I * (1 - tol)
        on_v = math.sqrt(self._v2(d, q, self.p * speed)) >= self.V * (1 - tol)
        return {(True, True): "current_and_voltage_limit", (True, False): "current_limit",
                (False, True): "voltage_limit", (False, False): "mtpa"}[(on_i, on_v)]

    def base_speed(self) -> float:
        """Highest mechanical speed (rad/s) at which the MTPA point of the
        current limit is within the voltage limit (the corner of the
        constant-torque region): ``|v|^2 = V^2`` at that point is the
        quadratic ``A w^2 + B w + C = 0`` in the electrical speed, its
        positive root (0 when ``C = R^2 I^2 - V^2 >= 0``)."""
        i_d = float(mtpa_d_current(self.I, self.Ld, self.Lq, self.flux))
        i_q = math.sqrt(max(self.I ** 2 - i_d ** 2, 0.0))
        lam_d, lam_q = self.Ld * i_d + self.flux, self.Lq * i_q
        A = lam_d * lam_d + lam_q * lam_q
        B = 2.0 * self.R * (i_q * lam_d - i_d * lam_q)
        C = self.R ** 2 * (i_d * i_d + i_q * i_q) - self.V ** 2
        if C >= 0.0:
            return 0.0
        root = math.sqrt(B * B - 4.0 * A * C)
        w = -2.0 * C / (B + root) if B >= 0 else (root - B) / (2.0 * A)
        return w / self.p

    # --------------------------------------------------------- the reference
    def operating_point(self, torque: float, speed: float,
                        limit: OperatingPoint | None = None) -> OperatingPoint:
        """Current reference of least amplitude for a torque (N m) at a
        mechanical speed (rad/s) within both limits: MTPA when it fits, else
        the field-weakening point of the torque curve on the voltage limit,
        else (torque beyond the limit at that speed) the largest torque point
        of that sign. ``limit``: :meth:`max_torque_point` of that speed and
        sign when the caller has it (a table over torque at one speed).

        Field weakening: on the torque curve ``i_q = tau / D``, ``D = psi +
        (Ld - Lq) i_d``, ``D^2 (|v|^2 - V^2)`` is the quartic
        ``(R i_d D - w Lq tau)^2 + (R tau + w (Ld i_d + psi) D)^2 - V^2 D^2``
        in ``i_d`` (``R`` kept); the reference is its real root (``D > 0``,
        ``|v| = V`` there) of least current amplitude (module docstring:
        ``|i|`` grows away from MTPA along the curve)."""
        sign = 1.0 if torque >= 0 else -1.0
        d, q = self.mtpa(torque)
        i_s, v = math.hypot(d, q), math.sqrt(self._v2(d, q, self.p * speed))
        # the MTPA point of the limit's torque lies on the current limit (at base
        # speed on both): round-off does not move it off (as SaturatedEnvelope)
        if i_s <= self.I * (1 + 1e-12) and v <= self.V * (1 + 1e-9):
            return OperatingPoint(d, q, float(torque), "mtpa")
        lim = limit if limit is not None else self.max_torque_point(speed, sign)
        if sign * torque >= sign * lim.torque:
            return lim
        if v <= self.V:   # MTPA within the voltage limit, beyond I
            return lim
        fw = self._field_weakening(torque, speed)
        if fw is None or math.hypot(*fw) > self.I * (1 + 1e-9):
            return lim
        return OperatingPoint(fw[0], fw[1], float(torque), "field_weakening")

    def _field_weakening(self, torque: float, speed: float) -> tuple[float, float] | None:
        """The least-``|i|`` real root of the field-weakening quartic
        (:meth:`operating_point`; ``P1 = R i_d D - w Lq tau``, ``P2 = R tau +
        w (Ld i_d + psi) D``, quadratics in ``i_d``, squared by hand), each
        polished by two Newton steps and kept where ``D > 0`` and ``|v| = V``
        to 1e-9 (not a root of the factor ``D^2``); None when none is."""
        tau, w, R, V2 = torque / self.kt, self.p * speed, self.R, self.V ** 2
        psi, Ld, Lq, a = self.flux, self.Ld, self.Lq, self.Ld - self.Lq
        p0, p1, p2 = R * a, R * psi, -w * Lq * tau
        r0, r1, r2 = w * Ld * a, w * psi * (Ld + a), w * psi * psi + R * tau
        Q = [p0 * p0 + r0 * r0, 2.0 * (p0 * p1 + r0 * r1),
             p1 * p1 + 2.0 * p0 * p2 + r1 * r1 + 2.0 * r0 * r2 - V2 * a * a,
             2.0 * (p1 * p2 + r1 * r2) - 2.0 * V2 * a * psi, p2 * p2 + r2 * r2 - V2 * psi * psi]
        dQ = [4.0 * Q[0], 3.0 * Q[1], 2.0 * Q[2], Q[3]]
        best = None
        for z in _poly_roots(Q):
            x = z.real
            if abs(z.imag) > 1e-7 * (abs(x) + self.I):
                continue
            for _ in range(2):
                der = ((dQ[0] * x + dQ[1]) * x + dQ[2]) * x + dQ[3]
                step = ((((Q[0] * x + Q[1]) * x + Q[2]) * x + Q[3]) * x + Q[4]) / der \
                    if der != 0 else math.inf
                if not abs(step) < 1e-6 * self.I:
                    break
                x -= step
            den = psi + a * x
            if not den > 1e-9 * psi:
                continue
            q = tau / den
            if abs(math.sqrt(self._v2(x, q, w)) - self.V) > 1e-9 * self.V:
                continue
            if best is None or x * x + q * q < best[0] ** 2 + best[1] ** 2:
                best = (x, q)
        return best

    def current_reference(self, torque: float, speed: float) -> tuple[float, float]:
        """``(i_d, i_q)`` (A) of :meth:`operating_point`."""
        op = self.operating_point(torque, speed)
        return op.i_d, op.i_q


def envelope_of(motor, drive=None, *, v_max: float | None = None,
                i_max: float | None = None, resistive: bool = True):
    """The operating envelope of ``motor`` on ``drive``: a
    :class:`~toolbox.plant.SaturatedEnvelope` for a saturated motor (``motor.magnetics``),
    else the constant-parameter :class:`OperatingEnvelope`
    (same arguments).

    Parameters
    ----------
    motor : Motor
        The motor; ``motor.magnetics`` selects the class.
    drive, v_max, i_max, resistive
        As :class:`~toolbox.plant.OperatingEnvelope` (the drive's voltage
        and current limits, their overrides, ``R`` kept in the steady state).
    """
    if motor.magnetics is None:
        return OperatingEnvelope(motor, drive, v_max=v_max, i_max=i_max, resistive=resistive)
    # lazy: its fallbacks' scipy.optimize, 0.25 s of start-up a constant motor does not need
    from ._envelope_saturated import SaturatedEnvelope
    return SaturatedEnvelope(motor, drive, v_max=v_max, i_max=i_max, resistive=resistive)
