"""H-infinity synthesised against the coupled dq plant at speed.

designs/003_azaiz2007_hinf_at_speed.toml: paper 003's motor (vdc 150 V,
Ts 100 us, delay 1) with ``[controller.hinf.at_speed]``: the 2x2 generalised
plant of toolbox.design._hinf_coupled (003 eq (3)-(4) at speed, the delayed
decoupling, the loop delay by Pade), R, Ld, Lq x0.5..x2 and the speed sensor
as a model set, one structured controller per axis minimising the worst
closed-loop H-infinity norm. Done when: 0 unstable sets on the full sweep with
the design delay, q rise time within 2x of paper 003's 0.013 s (Fig. 8).
"""

import math
import tomllib

import control as ct
import numpy as np
import pytest

from toolbox.analysis import compute_margins, robustness_sweep
from toolbox.design._hinf_coupled import (Model, _core, closed_loop_gamma, coupled_plant,
                                          full_order_gamma, model_set, structured_controller)
from toolbox.design._hinf_speed import AtSpeedCfg
from toolbox.errors import SpecError
from toolbox.pipeline import design_spec
from toolbox.plant import dq_matrices, max_electrical_speed
from toolbox.spec import load_spec, spec_from_dict

pytestmark = pytest.mark.slow   # the at-speed synthesis tunes over 116 models (about 17 CPU-s a design)

NOMINAL = "designs/003_azaiz2007_hinf.toml"
AT_SPEED = "designs/003_azaiz2007_hinf_at_speed.toml"
#: paper 003 Fig. 8 / sect. 5: q-axis rise time (s) of the per-axis design
PAPER_RISE_Q = 0.013


@pytest.fixture(scope="module")
def designs():
    spec = load_spec(AT_SPEED)
    return spec, design_spec(load_spec(NOMINAL)), design_spec(spec)


def _sweep(art, spec, **kw):
    return robustness_sweep(art, spec.motor, n=1000, drive=spec.drive, n_grid=200, **kw)


def test_full_sweep_with_the_design_delay_has_no_unstable_set(designs):
    """The full sweep (nominal, corners, 1000 Latin-hypercube sets of R, Ld, Lq
    x0.5..x2, flux, speed-sensor gain 0.9..1.1 and offset +/-10 rad/s; 9
    speeds -max..max) with the design delay: paper 003's per-axis design is
    unstable on many sets, the coupled design on none (measured 0 of 1065,
    worst spectral radius 0.979). With the sweep's delay range (one period
    more on half the sets; 1129 sets) it stays at 0 (measured worst radius
    0.982; the small-gain design of before lost 4)."""
    spec, nominal, at_speed = designs
    held = {"delay_samples": None}
    before = _sweep(nominal, spec, ranges=held, n_speeds=9)
    after = _sweep(at_speed, spec, ranges=held, n_speeds=9)
    assert after.n_sets == before.n_sets > 1000
    assert before.n_unstable > 50 and after.n_unstable == 0, (before.n_unstable,
                                                             after.n_unstable)
    assert after.worst_spectral_radius < 1
    full = _sweep(at_speed, spec, n_speeds=9)
    assert full.n_sets == 1129 and full.n_unstable == 0, full.unstable_examples


def test_q_rise_time_within_twice_the_paper(designs):
    """q-axis 10-90 % rise time of the sampled executed loop at standstill (ZOH,
    one period of delay) at most 2 x 0.013 s (paper 003 Fig. 8), and no
    slower than the per-axis design it replaces (which reproduces the
    paper's 0.013 s within 10 %): the coupling costs no bandwidth
    (measured 0.84 ms, the per-axis design 13.0 ms)."""
    spec, nominal, at_speed = designs
    ours = compute_margins(at_speed, spec.motor)["q"]
    paper = compute_margins(nominal, spec.motor)["q"]
    assert paper.rise_time_10_90 == pytest.approx(PAPER_RISE_Q, rel=0.1)
    assert ours.rise_time_10_90 <= 2 * PAPER_RISE_Q
    assert ours.rise_time_10_90 < paper.rise_time_10_90


def test_standstill_against_the_paper(designs):
    """At standstill (sampled executed loop) against paper 003 sect. 3.3-3.5 and
    5 (q: GM 31.2 dB, PM 83.7 deg, M_m 0.92 continuous; rise 0.013 s,
    settling 0.025 s): the coupled design trades gain margin for bandwidth
    (measured d 10.9 dB / 67.4 deg / M_m 0.67, q 17.3 dB / 55.7 deg / 0.80;
    the per-axis design reproduces the paper's q 26.3 dB / 82.4 deg / 0.90
    sampled) and keeps integral action (zero static error, 003 sect. 5:
    e_ss < 1e-4); both axes stay inside the spec's GM >= 8 dB, PM >= 50 deg,
    M_m >= 0.6 and settle faster than the paper's 0.025 s (4.3 / 4.9 ms)."""
    spec, _, at_speed = designs
    for ax, m in compute_margins(at_speed, spec.motor).items():
        assert m.stable, ax
        assert m.gain_margin_db >= 8 and m.phase_margin_deg >= 50, (ax, m)
        assert m.stability_margin >= 0.6 and m.static_error <= 1e-9, (ax, m)
        assert m.settling_time_2pct < 0.025, (ax, m)


def test_structured_level_against_an_independent_route(designs):
    """The worst level recorded is ``max_i ||F_l(P_i, K)||_inf`` over the model
    set; recomputed with python-control (its lower LFT with the stored laws'
    continuous twins, frequency response on a dense grid: a lower estimate of
    the peak) it agrees within 1 %."""
    spec, _, at_speed = designs
    rec = at_speed.design_parameters["at_speed"]
    wm = rec["worst_model"]
    model = Model(wm["R_ohm"], wm["Ld_H"], wm["Lq_H"], wm["speed_rad_s"],
                  wm["measured_speed_rad_s"], wm["extra_delay_s"])
    weights = _weights(at_speed)
    dec = at_speed.decoupling
    P = coupled_plant(model, weights, dec.Ld_c, dec.Lq_c, 1.5 * spec.drive.sample_time)
    Pc = ct.ss(P.A, np.hstack([P.B1, P.B2]), np.vstack([P.C1, P.C2]),
               np.block([[P.D11, P.D12], [P.D21, P.D22]]))
    K = ct.append(*[ct.ss(*(getattr(at_speed.axes[ax].continuous, x) for x in "ABCD"))
                    for ax in "dq"])
    cl = Pc.lft(K, 2, 2)
    assert np.max(np.linalg.eigvals(cl.A).real) < 0
    w = np.logspace(0, 6, 4000)
    H = cl.horner(1j * w)                             # (nz, nw, len(w))
    peak = max(np.linalg.svd(H[:, :, k], compute_uv=False)[0] for k in range(len(w)))
    assert peak == pytest.approx(rec["worst_gamma"], rel=0.01)
    assert peak <= rec["worst_gamma"] * (1 + 1e-6)


def test_full_order_bound_and_slycot_cross_check(designs):
    """On each nominal speed model, the full-order 2x2 optimum (Theorem 1, own
    gamma iteration) agrees with SLICOT sb10ad within 1 % (sb10ad bisects on
    its own test; ours stops 1e-4 above its last infeasible level, and the
    psd test of X decides the last digits near the optimum), and the
    structured controller's level is not below it (a structured controller
    is a particular LTI controller)."""
    from slycot import sb10ad

    spec, _, at_speed = designs
    rec = at_speed.design_parameters["at_speed"]
    dec = at_speed.decoupling
    weights = _weights(at_speed)
    for w, lower, struct in zip(rec["speeds_rad_s"], rec["full_order_gamma_nominal"],
                                rec["nominal_gamma"]):
        m = spec.motor
        P = coupled_plant(Model(m.R, m.Ld, m.Lq, w, w), weights, dec.Ld_c, dec.Lq_c,
                          1.5 * spec.drive.sample_time)
        ours = full_order_gamma(P)
        assert ours == lower
        ref = sb10ad(P.nx, P.nw + P.nu, P.nz + P.ny, P.nu, P.ny, 100.0, P.A,
                     np.hstack([P.B1, P.B2]), np.vstack([P.C1, P.C2]),
                     np.block([[P.D11, P.D12], [P.D21, P.D22]]), job=1, gtol=1e-6)[0]
        assert ours == pytest.approx(ref, rel=0.01), (w, ours, ref)
        assert struct >= ref * (1 - 1e-6), (w, struct, ref)


def test_coupled_plant_is_the_derived_dq_model():
    """Without delay and decoupling the core plant's state matrix is
    ``toolbox.plant``'s derived ``A(w)`` (paper 003 eq (3)-(4)); with the
    exact decoupling at the true speed and no delay the coupling cancels
    (diagonal state matrix)."""
    spec = load_spec(AT_SPEED)
    m = spec.motor
    w = 700.0
    core = _core(Model(m.R, m.Ld, m.Lq, w, 0.0), m.Ld, m.Lq, 0.0)
    A = dq_matrices(m.R, m.Ld, m.Lq, w)[0][0]
    assert np.allclose(core.A, A, rtol=1e-12, atol=0)
    exact = _core(Model(m.R, m.Ld, m.Lq, w, w), m.Ld, m.Lq, 0.0)
    assert np.allclose(exact.A, np.diag(np.diag(A)), rtol=1e-12, atol=1e-9)


def test_model_set_holds_the_worst_corner():
    """The box's corners at the maximum speed are in the set: Ld x0.5, Lq x2 with
    the speed under-read, whose open-loop coupled plant has a real pole near
    +400 rad/s (the reason paper 003's 270 rad/s loop cannot be kept)."""
    spec = load_spec(AT_SPEED)
    m = spec.motor
    wmax = max_electrical_speed(m, spec.drive)
    cfg = spec.controller.cfg.at_speed
    p = m.pole_pairs
    box = {"R": cfg.resistance_box, "Ld": cfg.inductance_box, "Lq": cfg.inductance_box,
           "speed_gain": cfg.speed_gain, "speed_offset": tuple(o * p for o in cfg.speed_offset)}
    models = model_set(m, m.Ld, m.Lq, wmax, box)
    # standstill: 8 corners x 2 offsets (the gain acts on zero) + nominal; at speed
    # 8 corners x 4 sensor corners + nominal, at half and full speed
    assert len(models) == (8 * 2 + 1) + 2 * (8 * 4 + 1)
    slow = model_set(m, m.Ld, m.Lq, wmax, box, spec.drive.sample_time)
    assert len(slow) == len(models) + 8 * 4 + 1
    assert {x.extra_delay for x in slow[len(models):]} == {spec.drive.sample_time}
    worst = Model(0.5 * m.R, 0.5 * m.Ld, 2 * m.Lq, wmax, 0.9 * wmax - 10 * p)
    assert worst in models
    core = _core(worst, m.Ld, m.Lq, 0.0)
    assert 300 < np.max(np.linalg.eigvals(core.A).real) < 600


def test_unstable_model_has_infinite_level():
    """An unstabilised model is never scored by its L-infinity norm."""
    spec = load_spec(AT_SPEED)
    m = spec.motor
    weights = _weights(design_spec(spec))
    P = coupled_plant(Model(m.R, m.Ld, m.Lq, 0.0, 0.0), weights, m.Ld, m.Lq, 1.5e-4)
    K = structured_controller(np.array([-1.0, 1.0, 1e-4, -1.0, 1.0, 1e-4]))
    assert math.isinf(closed_loop_gamma(P, K))


def test_spec_round_trip_and_refusals():
    """The table reads back to the same configuration; a box that excludes the
    nominal value or an unknown key is refused with its key path."""
    spec = load_spec(AT_SPEED)
    cfg = spec.controller.cfg
    raw = tomllib.loads(open(AT_SPEED, "rb").read().decode())
    again = spec_from_dict({**raw, "controller": {"method": "hinf",
                                                  "hinf": cfg.to_spec(spec)}})
    assert again.controller.cfg.at_speed == cfg.at_speed
    assert cfg.at_speed == AtSpeedCfg(max_speed=cfg.at_speed.max_speed)
    for bad, key in (({"inductance_box": [1.2, 2.0]}, "inductance_box"),
                     ({"resistance_box": [0.5, 0.9]}, "resistance_box"),
                     ({"extra_delay": 1.5}, "extra_delay"),
                     ({"max_speed": -1.0}, "max_speed"), ({"speeds": 3}, "speeds")):
        raw["controller"]["hinf"]["at_speed"] = bad
        with pytest.raises(SpecError) as err:
            spec_from_dict(raw)
        assert f"controller.hinf.at_speed.{key}" in str(err.value)


def _weights(art) -> dict:
    """The artifact's weights as SISO python-control-free transfer functions."""
    from toolbox.lti import TransferFunction

    out = {}
    for ax in "dq":
        W = art.weights[ax]
        out[ax] = {n: (None if getattr(W, n) is None
                       else TransferFunction(getattr(W, n).num, getattr(W, n).den))
                   for n in ("w1", "w2", "w3")}
    return out
