"""Test artifacts for the firmware export, built directly (no design module).

* ``pi_artifact``: PI per axis, pole-zero cancellation of R + sL at 500 rad/s
  (Kp = L wc, Ki = R wc), Tustin, back-calculation anti-windup; one-DOF, so the
  header uses second-order sections.
* ``ip_tc_artifact``: two-input laws: IP on d (v = Ki/s (r - y) - Kp y) and
  total compensation with integrator on q (paper 000 eq 18-20 shape:
  v = L (K1 (r - y) + K2 int(r - y)) + R y), both Tustin.
* ``hinf_artifact``: paper 003 q-axis central H-infinity controller at
  gamma = 1 (4th order, eq 68) on both axes, Tustin (as tests/papers/test_003_hinf.py).
"""

from __future__ import annotations

import control as ct
import numpy as np

from toolbox.artifact import (AxisController, AxisWeights, ControllerArtifact, Decoupling,
                              TransferFunctionData)
from toolbox.spec import Drive, Motor

TS = 1e-4
MOTOR = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4, J=1.11e-3,
              friction=1.4e-3, convention="amplitude", rated_current=10.0,
              max_current=20.0, rated_speed=300.0)
DRIVE = Drive(vdc=150.0, sample_time=TS, delay_samples=1, max_speed=400.0)
PROV = {"version": "test", "spec_sha256": "0" * 64, "created": "2026-01-01T00:00:00+00:00"}


def _dec(motor=MOTOR, delay_compensation_time: float = 0.0) -> Decoupling:
    return Decoupling(cross=True, emf=True, R_c=motor.R, Ld_c=motor.Ld, Lq_c=motor.Lq,
                      flux_c=motor.flux, pole_pairs=motor.pole_pairs,
                      delay_compensation_time=delay_compensation_time)


#: An H-infinity artifact must carry its weights (the export does not read them):
#: paper 003 eq (44)'s W1 on both axes.
_W1 = TransferFunctionData(np.array([1 / 1.51, 177.3493 / 1.51]), np.array([1.0, 0.0117]))
HINF_WEIGHTS = {ax: AxisWeights(gamma=1.0, w1=_W1) for ax in ("d", "q")}


def _artifact(method, axes, params=None, title="test controller",
              delay_compensation_time: float = 0.0) -> ControllerArtifact:
    return ControllerArtifact(method=method, spec={"title": title}, sample_time=TS,
                              delay_samples=1, axes=axes,
                              decoupling=_dec(delay_compensation_time=delay_compensation_time),
                              weights=HINF_WEIGHTS if method == "hinf" else None,
                              design_parameters=params or {}, provenance=dict(PROV))


def pi_gains(wc=500.0):
    return {ax: (L * wc, MOTOR.R * wc) for ax, L in (("d", MOTOR.Ld), ("q", MOTOR.Lq))}


def pi_artifact(wc=500.0, title="PI test") -> ControllerArtifact:
    s = ct.tf("s")
    g = pi_gains(wc)
    axes = {ax: AxisController.from_error_controller(kp + ki / s, TS) for ax, (kp, ki) in g.items()}
    return _artifact("pi", axes, {"Kp": {ax: g[ax][0] for ax in g},
                                  "Ki": {ax: g[ax][1] for ax in g}}, title,
                     delay_compensation_time=1.5 * TS)


def ip_tc_artifact() -> ControllerArtifact:
    kp, ki = MOTOR.Ld * 500.0, MOTOR.R * 500.0
    ip = ct.ss([[0.0]], [[ki, -ki]], [[1.0]], [[0.0, -kp]])
    K1, K2 = 800.0, 2.0e5
    L, R = MOTOR.Lq, MOTOR.R
    tc = ct.ss([[0.0]], [[1.0, -1.0]], [[L * K2]], [[L * K1, -L * K1 + R]])
    axes = {"d": AxisController.from_law(ip, sample_time=TS, method="tustin"),
            "q": AxisController.from_law(tc, sample_time=TS, method="tustin")}
    return _artifact("tci", axes, {"K1": K1, "K2": K2})


def hinf_controller() -> ct.StateSpace:
    from toolbox.design import _hinf_plant as HP, _hinf_riccati as HR
    from toolbox.design._weights import weight_from_tf
    G = ct.tf([1], [2.8e-3, 0.6])                          # paper 003 eq (34)
    w1 = weight_from_tf([1 / 1.51, 177.3493 / 1.51], [1, 0.0117])   # eq (44)
    w2 = weight_from_tf([0.5e-3, 0.5], [2e-5, 1])                   # eq (45)
    w3 = weight_from_tf([1e4, 1e4 * 135.68], [1, 2.7135e6])         # eq (46)
    return HR.central_controller(HP.augment_mixed_sensitivity(G, w1, w2, w3), 1.0).to_control()


def hinf_artifact() -> ControllerArtifact:
    K = hinf_controller()
    axes = {ax: AxisController.from_error_controller(K, TS) for ax in ("d", "q")}
    return _artifact("hinf", axes, {"gamma": 1.0})


def hinf_marginal_artifact() -> ControllerArtifact:
    """Paper 003's controller with the plain self-conditioned vector B/D, whose
    saturated recursion A - B C / D has a pole at z = -1 (the Tustin image of
    the zero at infinity of a strictly proper K). The artifact's default
    vector moves that mode to the origin; this one keeps it, to test the
    export's guard."""
    K = hinf_controller()
    axes = {}
    for ax in ("d", "q"):
        base = AxisController.from_error_controller(K, TS)
        law = base.law
        aw = law.B[:, 1:2] / law.D[0, 1]
        axes[ax] = AxisController(law, base.continuous, aw)
    return _artifact("hinf", axes, {"gamma": 1.0})


def unstable_artifact() -> ControllerArtifact:
    """A PI whose 'integrator' is an unstable pole at +50 rad/s (z = 1.005)."""
    s = ct.tf("s")
    K = 1.0 + 300.0 / (s - 50.0)
    axes = {ax: AxisController.from_error_controller(K, TS) for ax in ("d", "q")}
    return _artifact("pi", axes)


def ringing_artifact() -> ControllerArtifact:
    """A lead with an uncancelled pole at 5e6 rad/s (Tustin: z = -0.992)."""
    s = ct.tf("s")
    K = 2.0 * (s + 1e3) / (s / 5e6 + 1) / s * 50
    axes = {ax: AxisController.from_error_controller(K, TS) for ax in ("d", "q")}
    return _artifact("hinf", axes)


def static_artifact() -> ControllerArtifact:
    """Order-0 laws: a 1-DOF proportional gain (d) and total compensation
    without integrator (q; paper 000 eq 11: v = Lq K1 (r - y) + R y)."""
    K1 = 800.0
    p = ct.ss([], [], [], [[2.0]])
    tc = ct.ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)),
               [[MOTOR.Lq * K1, -MOTOR.Lq * K1 + MOTOR.R]])
    axes = {"d": AxisController.from_error_controller(p, TS),
            "q": AxisController.from_law(tc, sample_time=TS, method="tustin")}
    return _artifact("tc", axes, {"K1": K1})


def odd_order_artifact() -> ControllerArtifact:
    """Third-order 1-DOF law (PI x lead): SOS with a first-order stage."""
    s = ct.tf("s")
    K = (1.4 + 300.0 / s) * (s / 800.0 + 1) / (s / 4000.0 + 1)
    Kd = (0.7 + 300.0 / s) * (s / 500.0 + 1) * (s / 900.0 + 1) / ((s / 3000.0 + 1) * (s / 5000.0 + 1))
    axes = {"d": AxisController.from_error_controller(Kd, TS),
            "q": AxisController.from_error_controller(K, TS)}
    return _artifact("pi_lag", axes)
