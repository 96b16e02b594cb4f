"""Saturated (magnetically nonlinear) dq machine models.

A :class:`MagneticModel` is the one object that knows a saturated motor's
flux linkage ``psi(i)``, its inverse ``i(psi)``, the incremental inductance
matrix ``L_inc(i) = d psi / d i`` (with the cross term) and the torque
``tf p (psi_d i_q - psi_q i_d)``. Two sources (``[motor] flux_map`` and
``[motor.saturation]``, toolbox/ARCHITECTURE.md "Saturated motors"):

* ``map``: a flux map, psi_d and psi_q tabulated on a rectangular (i_d, i_q)
  grid (FEA or dynamometer export). ``psi(i)`` is the bilinear interpolant of
  the table (exact at the nodes, linearly extrapolated outside it); ``i(psi)``
  is its inverse by Newton's method.
* ``algebraic``: the algebraic saturation model with self-, cross- and
  bridge saturation written as current from flux (inverse inductance
  functions): Hinkkanen, Pescetto, Molsa, Saarakkala, Pellegrino, Bojoi, "Sensorless
  self-commissioning of synchronous reluctance motors at standstill without
  rotor locking", IEEE Trans. Ind. Appl. 53(3), 2017 (the SyRM model with
  cross saturation; its power-function form with exponents S, T, U, V) and,
  for PM machines, Lelli, Hinkkanen, Giulii Capponi, "A saturation model based
  on a simplified equivalent magnetic circuit for permanent magnet
  machines", Proc. ICEM 2024 (bridge saturation in parallel with a
  Norton-equivalent PM). With ``G_d = a_d0 + a_dd |psi_d|^S + a_dq/(V+2)
  |psi_d|^U |psi_q|^(V+2)``, ``G_q = a_q0 + a_qq |psi_q|^T + a_dq/(U+2)
  |psi_d|^(U+2) |psi_q|^V``, ``psi_b = psi_d - psi_n``, ``s = sqrt(psi_b^2 +
  k_q psi_q^2)``, ``G_b = a_b s^W / (1 + a_bp s^W)``::

      i_d = G_d psi_d + G_b psi_b
      i_q = (G_q + k_q G_b) psi_q

  ``i(psi)`` is this closed form; ``psi(i)`` its inverse by Newton's method
  (the current is the gradient of a convex co-energy, so the Jacobian is
  symmetric positive definite and Newton converges from the linear guess).
  The equation numbers of the two papers are not restated here: the papers
  are not among the project's seeds; the form is the one motulator's
  examples implement (motulator 0.5, ``plot_flux_vector_pmsyrm_5kw.py``).

The simulator integrates the flux linkage (``d psi/dt = v - R i(psi) - w J
psi``) and reads the current from :meth:`MagneticModel.inverse_table`, a
bilinear table on a regular flux grid (:mod:`toolbox.sim`). The nominal
``Ld``, ``Lq`` and ``flux`` a design uses are the incremental inductances at
the rated MTPA point and the d flux at ``i = 0`` (:meth:`MagneticModel.nominal`).
The model is part of the spec stage (a :class:`~toolbox.spec.Motor` carries
it, numpy and scipy only); the small-signal models at an operating point are
:mod:`toolbox.plant`'s (``incremental_dq_matrices``, ``at_operating_point``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["MagneticModel", "AlgebraicSaturation", "FluxMapData", "TABLE_HEADER"]

#: Slots before the two current tables of :meth:`MagneticModel.inverse_table`:
#: psi_d0, 1/dpsi_d, n_d, psi_q0, 1/dpsi_q, n_q, psi_d(i=0), psi_q(i=0).
TABLE_HEADER = 8


@dataclass(frozen=True, eq=False)
class FluxMapData:
    """A flux map: psi_d, psi_q (V s) on the rectangular grid i_d x i_q (A).

    Attributes
    ----------
    i_d : ndarray (n_d,)
        Strictly increasing d currents (A).
    i_q : ndarray (n_q,)
        Strictly increasing q currents (A).
    psi_d, psi_q : ndarray (n_d, n_q)
        Flux linkages (V s) at ``(i_d[j], i_q[k])``.
    source : str
        The file the map was read from.
    sha256 : str
        SHA-256 of the file's bytes (``sha256sum file.csv``), recorded in the
        controller's provenance (:meth:`MagneticModel.data_sha256`).
    """

    i_d: np.ndarray
    i_q: np.ndarray
    psi_d: np.ndarray
    psi_q: np.ndarray
    source: str = ""
    sha256: str = ""


@dataclass(frozen=True, eq=False)
class AlgebraicSaturation:
    """Parameters of the algebraic saturation model (module docstring).

    The ``a_*`` coefficients are inverse inductances in the units motulator
    uses (A / (V s)^(1+exponent)); ``psi_n`` in V s; ``S, T, U, V, W``
    exponents. ``a_b = 0`` gives the SyRM model of Hinkkanen et al. 2017.
    ``current_range`` (A) is the current amplitude the flux tables cover.
    """

    a_d0: float
    a_dd: float
    S: float
    a_q0: float
    a_qq: float
    T: float
    a_dq: float
    U: float
    V: float
    a_b: float = 0.0
    a_bp: float = 0.0
    k_q: float = 0.0
    psi_n: float = 0.0
    W: float = 2.0
    current_range: float = 0.0

    def current(self, psi_d, psi_q):
        """Closed-form ``(i_d, i_q)`` (A) at the flux ``(psi_d, psi_q)`` (V s)."""
        psi_d = np.asarray(psi_d, dtype=float)
        psi_q = np.asarray(psi_q, dtype=float)
        ad, aq = np.abs(psi_d), np.abs(psi_q)
        G_d = (self.a_d0 + self.a_dd * ad ** self.S
               + self.a_dq / (self.V + 2.0) * ad ** self.U * aq ** (self.V + 2.0))
        G_q = (self.a_q0 + self.a_qq * aq ** self.T
               + self.a_dq / (self.U + 2.0) * ad ** (self.U + 2.0) * aq ** self.V)
        psi_b = psi_d - self.psi_n
        s = np.sqrt(psi_b ** 2 + self.k_q * psi_q ** 2)
        G_b = self.a_b * s ** self.W / (1.0 + self.a_bp * s ** self.W)
        return G_d * psi_d + G_b * psi_b, (G_q + self.k_q * G_b) * psi_q


def _newton(f, ta, tb, xa, xb, step, what, iters=80):
    """Solve ``f(x) = t`` elementwise for 2-vectors by Newton's method with a
    central-difference Jacobian (step ``step``) and step halving."""
    xa = np.array(xa, dtype=float)
    xb = np.array(xb, dtype=float)
    ta = np.asarray(ta, dtype=float)
    tb = np.asarray(tb, dtype=float)
    scale = np.maximum(np.abs(ta) + np.abs(tb), 1.0)
    for _ in range(iters):
        fa, fb = f(xa, xb)
        ra, rb = fa - ta, fb - tb
        res = np.abs(ra) + np.abs(rb)
        if np.all(res <= 1e-11 * scale):
            return xa, xb
        pa, pb = f(xa + step, xb)
        ma, mb = f(xa - step, xb)
        j11, j21 = (pa - ma) / (2 * step), (pb - mb) / (2 * step)
        pa, pb = f(xa, xb + step)
        ma, mb = f(xa, xb - step)
        j12, j22 = (pa - ma) / (2 * step), (pb - mb) / (2 * step)
        det = j11 * j22 - j12 * j21
        da = (j22 * ra - j12 * rb) / det
        db = (-j21 * ra + j11 * rb) / det
        lam = np.ones_like(xa)
        for _h in range(30):  # halve the steps that do not reduce the residual
            na, nb = xa - lam * da, xb - lam * db
            ga, gb = f(na, nb)
            worse = (np.abs(ga - ta) + np.abs(gb - tb)) > res
            if not np.any(worse):
                break
            lam = np.where(worse, 0.5 * lam, lam)
        xa, xb = na, nb
    fa, fb = f(xa, xb)
    bad = (np.abs(fa - ta) + np.abs(fb - tb)) > 1e-8 * scale
    if np.any(bad):
        raise ValueError(f"{what}: Newton's method did not converge at "
                         f"{int(bad.sum())} of {bad.size} points")
    return xa, xb


@dataclass(frozen=True, eq=False)
class MagneticModel:
    """A saturated motor's magnetics (module docstring).

    Attributes
    ----------
    kind : {"map", "algebraic"}
    data : FluxMapData or AlgebraicSaturation
    nominal_current : float
        Current amplitude (A) of the nominal point (:meth:`nominal`); the
        spec sets the motor's rated current, else its maximum current.
    """

    kind: str
    data: Any
    nominal_current: float = 0.0

    # ---------------------------------------------------------- maps both ways
    def flux(self, i_d, i_q):
        """Flux linkage ``(psi_d, psi_q)`` (V s) at the current ``(i_d, i_q)`` (A)."""
        i_d = np.asarray(i_d, dtype=float)
        i_q = np.asarray(i_q, dtype=float)
        if self.kind == "map":
            return self._bilinear(i_d, i_q)
        L = self._l0()
        psi0 = self._psi0()
        ga = psi0[0] + L[0] * i_d
        gb = psi0[1] + L[1] * i_q
        return _newton(self.data.current, i_d, i_q, ga, gb, 1e-7, "flux from current")

    def current(self, psi_d, psi_q):
        """Current ``(i_d, i_q)`` (A) at the flux linkage ``(psi_d, psi_q)`` (V s)."""
        if self.kind == "algebraic":
            return self.data.current(psi_d, psi_q)
        psi_d = np.asarray(psi_d, dtype=float)
        psi_q = np.asarray(psi_q, dtype=float)
        L = self._l0()
        psi0 = self._psi0()
        ga = (psi_d - psi0[0]) / L[0]
        gb = (psi_q - psi0[1]) / L[1]
        step = 1e-3 * float(min(np.diff(self.data.i_d).min(), np.diff(self.data.i_q).min()))
        return _newton(self.flux, psi_d, psi_q, ga, gb, step, "current from flux map")

    def incremental_inductance(self, i_d: float, i_q: float) -> np.ndarray:
        """``L_inc = d psi / d i`` (H), 2x2 ``[[Ldd, Ldq], [Lqd, Lqq]]`` at the
        current ``(i_d, i_q)``: of a map, the central difference over one grid
        spacing each side (the slope of the bilinear interpolant averaged over
        the neighbouring cells); of the algebraic model, the inverse of the
        closed form's Jacobian ``d i / d psi`` (central differences, 1e-7 V s)."""
        if self.kind == "map":
            hd = float(np.diff(self.data.i_d).min())
            hq = float(np.diff(self.data.i_q).min())
            pa, pb = self.flux(i_d + hd, i_q)
            ma, mb = self.flux(i_d - hd, i_q)
            qa, qb = self.flux(i_d, i_q + hq)
            na, nb = self.flux(i_d, i_q - hq)
            return np.array([[(pa - ma) / (2 * hd), (qa - na) / (2 * hq)],
                             [(pb - mb) / (2 * hd), (qb - nb) / (2 * hq)]], dtype=float)
        psd, psq = self.flux(i_d, i_q)
        h = 1e-7
        f = self.data.current
        pa, pb = f(psd + h, psq)
        ma, mb = f(psd - h, psq)
        qa, qb = f(psd, psq + h)
        na, nb = f(psd, psq - h)
        G = np.array([[(pa - ma) / (2 * h), (qa - na) / (2 * h)],
                      [(pb - mb) / (2 * h), (qb - nb) / (2 * h)]], dtype=float)
        return np.linalg.inv(G)

    def torque(self, i_d, i_q, pole_pairs: int, torque_factor: float):
        """Electromagnetic torque ``tf p (psi_d i_q - psi_q i_d)`` (N m)."""
        psd, psq = self.flux(i_d, i_q)
        return torque_factor * pole_pairs * (psd * np.asarray(i_q) - psq * np.asarray(i_d))

    def mtpa(self, current: float, pole_pairs: int = 1,
             torque_factor: float = 1.5) -> tuple[float, float]:
        """Maximum torque per ampere at the current amplitude ``current`` (A):
        ``(i_d, i_q)`` maximising :meth:`torque` on the circle, ``i_q > 0``
        (a 181-angle grid over ``i_d = -I sin b, i_q = I cos b``, ``b`` in
        [-90, 90] deg, refined by a bounded scalar search around the best)."""
        from scipy.optimize import minimize_scalar
        b = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 181)
        tq = self.torque(-current * np.sin(b), current * np.cos(b), pole_pairs, torque_factor)
        j = int(np.argmax(tq))
        lo, hi = b[max(j - 1, 0)], b[min(j + 1, len(b) - 1)]
        res = minimize_scalar(
            lambda x: -float(self.torque(-current * np.sin(x), current * np.cos(x),
                                         pole_pairs, torque_factor)),
            bounds=(lo, hi), method="bounded", options={"xatol": 1e-10})
        return float(-current * np.sin(res.x)), float(current * np.cos(res.x))

    def nominal(self, current: float | None = None) -> tuple[float, float, float]:
        """``(Ld, Lq, flux)`` a design uses (the one route): the diagonal
        incremental inductances at the MTPA point of the current amplitude
        ``current`` (A; default :attr:`nominal_current`: the motor's rated
        current, else its maximum current) and the d flux at ``i = 0``
        (the no-load PM flux, which sets the back-EMF). Why that point: the
        incremental inductances fall with current (a q axis to a fifth at
        rated current in the PM-SyRM of tests/plant), so a gain designed at
        ``i = 0`` is too high by that factor at load and the loop goes
        unstable; designed at rated current it is lower than designed at
        light load, which a current loop tolerates."""
        i_d, i_q = self.mtpa(self.nominal_current if current is None else current)
        L = self.incremental_inductance(i_d, i_q)
        return float(L[0, 0]), float(L[1, 1]), float(self._psi0()[0])

    def data_sha256(self) -> str:
        """SHA-256 identifying the magnetic data a design used (the artifact's
        ``provenance.magnetics_sha256``): of a map, the file's bytes as read
        (:attr:`FluxMapData.sha256`; of the table's numbers when built in
        memory); of the algebraic model, the canonical JSON of its parameters
        (sorted keys, floats at ``repr`` precision)."""
        import hashlib
        import json
        d = self.data
        if self.kind == "map":
            if d.sha256:
                return d.sha256
            text = json.dumps({k: np.asarray(getattr(d, k), float).ravel().tolist()
                               for k in ("i_d", "i_q", "psi_d", "psi_q")}, sort_keys=True)
        else:
            text = json.dumps({k: float(getattr(d, k)) for k in d.__dataclass_fields__},
                              sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    # ------------------------------------------------------------- kernel table
    def current_box(self) -> tuple[float, float, float, float]:
        """The current range the tables cover: the map's grid, or
        ``+-current_range`` of the algebraic model (A)."""
        if self.kind == "map":
            return (float(self.data.i_d[0]), float(self.data.i_d[-1]),
                    float(self.data.i_q[0]), float(self.data.i_q[-1]))
        r = float(self.data.current_range)
        return -r, r, -r, r

    def inverse_table(self, n: int = 129) -> np.ndarray:
        """The simulator's current-from-flux table, packed flat:
        :data:`TABLE_HEADER` slots (psi_d0, 1/dpsi_d, n_d, psi_q0, 1/dpsi_q,
        n_q, psi(i=0)) then ``i_d`` and ``i_q`` on the regular flux grid
        ``psi_d0 + j dpsi_d`` x ``psi_q0 + k dpsi_q`` (row-major, ``n`` x ``n``)
        covering the flux of :meth:`current_box` with a 10 % margin. Read by
        bilinear interpolation (linear extrapolation outside)."""
        d0, d1, q0, q1 = self.current_box()
        edge = np.linspace(0.0, 1.0, 41)
        ids = np.concatenate([d0 + (d1 - d0) * edge, np.full(41, d1),
                              d0 + (d1 - d0) * edge, np.full(41, d0)])
        iqs = np.concatenate([np.full(41, q0), q0 + (q1 - q0) * edge, np.full(41, q1),
                              q0 + (q1 - q0) * edge])
        psd, psq = self.flux(ids, iqs)
        lo_d, hi_d = float(psd.min()), float(psd.max())
        lo_q, hi_q = float(psq.min()), float(psq.max())
        md, mq = 0.05 * (hi_d - lo_d), 0.05 * (hi_q - lo_q)
        gd = np.linspace(lo_d - md, hi_d + md, n)
        gq = np.linspace(lo_q - mq, hi_q + mq, n)
        PD, PQ = np.meshgrid(gd, gq, indexing="ij")
        i_d, i_q = self.current(PD.ravel(), PQ.ravel())
        psi0 = self._psi0()
        head = [gd[0], 1.0 / (gd[1] - gd[0]), n, gq[0], 1.0 / (gq[1] - gq[0]), n,
                psi0[0], psi0[1]]
        return np.concatenate([np.array(head, dtype=float), np.asarray(i_d, float),
                               np.asarray(i_q, float)])

    # --------------------------------------------------------------- internals
    def _bilinear(self, i_d, i_q):
        m = self.data
        return _bilinear_grid(m.i_d, m.i_q, (m.psi_d, m.psi_q), i_d, i_q)

    def _psi0(self) -> tuple[float, float]:
        """Flux at zero current (V s)."""
        if self.kind == "map":
            a, b = self._bilinear(np.array(0.0), np.array(0.0))
            return float(a), float(b)
        from scipy.optimize import brentq
        f = self.data
        # i_q = 0 on psi_q = 0 (odd in psi_q); i_d(psi_d, 0) is increasing
        g = lambda x: float(f.current(x, 0.0)[0])  # noqa: E731
        if g(0.0) == 0.0:
            return 0.0, 0.0
        hi = 1.0
        while g(hi) < 0.0:
            hi *= 2.0
        return brentq(g, -1.0 if g(0.0) > 0 else 0.0, hi, xtol=1e-15), 0.0

    def _l0(self) -> tuple[float, float]:
        """Unsaturated diagonal inductances (H) for Newton's first guess."""
        if self.kind == "map":
            m = self.data
            j = int(np.clip(np.searchsorted(m.i_d, 0.0), 1, len(m.i_d) - 1))
            k = int(np.clip(np.searchsorted(m.i_q, 0.0), 1, len(m.i_q) - 1))
            Ld = (m.psi_d[j, k] - m.psi_d[j - 1, k]) / (m.i_d[j] - m.i_d[j - 1])
            Lq = (m.psi_q[j, k] - m.psi_q[j, k - 1]) / (m.i_q[k] - m.i_q[k - 1])
            return float(Ld), float(Lq)
        f = self.data
        psi0 = self._psi0()[0]
        h = 1e-7
        Gd = (f.current(psi0 + h, 0.0)[0] - f.current(psi0 - h, 0.0)[0]) / (2 * h)
        Gq = (f.current(psi0, h)[1] - f.current(psi0, -h)[1]) / (2 * h)
        return 1.0 / float(Gd), 1.0 / float(Gq)


def _bilinear_grid(x, y, Zs, xi, yi):
    """Bilinear interpolation of each ``Z[j, k]`` of ``Zs`` on the rectangular
    grid x, y at (xi, yi), linear extrapolation outside (the edge cells
    extended); the cells and weights are found once for all of them."""
    xi = np.asarray(xi, dtype=float)
    yi = np.asarray(yi, dtype=float)
    j = np.clip(np.searchsorted(x, xi, side="right") - 1, 0, len(x) - 2)
    k = np.clip(np.searchsorted(y, yi, side="right") - 1, 0, len(y) - 2)
    u = (xi - x[j]) / (x[j + 1] - x[j])
    v = (yi - y[k]) / (y[k + 1] - y[k])
    return tuple((1 - u) * ((1 - v) * Z[j, k] + v * Z[j, k + 1])
                 + u * ((1 - v) * Z[j + 1, k] + v * Z[j + 1, k + 1]) for Z in Zs)

