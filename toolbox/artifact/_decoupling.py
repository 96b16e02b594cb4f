"""The nonlinear compensation of the controller artifact: cross-coupling,
back-EMF and the delay-compensation rotation (:class:`Decoupling`), kept
apart from the linear laws of the axes (toolbox/ARCHITECTURE.md "The digital
loop")."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from ..errors import ArtifactError
from ._fields import _no_unknown, finite_number

@dataclass(frozen=True)
class Decoupling:
    """Nonlinear compensation terms added to the linear controllers' outputs.

    ``v_d += -cross * w_m * Lq_c * i_q`` and
    ``v_q += cross * w_m * Ld_c * i_d + emf * w_m * flux_c``, with the
    measured electrical speed ``w_m = pole_pairs * Omega_m`` (rad/s).

    Attributes
    ----------
    cross : bool
        Cross-coupling compensation (the omega L i terms).
    emf : bool
        Back-EMF compensation (omega flux).
    R_c, Ld_c, Lq_c, flux_c : float
        Model parameters the controller uses (ohm, H, H, Wb); they may
        differ from the plant's.
    pole_pairs : int
        Pole pairs used to convert measured mechanical speed.
    delay_compensation_time : float
        Delay-compensation time (s, >= 0; 0 = none): the law's ``v_dq`` is
        rotated by ``delay_compensation_time * w_e`` before the inverse Park
        transform (motulator's complex-vector PI: 1.5 Ts, one period of
        computation delay plus half a period of PWM/ZOH delay). The firmware
        header exports it.
    """

    cross: bool
    emf: bool
    R_c: float
    Ld_c: float
    Lq_c: float
    flux_c: float
    pole_pairs: int
    delay_compensation_time: float = 0.0

    @classmethod
    def from_motor(cls, motor, *, cross: bool = True, emf: bool = True,
                   delay_compensation_time: float = 0.0) -> "Decoupling":
        """The controller-side model equal to a motor's nominal parameters.

        Parameters
        ----------
        motor : toolbox.spec.Motor
            The motor the controller believes in (its ``R``, ``Ld``, ``Lq``,
            ``flux``, ``pole_pairs`` are copied into ``R_c`` ... ``pole_pairs``).
        cross, emf : bool
            Cross-coupling and back-EMF compensation on.
        delay_compensation_time : float
            Rotation time of ``v_dq`` (s, 0 = none).
        """
        return cls(cross=cross, emf=emf, R_c=motor.R, Ld_c=motor.Ld, Lq_c=motor.Lq,
                   flux_c=motor.flux, pole_pairs=motor.pole_pairs,
                   delay_compensation_time=delay_compensation_time)

    def to_json(self) -> dict:
        return {"cross": self.cross, "emf": self.emf, "R_c": self.R_c,
                "Ld_c": self.Ld_c, "Lq_c": self.Lq_c, "flux_c": self.flux_c,
                "pole_pairs": self.pole_pairs,
                "delay_compensation_time": self.delay_compensation_time}

    @classmethod
    def from_json(cls, data: Any, key: str = "decoupling") -> "Decoupling":
        if not isinstance(data, Mapping):
            raise ArtifactError(key, "an object", data)
        names = ("cross", "emf", "R_c", "Ld_c", "Lq_c", "flux_c", "pole_pairs",
                 "delay_compensation_time")
        _no_unknown(data, set(names), key)
        for name in ("cross", "emf"):
            if not isinstance(data.get(name), bool):
                raise ArtifactError(f"{key}.{name}", "true or false", data.get(name))
        for name in ("R_c", "Ld_c", "Lq_c", "flux_c"):
            v = data.get(name)
            if not finite_number(v) or v < 0:
                raise ArtifactError(f"{key}.{name}", "a finite number >= 0", v)
        pp = data.get("pole_pairs")
        if not isinstance(pp, int) or isinstance(pp, bool) or pp < 1:
            raise ArtifactError(f"{key}.pole_pairs", "an integer >= 1", pp)
        t_comp = data.get("delay_compensation_time", 0.0)
        if not finite_number(t_comp) or t_comp < 0:
            raise ArtifactError(f"{key}.delay_compensation_time", "a finite number >= 0 (s)",
                                t_comp)
        return cls(data["cross"], data["emf"], float(data["R_c"]), float(data["Ld_c"]),
                   float(data["Lq_c"]), float(data["flux_c"]), pp, float(t_comp))
