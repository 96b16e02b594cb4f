"""Inverter helpers: paper 002 eq (21)-(22) volt-second balance, the hexagon
clip, the inverter-state vectors, and SVM against the average model."""

import math

import numpy as np
import pytest

from toolbox.artifact import Decoupling
from toolbox.sim._inverter import (bit_changes, hexagon_scale, state_vector,
                                   svm_times)
from toolbox.spec import Scenario
from toolbox.sim._simulate import ControlLaw, DriveParams, discrete_pi, simulate

from sim_helpers import PAPER000 as M

R_HEX = 100.0


def test_state_vectors_form_the_hexagon():
    v = np.array([state_vector(i, R_HEX) for i in range(8)])
    assert np.allclose(v[0], 0) and np.allclose(v[7], 0)
    assert np.allclose(np.hypot(v[1:7, 0], v[1:7, 1]), R_HEX)
    # paper 002 numbering: state 4 = (m1, m2, m3) = (1, 0, 0) lies on the alpha axis
    assert np.allclose(v[4], [R_HEX, 0.0])


@pytest.mark.parametrize("ang_deg", [0.0, 17.0, 59.9, 60.0, 133.0, 200.0, 299.0, 359.0])
@pytest.mark.parametrize("mag", [0.0, 30.0, 80.0])
def test_svm_volt_second_balance(ang_deg, mag):
    """T0 V0 + Tk Vk + Tl Vl = V Ts and T0 + Tk + Tl = Ts (eq 21-22), with the
    first active state one cell away from 000 (so 0-k-l-7 commutes one cell at a time)."""
    Ts = 1e-4
    va, vb = mag * math.cos(math.radians(ang_deg)), mag * math.sin(math.radians(ang_deg))
    k, l, tk, tl, t0 = svm_times(va, vb, R_HEX, Ts)
    vk, vl = np.array(state_vector(k, R_HEX)), np.array(state_vector(l, R_HEX))
    assert np.allclose(tk * vk + tl * vl, np.array([va, vb]) * Ts, atol=1e-12)
    assert t0 + tk + tl == pytest.approx(Ts) and min(t0, tk, tl) >= 0
    assert bit_changes(0, k) == 1 and bit_changes(k, l) == 1 and bit_changes(l, 7) == 1


def test_hexagon_clip():
    inner = R_HEX * math.sqrt(3) / 2
    assert hexagon_scale(R_HEX * 1.5, 0.0, R_HEX) == pytest.approx(1 / 1.5)   # vertex
    va, vb = 2 * inner * math.cos(math.pi / 6), 2 * inner * math.sin(math.pi / 6)
    assert hexagon_scale(va, vb, R_HEX) == pytest.approx(0.5)                 # edge middle
    assert hexagon_scale(10.0, 5.0, R_HEX) == 1.0


def test_svm_current_tracks_average_model():
    """At 1500 rad/s electrical the period-averaged SVM voltage equals the
    average model's: the static i_q agrees within 0.05 A (ripple at 10 kHz
    with L = 2.8 mH is ~0.3 A peak-to-peak and averages out over the last 10 %)."""
    Ts, wc = 1e-4, 1500.0
    law = ControlLaw(d=discrete_pi(M.Ld * wc, M.R * wc, Ts), q=discrete_pi(M.Lq * wc, M.R * wc, Ts),
                     sample_time=Ts, decoupling=Decoupling.from_motor(M))
    sc = Scenario(kind="current_step", duration=0.03, iq_ref=8.0, id_ref=-2.0,
                  initial_speed=375.0)
    out = {}
    for inv in ("average", "svm"):
        drive = DriveParams(vdc=150, sample_time=Ts, delay_samples=1, v_limit="hexagon",
                            inverter=inv)
        out[inv] = simulate(law, M, sc, drive).metrics
    assert abs(out["svm"]["final_value"] - out["average"]["final_value"]) < 0.05
    assert out["svm"]["commutations_per_s"] == pytest.approx(12 / Ts)
    assert out["average"]["commutations_per_s"] == 0.0
