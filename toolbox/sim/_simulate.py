"""Closed-loop verification: the public entry points :func:`simulate` and
:func:`simulate_batch`, and the plain-data inputs they take.

References
----------
Le Pioufle 1992 (paper 000): PI and total compensation in dq, sampled
simulation with ZOH and one-period computation delay. Cormerais 2002 (paper
002): SVM eq (21)-(22), Boolean predictive control criterion (23), metrics
E_Gamma, E_Id, Nb_c. Takami (paper 001): plant at 1 us, controller at 0.1 ms.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Callable, Mapping, Sequence

import numba
import numpy as np

from toolbox.artifact import CvLaw, Decoupling, FcsWeights  # typed in the artifact; FcsWeights re-exported
from toolbox.errors import SpecError
from toolbox.spec import Motor, Scenario, inverter_radii

from . import _kernel
from ._metrics import METRIC_NAMES, metrics_dict

__all__ = ["DriveParams", "AxisLaw", "SpeedLoop", "FcsWeights",
           "ControlLaw", "SimResult", "BatchResult", "simulate", "simulate_batch",
           "discrete_pi"]


@dataclass(frozen=True)
class DriveParams:
    """Inverter and sampling.

    Parameters
    ----------
    vdc : float
        DC-link voltage (V).
    sample_time : float
        Controller period Ts (s).
    delay_samples : int
        Computation delay: the voltage computed at sample k is applied over
        period k + delay_samples (0 = at once, 1 = paper 000).
    v_limit : str
        ``"circle"`` (|v| <= v_max), ``"hexagon"`` (exact SVM hexagon in the
        stationary frame, at the angle where the voltage is placed:
        theta + t_c w) or ``"none"`` (average model only; with ``"svm"``
        "none" means the hexagon, the most the modulator can produce).
    v_max : float, optional
        Circle radius (V). Default: inscribed circle of the hexagon,
        ``vdc/sqrt(3)`` amplitude-invariant, ``vdc/sqrt(2)`` power-invariant.
    hex_radius : float, optional
        Hexagon vertex radius = length of an active inverter vector (V).
        Default ``2/3 vdc`` (torque_factor 1.5) or ``sqrt(2/3) vdc`` (torque_factor 1).
    inverter : str
        ``"average"``, ``"svm"`` or ``"fcs_mpc"``.
    switching_frequency : float, optional
        PWM carrier frequency (Hz) of the ``"svm"`` inverter: a symmetric
        triangle carrier, regular sampled (duties loaded at each sample and
        held over it), with min-max injection (the carrier form of the
        centred space-vector pattern); ``sample_time`` must be a whole
        number ``n`` of half carrier periods and each period switches over
        ``n`` half periods. None: one centred pattern per sample (the
        carrier at ``1 / sample_time``, paper 002 eq (21)-(22)).
    hold_frame : str
        Frame in which the ``"average"`` inverter holds the commanded voltage
        over a period: ``"rotor"`` (constant ``v_dq``, the ideal average) or
        ``"stationary"`` (constant ``v_alpha_beta`` at the placement angle,
        rotating in dq: what a PWM inverter averages to); the rotor hold
        applies ``v_dq`` rotated by the placement's error from the true
        mid-period angle.
    voltage_priority : str
        How the law's voltage limit brings an unreachable ``v_dq`` back:
        ``"radial"`` (default: scaled towards the origin, both components
        shrink) or ``"d_axis"`` (``v_d`` kept, clamped to the limit, and
        ``v_q`` given the rest, ``sign(v_q) sqrt(V^2 - v_d^2)`` on the circle,
        the hexagon's chord at that ``v_d`` otherwise: what field-weakening
        drives use, so that ``i_d`` holds when ``v_q`` saturates). Anti-windup is
        back-calculation on the difference either way.
    """

    vdc: float
    sample_time: float
    delay_samples: int = 1
    v_limit: str = "circle"
    v_max: float | None = None
    hex_radius: float | None = None
    inverter: str = "average"
    switching_frequency: float | None = None
    hold_frame: str = "rotor"
    voltage_priority: str = "radial"

    def radii(self, torque_factor: float) -> tuple[float, float]:
        """(hexagon vertex radius, circle radius) in V for a dq convention."""
        r_hex = self.hex_radius
        if r_hex is None:
            conventions = {1.5: "amplitude", 1.0: "power"}
            if torque_factor not in conventions:
                raise SpecError("drive.hex_radius", "an explicit hexagon radius (V) for "
                                "torque_factor other than 1.5 or 1", torque_factor)
            r_hex = inverter_radii(self.vdc, conventions[torque_factor])[0]
        v_max = self.v_max if self.v_max is not None else r_hex * math.sqrt(3.0) / 2.0
        return r_hex, v_max


@dataclass(frozen=True)
class AxisLaw:
    """Discrete two-input controller of one current axis (period Ts).

    ``x[k+1] = A x[k] + B [i_ref, i_meas] + antiwindup (v_sat - v_unsat)``,
    ``v = C x[k] + D [i_ref, i_meas]`` (V). Shapes n x n, n x 2, 1 x n, 1 x 2,
    antiwindup n (or None). n may be 0 (static law).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    antiwindup: np.ndarray | None = None

    @classmethod
    def from_error_controller(cls, A, B, C, D, antiwindup=None) -> "AxisLaw":
        """From a one-input discrete controller ``e = i_ref - i_meas -> v``
        (the artifact's AXIS "discrete" entry): B -> [B, -B], D -> [D, -D]."""
        A = np.atleast_2d(np.asarray(A, float)) if np.size(A) else np.zeros((0, 0))
        n = A.shape[0]
        B = np.asarray(B, float).reshape(n, 1)
        C = np.asarray(C, float).reshape(1, n)
        d = float(np.asarray(D, float).reshape(-1)[0])
        return cls(A, np.hstack([B, -B]), C, np.array([[d, -d]]), antiwindup)

    @classmethod
    def from_statespace(cls, sys, antiwindup=None) -> "AxisLaw":
        """From a python-control discrete ``StateSpace`` with inputs [i_ref, i_meas]."""
        return cls(np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C),
                   np.asarray(sys.D), antiwindup)


@dataclass(frozen=True)
class SpeedLoop:
    """Outer speed PID producing i_q,ref (paper 003: Kp 0.5045, KD 0.0045, KI 0.5).

    ``i_q,ref = sat(kp e + ki sum(e) T + kd (e - e_prev)/T, +/- iq_limit)``,
    ``e = speed_ref - Omega_measured`` (rad/s), with conditional integration
    while saturated.

    Parameters
    ----------
    kp : float
        Proportional gain (A s/rad).
    ki : float
        Integral gain (A/rad).
    kd : float
        Derivative gain (A s^2/rad).
    sample_time : float
        Period (s), an integer multiple of the current-loop period.
    iq_limit : float
        Current-reference limit (A).
    """

    kp: float
    ki: float
    kd: float = 0.0
    sample_time: float = 1e-3
    iq_limit: float = math.inf


@dataclass(frozen=True)
class ControlLaw:
    """The whole current-control law: linear axis laws plus what the
    controller believes about the motor.

    Parameters
    ----------
    d, q : AxisLaw
        Linear controllers of the two current loops (outputs in V); not
        used by the ``"fcs_mpc"`` inverter, which chooses switch states directly.
    sample_time : float
        Period the discrete controllers were designed for (s).
    decoupling : Decoupling
        The artifact's controller-side model (``R_c``, ``Ld_c``, ``Lq_c``,
        ``flux_c``) and decoupling flags: ``v_d += -cross w_m Lq_c iq_m``,
        ``v_q += cross w_m Ld_c id_m + emf w_m flux_c`` with ``w_m = p
        Omega_m``; the predictive law of ``fcs_mpc`` predicts with the same
        model. It is what the controller believes, a distinct concept from
        the true plant (a :class:`toolbox.spec.Motor`) it controls.
        Its ``delay_compensation_time`` ``t_c`` places the voltage as the
        firmware header does: at the sampled angle plus ``t_c`` times the
        measured electrical speed (toolbox/ARCHITECTURE.md "The digital loop").
    speed_loop : SpeedLoop, optional
        Outer loop for ``speed_step`` and ``load_step`` scenarios.
    fcs : FcsWeights, optional
        Weights for the ``"fcs_mpc"`` inverter.
    cv : CvLaw, optional
        The complex-vector law of method ``cv``: executed instead of ``d``
        and ``q`` (which then give the size of its state: the integrator and
        ``delay_samples`` delayed voltages, the coordinates of the artifact's
        standstill axes), its gains recomputed each period at the measured
        speed (``_kernel_cv``); ``decoupling.cross`` must be off.
    """

    d: AxisLaw
    q: AxisLaw
    sample_time: float
    decoupling: Decoupling
    speed_loop: SpeedLoop | None = None
    fcs: FcsWeights | None = None
    cv: CvLaw | None = None


@dataclass
class SimResult:
    """Result of :func:`simulate`.

    ``metrics`` maps the names of :data:`toolbox.sim._metrics.METRIC_NAMES` to
    floats (units in that module). Traces (None unless the scenario keeps
    them) are sampled at controller instants: t (s), id, iq, id_ref, iq_ref (A),
    vd, vq (V, average applied voltage over the period; a saturated command
    is scaled along its direction onto the limit), speed and
    speed_measured (mechanical rad/s), torque (N m).
    """

    metrics: dict
    t: np.ndarray | None = None
    id: np.ndarray | None = None
    iq: np.ndarray | None = None
    vd: np.ndarray | None = None
    vq: np.ndarray | None = None
    speed: np.ndarray | None = None
    torque: np.ndarray | None = None
    id_ref: np.ndarray | None = None
    iq_ref: np.ndarray | None = None
    speed_measured: np.ndarray | None = None


@dataclass
class BatchResult:
    """Result of :func:`simulate_batch`: ``metrics[name]`` is an array of length N."""

    metrics: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(next(iter(self.metrics.values()))) if self.metrics else 0


def discrete_pi(kp: float, ki: float, sample_time: float, antiwindup: bool = True
                ) -> AxisLaw:
    """Discrete PI (forward-Euler integrator) as an :class:`AxisLaw`.

    ``v[k] = kp e[k] + ki x[k]``, ``x[k+1] = x[k] + Ts e[k]``, ``e = i_ref - i_meas``.

    Parameters
    ----------
    kp : float
        Proportional gain (V/A).
    ki : float
        Integral gain (V/(A s)).
    sample_time : float
        Controller period Ts (s).
    antiwindup : bool
        Hanus's conditioning on the reference (Hanus, Kinnaert and Henrotte
        1987, Automatica 23(6)): ``aw = B_r / D_r = Ts / kp``, i.e. the
        integrator integrates the error of the reference that would have
        produced the saturated voltage. While saturated the state decays
        at the PI zero (``x+ = (1 - Ts ki/kp) x + ...``) instead of being
        loaded with the whole clipped voltage (``aw = 1/ki``, deadbeat),
        which left ``v`` at ``ki x ~ R i_ref`` after saturation and the
        current crawling at the open-loop ``R/L``.
    """
    Ts = sample_time
    aw = np.array([Ts / kp]) if (antiwindup and kp != 0) else None
    return AxisLaw(np.array([[1.0]]), np.array([[Ts, -Ts]]), np.array([[ki]]),
                   np.array([[kp, -kp]]), aw)


# ----------------------------------------------------------------- packing
def _packed(array: str, **values: float) -> np.ndarray:
    """A kernel parameter array filled by slot name (``_kernel.LAYOUTS[array]``).

    Every slot must be given: a slot added to the layout and forgotten here
    is a bug caught at once, not a silent zero.
    """
    names = _kernel.LAYOUTS[array]
    missing = set(names) - set(values)
    unknown = set(values) - set(names)
    if missing or unknown:  # internal inconsistency, not a user error
        raise ValueError(f"kernel array {array}: missing slots {sorted(missing)}, "
                         f"unknown slots {sorted(unknown)}")
    return np.array([values[n] for n in names], dtype=float)


def _pack_law(law: ControlLaw):
    axes = (law.d, law.q)
    n = max(1, max(np.atleast_2d(np.asarray(ax.A, float)).shape[0]
                   if np.size(ax.A) else 0 for ax in axes))
    A = np.zeros((2, n, n))
    B = np.zeros((2, n, 2))
    C = np.zeros((2, n))
    D = np.zeros((2, 2))
    W = np.zeros((2, n))
    for i, (name, ax) in enumerate(zip("dq", axes)):
        m = np.size(ax.A) and np.atleast_2d(np.asarray(ax.A, float)).shape[0]
        try:
            if m:
                A[i, :m, :m] = np.asarray(ax.A, float).reshape(m, m)
                B[i, :m, :] = np.asarray(ax.B, float).reshape(m, 2)
                C[i, :m] = np.asarray(ax.C, float).reshape(m)
                if ax.antiwindup is not None:
                    W[i, :m] = np.asarray(ax.antiwindup, float).reshape(m)
            D[i] = np.asarray(ax.D, float).reshape(2)
        except ValueError as exc:
            raise SpecError(f"law.{name}", f"A {m}x{m}, B {m}x2, C 1x{m}, D 1x2, "
                            f"antiwindup {m}", str(exc)) from None
    # one isfinite over all five (each np.all(np.isfinite(.)) cost ~1.6 us per call)
    if not np.isfinite(np.concatenate([a.ravel() for a in (A, B, C, D, W)])).all():
        raise SpecError("law", "finite controller matrices", "NaN or inf")
    f = law.fcs or FcsWeights()
    dec = law.decoupling
    cv = law.cv
    if cv is not None and (np.shape(law.d.A) != np.shape(law.q.A) or not np.size(law.d.A)):
        raise SpecError("law.cv", "standstill axes of equal order >= 1 (the integrator and "
                        "the design's delayed voltages)", [np.shape(law.d.A), np.shape(law.q.A)])
    if cv is not None and dec.cross:
        raise SpecError("law.decoupling.cross", "false with a cv law (its gains hold the "
                        "dq coupling)", True)
    pc, pi, pd = (0.0, 0.0, 0.0) if cv is None else cv.poles(law.sample_time, 1)
    # the cv law's design delay: its standstill axes hold the integrator and that
    # many delayed voltages (toolbox.design.cv_discrete.standstill_axes)
    cv_d = n - 1 if cv is not None else 0
    LP = _packed("LP", R_c=dec.R_c, Ld_c=dec.Ld_c, Lq_c=dec.Lq_c, flux_c=dec.flux_c,
                 cross=float(dec.cross), emf=float(dec.emf), alpha=f.alpha, beta=f.beta,
                 gamma=f.gamma, cv=float(cv is not None), cv_pc=pc, cv_pi=pi, cv_pd=pd,
                 cv_d=cv_d)
    return A, B, C, D, W, LP


def _half_periods(drive: DriveParams) -> int:
    """Carrier half periods per sample (0: no carrier given, one centred pattern)."""
    fsw = drive.switching_frequency
    if fsw is None:
        return 0
    n = drive.sample_time * 2.0 * fsw if (fsw > 0 and math.isfinite(fsw)) else 0.0
    if n < 1 - 1e-9 or abs(n - round(n)) > 1e-6:
        raise SpecError("drive.switching_frequency", "a carrier with a whole number of "
                        f"half periods per sample ({drive.sample_time} s)", fsw)
    return int(round(n))


#: Largest plant step as a fraction of the fastest electrical time constant
#: ``min(Ld, Lq) / R``: RK4's local error then stays below 1e-8 of the state
#: per step, so a stable loop is never failed by integration error.
STIFF_STEP_FRACTION = 0.05


def plant_step(scenario: Scenario, plants) -> float:
    """The plant integration step (s): the scenario's ``plant_step``, reduced
    to :data:`STIFF_STEP_FRACTION` of the fastest electrical time constant of
    ``plants`` (a motor with L/R below 20 us: the 1 us default would be
    unstable or inaccurate)."""
    tau = min(min(p.Ld, p.Lq) / p.R for p in plants)
    return min(scenario.plant_step, STIFF_STEP_FRACTION * tau)


def _pack(law: ControlLaw, plant: Motor, scenario: Scenario, drive: DriveParams,
          plants=None):
    Ts = drive.sample_time
    if not (Ts > 0 and math.isfinite(Ts)):
        raise SpecError("drive.sample_time", "a number > 0 (s)", Ts)
    if abs(law.sample_time - Ts) > 1e-12 * Ts:
        raise SpecError("drive.sample_time", f"the controller's sample time "
                        f"({law.sample_time} s)", Ts)
    if not (isinstance(drive.delay_samples, (int, np.integer)) and drive.delay_samples >= 0):
        raise SpecError("drive.delay_samples", "an integer >= 0", drive.delay_samples)
    scenario.check_plant_step(Ts)  # the rest was validated when the frozen scenario was built
    inverter = scenario.inverter or drive.inverter
    inv_code = {"average": 0, "svm": 1, "fcs_mpc": 2}.get(inverter)
    if inv_code is None:
        raise SpecError("drive.inverter", '"average", "svm" or "fcs_mpc"', inverter)
    if inv_code == 2 and drive.delay_samples > 1:
        raise SpecError("drive.delay_samples", "0 or 1 with the fcs_mpc inverter",
                        drive.delay_samples)
    if inv_code == 2 and law.fcs is None:
        raise SpecError("law.fcs", "criterion weights for the fcs_mpc inverter", None)
    vl = {"none": 0, "circle": 1, "hexagon": 2}.get(drive.v_limit)
    if vl is None:
        raise SpecError("drive.v_limit", '"circle", "hexagon" or "none"', drive.v_limit)
    if inv_code == 1 and vl == 0:
        vl = 2  # SVM cannot exceed its hexagon: let the anti-windup know it
    vprio = {"radial": 0, "d_axis": 1}.get(drive.voltage_priority)
    if vprio is None:
        raise SpecError("drive.voltage_priority", '"radial" or "d_axis"',
                        drive.voltage_priority)
    r_hex, v_max = drive.radii(plant.torque_factor)
    hold = {"rotor": 0, "stationary": 1}.get(drive.hold_frame)
    if hold is None:
        raise SpecError("drive.hold_frame", '"rotor" or "stationary"', drive.hold_frame)
    DP = _packed("DP", Ts=Ts, delay=drive.delay_samples, vlim=vl, v_max=v_max, r_hex=r_hex,
                 inverter=inv_code, half_periods=_half_periods(drive) if inv_code == 1 else 0,
                 hold=hold, t_comp=law.decoupling.delay_compensation_time, vprio=vprio)

    kind = scenario.kind
    sl = law.speed_loop
    if kind in ("speed_step", "load_step") and sl is None:
        raise SpecError("scenario.kind", "a law with a speed loop for kind "
                        f'"{kind}"', kind)
    if sl is not None and kind in ("speed_step", "load_step"):
        dec = sl.sample_time / Ts
        if abs(dec - round(dec)) > 1e-6 or round(dec) < 1:
            raise SpecError("law.speed_loop.sample_time", "an integer multiple of the "
                            f"current sample time ({Ts} s)", sl.sample_time)
        SP = _packed("SP", enabled=1.0, kp=sl.kp, ki=sl.ki, kd=sl.kd, decim=round(dec),
                     iq_limit=sl.iq_limit)
    else:
        SP = np.zeros(len(_kernel.LAYOUTS["SP"]))  # enabled = 0: no speed loop

    tf = plant.torque_factor
    iq1 = scenario.iq_ref
    if scenario.torque_ref is not None:
        iq1 = scenario.torque_ref / (tf * plant.pole_pairs * law.decoupling.flux_c)
    if kind in ("speed_step", "load_step"):
        sig = 2
    elif iq1 == scenario.iq_ref0 and scenario.id_ref != scenario.id_ref0:
        sig = 1
    else:
        sig = 0
    speed0 = scenario.speed_ref if kind == "load_step" else scenario.speed_ref0
    SC = _packed(
        "SC", duration=scenario.duration,
        mech=1.0 if kind in ("current_step", "constant_acceleration") else 0.0,
        omega0=scenario.initial_speed, acc=scenario.acceleration,
        id0=scenario.id_ref0, iq0=scenario.iq_ref0, id1=scenario.id_ref, iq1=iq1,
        t_step=scenario.step_time, speed0=speed0, speed1=scenario.speed_ref,
        load=scenario.load_torque, load_time=scenario.load_time,
        iq_amp=scenario.torque_amplitude / (tf * plant.pole_pairs * law.decoupling.flux_c),
        f_sin=scenario.torque_frequency,
        ref_mode={"sinusoidal_torque": 1, "speed_step": 2, "load_step": 2}.get(kind, 0),
        signal=sig, gain=scenario.speed_gain_error, offset=scenario.speed_offset,
        speed_noise=scenario.speed_noise,
        noise_kind=0.0 if scenario.noise == "uniform" else 1.0,
        current_noise=scenario.current_noise, current_quantum=scenario.current_quantum,
        seed=scenario.seed, h=plant_step(scenario, plants or [plant]),
        current_gain_d=scenario.current_gain_d, current_gain_q=scenario.current_gain_q,
        current_delay_d=scenario.current_delay_d, current_delay_q=scenario.current_delay_q,
        trace_decim=1 if scenario.trace_step is None
        else max(1, round(scenario.trace_step / Ts)))
    return DP, SP, SC


def _plant_array(motor: Motor) -> np.ndarray:
    """The kernel's plant array (slots ``_kernel.LAYOUTS["P"]``) of a true motor.

    The only place a :class:`~toolbox.spec.Motor` is packed for the kernel;
    its dq convention enters as ``torque_factor`` (``Motor.torque_factor``).
    """
    P = _packed("P", R=motor.R, Ld=motor.Ld, Lq=motor.Lq, flux=motor.flux,
                pole_pairs=motor.pole_pairs, J=motor.J, friction=motor.friction,
                torque_factor=motor.torque_factor,
                magnetic=0.0 if motor.magnetics is None else 1.0)
    if motor.magnetics is None:
        return P
    # a saturated motor: its current-from-flux table follows the named slots
    # (flux-linkage state, toolbox.sim._kernel_plant._current_of_flux); the
    # map fixes Ld, Lq and flux, so a scenario may not replace them
    Ld, Lq, flux = motor.magnetics.nominal()
    for name, nominal in (("Ld", Ld), ("Lq", Lq), ("flux", flux)):
        if not math.isclose(getattr(motor, name), nominal, rel_tol=1e-12, abs_tol=1e-15):
            raise SpecError(f"plant.{name}", "the value of the motor's magnetic model "
                            f"({nominal:.6g}): a saturated motor's {name} comes from its "
                            "flux map or saturation model", getattr(motor, name))
    return np.concatenate([P, _inverse_table(motor.magnetics)])


def _inverse_table(magnetics) -> np.ndarray:
    """The kernel's current-from-flux table of a magnetic model, computed once
    per model object (``MagneticModel.inverse_table``)."""
    table = _TABLES.get(id(magnetics))
    if table is None or table[0] is not magnetics:
        table = (magnetics, magnetics.inverse_table())
        _TABLES[id(magnetics)] = table
    return table[1]


#: id(model) -> (model, table): a table per magnetic model object (a design's
#: scenarios simulate the same motor many times).
_TABLES: dict = {}


def _check_plant(plant: Motor, key: str = "plant") -> None:
    for name in ("R", "Ld", "Lq", "flux", "pole_pairs", "J"):
        v = getattr(plant, name)
        if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v)
                and v > 0):
            raise SpecError(f"{key}.{name}", "a finite number > 0", v)
    if not (math.isfinite(plant.friction) and plant.friction >= 0):
        raise SpecError(f"{key}.friction", "a finite number >= 0", plant.friction)


def simulate(law: ControlLaw, plant: Motor, scenario: Scenario,
             drive: DriveParams) -> SimResult:
    """Simulate one closed loop: nonlinear PMSM + sampled control + inverter.

    The plant (``plant.with_overrides(scenario.plant_values,
    scenario.plant_scale)``) is integrated by RK4 at :func:`plant_step`;
    the control law runs every ``drive.sample_time`` with ZOH and
    ``drive.delay_samples`` periods of computation delay.

    Parameters
    ----------
    law : ControlLaw
        Controller (plain arrays, its model of the motor, decoupling flags).
    plant : toolbox.spec.Motor
        Nominal true motor (SI); its ``convention`` sets the torque factor.
    scenario : Scenario
        What happens (references, speed, load, sensor errors, inverter, traces).
    drive : DriveParams
        DC link (V), sampling (s), delay, voltage limit, inverter model.

    Returns
    -------
    SimResult
        Metrics (see :mod:`toolbox.sim._metrics`) and optional traces.

    Raises
    ------
    SpecError
        Inconsistent inputs (sample times, unknown inverter, plant step > Ts, ...).
    """
    true_plant = plant.with_overrides(scenario.plant_values, scenario.plant_scale)
    _check_plant(true_plant)
    A, B, C, D, W, LP = _pack_law(law)
    DP, SP, SC = _pack(law, true_plant, scenario, drive)
    M, tr = _kernel.run(_plant_array(true_plant), A, B, C, D, W, LP, SP, DP, SC,
                        bool(scenario.keep_traces))
    res = SimResult(metrics=metrics_dict(M))
    if scenario.keep_traces:
        for j, name in enumerate(("t", "id", "iq", "vd", "vq", "speed", "torque",
                                  "id_ref", "iq_ref", "speed_measured")):
            setattr(res, name, tr[:, j].copy())
    return res


#: dq convention of each kernel torque factor (``Motor.torque_factor`` inverse).
_CONVENTION_OF_TORQUE_FACTOR = {1.5: "amplitude", 1.0: "power"}


def _motors_from_columns(plants: Mapping[str, Sequence[float]]) -> list[Motor]:
    """N motors from parameter arrays (``simulate_batch``'s mapping form).

    Keys are the kernel's plant slots (``R`` ... ``friction``, and
    ``torque_factor`` 1.5 or 1, which selects the dq convention; default 1.5),
    not ``magnetic``: these are constant-parameter motors.
    """
    names = tuple(n for n in _kernel.LAYOUTS["P"] if n != "magnetic")
    unknown = set(plants) - set(names)
    if unknown:
        raise SpecError("plants", "parameter arrays named " + ", ".join(names),
                        sorted(unknown)[0])
    N = max(np.size(v) for v in plants.values())
    defaults = {"friction": 0.0, "torque_factor": 1.5}
    cols = {k: np.broadcast_to(np.asarray(plants.get(k, defaults.get(k, np.nan)), float), (N,))
            for k in names}
    motors = []
    for i in range(N):
        tf = float(cols["torque_factor"][i])
        if tf not in _CONVENTION_OF_TORQUE_FACTOR:
            raise SpecError(f"plants.torque_factor[{i}]", "1.5 (amplitude-invariant) or 1 "
                            "(power-invariant)", tf)
        motors.append(Motor(R=float(cols["R"][i]), Ld=float(cols["Ld"][i]),
                            Lq=float(cols["Lq"][i]), flux=float(cols["flux"][i]),
                            pole_pairs=float(cols["pole_pairs"][i]), J=float(cols["J"][i]),
                            friction=float(cols["friction"][i]),
                            convention=_CONVENTION_OF_TORQUE_FACTOR[tf]))
    return motors


def simulate_batch(law: ControlLaw,
                   plants: Sequence[Motor] | Mapping[str, Sequence[float]],
                   scenario: Scenario, drive: DriveParams,
                   progress: Callable[[int, int], None] | None = None,
                   chunk: int | None = None, threads: int | None = None) -> BatchResult:
    """Run N closed-loop simulations in parallel, on ``threads`` threads.

    Each thread runs its share of the rows through the compiled kernel
    (``_kernel.run_rows``, a loop over :func:`simulate`'s ``_kernel.run``),
    which releases the GIL: the batch reuses the single run's compiled code
    (a ``prange`` entry point compiled ~5 s more per process; the
    share loop ~0.5 s). The rows are independent: the metrics are
    :func:`simulate`'s, bit for bit, for any ``threads`` and ``chunk``.

    Parameters
    ----------
    law, scenario, drive
        As for :func:`simulate` (traces are never kept).
    plants : sequence of toolbox.spec.Motor, or mapping
        The N true plants: a list of motors (e.g. ``Motor.with_overrides`` of
        a nominal one), or a mapping from parameter name (``R``, ``Ld``, ...
        ``friction``, ``torque_factor``) to arrays of length N (scalars
        broadcast). The scenario's plant overrides apply on top of each.
    progress : callable, optional
        Called as ``progress(done, N)`` after each chunk.
    chunk : int, optional
        Simulations between two progress calls, run by all the threads
        (default: about 1 % of N, at least 64 and 8 per thread; all N
        without ``progress``: the threads then never wait for each other).
    threads : int, optional
        Threads (default ``numba.config.NUMBA_NUM_THREADS``: one per core,
        or the ``NUMBA_NUM_THREADS`` environment variable).

    Returns
    -------
    BatchResult
        ``metrics[name]``: array of length N.
    """
    plant_list = (_motors_from_columns(plants) if isinstance(plants, Mapping)
                  else list(plants))
    N = len(plant_list)
    if N == 0:
        return BatchResult({name: np.empty(0) for name in METRIC_NAMES})
    trues = [p.with_overrides(scenario.plant_values, scenario.plant_scale)
             for p in plant_list]
    tf0 = trues[0].torque_factor
    for i, p in enumerate(trues):
        _check_plant(p, f"plants[{i}]")
        if p.torque_factor != tf0 or p.pole_pairs != trues[0].pole_pairs:
            raise SpecError(f"plants[{i}].torque_factor", "the same torque factor and "
                            "pole pairs for every plant of a batch", p.torque_factor)
    P = np.array([_plant_array(p) for p in trues])
    A, B, C, D, W, LP = _pack_law(law)
    scen = replace(scenario, keep_traces=False)
    DP, SP, SC = _pack(law, trues[0], scen, drive, trues)
    if threads is None:
        threads = numba.config.NUMBA_NUM_THREADS
    if chunk is None:
        chunk = N if progress is None else max(64, 8 * threads, N // 100)
    if chunk < 1 or threads < 1:
        raise ValueError(f"simulate_batch: chunk and threads must be >= 1, got {chunk}, "
                         f"{threads}")
    out = np.empty((N, len(METRIC_NAMES)))
    n_threads = min(threads, chunk, N)

    def run_share(first: int, stop: int) -> None:
        _kernel.run_rows(P, first, stop, n_threads, A, B, C, D, W, LP, SP, DP, SC, out)

    with ThreadPoolExecutor(n_threads) as pool:
        done = 0
        while done < N:
            stop = min(N, done + chunk)
            # strided rows: a sweep ordered by a parameter spreads its slow
            # (long or diverging) simulations over the threads
            list(pool.map(run_share, range(done, done + n_threads), [stop] * n_threads))
            done = stop
            if progress is not None:
                progress(done, N)
    return BatchResult({name: out[:, j].copy() for j, name in enumerate(METRIC_NAMES)})
