"""H-infinity mixed-sensitivity current controllers (paper 003).

A. Azaiz, Y. Ramdani, A. Meroufel, B. Belabbes, "H-infinity design of
controllers ensuring the regulation of currents of the decoupled field
orientation control applied to a PMS motor" (2007). Equation numbers refer to
it. The numerics live in :mod:`._hinf_plant` (augmented plant eq
(35)-(40), (50)-(64)), :mod:`._hinf_assumptions` (A1-A4),
:mod:`._hinf_riccati` (Riccati formulae eq (10)-(32), (65)-(67)),
:mod:`._hinf_gamma` (gamma iteration with back-off), :mod:`._hinf_bounds`
(eq (41)-(43)), :mod:`._weights` (eq (44)-(49) and ``makeweight``)
and :mod:`._reduction` (eq (71)-(72)); this module turns a spec into them and
the result into a :class:`~toolbox.artifact.ControllerArtifact`.

Per axis: ``G = axis_plant_models(motor)[axis]`` (eq (33)-(34)), weights from
``[controller.hinf.weights.<axis>]``, synthesis at ``gamma`` (or the optimum
with back-off, realisable at ``drive.sample_time``), weight-bound checks (41)-(43),
then optionally order reduction with a margin comparison. With
``[controller.hinf.at_speed]`` the synthesis is instead the 2x2 coupled,
multi-model one of :mod:`._hinf_coupled` (one structured controller per axis,
no order reduction).

Which controller runs: each axis holds one executed law (``law``, its
continuous twin ``continuous``, the derived ``discrete`` and ``zpk`` views).
With ``reduce_order`` given, the executed law is by default the reduced
controller's (``executed = "reduced"``): reduction is asked precisely to run
a simpler controller, and the full-order design is kept, not executed, under
``axes.<axis>.full_order``. With ``executed = "full"`` the axis runs the
full-order controller and the reduced candidate is kept under
``axes.<axis>.reduced``. Analysis, margins and figures are thus always those
of the law that runs (003's 3rd-order reduced law, eq (71)-(72)). The
anti-windup (back-calculation) gain is the artifact's default, whose
saturated recursion is Schur (Tustin's zero at z = -1 moved to the origin).

The validated weights of each axis and the level gamma are recorded in the
typed ``artifact.weights`` (:class:`~toolbox.artifact.AxisWeights`: ``w1``,
``w2``, ``w3`` as continuous ``{num, den}``, coefficients in s, highest power
first, whatever their spec form: constant, num/den, zpk, makeweight):
analysis draws the bounds of eq (41)-(43) from them and nothing after design
re-reads the spec's weight tables. The reduction guard's continuous-loop
margins are informational, under ``design_parameters.design_margins_continuous``
(the headline margins are the artifact's ``margins``: the sampled executed loop).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import Any, Mapping

import numpy as np

from ..lti import StateSpace, TransferFunction
from ..artifact import AxisController, AxisWeights, ControllerArtifact, TransferFunctionData
from ..errors import DesignInfeasible, SpecError
from ..plant import axis_plant_models
from ..spec import Table
from ._common import decoupling_from_motor, make_artifact
from ._hinf_defaults import default_w2, w1_params, w2_params, w2_toml
from ._hinf_speed import AtSpeedCfg, design_at_speed, read_at_speed
from ._hinf_bounds import weight_bound_check
from ._hinf_gamma import GammaBelowOptimum, fastest_pole_modulus, gamma_iteration, synthesize
from ._hinf_plant import _ss_blocks, augment_mixed_sensitivity
from ._reduction import compare_margins, loop_margins, reduce_controller
from ._weights import makeweight, validate_weight, weight_from_tf, weight_from_zpk

__all__ = ["HinfCfg", "HinfAxisResult", "read_weight", "design_hinf_axis", "read_cfg",
           "design"]

_KEY = "controller.hinf"
AXES = ("d", "q")
CFG_KEYS = ("gamma", "backoff", "reduce_order", "integrator_tol", "margin_loss",
            "on_margin_loss", "executed", "weights", "at_speed")
_FORMS = {"tf": ("num", "den"), "zpk": ("zeros", "poles", "gain"),
          "makeweight": ("dc_gain", "crossover", "crossover_gain", "hf_gain", "order")}


@dataclass(frozen=True)
class HinfCfg:
    """Validated ``[controller.hinf]``.

    Attributes
    ----------
    gamma : float or "optimal"
        Fixed level (dimensionless) or the optimum with back-off.
    backoff : float
        Relative back-off above gamma_opt (default 0.05).
    reduce_order : int or None
        Target controller order.
    integrator_tol : float
        Poles with |p| below this become integrators in the reduction (rad/s).
    margin_loss : float
        Largest relative loss of GM, PM or M_m accepted from the reduction.
    on_margin_loss : str
        ``"refuse"`` (SpecError) or ``"flag"`` (recorded in design_parameters.reduction).
    executed : str
        ``"reduced"`` or ``"full"``: the controller the law runs.
    weights : dict
        ``{axis: {"w1": tf or None, "w2": tf, "w3": tf or None}}``; a ``w1``
        of ``None`` is built at design time from the requirements
        (:mod:`toolbox.design._hinf_defaults`).
    defaults : dict or None
        Method-level defaults taken (``gamma``), stated in the artifact.
    stated : dict
        Per axis, the default weights used and the rule of each.
    at_speed : AtSpeedCfg or None
        Synthesis against the coupled plant at speed
        (:mod:`toolbox.design._hinf_speed`), or None (paper 003's per-axis design).
    """

    gamma: float | str
    backoff: float
    reduce_order: int | None
    integrator_tol: float
    margin_loss: float
    on_margin_loss: str
    executed: str
    weights: dict
    defaults: dict | None = None
    stated: dict = field(default_factory=dict)
    at_speed: AtSpeedCfg | None = None

    def to_spec(self, spec=None) -> dict[str, Any]:
        """``[controller.hinf]`` keys that read back to this configuration.

        Every weight is written: a default one as its makeweight parameters
        (``w2`` from the drive, ``w1`` from the requirements, which needs
        ``spec``), a given one as given in ``spec`` (else ``{num, den}`` of
        its transfer function).

        Parameters
        ----------
        spec : Spec, optional
            Drive and requirements for the default ``w1``; without it a
            default ``w1`` is not representable and ValueError is raised.

        Returns
        -------
        dict
        """
        out: dict[str, Any] = {"gamma": self.gamma, "backoff": float(self.backoff)}
        if self.reduce_order is not None:
            out["reduce_order"] = int(self.reduce_order)
        out.update(integrator_tol=float(self.integrator_tol),
                   margin_loss=float(self.margin_loss), on_margin_loss=self.on_margin_loss,
                   executed=self.executed)
        weights: dict[str, Any] = {}
        for ax in AXES:
            stated = self.stated.get(ax, {})
            weights[ax] = {}
            for name in ("w1", "w2", "w3"):
                W = self.weights[ax][name]
                if name == "w1" and W is None:
                    if spec is None:
                        raise ValueError("HinfCfg.to_spec: a default w1 needs the spec "
                                         "(drive and requirements)")
                    weights[ax][name] = dict(w1_params(spec.drive, spec.requirements)[0])
                elif name == "w2" and isinstance(stated.get("w2"), dict):
                    weights[ax][name] = dict(stated["w2"]["makeweight"])
                elif W is not None:
                    given = _given_weight(spec, ax, name)
                    weights[ax][name] = given if given is not None else _tf_table(W)
        out["weights"] = weights
        if self.at_speed is not None:
            out["at_speed"] = self.at_speed.to_spec()
        return out


def _tf_table(W: Any) -> dict[str, list[float]]:
    """A SISO weight as the spec's ``{num = [..], den = [..]}`` (highest power first)."""
    tf = TransferFunction.from_system(W)
    return {"num": [float(c) for c in tf.num], "den": [float(c) for c in tf.den]}


def _given_weight(spec, ax: str, name: str) -> Any:
    """The weight table as written in the spec file, or None."""
    raw = getattr(spec, "raw", None) or {}
    for key in ("controller", "hinf", "weights", ax, name):
        raw = raw.get(key) if isinstance(raw, Mapping) else None
    return raw


def _root(value: Any, key: str) -> complex:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return complex(value)
    if (isinstance(value, (list, tuple)) and len(value) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        return complex(value[0], value[1])
    raise SpecError(key, "a number or a pair [re, im] (rad/s)", value)


def read_weight(value: Any, key: str) -> TransferFunction:
    """A weight from spec data (paper 003 eq (44)-(49) style).

    Parameters
    ----------
    value : number or mapping
        A positive constant; ``{num = [..], den = [..]}`` (coefficients in s,
        highest power first); ``{zeros = [..], poles = [..], gain = k}``
        (roots as numbers or ``[re, im]``, rad/s); or ``{dc_gain =,
        crossover =, crossover_gain =, hf_gain =, order =}`` (makeweight,
        absolute gains, rad/s).
    key : str
        Dotted key for messages, e.g. ``controller.hinf.weights.q.w1``.

    Returns
    -------
    toolbox.lti.TransferFunction

    Raises
    ------
    SpecError
        Unknown form, bad numbers, improper or unstable weight.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if not (math.isfinite(value) and value > 0):
            raise SpecError(key, "a constant weight > 0", value)
        return validate_weight(TransferFunction([float(value)], [1.0]), key)
    if not isinstance(value, Mapping):
        raise SpecError(key, "a number or a table {num, den} | {zeros, poles, gain} | "
                        "{dc_gain, crossover, crossover_gain, hf_gain, order}", value)
    form = next((f for f, names in _FORMS.items() if names[0] in value), None)
    if form is None:
        raise SpecError(key, "one of the forms {num, den}, {zeros, poles, gain}, "
                        "{dc_gain, crossover, crossover_gain, hf_gain, order}",
                        sorted(value))
    t = Table(value, key, _FORMS[form])
    if form == "tf":
        # order <= MAX_WEIGHT_ORDER: at most that many + 1 coefficients
        n = MAX_WEIGHT_ORDER + 1
        return weight_from_tf(t.numbers("num", min_length=1, max_length=n),
                              t.numbers("den", min_length=1, max_length=n), key)
    if form == "zpk":
        roots = {}
        for name in ("zeros", "poles"):
            raw = t.raw(name, [])
            if not isinstance(raw, (list, tuple)):
                raise SpecError(t.key(name), "a list of roots", raw)
            if len(raw) > MAX_WEIGHT_ORDER:
                raise SpecError(t.key(name), f"at most {MAX_WEIGHT_ORDER} roots",
                                f"{len(raw)} roots")
            roots[name] = [_root(r, f"{t.key(name)}[{i}]") for i, r in enumerate(raw)]
        return weight_from_zpk(roots["zeros"], roots["poles"], t.number("gain"), key)
    return makeweight(t.number("dc_gain", positive=True), t.number("crossover", positive=True,
                                                                   unit="rad/s"),
                      t.number("crossover_gain", positive=True), t.number("hf_gain", positive=True),
                      t.integer("order", 1, minimum=1, maximum=MAX_MAKEWEIGHT_ORDER), key)


#: Parameter bounds. A weight of order 20 per channel already gives a
#: generalised plant of order > 60 per axis; beyond it the Riccati solutions
#: lose all accuracy. makeweight's n-th power of a first-order filter is
#: numerically flat beyond order 10. gamma above 1e4 means the weights
#: impose nothing (the S/KS/T bounds are 1e4 times the weights), and a
#: back-off of 10 already designs at 11 gamma_opt.
MAX_WEIGHT_ORDER = 20
MAX_MAKEWEIGHT_ORDER = 10
MAX_GAMMA = 1e4
MAX_BACKOFF = 10.0


def read_cfg(method: str, table, motor, drive) -> HinfCfg:
    """Validate ``[controller.hinf]`` and its weights.

    Keys: ``gamma`` (number > 0 or "optimal", default 1), ``backoff`` (>= 0,
    default 0.05), ``reduce_order`` (int >= 1, optional), ``integrator_tol``
    (rad/s, default 0.1), ``margin_loss`` (0..1, default 0.1),
    ``on_margin_loss`` ("refuse" | "flag", default "refuse"), ``executed``
    ("reduced" | "full", default "reduced" when reduce_order is given),
    ``[controller.hinf.weights.d|q]`` with ``w1`` (required), ``w2``, ``w3``,
    and ``[controller.hinf.at_speed]`` (optional: synthesis against the coupled
    plant at speed, :func:`toolbox.design._hinf_speed.read_at_speed`).

    Parameters: as :func:`toolbox.design.read_method_cfg`.

    Returns
    -------
    HinfCfg
    """
    t = Table(table.data, table.prefix, CFG_KEYS)
    # default weights: gamma defaults to the optimum (their level is not tuned to 1)
    gamma_default = 1.0 if t.has("weights") else "optimal"
    gamma = t.raw("gamma", gamma_default)
    if isinstance(gamma, str):
        if gamma != "optimal":
            raise SpecError(t.key("gamma"), 'a number > 0 or "optimal"', gamma)
    else:
        gamma = t.number("gamma", 1.0, positive=True, maximum=MAX_GAMMA)
    backoff = t.number("backoff", 0.05, nonnegative=True, maximum=MAX_BACKOFF)
    order = t.integer("reduce_order", None, minimum=1)
    itol = t.number("integrator_tol", 0.1, positive=True, unit="rad/s")
    loss = t.number("margin_loss", 0.1, nonnegative=True, maximum=1.0)
    on_loss = t.string("on_margin_loss", "refuse", choices=("refuse", "flag"))
    executed = t.string("executed", "reduced" if order is not None else "full",
                        choices=("reduced", "full"))
    if executed == "reduced" and order is None:
        raise SpecError(t.key("executed"), '"full" unless reduce_order is given', executed)
    wt = t.table("weights", AXES)
    weights, stated = {}, {}
    for ax, L in zip(AXES, (motor.Ld, motor.Lq)):
        sub = wt.table(ax, ("w1", "w2", "w3"))
        weights[ax] = {w: (read_weight(sub.raw(w), sub.key(w)) if sub.has(w) else None)
                       for w in ("w1", "w2", "w3")}
        if weights[ax]["w2"] is None:
            # assumption A2 (D12 full column rank) needs a control weight: the default one
            weights[ax]["w2"] = default_w2(L, drive, sub.key("w2"))
            stated.setdefault(ax, {})["w2"] = dict(zip(("makeweight", "rule"),
                                                       w2_params(L, drive)))
        elif _hf_gain(weights[ax]["w2"]) == 0.0:
            raise SpecError(sub.key("w2"), "a control weight with a non-zero high-frequency "
                            "gain (assumption A2 of the H-infinity problem: u weighted "
                            "directly, D12 of full column rank)", sub.raw("w2"),
                            hint=f"e.g. the default for this axis, {w2_toml(L, drive)}, "
                                 "or leave w2 out to get it")
        if weights[ax]["w1"] is None:
            stated.setdefault(ax, {})["w1"] = "default, from requirements (see design)"
    return HinfCfg(gamma, backoff, order, itol, loss, on_loss, executed, weights,
                   defaults={"gamma": gamma} if not t.has("gamma") and not t.has("weights")
                   else None, stated=stated, at_speed=read_at_speed(t, motor, drive))


def _hf_gain(W: Any) -> float:
    """``|W(j inf)|`` of a proper weight (0 for a strictly proper one)."""
    return TransferFunction.from_system(W).hf_gain()


def _fill_default_w1(cfg: HinfCfg, spec) -> tuple[dict, dict]:
    """The weights with every missing ``w1`` built from the requirements
    (:mod:`toolbox.design._hinf_defaults`), and the stated defaults."""
    weights = {ax: dict(w) for ax, w in cfg.weights.items()}
    stated = {ax: dict(v) for ax, v in cfg.stated.items()}
    for ax in AXES:
        if weights[ax]["w1"] is None:
            p, rule = w1_params(spec.drive, spec.requirements)
            weights[ax]["w1"] = makeweight(p["dc_gain"], p["crossover"], p["crossover_gain"],
                                           p["hf_gain"], key=f"{_KEY}.weights.{ax}.w1")
            stated.setdefault(ax, {})["w1"] = {"makeweight": p, "rule": rule}
    return weights, stated


@dataclass
class HinfAxisResult:
    """One axis of an H-infinity design.

    Attributes
    ----------
    G : LTI system
        Plant (A/V), as given (:func:`toolbox.plant.axis_plant_models` in a design).
    K : toolbox.lti.StateSpace
        Central controller (V/A).
    Kr : toolbox.lti.StateSpace or None
        Reduced controller.
    synthesis : HinfResult
    bounds : dict
        Weight-bound worst ratios, eq (41)-(43).
    reduction : ReductionResult or None
    margins : MarginComparison or LoopMargins
    """

    G: Any
    K: Any
    Kr: Any
    synthesis: Any
    bounds: dict
    reduction: Any
    margins: Any


def design_hinf_axis(G: Any, w1: Any, w2: Any = None, w3: Any = None, *,
                     gamma: float | str = 1.0, backoff: float = 0.05,
                     sample_time: float | None = None, reduce_order: int | None = None,
                     integrator_tol: float = 0.1, margin_loss: float = 0.1,
                     on_margin_loss: str = "refuse", axis: str = "q") -> HinfAxisResult:
    """Synthesize (and optionally reduce) the controller of one current loop.

    Parameters
    ----------
    G : LTI system (toolbox.lti or python-control)
        Plant, e.g. ``1/(R + s Lq)`` (A/V).
    w1, w2, w3 : TransferFunction, python-control system, number or None
        Weights on S, KS, T (eq 35-40).
    gamma : float or "optimal"
    backoff : float
    sample_time : float, optional
        Controller period (s), for the realisability test.
    reduce_order : int, optional
    integrator_tol : float
        Near-zero poles below this become integrators (rad/s), eq (71)-(72).
    margin_loss : float
        Allowed relative margin loss of the reduction.
    on_margin_loss : {"refuse", "flag"}
    axis : str
        Axis name for messages.

    Returns
    -------
    HinfAxisResult

    Raises
    ------
    SpecError
        ``controller.hinf.gamma`` (infeasible, with the best achievable gamma),
        ``controller.hinf.reduce_order`` (margins lost beyond ``margin_loss``).
    """
    Gs = StateSpace(*_ss_blocks(G))   # realised once for synthesis and margins
    P = augment_mixed_sensitivity(Gs, w1, w2, w3)
    try:
        with warnings.catch_warnings(record=True):
            warnings.simplefilter("always")
            res = synthesize(P, gamma, backoff=backoff, sample_time=sample_time)
    except SpecError as err:
        raise _on_axis(err, axis) from None
    bounds = weight_bound_check(G, res.K, w1, w2, w3)
    red = Kr = None
    if reduce_order is not None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            red = reduce_controller(res.K, order=reduce_order, integrator_tol=integrator_tol)
        Kr = red.K
        margins = compare_margins(Gs, res.K, Kr, max_loss=margin_loss)
        if not margins.ok and on_margin_loss == "refuse":
            raise DesignInfeasible(f"{_KEY}.reduce_order",
                            f"an order whose {axis}-axis controller keeps GM, PM and M_m "
                            f"within {100 * margin_loss:g} % of the full controller's",
                            reduce_order,
                            hint="; ".join(margins.flags) + '; raise reduce_order or set '
                                 'on_margin_loss = "flag"')
    else:
        margins = loop_margins(Gs, res.K)
    _refuse_unrealisable(res, Kr, gamma, axis)
    return HinfAxisResult(G, res.K, Kr, res, bounds, red, margins)


def _on_axis(err: SpecError, axis: str) -> SpecError:
    """The same error (same class and data) with ``"<axis> axis"`` in its hint."""
    new = err._copy(err.key, err.file)   # keeps the class and its data fields
    new.hint = f"{axis} axis: {err.hint}" if err.hint else f"{axis} axis"
    new.axis = axis
    new.args = (new._text(),)             # the message is built at construction
    return new


def _refuse_unrealisable(res, Kr, gamma, axis: str) -> None:
    """A controller pole faster than pi/Ts cannot run at the sample time (the
    known trap of paper 003 at the exact optimal gamma): refuse it unless the
    order reduction (the executed controller) removed that pole."""
    if res.pole_limit is None or res.fastest_pole <= res.pole_limit:
        return
    if Kr is not None and fastest_pole_modulus(Kr) <= res.pole_limit:
        return
    if gamma == "optimal":
        # the back-off already went up to its limit: a larger gamma is not the cure,
        # the weights ask for a loop faster than the sampling allows
        advice = (f"gamma = \"optimal\" backed off to {res.backoff:.3g} without removing it: "
                  f"lower w1's crossover or give w2 a larger high-frequency gain (roll-off), "
                  "e.g. leave the weights out for defaults derived from the sample time")
    else:
        advice = 'raise gamma or use gamma = "optimal" (automatic back-off)'
    raise DesignInfeasible(f"{_KEY}.gamma", "a gamma whose controller has no pole faster than "
                    f"pi/Ts = {res.pole_limit:.4g} rad/s", gamma,
                    hint=f"{axis} axis: fastest pole |s| = {res.fastest_pole:.4g} rad/s; {advice}")


def _weight_data(W: Any) -> TransferFunctionData | None:
    """``num/den`` (coefficients in s, highest power first) of a validated weight.

    Every spec form (constant, ``num/den``, ``zeros/poles/gain``, ``makeweight``)
    is a transfer function once read, so the artifact records one form and
    later stages (analysis' weight bounds, eq (41)-(43)) never re-read the spec.
    """
    if W is None:
        return None
    tf = TransferFunction.from_system(W)
    return TransferFunctionData(np.array(tf.num), np.array(tf.den))


def _margins_json(m: Any) -> dict:
    return dict(vars(m))


def design(spec) -> ControllerArtifact:
    """H-infinity artifact from a validated spec (method ``hinf``).

    See the module docstring for which controller the law executes.

    Parameters
    ----------
    spec : Spec
        Validated spec with ``controller.method = "hinf"``.

    Returns
    -------
    ControllerArtifact
    """
    cfg: HinfCfg = spec.controller.cfg
    ts = spec.drive.sample_time
    plants = axis_plant_models(spec.motor)
    weights, stated = _fill_default_w1(cfg, spec)
    cfg = replace(cfg, weights=weights, stated=stated)
    decoupling = decoupling_from_motor(spec.motor)
    if cfg.at_speed is not None:
        return _design_at_speed(spec, cfg, plants, decoupling)
    results = _synthesise(cfg, plants, ts)
    axes = {ax: _executed_axis(r, ts, cfg.executed) for ax, r in results.items()}
    weights = {ax: AxisWeights(gamma=float(r.synthesis.gamma),
                               **{k: _weight_data(W) for k, W in cfg.weights[ax].items()})
               for ax, r in results.items()}
    eqs = ["003 eq (33)-(34)", "003 eq (35)-(40)", "003 eq (10)-(32)", "003 eq (65)-(67)",
           "003 eq (41)-(43)"] + (["003 eq (71)-(72)"] if cfg.reduce_order else [])
    params = _design_parameters(cfg, results)
    return make_artifact(spec, axes, decoupling, params, eqs, weights=weights)


def _synthesise(cfg: HinfCfg, plants: dict, ts: float) -> dict:
    """Both axes' syntheses with the weights of ``cfg`` (one gamma for both)."""
    try:
        return {ax: design_hinf_axis(plants[ax], **cfg.weights[ax], gamma=cfg.gamma,
                                     backoff=cfg.backoff, sample_time=ts,
                                     reduce_order=cfg.reduce_order,
                                     integrator_tol=cfg.integrator_tol,
                                     margin_loss=cfg.margin_loss,
                                     on_margin_loss=cfg.on_margin_loss, axis=ax)
                for ax in AXES}
    except GammaBelowOptimum as err:
        # one gamma serves both axes: quote the best achievable for both
        best = {ax: gamma_iteration(augment_mixed_sensitivity(plants[ax], **cfg.weights[ax]))
                for ax in AXES}
        worst = max(best.values())
        failed = f"{err.axis} axis: {err.condition}"  # which condition failed where
        raise DesignInfeasible(f"{_KEY}.gamma", f"gamma >= the best achievable {worst:.4g} "
                               "(both axes)", cfg.gamma,
                        hint=f"{failed}; best per axis: "
                        + ", ".join(f"{ax} {g:.4g}" for ax, g in best.items())
                        + f'; set gamma above {worst:.4g} or "optimal"') from None


def _design_at_speed(spec, cfg: HinfCfg, plants: dict, decoupling) -> ControllerArtifact:
    """The artifact of the synthesis against the coupled plant at speed
    (:mod:`._hinf_coupled`): one structured controller per axis (a PI with a
    roll-off, no order reduction), the nominal decoupling, the weights' level
    the worst closed-loop norm over the model set. ``gamma``, ``backoff`` and
    ``reduce_order`` of the table do not apply (recorded in ``warnings``)."""
    ts = spec.drive.sample_time
    out = design_at_speed(cfg.weights, spec.motor, spec.drive, decoupling, cfg.at_speed)
    axes = {ax: AxisController.from_error_controller(K, ts, method="tustin")
            for ax, K in out["controllers"].items()}
    weights = {ax: AxisWeights(gamma=float(out["gamma"]),
                               **{k: _weight_data(W) for k, W in cfg.weights[ax].items()})
               for ax in AXES}
    ignored = [k for k, v in (("reduce_order", cfg.reduce_order),) if v is not None]
    params: dict[str, Any] = {
        "gamma": {ax: float(out["gamma"]) for ax in AXES},
        "weight_bounds": {ax: {k: {"worst_ratio": v.worst_ratio,
                                   "worst_freq_rad_s": v.worst_freq}
                               for k, v in weight_bound_check(plants[ax], K,
                                                              **cfg.weights[ax]).items()}
                          for ax, K in out["controllers"].items()},
        "design_margins_continuous": {ax: {"full": _margins_json(loop_margins(
            StateSpace(*_ss_blocks(plants[ax])), K))} for ax, K in out["controllers"].items()},
        "warnings": {ax: ([f"{', '.join(ignored)} not used by the structured synthesis at "
                           "speed (second-order law per axis)"] if ignored else [])
                     for ax in AXES},
        "at_speed": out["record"],
    }
    if cfg.stated or cfg.defaults:
        params["defaults"] = {"weights": cfg.stated, **(cfg.defaults or {}),
                              "source": "toolbox.design._hinf_defaults (makeweight from "
                                        "requirements, sample time and delay)"}
    eqs = ["003 eq (3)-(4)", "003 eq (35)-(40)", "003 eq (10)-(19)", "003 eq (41)-(43)",
           "coupled 2x2 generalised plant at speed with the loop delay; structured "
           "multi-model H-infinity (toolbox.design._hinf_coupled)"]
    return make_artifact(spec, axes, decoupling, params, eqs, weights=weights)


def _executed_axis(r: Any, ts: float, executed: str) -> AxisController:
    """One axis whose ``law`` is the executed controller; the other one kept apart.

    ``executed = "reduced"``: the law, its continuous twin and antiwindup are
    the reduced controller's (eq (71)-(72)); the full-order design goes to
    ``full_order``. ``"full"``: the full-order law, the reduced candidate (if
    any) in ``reduced``.
    """
    full = AxisController.from_error_controller(r.K, ts, method="tustin")
    if r.Kr is None:
        return full
    red = AxisController.from_error_controller(r.Kr, ts, method="tustin")
    if executed == "reduced":
        return replace(red, full_order=full)
    return replace(full, reduced=red)


def _design_parameters(cfg: HinfCfg, results: dict) -> dict:
    """Informational numbers of the synthesis (report only; nothing branches on them)."""
    g: dict[str, Any] = {
        "gamma": {ax: r.synthesis.gamma for ax, r in results.items()},
        "gamma_opt": {ax: r.synthesis.gamma_opt for ax, r in results.items()},
        "backoff": {ax: r.synthesis.backoff for ax, r in results.items()},
        "closed_loop_norm": {ax: r.synthesis.closed_loop_norm for ax, r in results.items()},
        "fastest_pole_rad_s": {ax: r.synthesis.fastest_pole for ax, r in results.items()},
        "weight_bounds": {ax: {k: {"worst_ratio": v.worst_ratio, "worst_freq_rad_s": v.worst_freq}
                               for k, v in r.bounds.items()} for ax, r in results.items()},
        "warnings": {ax: list(r.synthesis.warnings) for ax, r in results.items()},
    }
    if cfg.stated or cfg.defaults:
        g["defaults"] = {"weights": cfg.stated, **(cfg.defaults or {}),
                         "source": "toolbox.design._hinf_defaults (makeweight from requirements, "
                                   "sample time and delay)"}
    if cfg.reduce_order is not None:
        g["reduction"] = {ax: {"order_before": r.reduction.order_before,
                               "order_after": r.reduction.order_after,
                               "error_bound": r.reduction.error_bound,
                               "actions": list(r.reduction.actions),
                               "margin_flags": list(r.margins.flags)}
                          for ax, r in results.items()}
        g["design_margins_continuous"] = {ax: {"full": _margins_json(r.margins.full),
                                               "reduced": _margins_json(r.margins.reduced)}
                                          for ax, r in results.items()}
    else:
        g["design_margins_continuous"] = {ax: {"full": _margins_json(r.margins)}
                                          for ax, r in results.items()}
    return g
