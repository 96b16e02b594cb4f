"""Shared motors and law builders for the simulator tests."""

import numpy as np

from toolbox.artifact import Decoupling
from toolbox.sim._simulate import AxisLaw, ControlLaw
from toolbox.spec import Motor

# Le Pioufle 1992 (paper 000), appendix; power-invariant dq (torque factor 1)
PAPER000 = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4,
                 J=1.11e-3, friction=1.4e-3, convention="power")
# Cormerais 2002 (paper 002), section 3.2; power-invariant (eq 3)
PAPER002 = Motor(R=0.02, Ld=112.6e-6, Lq=112.6e-6, flux=60.39e-3,
                 pole_pairs=6, J=1.0, friction=0.0, convention="power")


def placed(plant, Ts, delay=1, **flags):
    """The nominal decoupling with the default voltage placement of a design
    (``(delay + 1/2) Ts``, toolbox/ARCHITECTURE.md "The digital loop")."""
    return Decoupling.from_motor(plant, delay_compensation_time=(delay + 0.5) * Ts, **flags)


def tc_law(plant, K1, K2, Ts, **kw):
    """Total compensation, paper 000 eq (11): v = R i + K L (i_ref - i) + decoupling."""
    def ax(L, K):
        return AxisLaw(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)),
                       np.array([[K * L, plant.R - K * L]]))
    return ControlLaw(d=ax(plant.Ld, K1), q=ax(plant.Lq, K2), sample_time=Ts,
                      decoupling=placed(plant, Ts), **kw)


def tci_law(plant, K11, K12, K21, K22, Ts):
    """Total compensation with integrators, paper 000 eq (20), forward-Euler integrator.

    v = R i + K1 L e + K2 L x + decoupling, x[k+1] = x[k] + Ts e[k];
    back-calculation anti-windup gain 1/(K2 L).
    """
    def ax(L, Kp, Ki):
        return AxisLaw(np.array([[1.0]]), np.array([[Ts, -Ts]]), np.array([[Ki * L]]),
                       np.array([[Kp * L, plant.R - Kp * L]]), np.array([1.0 / (Ki * L)]))
    return ControlLaw(d=ax(plant.Ld, K11, K12), q=ax(plant.Lq, K21, K22), sample_time=Ts,
                      decoupling=placed(plant, Ts))
