"""Boolean predictive control (finite-control-set MPC) of paper 002.

G. Cormerais et al., "Optimal torque control of a synchronous machine"
(IFAC 2002). At each period the inverter state (of 8) minimising criterion
(23) (weights alpha on the i_q (torque-producing current) error, beta on the i_d error, gamma on the
number of commutations) is applied; the simulator does that itself
(:class:`toolbox.artifact.FcsWeights`, executed by the simulator). The design step only validates the weights
and, so that margins can still be compared with the other methods, fills the
axes with the paper's SVM baseline PI, eq (19)-(20): ``K = 10 R``,
``Ti = L/R``, i.e. ``Kp = 10 R`` and ``Ki = Kp / Ti = 10 R^2 / L`` per axis.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..lti import StateSpace
from ..artifact import AxisController, ControllerArtifact, FcsWeights
from ..errors import SpecError
from ..spec import Table
from ._common import decoupling_from_motor, make_artifact

__all__ = ["FcsMpcCfg", "baseline_pi", "read_cfg", "design"]

_KEY = "controller.fcs_mpc"
#: Largest criterion weight: only the ratios alpha : beta : gamma matter, and the
#: header evaluates alpha e_q^2 + beta e_d^2 + gamma n in float32 (max 3.4e38);
#: with errors up to 1e3 A a weight of 1e12 keeps every term below 1e18.
MAX_FCS_WEIGHT = 1e12


@dataclass(frozen=True)
class FcsMpcCfg:
    """Validated ``[controller.fcs_mpc]``: weights of criterion (23) of paper 002.

    Attributes
    ----------
    alpha : float
        Weight of the squared i_q error of criterion (23) (1/A^2), >= 0.
    beta : float
        Weight of the squared i_d error (1/A^2), >= 0.
    gamma : float
        Weight of the number of commutations, >= 0.
    """

    alpha: float = 1.0
    beta: float = 1.0
    gamma: float = 0.0

    def to_spec(self, spec=None) -> dict[str, float]:
        """``[controller.fcs_mpc]`` keys that read back to this configuration.

        Parameters
        ----------
        spec : Spec, optional
            Unused (same signature as the other methods' ``to_spec``).

        Returns
        -------
        dict
            ``alpha``, ``beta``, ``gamma``.
        """
        return {"alpha": float(self.alpha), "beta": float(self.beta), "gamma": float(self.gamma)}


def baseline_pi(R: float, L: float) -> tuple[float, float]:
    """SVM baseline PI of paper 002 eq (19)-(20).

    Parameters
    ----------
    R : float
        Resistance (ohm).
    L : float
        Axis inductance (H).

    Returns
    -------
    Kp, Ki : float
        ``10 R`` (V/A) and ``10 R^2 / L`` (V/(A s)).
    """
    Kp = 10.0 * R
    return Kp, Kp * R / L


def read_cfg(method: str, table, motor, drive) -> FcsMpcCfg:
    """Validate ``[controller.fcs_mpc]``: ``alpha``, ``beta``, ``gamma`` (all in
    [0, :data:`MAX_FCS_WEIGHT`], defaults 1, 1, 0) with ``alpha + beta > 0``.

    Parameters: as :func:`toolbox.design.read_method_cfg`.

    Returns
    -------
    FcsMpcCfg
    """
    t = Table(table.data, table.prefix, ("alpha", "beta", "gamma"))
    alpha = t.number("alpha", 1.0, nonnegative=True, maximum=MAX_FCS_WEIGHT)
    beta = t.number("beta", 1.0, nonnegative=True, maximum=MAX_FCS_WEIGHT)
    gamma = t.number("gamma", 0.0, nonnegative=True, maximum=MAX_FCS_WEIGHT)
    if not alpha + beta > 0:
        raise SpecError(t.key("alpha"), "alpha + beta > 0 (criterion (23) must weight the "
                        "torque or the i_d error)", [alpha, beta])
    return FcsMpcCfg(alpha, beta, gamma)


def design(spec) -> ControllerArtifact:
    """FCS-MPC artifact: criterion (23) weights in ``fcs``, the eq (19)-(20) PI on the axes.

    Parameters
    ----------
    spec : Spec
        Validated spec with ``controller.method = "fcs_mpc"``.

    Returns
    -------
    ControllerArtifact
    """
    cfg: FcsMpcCfg = spec.controller.cfg
    m, ts = spec.motor, spec.drive.sample_time
    axes, pis = {}, {}
    for ax, L in (("d", m.Ld), ("q", m.Lq)):
        Kp, Ki = baseline_pi(m.R, L)
        pis[ax] = {"Kp": Kp, "Ki": Ki}
        pi = StateSpace([[0.0]], [[1.0]], [[Ki]], [[Kp]])          # Kp + Ki/s
        axes[ax] = AxisController.from_error_controller(pi, ts, method="tustin")
    params = {"baseline": "002 eq (19)-(20)", "baseline_pi": pis}
    return make_artifact(spec, axes, decoupling_from_motor(m), params,
                         ["002 eq (19)-(20)", "002 eq (23)"],
                         fcs=FcsWeights(alpha=cfg.alpha, beta=cfg.beta, gamma=cfg.gamma))
