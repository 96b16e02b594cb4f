"""H-infinity synthesis against the coupled plant at speed (issue 17 item 4).

designs/003_azaiz2007_hinf_at_speed.toml is paper 003's design with
``[controller.hinf.at_speed]``: the S weight of each axis gets the small-gain
term of the residual cross-coupling (toolbox.design._hinf_speed). Paper 003's
per-axis design loses 178 of the 1129 robustness-sweep sets (148 of them with
the design's own delay); the at-speed design must keep every set with the
design delay, lose no set that the per-axis design keeps, and still have
sensible margins at standstill.
"""

import tomllib

import control as ct
import numpy as np
import pytest

from toolbox.analysis import compute_margins, robustness_sweep
from toolbox.design._hinf_speed import AtSpeedCfg, coupling_gains
from toolbox.errors import SpecError
from toolbox.pipeline import design_spec
from toolbox.plant import axis_plants
from toolbox.spec import load_spec, spec_from_dict

NOMINAL = "designs/003_azaiz2007_hinf.toml"
AT_SPEED = "designs/003_azaiz2007_hinf_at_speed.toml"


@pytest.fixture(scope="module")
def designs():
    spec = load_spec(AT_SPEED)
    return spec, design_spec(load_spec(NOMINAL)), design_spec(spec)


def _sweep(art, spec, **kw):
    return robustness_sweep(art, spec.motor, n=1000, drive=spec.drive, n_grid=200, **kw)


def test_stable_where_the_per_axis_design_fails(designs):
    """With the design delay held (the sets and speeds are the same for both
    designs: the sampler depends only on the seed), the per-axis design is
    unstable on many sets and the at-speed design on none."""
    spec, nominal, at_speed = designs
    held = {"delay_samples": None}
    before, after = _sweep(nominal, spec, ranges=held), _sweep(at_speed, spec, ranges=held)
    assert before.n_unstable > 100 and after.n_unstable == 0, (before.n_unstable,
                                                              after.n_unstable)
    assert after.worst_spectral_radius < 1


def test_default_sweep_loses_only_extra_delay_sets(designs):
    """Over the default sweep (delay up to one period more than designed) the
    count falls from 249 to 4 (249 with the header's voltage placement, whose
    speed-sensor errors mis-rotate the voltage: toolbox/ARCHITECTURE.md "The
    digital loop"; 178 before it was modelled); what is left needs the extra period (the
    continuous synthesis does not model it), and those sets are unstable for
    the per-axis design too (its worst radius there is also above 1)."""
    spec, nominal, at_speed = designs
    before, after = _sweep(nominal, spec), _sweep(at_speed, spec)
    assert before.n_unstable == 249 and after.n_unstable < 10, (before.n_unstable,
                                                               after.n_unstable)
    for ex in after.unstable_examples:
        assert ex["delay_samples"] == at_speed.delay_samples + 1
        probe = robustness_sweep(nominal, spec.motor,
                                 {k: (ex[k], ex[k]) for k in ("R", "Ld", "Lq", "speed_gain",
                                                              "speed_offset", "delay_samples")},
                                 n=0, drive=spec.drive, n_grid=50)
        assert probe.n_unstable > 0


def test_standstill_margins_stay_sensible(designs):
    """At standstill (sampled executed loop, ZOH, one period of delay) both axes
    keep GM >= 14 dB, PM >= 80 deg, M_m >= 0.7 and zero static error (integral
    action); measured 15.0/18.5 dB, 88/95 deg, 0.74/0.82. A design that gave
    up robustness for speed (or lost its integrators) fails these."""
    spec, _, at_speed = designs
    for ax, m in compute_margins(at_speed, spec.motor).items():
        assert m.stable, ax
        assert m.gain_margin_db >= 14 and m.phase_margin_deg >= 80, (ax, m)
        assert m.stability_margin >= 0.7 and m.static_error <= 1e-9, (ax, m)


def test_small_gain_condition_from_the_stored_law(designs):
    """The small-gain peak ``c_d c_q |S_d G_d S_q G_q|`` recomputed from the
    artifact's executed laws (their continuous twins) and the coupling gains
    of the box is below 1, as design_parameters.at_speed records."""
    spec, _, at_speed = designs
    rec = at_speed.design_parameters["at_speed"]
    c_d, c_q = coupling_gains(spec.motor, at_speed.decoupling, spec.controller.cfg.at_speed)
    assert (c_d, c_q) == (rec["coupling_gain_d_ohm"], rec["coupling_gain_q_ohm"])
    G = axis_plants(spec.motor)
    w = np.logspace(-2, 6, 6001)
    prod = c_d * c_q
    for ax in "dq":
        cont = at_speed.axes[ax].continuous
        K = ct.ss(cont.A, cont.B, cont.C, cont.D)
        prod = prod * np.abs(ct.frequency_response(ct.feedback(ct.ss(G[ax]), K), w)
                             .magnitude).ravel()
    assert np.max(prod) < 1 and np.max(prod) == pytest.approx(rec["small_gain_peak"], rel=0.01)


def test_coupling_gains_by_hand():
    """Largest |w Lq - (g w + o) Lq_c| over the default box: Lq x2 at full speed
    with the speed under-read by the sensor (g = 0.9, o = -10 rad/s mech)."""
    spec = load_spec(AT_SPEED)
    m = spec.motor
    cfg = AtSpeedCfg(max_speed=230.0)
    from toolbox.design._common import decoupling_from_motor
    c_d, c_q = coupling_gains(m, decoupling_from_motor(m), cfg)
    w = 230.0 * m.pole_pairs
    assert c_d == pytest.approx(w * 2 * m.Lq - (0.9 * w - 10 * m.pole_pairs) * m.Lq)
    assert c_q == pytest.approx(w * 2 * m.Ld - (0.9 * w - 10 * m.pole_pairs) * m.Ld)


def test_spec_round_trip_and_refusals():
    """The table reads back to the same configuration; a box that excludes the
    nominal inductance or an unknown key is refused with its key path."""
    spec = load_spec(AT_SPEED)
    cfg = spec.controller.cfg
    again = spec_from_dict({**tomllib.loads(open(AT_SPEED, "rb").read().decode()),
                            "controller": {"method": "hinf",
                                           "hinf": cfg.to_spec(spec)}})
    assert again.controller.cfg.at_speed == cfg.at_speed
    raw = tomllib.loads(open(AT_SPEED, "rb").read().decode())
    for bad, key in (({"inductance_box": [1.2, 2.0]}, "inductance_box"),
                     ({"max_speed": -1.0}, "max_speed"), ({"speeds": 3}, "speeds")):
        raw["controller"]["hinf"]["at_speed"] = bad
        with pytest.raises(SpecError) as err:
            spec_from_dict(raw)
        assert f"controller.hinf.at_speed.{key}" in str(err.value)
