"""One current axis of the controller artifact: the executed law and its views.

:class:`AxisController` holds the two-input law ``[i_ref, i_meas] -> v`` the
simulator and the firmware run, its continuous-time twin and the
anti-windup gain; :class:`StateSpaceData` and :class:`Zpk` are the
state-space and zeros-poles-gain forms it is stored and drawn in (with their
JSON readers). The artifact that holds one per axis is
:class:`toolbox.artifact.ControllerArtifact`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ..lti import StateSpace, acker, as_statespace, c2d, ss2tf
from ..errors import ArtifactError
from ._fields import _no_unknown, finite_number

DISCRETISATIONS = ("tustin", "zoh", "foh", "backward_diff", "euler", "native")


def _matrix(value: Any, key: str, rows: int | None = None,
            cols: int | None = None) -> np.ndarray:
    """Read a JSON matrix (list of lists of finite numbers)."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):  # OverflowError: a 400-digit integer
        raise ArtifactError(key, "a matrix (list of lists of numbers)", value) from None
    if arr.ndim == 1 and arr.size == 0:
        arr = arr.reshape(0, 0 if cols is None else cols)
    if arr.ndim != 2:
        raise ArtifactError(key, "a matrix (list of lists of numbers)", value)
    if not np.all(np.isfinite(arr)):
        raise ArtifactError(key, "finite numbers only", value)
    if rows is not None and arr.shape[0] != rows:
        raise ArtifactError(key, f"{rows} rows", f"{arr.shape[0]} rows")
    if cols is not None and arr.shape[1] != cols:
        raise ArtifactError(key, f"{cols} columns", f"{arr.shape[1]} columns")
    return arr


def _list(arr: np.ndarray) -> list:
    return [[float(x) for x in row] for row in np.atleast_2d(arr)] if arr.size else []


@dataclass(frozen=True, eq=False)
class StateSpaceData:
    """State-space matrices, continuous (``dt is None``) or discrete.

    Attributes
    ----------
    A, B, C, D : ndarray
        System matrices (SI units: inputs A, outputs V), kept as read-only
        float copies.
    dt : float or None
        Sample time (s); ``None`` for a continuous system.
    method : str or None
        How the discrete system was obtained (``tustin``, ``zoh``, ...;
        ``native`` for a design made in discrete time).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float | None = None
    method: str | None = None

    def __post_init__(self) -> None:
        # read-only float copies: the artifact is the hinge between the stages, and
        # the analysis keeps results keyed on a live controller (``_axis._MARGINS``,
        # ``_laws._CONTINUOUS``), which an edit of its matrices in place would
        # leave stale
        for name in ("A", "B", "C", "D"):
            arr = np.array(getattr(self, name), dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        n = self.A.shape[0]
        if self.A.shape != (n, n):
            raise ArtifactError("A", "a square matrix", list(self.A.shape))
        if self.B.shape[0] != n or self.C.shape[1] != n:
            raise ArtifactError("B/C", f"{n} rows in B and {n} columns in C",
                            [list(self.B.shape), list(self.C.shape)])
        if self.D.shape != (self.C.shape[0], self.B.shape[1]):
            raise ArtifactError("D", f"shape {(self.C.shape[0], self.B.shape[1])}",
                            list(self.D.shape))

    @property
    def order(self) -> int:
        return self.A.shape[0]

    @classmethod
    def from_statespace(cls, sys: Any, method: str | None = None) -> "StateSpaceData":
        """Wrap a system: a :class:`toolbox.lti.StateSpace` or anything
        :func:`toolbox.lti.as_statespace` reads (python-control systems:
        ``dt`` 0 or None means continuous)."""
        g = as_statespace(sys)
        return cls(g.A, g.B, g.C, g.D, g.dt, method if g.dt else None)

    def to_statespace(self) -> StateSpace:
        """The system as a :class:`toolbox.lti.StateSpace` (continuous when
        ``dt`` is None; ``.to_control()`` gives the python-control one)."""
        return StateSpace(self.A, self.B, self.C, self.D, self.dt)

    def to_json(self) -> dict:
        out: dict[str, Any] = {"A": _list(self.A), "B": _list(self.B),
                               "C": _list(self.C), "D": _list(self.D)}
        if self.dt is not None:
            out["dt"] = self.dt
            out["method"] = self.method
        return out

    @classmethod
    def from_json(cls, data: Any, key: str, discrete: bool) -> "StateSpaceData":
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object with A, B, C, D", data)
        allowed = {"A", "B", "C", "D"} | ({"dt", "method"} if discrete else set())
        _no_unknown(data, allowed, key)
        for name in ("A", "B", "C", "D"):
            if name not in data:
                raise ArtifactError(f"{key}.{name}", "a matrix (missing)")
        A = _matrix(data["A"], f"{key}.A")
        n = A.shape[0] if A.size else 0
        if A.size and A.shape != (n, n):
            raise ArtifactError(f"{key}.A", "a square matrix", list(A.shape))
        A = A.reshape(n, n)
        B = _matrix(data["B"], f"{key}.B")
        C = _matrix(data["C"], f"{key}.C")
        D = _matrix(data["D"], f"{key}.D")
        if n == 0:
            B = B.reshape(0, D.shape[1])
            C = C.reshape(D.shape[0], 0)
        dt = method = None
        if discrete:
            dt = data.get("dt")
            if not finite_number(dt) or not dt > 0:
                raise ArtifactError(f"{key}.dt", "a sample time > 0 (s)", dt)
            method = data.get("method")
            if method not in DISCRETISATIONS:
                raise ArtifactError(f"{key}.method", f"one of {list(DISCRETISATIONS)}", method)
            dt = float(dt)
        try:
            return cls(A, B, C, D, dt, method)
        except ArtifactError as err:
            raise err.under(key) from None


@dataclass(frozen=True, eq=False)
class Zpk:
    """Zeros, poles (rad/s or z-plane) and gain of a SISO transfer function."""

    zeros: np.ndarray
    poles: np.ndarray
    gain: float

    @classmethod
    def from_statespace(cls, sys: Any) -> "Zpk":
        """Zeros, poles and gain of a SISO system (:func:`toolbox.lti.ss2tf`)."""
        num, den = ss2tf(sys)
        num = np.trim_zeros(num, "f")
        if num.size == 0:
            return cls(np.zeros(0, complex), np.roots(den).astype(complex), 0.0)
        gain = float(num[0] / den[0])
        return cls(_sorted_roots(num), _sorted_roots(den), gain)

    def to_json(self) -> dict:
        return {"zeros": [[float(z.real), float(z.imag)] for z in self.zeros],
                "poles": [[float(p.real), float(p.imag)] for p in self.poles],
                "gain": float(self.gain)}

    @classmethod
    def from_json(cls, data: Any, key: str) -> "Zpk":
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object with zeros, poles, gain", data)
        _no_unknown(data, {"zeros", "poles", "gain"}, key)
        roots = {}
        for name in ("zeros", "poles"):
            arr = _matrix(data.get(name, []), f"{key}.{name}", cols=2)
            roots[name] = arr[:, 0] + 1j * arr[:, 1]
        gain = data.get("gain")
        if not finite_number(gain):
            raise ArtifactError(f"{key}.gain", "a finite number", gain)
        return cls(roots["zeros"], roots["poles"], float(gain))


#: A mode of the saturated recursion slower than this many periods counts as
#: on the unit circle (it would let the state drift: windup).
_AW_SLOW_SAMPLES = 1e6


def _continuous_image(z: complex, sample_time: float, method: str | None) -> complex:
    """Discrete mode ``z`` -> ``exp(s Ts)`` of the continuous root it came from.

    Tustin maps ``s = (2/Ts)(z - 1)/(z + 1)``; a real continuous zero beyond
    ``-2/Ts`` lands on the negative real axis and a zero at infinity on
    ``z = -1``, where the sampled recursion would alternate in sign. The exact
    sampling of the same root, ``exp(s Ts)``, is the sensible location (0 for
    a root at infinity).
    """
    if method != "tustin" or abs(z + 1.0) < 1e-12:
        return 0.0
    s = 2.0 / sample_time * (z - 1.0) / (z + 1.0)
    if s.real >= 0.0:
        return 0.0
    return complex(np.exp(s * sample_time))


def _relocated(z: complex, sample_time: float | None, method: str | None) -> complex | None:
    """Where a bad mode of the saturated recursion goes (``None``: keep it).

    * ``|z| > 1``: mirrored into the unit disc (``1/conj(z)``), the same time
      constant but decaying;
    * on or numerically near the circle (time constant above
      :data:`_AW_SLOW_SAMPLES` periods): the origin, since a mode that does
      not decay lets the state drift while saturated (windup);
    * Tustin's modes with ``Re z < 0``: ``exp(s Ts)`` of their continuous root.

    Stable slow modes are kept: they are the controller's own zeros (for a PI
    the zero at ``-Ki/Kp``), and moving them would put more of the clipped
    voltage into the state than Hanus's conditioning does.
    """
    r = abs(z)
    mirrored = r > 1.0 + 1.0 / _AW_SLOW_SAMPLES
    if mirrored:
        z = z / r ** 2
        r = abs(z)
    if r >= math.exp(-1.0 / _AW_SLOW_SAMPLES):
        return 0.0
    if method == "tustin" and z.real < 0.0 and sample_time:
        return _continuous_image(z, sample_time, method)
    return z if mirrored else None


def _antiwindup_gain(A: np.ndarray, B_r: np.ndarray, C: np.ndarray, D_r: float,
                     B_y: np.ndarray | None = None, D_y: float = 0.0,
                     sample_time: float | None = None,
                     method: str | None = None) -> np.ndarray:
    """Anti-windup gain ``aw`` of a law ``x+ = A x + B_r r + B_y y + aw (v_sat - v)``.

    Conditioning technique of Hanus, Kinnaert and Henrotte (1987,
    "Conditioning technique, a general anti-windup and bumpless transfer
    method", Automatica 23(6), 729-739) on the **reference** channel:
    ``aw = B_r / D_r``. Then ``x+ = A x + B_r r_c + B_y y`` with the realisable
    reference ``r_c = r + (v_sat - v)/D_r``, the one for which the law's own
    output (decoupling terms included) would have been exactly ``v_sat``.
    While the voltage limits, the law's state therefore evolves as if it had
    asked for what the inverter produced, and leaves saturation with no
    stored excess. The reference channel, not the measurement or the error:
    for 2-DOF laws (IP, TCI, ILQ, LQ) only the reference is free to be
    re-interpreted (the measurement is what it is), and conditioning on the
    measurement makes the integrator integrate a fictitious current, the
    windup this avoids. For a 1-DOF law the two coincide. For a PI the state
    is left almost frozen while saturated (mode at the controller's zero,
    ``1 - Ts Ki/Kp``), not loaded with the whole clipped voltage.

    While saturated the state obeys ``x+ = (A - aw C) x + ...``, whose poles
    are the zeros of the reference channel. Bad ones are moved (see
    :func:`_relocated`) by pole placement on the dual pair ``(A', C')``; the
    good ones are kept. With no reference feedthrough (``D_r = 0``, e.g. the
    IP structure) there is no realisable reference; the fallback ``aw = 0``
    with the same relocation moves the integrators to the origin, i.e. the
    integral state is reset to the value that reproduces ``v_sat`` (the
    observer-like choice, stable and windup-free), other modes kept.

    Parameters
    ----------
    A, C : ndarray
        Law state and output matrices (n x n, 1 x n).
    B_r : ndarray
        Reference input column (n x 1); ``D_r`` its feedthrough (V/A).
    B_y, D_y : ndarray, float, optional
        Measurement column and feedthrough (unused in the gain; kept so that
        callers pass the whole law).
    sample_time : float, optional
        Period (s), to map Tustin's fast modes back to ``exp(s Ts)``.
    method : str, optional
        Discretisation of the law (``tustin`` enables that mapping).

    Returns
    -------
    ndarray
        ``aw`` (n x 1). When the placement cannot move a bad mode (it is
        unobservable from ``C``, so no correction through the output can),
        the unrelocated conditioning gain.
    """
    n = A.shape[0]
    # D_r is "zero" against the size of the dynamic path C B_r (both V/A)
    scale = float(np.max(np.abs(C)) * np.max(np.abs(B_r))) if n else 0.0
    if abs(D_r) > 1e-12 * scale and D_r != 0.0:
        aw = B_r.reshape(n, 1) / D_r
    else:
        aw = np.zeros((n, 1))
    poles = np.linalg.eigvals(A - aw @ C)
    moved = [_relocated(complex(p), sample_time, method) for p in poles]
    if all(m is None for m in moved):
        return np.real(aw)
    target = np.array([p if m is None else m for p, m in zip(poles, moved)])
    # conjugate symmetry: a relocated complex pair maps to a conjugate pair
    try:
        gain = acker(A.T, C.T, np.sort_complex(target))
    except (ValueError, np.linalg.LinAlgError):
        return np.real(aw)
    aw_new = np.real(np.asarray(gain, float).reshape(n, 1))
    got = np.linalg.eigvals(A - aw_new @ C)
    if not np.all(np.abs(got) < 1.0) or not np.all(np.isfinite(aw_new)):
        return np.real(aw)  # a bad mode is unobservable, or acker lost the accuracy
    return aw_new


def _sorted_roots(poly: np.ndarray) -> np.ndarray:
    roots = np.roots(poly).astype(complex)
    return roots[np.lexsort((roots.imag, roots.real))]


@dataclass(frozen=True, eq=False)
class AxisController:
    """The linear controller of one current loop: one executed law.

    ``law`` is what the simulator and the firmware run; every other view of
    the axis is derived from it (``discrete``, ``zpk``) or is its
    continuous-time twin (``continuous``, same order). Controllers that are
    *not* executed are kept apart under names that say so: ``full_order``
    (the design before an order reduction, when the law runs the reduced
    controller) and ``reduced`` (an order-reduced candidate, when the law runs
    the full-order one).

    Attributes
    ----------
    law : StateSpaceData
        Discrete two-input law ``[i_ref, i_meas] -> v`` actually executed.
        Its measurement channel equals minus the error controller.
    continuous : StateSpaceData or None
        Continuous-time error -> voltage controller of the same law (same
        order; ``None`` for a design made natively in discrete time).
    antiwindup : ndarray or None
        Anti-windup gain (n x 1): the law's state is corrected by
        ``antiwindup * (v_saturated - v_unsaturated)``. By default Hanus's
        conditioning on the reference channel (see :func:`_antiwindup_gain`).
    reduced : AxisController or None
        Order-reduced candidate that is **not** executed (H-infinity with
        ``executed = "full"``); informational.
    full_order : AxisController or None
        The full-order design before the order reduction, **not** executed
        (H-infinity with ``executed = "reduced"``: ``law`` is the reduced
        controller); informational.
    """

    law: StateSpaceData
    continuous: StateSpaceData | None = None
    antiwindup: np.ndarray | None = None
    reduced: "AxisController | None" = None
    full_order: "AxisController | None" = None

    def __post_init__(self) -> None:
        if self.law.dt is None:
            raise ArtifactError("law", "a discrete system (dt > 0)")
        if self.law.B.shape[1] != 2 or self.law.C.shape[0] != 1:
            raise ArtifactError("law", "a two-input ([i_ref, i_meas]), one-output system",
                            [self.law.B.shape[1], self.law.C.shape[0]])
        if self.antiwindup is not None and self.antiwindup.shape != (self.law.order, 1):
            raise ArtifactError("antiwindup", f"a {self.law.order} x 1 matrix",
                            list(self.antiwindup.shape))
        if self.continuous is not None and self.continuous.order != self.law.order:
            # the continuous twin of another controller (e.g. the unreduced
            # design next to a reduced law) would make figures and margins
            # describe a loop that does not run
            raise ArtifactError("continuous", f"the continuous twin of the executed law "
                                f"(order {self.law.order})", f"order {self.continuous.order}",
                                hint="a controller that is not executed belongs under "
                                "full_order or reduced")
        if self.reduced is not None and self.full_order is not None:
            raise ArtifactError("reduced", "either reduced (law runs the full-order "
                                "controller) or full_order (law runs the reduced one), "
                                "not both", "both")

    @property
    def discrete(self) -> StateSpaceData:
        """Error (A) -> voltage (V) view of the executed law at the sample time.

        Derived, never stored: minus the law's measurement channel, same
        states and order as ``law`` (what margins on the sampled loop use).
        """
        law = self.law
        return StateSpaceData(law.A, -law.B[:, 1:2], law.C, -law.D[:, 1:2], law.dt, law.method)

    @property
    def order(self) -> int:
        """Order of the executed law."""
        return self.law.order

    @property
    def zpk(self) -> Zpk:
        """Zeros, poles and gain of the continuous controller (discrete if none)."""
        return Zpk.from_statespace((self.continuous or self.discrete).to_statespace())

    @classmethod
    def from_error_controller(cls, K: Any, sample_time: float, method: str = "tustin",
                              antiwindup: bool = True) -> "AxisController":
        """Build an axis from a continuous one-degree-of-freedom controller.

        The executed law is ``v = K (i_ref - i_meas)``; with ``antiwindup`` the
        gain is Hanus's conditioning ``B_d D_d^{-1}`` (the state is updated as
        if the reference had been the one that produces the saturated voltage),
        with bad saturated modes relocated (:func:`_antiwindup_gain`).
        """
        Kc = as_statespace(K)
        Kd = c2d(Kc, sample_time, method)
        law = StateSpace(Kd.A, np.hstack([Kd.B, -Kd.B]), Kd.C, np.hstack([Kd.D, -Kd.D]),
                         sample_time)
        return cls.from_law(law, error_controller=Kc, sample_time=sample_time,
                            method=method, antiwindup=antiwindup)

    @classmethod
    def from_law(cls, law: Any, *, sample_time: float, method: str,
                 error_controller: Any = None,
                 antiwindup: bool | np.ndarray = True) -> "AxisController":
        """Build an axis from a two-input law ``[i_ref, i_meas] -> v``.

        ``law`` is continuous (``law.dt`` falsy, discretised with ``method``) or
        discrete at ``sample_time`` (``method`` then says how it was obtained).
        The error controller of the loop is minus the measurement channel.
        """
        law = as_statespace(law)
        if not law.discrete:
            law_c = law
            law = c2d(law_c, sample_time, method)
            if error_controller is None:
                error_controller = -law_c[0, 1]
        if isinstance(antiwindup, np.ndarray):
            aw = antiwindup.reshape(law.nstates, 1)
        elif antiwindup and law.nstates:
            aw = _antiwindup_gain(law.A, law.B[:, 0:1], law.C, float(law.D[0, 0]),
                                  law.B[:, 1:2], float(law.D[0, 1]),
                                  sample_time=sample_time, method=method)
        else:
            aw = None
        return cls(
            law=StateSpaceData.from_statespace(law, method),
            continuous=(None if error_controller is None
                        else StateSpaceData.from_statespace(error_controller)),
            antiwindup=aw,
        )

    def to_statespace(self, domain: str = "discrete", *,
                      discrete: bool | None = None) -> StateSpace:
        """The error -> voltage controller (:class:`toolbox.lti.StateSpace`;
        ``.to_control()`` gives the python-control one).

        Parameters
        ----------
        domain : {"discrete", "continuous"}
            ``"discrete"`` (default): the law the firmware executes, ``dt =
            sample_time``. ``"continuous"``: the design model (s domain); a
            design made in discrete time has none (ValueError).
        discrete : bool, optional
            Older spelling: True is ``domain="discrete"``, False ``"continuous"``
            (falling back on the discrete law when there is no continuous one).
        """
        if discrete is not None:
            if discrete or self.continuous is None:
                return self.discrete.to_statespace()
            return self.continuous.to_statespace()
        if domain == "discrete":
            return self.discrete.to_statespace()
        if domain == "continuous":
            if self.continuous is None:
                raise ValueError("this axis was designed in discrete time: it has no "
                                 'continuous model (use domain="discrete")')
            return self.continuous.to_statespace()
        raise ValueError(f'domain: expected "discrete" or "continuous", got {domain!r}')

    def to_json(self) -> dict:
        out: dict[str, Any] = {}
        if self.continuous is not None:
            out["continuous"] = self.continuous.to_json()
        out["zpk"] = self.zpk.to_json()
        out["law"] = self.law.to_json()
        if self.antiwindup is not None:
            out["antiwindup"] = _list(self.antiwindup)
        for name in ("reduced", "full_order"):
            other = getattr(self, name)
            if other is not None:
                out[name] = other.to_json()
        return out

    @classmethod
    def from_json(cls, data: Any, key: str, nested: bool = False) -> "AxisController":
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object (AXIS)", data)
        allowed = {"continuous", "zpk", "law", "antiwindup"}
        if not nested:
            allowed |= {"reduced", "full_order"}
        if "discrete" in data:
            # schema 1 stored it separately (and for paper 003 it was the
            # unreduced 4th-order design next to a 3rd-order law)
            raise ArtifactError(f"{key}.discrete", "no stored discrete controller (it is "
                                "derived from law)", "a stored one (cct.controller/1)",
                                hint="re-run cct design on the spec")
        _no_unknown(data, allowed, key)
        if "law" not in data:
            raise ArtifactError(f"{key}.law", "a discrete system (missing)")
        cont = (StateSpaceData.from_json(data["continuous"], f"{key}.continuous", False)
                if "continuous" in data else None)
        law = StateSpaceData.from_json(data["law"], f"{key}.law", True)
        aw = (_matrix(data["antiwindup"], f"{key}.antiwindup", law.order, 1)
              if "antiwindup" in data else None)
        if "zpk" in data:
            Zpk.from_json(data["zpk"], f"{key}.zpk")  # validated; recomputed on use
        others = {name: cls.from_json(data[name], f"{key}.{name}", nested=True)
                  for name in ("reduced", "full_order") if name in data}
        try:
            return cls(law, cont, aw, **others)
        except ArtifactError as err:
            raise err.under(key) from None
