"""Artifacts built by hand for the analysis tests (no dependency on the design modules).

* PI by pole-zero cancellation: Kp = L wc, Ki = R wc (paper 000 sect. 2 / 002 eq 19-20);
* total compensation without integrators (paper 000 eq 11): v = L K (i_ref - i) + R i
  (+ decoupling and EMF compensation), a two-input law;
* paper 003 central H-infinity controllers at gamma = 1 (eq 68, 70) from toolbox/design/_hinf_riccati.py (Theorem 2).
Motor: paper 003 sect. 6 (amplitude-invariant), Ts = 1e-4 s, one period of delay.
"""
import control as ct
import numpy as np
from toolbox.artifact import (AxisController, AxisWeights, ControllerArtifact, Decoupling,
                              TransferFunctionData)
from toolbox.spec import Motor, Drive
from toolbox.design import _hinf_plant as HP, _hinf_riccati as HR
from toolbox.lti import TransferFunction
from toolbox.design._weights import weight_from_tf

AZAIZ = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4, J=1.11e-3, friction=1.4e-3,
              convention="amplitude", rated_speed=230.0)
DRIVE = Drive(vdc=150.0, sample_time=1e-4, delay_samples=1, max_speed=230.0)

def dec(m, cross=True, emf=True):
    return Decoupling(cross, emf, m.R, m.Ld, m.Lq, m.flux, m.pole_pairs)

def art(method, axes, m=AZAIZ, Ts=1e-4, d=1, cross=True, weights=None):
    return ControllerArtifact(method=method, spec={}, sample_time=Ts, delay_samples=d,
                              axes=axes, decoupling=dec(m, cross), weights=weights)


def _tf_data(w) -> TransferFunctionData:
    tf = TransferFunction.from_system(w)      # the weights are toolbox.lti's
    return TransferFunctionData(np.array(tf.num), np.array(tf.den))

def pi_artifact(wc=1000.0, m=AZAIZ, Ts=1e-4, d=1):
    s = ct.tf("s")
    ax = {n: AxisController.from_error_controller((L * wc * s + m.R * wc) / s, Ts)
          for n, L in (("d", m.Ld), ("q", m.Lq))}
    return art("pi", ax, m, Ts, d)

def hinf_artifact(Ts=1e-4, d=1):
    W = {"q": (ct.tf([1], [2.8e-3, 0.6]), weight_from_tf([1 / 1.51, 177.3493 / 1.51], [1, 0.0117]),
               weight_from_tf([0.5e-3, 0.5], [2e-5, 1]), weight_from_tf([1e4, 1e4 * 135.68], [1, 2.7135e6])),
         "d": (ct.tf([1], [1.4e-3, 0.6]), weight_from_tf([1 / 1.7, 68.7386 / 1.7], [1, 0.0040]),
               weight_from_tf([25, 25e3], [1, 5e4]), weight_from_tf([1e4, 1e4 * 577.3503], [1, 1.1547e7]))}
    ax, weights = {}, {}
    for n, (G, w1, w2, w3) in W.items():
        K = HR.central_controller(HP.augment_mixed_sensitivity(G, w1, w2, w3), 1.0).to_control()
        ax[n] = AxisController.from_error_controller(K, Ts)
        weights[n] = AxisWeights(1.0, _tf_data(w1), _tf_data(w2), _tf_data(w3))
    return art("hinf", ax, AZAIZ, Ts, d, weights=weights)

def tc_artifact(K=800.0, m=AZAIZ, Ts=1e-4, d=1):
    """Total compensation (paper 000 eq 11): v = L K (i_ref - i) + R i (+ decoupling)."""
    ax = {}
    for n, L in (("d", m.Ld), ("q", m.Lq)):
        law = ct.ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[L * K, -(L * K - m.R)]], Ts)
        ax[n] = AxisController.from_law(law, sample_time=Ts, method="native", antiwindup=False)
    return art("tc", ax, m, Ts, d)


def plain_bisection(ok, tol: float) -> float:
    """Largest scale in [0, 1] with ``ok(scale)``, by plain bisection to ``tol``
    (the reference the certificates' warm-started bisections are tested against)."""
    if ok(1.0):
        return 1.0
    if not ok(0.0):
        return 0.0
    lo, hi = 0.0, 1.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo
