"""Operating envelope of a saturated PMSM: MTPA, field weakening and MTPV
current references from its magnetic model (``toolbox.spec.MagneticModel``),
behind the interface of :class:`~toolbox.plant.OperatingEnvelope`
(toolbox/ARCHITECTURE.md "Operating envelope").

Model: the flux linkage ``psi(i)`` of the magnetic model, ``w = p Omega`` the
electrical speed, ``k = motor.torque_factor``; the steady state of the
flux-linkage model (``d psi/dt = v - R i - w J psi = 0``,
:func:`toolbox.plant.derive_flux_linkage_model`)::

    T = k p (psi_d i_q - psi_q i_d)
    v = R i + w J psi = (R i_d - w psi_q, R i_q + w psi_d)

with ``R`` kept, the limits ``|v| <= V`` and ``|i| <= I`` of
:class:`~toolbox.plant.OperatingEnvelope` (same defaults, same ``HEADROOM``).
With linear flux (``psi = (Ld i_d + flux, Lq i_q)``) every problem below is
the constant-parameter one (``tests/plant/test_envelope_saturated.py``).

The references, each a constrained optimisation over the operating point,
seeded from a 61 x 61 sample of the current disc and solved by Newton's
method on its optimality conditions with the active constraints known (the
Lagrange conditions with one, the two constraints themselves with two;
gradients and Hessians by central differences of step 1e-4, normalised:
exact for quadratic and bilinear functions, ~1e-8 of the model's scale
otherwise), with scipy's SLSQP on the full inequality-constrained problem as
the route when a Newton solve does not converge (a flux map's cell edges,
where its derivatives jump):

* **MTPA**: least ``|i|`` with ``T(i) = T`` (Morimoto et al. 1990's
  criterion, here with the saturated torque; no closed form).
* **Field weakening**: least ``|i|`` with ``T(i) = T`` and ``|v| <= V``: the
  point of the torque curve nearest MTPA on the voltage limit.
* **Maximum torque at a speed**: largest ``sign x T`` with ``|i| <= I`` and
  ``|v| <= V``: the current limit's MTPA point when it fits the voltage,
  else the MTPV point (largest torque on ``|v| = V``) when within the
  current limit, else the corner of both limits. MTPV beyond the model's
  current range (the map's grid, the algebraic model's ``current_range``) is
  NaN: the data end there.

Coordinates: a flux map's model is cheap from current (bilinear), the
algebraic model from flux (closed form ``i(psi)``, its inverse is Newton's
method), so the problems are posed over the current (map) or over the flux
(algebraic), normalised by the current limit and the unsaturated
inductances. Each evaluation returns the quantities and their central
differences in one vectorised call of the model.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize, minimize_scalar

from ..errors import SpecError
from ._envelope import OperatingEnvelope, OperatingPoint

__all__ = ["SaturatedEnvelope"]

#: Samples per axis of the seed grid over the current disc.
_N_SAMPLE = 61
#: Step of the central differences in normalised coordinates.
_H = 1e-6
#: Relative tolerance of "on a limit" (region labels) and of feasibility
#: (|i|^2 / I^2, |v|^2 / V^2: 5e-7 of the amplitude); SLSQP's results to 1e-5
#: (its constraint accuracy on a map's cell edges, 5e-6 of the amplitude).
_TOL = 1e-6
_TOL_SLSQP = 1e-5
#: Step of the Newton stencil (normalised): its central differences are
#: exact to ~h^2 x the third derivative, 1e-8 of the model's scale.
_H_NEWTON = 1e-4
#: Newton iterations before the SLSQP route takes over; the largest step.
_N_NEWTON = 30
_MAX_STEP = 0.2


class SaturatedEnvelope:
    """MTPA, field-weakening and MTPV references of a saturated motor on a
    drive (module docstring); the interface of
    :class:`~toolbox.plant.OperatingEnvelope`: :meth:`operating_point`,
    :meth:`current_reference`, :meth:`max_torque_point`, :meth:`mtpv`,
    :meth:`mtpa`, :meth:`torque`, :meth:`voltage`, :meth:`base_speed`,
    ``V``, ``I``, ``HEADROOM``.

    Parameters
    ----------
    motor : Motor
        With ``magnetics`` (a :class:`toolbox.spec.MagneticModel`), ``R``,
        ``pole_pairs``, ``torque_factor``; ``max_current`` or
        ``rated_current`` unless ``i_max`` is given.
    drive, v_max, i_max, resistive
        As :class:`~toolbox.plant.OperatingEnvelope`.
    """

    HEADROOM = OperatingEnvelope.HEADROOM

    def __init__(self, motor, drive=None, *, v_max: float | None = None,
                 i_max: float | None = None, resistive: bool = True) -> None:
        if motor.magnetics is None:
            raise SpecError("motor.saturation", "a saturated motor (flux_map or "
                            "[motor.saturation]) for the saturated envelope", None)
        lin = OperatingEnvelope(motor, drive, v_max=v_max, i_max=i_max, resistive=resistive)
        self.motor = motor
        self.mag = motor.magnetics
        self.V, self.I, self.R = lin.V, lin.I, lin.R
        self.p = motor.pole_pairs
        self.kt = float(motor.torque_factor) * motor.pole_pairs
        self._by_flux = self.mag.kind == "algebraic"
        L0 = self.mag.incremental_inductance(0.0, 0.0)
        if self._by_flux:
            psi0 = self.mag.flux(0.0, 0.0)
            self._x0 = np.array([float(psi0[0]), float(psi0[1])])
            self._s = np.array([float(L0[0, 0]), float(L0[1, 1])]) * self.I
        else:
            self._x0 = np.zeros(2)
            self._s = np.array([self.I, self.I])
        d0, d1, q0, q1 = self.mag.current_box()
        #: current amplitude (A) within the model's data (map grid / table range)
        self.model_range = float(min(-d0, d1, -q0, q1))
        self._mtpa_cache: dict = {}
        self._limit_cache: dict = {}
        self._torque_of: dict = {}
        self._flux_of: dict = {(0.0, 0.0): tuple(float(x) for x in self.mag.flux(0.0, 0.0))}
        self._sample()

    # ------------------------------------------------------------ the model
    def _state(self, u):
        """``(i_d, i_q, psi_d, psi_q)`` at normalised coordinates ``u``
        (arrays, leading axis 2)."""
        x_d = self._x0[0] + self._s[0] * u[0]
        x_q = self._x0[1] + self._s[1] * u[1]
        if self._by_flux:
            i_d, i_q = self.mag.current(x_d, x_q)
            return np.asarray(i_d), np.asarray(i_q), x_d, x_q
        ps_d, ps_q = self.mag.flux(x_d, x_q)
        return x_d, x_q, np.asarray(ps_d), np.asarray(ps_q)

    def _sample(self) -> None:
        """The seed grid of the current disc ``|i| <= I``."""
        (self._U, self._si, self._spsi, self._sT) = self._disc(self.I)
        self._Tscale = max(float(np.abs(self._sT).max()), 1e-12)
        self._wide = None

    def _disc(self, radius):
        """Samples of the disc ``|i| <= radius``: the rectangle of
        coordinates covering it (its flux image for the algebraic model),
        kept where ``|i| <= radius``; ``(U, (i_d, i_q), (psi_d, psi_q), T)``."""
        if self._by_flux:
            b = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
            pd, pq = self.mag.flux(radius * np.cos(b), radius * np.sin(b))
            ud = (np.asarray(pd) - self._x0[0]) / self._s[0]
            uq = (np.asarray(pq) - self._x0[1]) / self._s[1]
            lo_d, hi_d, lo_q, hi_q = ud.min(), ud.max(), uq.min(), uq.max()
            md, mq = 0.05 * (hi_d - lo_d), 0.05 * (hi_q - lo_q)
            gd = np.linspace(lo_d - md, hi_d + md, _N_SAMPLE)
            gq = np.linspace(lo_q - mq, hi_q + mq, _N_SAMPLE)
        else:
            gd = gq = np.linspace(-1.0, 1.0, _N_SAMPLE) * (radius / self.I)
        U = np.array(np.meshgrid(gd, gq, indexing="ij")).reshape(2, -1)
        i_d, i_q, ps_d, ps_q = self._state(U)
        keep = i_d ** 2 + i_q ** 2 <= radius ** 2 * (1 + 1e-9)
        keep |= np.hypot(U[0], U[1]) == np.hypot(U[0], U[1]).min()   # i = 0's neighbour
        return (U[:, keep], (i_d[keep], i_q[keep]), (ps_d[keep], ps_q[keep]),
                self.kt * (ps_d[keep] * i_q[keep] - ps_q[keep] * i_d[keep]))

    def _quantities(self, u, speed):
        """Torque / T scale, ``|i|^2 / I^2`` and ``|v|^2 / V^2`` at ``u``
        (arrays broadcast over the trailing axes)."""
        i_d, i_q, ps_d, ps_q = self._state(u)
        w = self.p * speed
        T = self.kt * (ps_d * i_q - ps_q * i_d) / self._Tscale
        c = (i_d ** 2 + i_q ** 2) / self.I ** 2
        v = ((self.R * i_d - w * ps_q) ** 2 + (self.R * i_q + w * ps_d) ** 2) / self.V ** 2
        return np.array([T, c, v])

    def _evaluator(self, speed):
        """``f(u) -> (values (3,), jacobian (3, 2))`` of :meth:`_quantities`
        (central differences, one vectorised call), cached on the last ``u``."""
        last: dict = {}
        offs = np.array([[0.0, _H, -_H, 0.0, 0.0], [0.0, 0.0, 0.0, _H, -_H]])

        def f(u):
            key = (float(u[0]), float(u[1]))
            if last.get("key") != key:
                q = self._quantities(np.asarray(u, float)[:, None] + offs, speed)
                jac = np.stack([(q[:, 1] - q[:, 2]) / (2 * _H), (q[:, 3] - q[:, 4]) / (2 * _H)],
                               axis=1)
                last.update(key=key, val=q[:, 0], jac=jac)
            return last["val"], last["jac"]
        return f

    def _solve(self, speed, objective, eq=None, ineq=(), seed=None):
        """SLSQP over ``u``: minimise ``objective(val, jac) -> (f, g)`` with
        equality ``eq(val, jac) -> (h, dh)`` and inequalities ``>= 0``."""
        f = self._evaluator(speed)
        cons = []
        if eq is not None:
            cons.append({"type": "eq", "fun": lambda u: eq(*f(u))[0],
                         "jac": lambda u: eq(*f(u))[1]})
        for g in ineq:
            cons.append({"type": "ineq", "fun": (lambda g: lambda u: g(*f(u))[0])(g),
                         "jac": (lambda g: lambda u: g(*f(u))[1])(g)})
        res = minimize(lambda u: objective(*f(u))[0], seed, jac=lambda u: objective(*f(u))[1],
                       method="SLSQP", constraints=cons,
                       options={"ftol": 1e-11, "maxiter": 200})
        return res.x, f(res.x)[0]

    def _stencil(self, u, speed):
        """Values (3,), gradients (3, 2) and Hessians (3, 2, 2) of
        :meth:`_quantities` at ``u`` by central differences (step
        :data:`_H_NEWTON`, one vectorised call of seven points)."""
        h = _H_NEWTON
        off = np.array([[0.0, h, -h, 0.0, 0.0, h, -h], [0.0, 0.0, 0.0, h, -h, h, -h]])
        q = self._quantities(u[:, None] + off, speed)
        g = np.stack([(q[:, 1] - q[:, 2]) / (2 * h), (q[:, 3] - q[:, 4]) / (2 * h)], axis=1)
        hdd = (q[:, 1] - 2 * q[:, 0] + q[:, 2]) / h ** 2
        hqq = (q[:, 3] - 2 * q[:, 0] + q[:, 4]) / h ** 2
        hdq = ((q[:, 5] + q[:, 6] - q[:, 1] - q[:, 2] - q[:, 3] - q[:, 4] + 2 * q[:, 0])
               / (2 * h * h))
        H = np.stack([np.stack([hdd, hdq], axis=1), np.stack([hdq, hqq], axis=1)], axis=1)
        return q[:, 0], g, H

    def _newton(self, speed, seed, eqs, obj=None, bound=None):
        """Newton's method on the conditions of a problem with known active
        constraints: ``eqs`` = [(index, target)] equalities on
        :meth:`_quantities`; with ``obj = (index, sign)`` one equality and
        the stationarity of ``sign x q[index]`` along it (Lagrange, Hessians
        by central differences), without it two equalities (a square
        system). Returns ``u``, None when it does not converge, or NaNs when
        an iterate's ``|i|^2 / I^2`` exceeds ``bound``."""
        u = np.array(seed, float)
        lam = None
        back = [None, None]   # the last two iterates: a 2-cycle is a cell edge's kink
        for _ in range(_N_NEWTON):
            val, g, H = self._stencil(u, speed)
            if bound is not None and val[1] > bound:
                return np.full(2, np.nan)
            if obj is None:
                (a, ta), (b, tb) = eqs
                r = np.array([val[a] - ta, val[b] - tb])
                Jm = np.array([g[a], g[b]])
                try:
                    du = -np.linalg.solve(Jm, r)
                except np.linalg.LinAlgError:
                    return None
                step = du
            else:
                (a, ta), = eqs
                k, sg = obj
                gf, gc = sg * g[k], g[a]
                if lam is None:
                    lam = float(gf @ gc / max(gc @ gc, 1e-300))
                r = np.array([*(gf - lam * gc), val[a] - ta])
                K = np.zeros((3, 3))
                K[:2, :2] = sg * H[k] - lam * H[a]
                K[:2, 2] = -gc
                K[2, :2] = gc
                try:
                    d = -np.linalg.solve(K, r)
                except np.linalg.LinAlgError:
                    return None
                step = d[:2]
            n = float(np.hypot(*step))
            if n > _MAX_STEP:
                step = step * (_MAX_STEP / n)
            elif obj is not None:
                lam += float(d[2])
            u = u + step
            if n < 1e-11 and np.all(np.abs(r) < 1e-9):
                return u
            if back[0] is not None and float(np.hypot(*(u - back[0]))) < 1e-9:
                return None
            back = [back[1], u.copy()]
        return None

    # constraint/objective pieces over (val, jac) of _quantities
    @staticmethod
    def _cur_le(val, jac):
        return 1.0 - val[1], -jac[1]

    @staticmethod
    def _volt_le(val, jac):
        return 1.0 - val[2], -jac[2]

    def _point(self, u):
        i_d, i_q, ps_d, ps_q = self._state(np.asarray(u, float))
        d, q = float(i_d), float(i_q)
        self._torque_of[(d, q)] = float(self.kt * (ps_d * i_q - ps_q * i_d))
        self._flux_of[(d, q)] = (float(ps_d), float(ps_q))
        return d, q

    def _seed(self, score):
        return self._U[:, int(np.argmin(score))].copy()

    def _sample_v2(self, speed):
        w = self.p * speed
        (i_d, i_q), (ps_d, ps_q) = self._si, self._spsi
        return ((self.R * i_d - w * ps_q) ** 2 + (self.R * i_q + w * ps_d) ** 2) / self.V ** 2

    # ------------------------------------------------------------ interface
    def torque(self, i_d, i_q):
        """Torque (N m) of the currents (A): :meth:`MagneticModel.torque`
        (points this envelope returned are looked up); NaN currents give NaN."""
        if np.ndim(i_d) == 0 and np.ndim(i_q) == 0:
            key = (float(i_d), float(i_q))
            if not (math.isfinite(key[0]) and math.isfinite(key[1])):
                return float("nan")
            if key not in self._torque_of:
                self._torque_of[key] = float(self.mag.torque(key[0], key[1], self.p,
                                                             self.motor.torque_factor))
            return self._torque_of[key]
        return self.mag.torque(i_d, i_q, self.p, self.motor.torque_factor)

    def voltage(self, i_d, i_q, speed):
        """Steady-state ``(v_d, v_q)`` (V) at the mechanical speed (rad/s)."""
        ps_d, ps_q = self.mag.flux(i_d, i_q)
        w = self.p * speed
        return (self.R * np.asarray(i_d) - w * ps_q, self.R * np.asarray(i_q) + w * ps_d)

    def mtpa(self, torque: float) -> tuple[float, float]:
        """MTPA currents ``(i_d, i_q)`` (A) for a torque (N m), no limits:
        least ``|i|`` on the torque curve."""
        if torque == 0:
            return 0.0, 0.0
        if torque not in self._mtpa_cache:
            t = torque / self._Tscale
            seed = self._seed(self._sample_c() + 100.0 * (self._sT / self._Tscale - t) ** 2)
            u = self._newton(0.0, seed, [(0, t)], obj=(1, 1.0))
            if u is None and not self._by_flux:
                u = self._map_mtpa(t, seed)
            if u is None:
                u, _ = self._solve(0.0, lambda v, j: (v[1], j[1]),
                                   eq=lambda v, j: (v[0] - t, j[0]), seed=seed)
            self._mtpa_cache[torque] = self._point(u)
        return self._mtpa_cache[torque]

    def _map_mtpa(self, t, seed):
        """A map's MTPA point of the torque ``t`` (normalised) where Newton's
        method stalls on a cell edge: along the torque curve by the current
        angle ``b`` (the amplitude ``r(b)`` giving the torque, brentq), the
        least ``r`` by a bounded scalar search within 0.3 rad of the seed's
        angle; None when the torque curve leaves the model's range there."""
        sg = math.copysign(1.0, t)
        r_hi = self.model_range / self.I

        def tq(r, b):
            return sg * float(self._quantities(np.array([r * math.cos(b), r * math.sin(b)]),
                                               0.0)[0]) - sg * t

        def r_of(b):
            if tq(r_hi, b) < 0:
                return 10.0 * r_hi   # the torque is not reached within the range
            return brentq(lambda r: tq(r, b), 0.0, r_hi, xtol=1e-13)

        b0 = math.atan2(seed[1] * self._s[1], seed[0] * self._s[0])
        res = minimize_scalar(r_of, bounds=(b0 - 0.3, b0 + 0.3), method="bounded",
                              options={"xatol": 1e-12})
        if not res.fun < r_hi or abs(res.x - b0) > 0.3 - 1e-6:
            return None
        return np.array([res.fun * math.cos(res.x), res.fun * math.sin(res.x)])

    def _circle_max(self, radius, sign):
        """A map's largest ``sign x T`` on the current circle ``|i| = radius``
        (A) by its angle (361 samples, then a bounded scalar search):
        ``(u, T / T scale)``."""
        b = np.linspace(-math.pi, math.pi, 361)
        rn = radius / self.I

        def tq(a):
            return self._quantities(np.array([rn * np.cos(a), rn * np.sin(a)]), 0.0)[0]

        k = int(np.argmax(sign * tq(b)))
        res = minimize_scalar(lambda a: -sign * float(tq(np.array([a]))[0]),
                              bounds=(b[max(k - 1, 0)], b[min(k + 1, 360)]), method="bounded",
                              options={"xatol": 1e-13})
        return np.array([rn * math.cos(res.x), rn * math.sin(res.x)]), -sign * res.fun

    def _sample_c(self):
        return (self._si[0] ** 2 + self._si[1] ** 2) / self.I ** 2

    def max_torque_point(self, speed: float, sign: float = 1.0) -> OperatingPoint:
        """The largest torque (``sign = 1``; the most negative with -1) the
        limits allow at a mechanical speed (rad/s), and its currents;
        SpecError when no current within the limit fits the voltage limit."""
        key = (float(speed), float(sign))
        if key not in self._limit_cache:
            op = self._max_torque_newton(speed, sign)
            self._limit_cache[key] = (op if op is not None else
                                      self._max_torque(speed, sign, current_limit=True))
        return self._limit_cache[key]

    def _max_torque_newton(self, speed, sign):
        """The maximum torque by the active constraints: the current limit's
        MTPA point when it fits the voltage, else the MTPV point when within
        the current limit, else the corner of both limits; None (the SLSQP
        route) when a step does not converge or the answer is not
        consistent."""
        ck = ("mtpa_limit", float(sign))
        if ck not in self._limit_cache:
            if self._by_flux:
                seed = self._seed(np.where(self._sample_c() >= 0.9, -sign * self._sT, np.inf))
                self._limit_cache[ck] = self._newton(0.0, seed, [(1, 1.0)], obj=(0, -sign))
            else:   # a map's circle by its angle (its cell edges stall Newton's method)
                self._limit_cache[ck] = self._circle_max(self.I, sign)[0]
        u = self._limit_cache[ck]
        if u is None:
            return None
        v2 = self._sample_v2(speed)
        ok = v2 <= 1.0
        val = self._quantities(u, speed)
        if val[2] <= 1.0:
            d, q = self._point(u)
            return OperatingPoint(d, q, self._torque_of[(d, q)], self._region(val))
        if not ok.any():
            return None
        k = int(np.argmin(np.where(ok, -sign * self._sT, np.inf)))
        seed = self._U[:, k].copy()
        # the best sample inside the disc: MTPV there, else the corner of both limits
        inside = self._sample_c()[k] < 0.9
        um = self._newton(speed, seed, [(2, 1.0)], obj=(0, -sign), bound=4.0) if inside else None
        if um is not None and not np.isnan(um[0]):
            val = self._quantities(um, speed)
            if val[1] <= 1.0:
                d, q = self._point(um)
                return OperatingPoint(d, q, self._torque_of[(d, q)], self._region(val))
        uc = self._newton(speed, seed, [(1, 1.0), (2, 1.0)])
        if uc is None:
            return None
        val = self._quantities(uc, speed)
        if sign * val[0] < sign * self._sT[int(np.argmin(np.where(ok, -sign * self._sT, np.inf)))] \
                / self._Tscale - 1e-9:
            return None
        d, q = self._point(uc)
        return OperatingPoint(d, q, self._torque_of[(d, q)], self._region(val))

    def _max_torque(self, speed, sign, current_limit):
        v2 = self._sample_v2(speed)
        ok = v2 <= 1.0
        ineq = [self._volt_le]
        if current_limit:
            ineq.append(self._cur_le)
        else:   # MTPV: the current within the model's data only
            r2 = (self.model_range / self.I) ** 2
            ineq.append(lambda v, j: (r2 - v[1], -j[1]))
        if ok.any():
            seed = self._seed(np.where(ok, -sign * self._sT, np.inf))
        else:   # the least voltage within the current limit: does any current fit?
            seed = self._seed(v2)
            u, val = self._solve(speed, lambda v, j: (v[2], j[2]), ineq=[self._cur_le],
                                 seed=seed)
            if val[2] > 1.0 + _TOL_SLSQP or val[1] > 1.0 + _TOL_SLSQP:
                raise SpecError("drive.vdc", f"a voltage limit the back-EMF at {speed:g} rad/s "
                                "leaves room for within the current limit", self.V)
            seed = u
        u, val = self._solve(speed, lambda v, j: (-sign * v[0], -sign * j[0]), ineq=ineq,
                             seed=seed)
        if val[2] > 1.0 + _TOL_SLSQP or (current_limit and val[1] > 1.0 + _TOL_SLSQP):
            raise SpecError("drive.vdc", f"a voltage limit the back-EMF at {speed:g} rad/s "
                            "leaves room for within the current limit", self.V)
        d, q = self._point(u)
        if not current_limit:
            if val[1] >= (self.model_range / self.I) ** 2 * (1 - _TOL):
                return float("nan"), float("nan")
            return d, q
        return OperatingPoint(d, q, self._torque_of[(d, q)], self._region(val))

    def mtpv(self, speed: float, sign: float = 1.0) -> tuple[float, float]:
        """The MTPV currents (A): the largest torque on the voltage limit at a
        mechanical speed (rad/s), the current limit ignored; NaN when that
        point lies beyond the model's current range (its data end there)."""
        if self._wide is None:
            self._wide = self._disc(self.model_range)
        U, (i_d, i_q), (ps_d, ps_q), T = self._wide
        w = self.p * speed
        v2 = ((self.R * i_d - w * ps_q) ** 2 + (self.R * i_q + w * ps_d) ** 2) / self.V ** 2
        ok = v2 <= 1.0
        if ok.any():
            k = int(np.argmin(np.where(ok, -sign * T, np.inf)))
            r2 = (self.model_range / self.I) ** 2
            if ok.sum() >= 50 and (i_d[k] ** 2 + i_q[k] ** 2) / self.I ** 2 >= 0.95 * r2:
                return float("nan"), float("nan")   # the torque still rises at the data's end
            u = self._newton(speed, U[:, k], [(2, 1.0)], obj=(0, -sign), bound=4.0 * r2)
            if u is not None and not np.isnan(u[0]):
                val = self._quantities(u, speed)
                # a stationary point better than the best sample: MTPV (NaN beyond the data)
                if sign * val[0] * self._Tscale >= sign * T[k] - 1e-9 * self._Tscale:
                    return (float("nan"), float("nan")) if val[1] >= r2 else self._point(u)
        return self._max_torque(speed, sign, current_limit=False)

    @staticmethod
    def _region(val):
        on_i = val[1] >= 1.0 - _TOL
        on_v = val[2] >= 1.0 - _TOL
        return {(True, True): "current_and_voltage_limit", (True, False): "current_limit",
                (False, True): "voltage_limit", (False, False): "mtpa"}[(on_i, on_v)]

    def base_speed(self) -> float:
        """Highest mechanical speed (rad/s) at which the MTPA point of the
        current limit is within the voltage limit: the positive root of
        ``|R i + w J psi(i)|^2 = V^2``, quadratic in ``w``."""
        if "base" not in self._limit_cache:
            op = self.max_torque_point(0.0)
            ps_d, ps_q = self._flux_of[(op.i_d, op.i_q)]
            a = float(ps_d) ** 2 + float(ps_q) ** 2
            b = 2.0 * self.R * (op.i_q * float(ps_d) - op.i_d * float(ps_q))
            c = self.R ** 2 * (op.i_d ** 2 + op.i_q ** 2) - self.V ** 2
            w = 0.0 if c >= 0 else (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
            self._limit_cache["base"] = w / self.p
        return self._limit_cache["base"]

    def operating_point(self, torque: float, speed: float,
                        limit: OperatingPoint | None = None) -> OperatingPoint:
        """Current reference of least amplitude for a torque (N m) at a
        mechanical speed (rad/s) within both limits: MTPA when it fits, else
        the field-weakening point (least ``|i|`` on the torque curve within
        the voltage limit), else the largest torque point of that sign.
        ``limit``: :meth:`max_torque_point` of that speed and sign."""
        sign = 1.0 if torque >= 0 else -1.0
        d, q = self.mtpa(torque)
        w = self.p * speed
        if math.hypot(d, q) <= self.I * (1 + 1e-12):
            ps_d, ps_q = self._flux_of[(d, q)]
            # MTPA of the limit's torque lies on the current limit, at base speed
            # on the voltage limit too: round-off does not move it off
            if math.hypot(self.R * d - w * ps_q, self.R * q + w * ps_d) <= self.V * (1 + 1e-9):
                return OperatingPoint(d, q, float(torque), "mtpa")
        lim = limit if limit is not None else self.max_torque_point(speed, sign)
        if sign * torque >= sign * lim.torque:
            return lim
        t = torque / self._Tscale
        v2 = self._sample_v2(speed)
        seed = self._seed(self._sample_c() + 100.0 * (self._sT / self._Tscale - t) ** 2
                          + 100.0 * np.maximum(v2 - 1.0, 0.0) ** 2)
        u = self._newton(speed, seed, [(0, t), (2, 1.0)])
        val = None if u is None else self._quantities(u, speed)
        if val is None or val[1] > 1.0 + _TOL:
            u, val = self._solve(speed, lambda v, j: (v[1], j[1]), eq=lambda v, j: (v[0] - t, j[0]),
                                 ineq=[self._volt_le], seed=seed)
        if (val[1] > 1.0 + _TOL_SLSQP or val[2] > 1.0 + _TOL_SLSQP
                or abs(val[0] - t) > _TOL_SLSQP * max(abs(t), 1.0)):
            return lim
        d, q = self._point(u)
        return OperatingPoint(d, q, float(torque), "field_weakening")

    def current_reference(self, torque: float, speed: float) -> tuple[float, float]:
        """``(i_d, i_q)`` (A) of :meth:`operating_point`."""
        op = self.operating_point(torque, speed)
        return op.i_d, op.i_q
