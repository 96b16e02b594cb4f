"""MIMO disk margins over the parameter box and the speed range (toolbox/ARCHITECTURE.md
"analysis.json", ``mimo_over_box``).

``mimo_over_box`` (in analysis.json as ``mimo_over_box`` and in the rows of
``cct compare`` as ``mimo_box``) evaluates the executed coupled loop on the
nominal plant and the 8 corners of R, Ld, Lq x0.5..x2 at speeds 0..max with
the vectorised :class:`MultiModelLoops`. Checked against the one-plant
reference :func:`mimo_disk_margins` (same grid, same mu bound: equal to
1e-9 relative, the only difference being the stacking and the speed sign,
which the loop is even in), and on paper 003's motor: the 145 rad/s
cancellation PI is unstable on box corners at speed, the robust PI is not.
"""

import numpy as np
import pytest

from toolbox.analysis import compare_designs, mimo_disk_margins, mimo_over_box
from toolbox.design import design
from toolbox.spec import spec_from_dict

DRIVE = {"vdc": 150, "sample_time": 1e-4, "delay_samples": 1}


def make(method, cfg=None):
    spec = spec_from_dict({"motor": {"catalog": "azaiz2007"}, "drive": dict(DRIVE),
                           "controller": {"method": method, method: cfg or {}}})
    return spec, design(spec)


@pytest.fixture(scope="module")
def pi_145():
    return make("pi", {"rule": "cancellation", "bandwidth": 145.0})


def test_box_finds_the_unstable_corner_at_speed(pi_145):
    spec, art = pi_145
    res = mimo_over_box(art, spec.motor, spec.drive, n_grid=600)
    assert res.n_models == 9 and res.speeds_rad_s[-1] == pytest.approx(920.0)
    assert res.n_unstable > 0 and res.worst_disk_margin == 0.0
    assert res.worst_speed_rad_s > 0                      # stable at standstill
    assert set(res.worst_params.values()) <= {0.5, 2.0}   # a corner, not the nominal plant
    assert res.nominal_worst_disk_margin > 0               # nominal plant stable at every speed
    js = res.to_json()
    assert js["worst_params"] == res.worst_params and js["n_unstable"] == res.n_unstable


def test_box_equals_the_one_plant_reference():
    spec, art = make("pi")                                # default bandwidth: stable everywhere
    res = mimo_over_box(art, spec.motor, spec.drive, n_grid=600)
    assert res.n_unstable == 0
    corner = spec.motor.with_overrides(None, res.worst_params)
    ref = mimo_disk_margins(art, corner, n_speeds=1, n_grid=600,
                            max_speed_rad_s=res.worst_speed_rad_s)   # evaluated at -speed
    assert ref.worst_disk_margin == pytest.approx(res.worst_disk_margin, rel=1e-9)
    # the pi default keeps ~0.31 at L x0.5 at top speed (tests/design/test_robust_pi.py)
    assert res.worst_disk_margin < 0.4


@pytest.mark.slow
def test_compare_rows_carry_the_box_worst_case(pi_145):
    spec, art = pi_145
    # the tuner's R, Ld, Lq models made equal to the box's (nominal + corners, the same 5
    # speeds), with the speed-sensor errors on top: the box sees an exact sensor
    rob = make("robust_pi", {"samples": 0, "n_speeds": 5, "zero_ratios": [10.0]})[1]
    rows = compare_designs([art, rob], spec.motor, spec.drive, sweep_sets=20, certificate=False)
    assert rows[0]["mimo_box"]["worst_disk_margin"] == 0.0 and rows[0]["mimo_box"]["n_unstable"] > 0
    assert rows[1]["mimo_box"]["worst_disk_margin"] >= 0.5 * 0.99   # the tuner's target, 1 % grid tolerance
    assert rows[1]["mimo_box"]["n_unstable"] == 0
    assert np.isfinite(rows[1]["mimo_box"]["worst_speed_rad_s"])


def test_sensor_errors_per_model_equal_the_one_plant_reference():
    """MultiModelLoops with a speed-sensor error per model (``w_meas = g w + o``
    in the decoupling, the voltage placement and the stability check) equals
    mimo_disk_margins with the same sensor; models sharing a plant share its
    precomputed response without mixing their sensors; the loop at ``(-w, o)``
    is the loop at ``(w, -o)``."""
    from toolbox.analysis.margins import MultiModelLoops

    spec, art = make("pi")
    corner = spec.motor.with_overrides(None, {"R": 0.5, "Ld": 0.5, "Lq": 0.5})
    motors = [corner, spec.motor, corner]
    gain, offset = [1.1, 0.9, 1.0], [40.0, -40.0, 0.0]
    speeds = [0.0, 920.0]
    M = MultiModelLoops(motors, speeds, art.sample_time, art.delay_samples, 600,
                        speed_gain=gain, speed_offset=offset).disk_margins(art)
    for i, motor in enumerate(motors):
        ref = mimo_disk_margins(art, motor, n_speeds=3, n_grid=600, max_speed_rad_s=920.0,
                                speed_gain=gain[i], speed_offset=offset[i])
        assert ref.disk_margin[1] == pytest.approx(M[i, 0], rel=1e-9)          # 0 rad/s
        assert ref.disk_margin[2] == pytest.approx(M[i, 1], rel=1e-9)          # +920
        mirror = mimo_disk_margins(art, motor, n_speeds=3, n_grid=600, max_speed_rad_s=920.0,
                                   speed_gain=gain[i], speed_offset=-offset[i])
        assert mirror.disk_margin[0] == pytest.approx(M[i, 1], rel=1e-9)       # -920, -o
    # the sensor matters at the corner: 1.1 and +40 rad/s cost margin against exact
    assert M[0, 1] < M[2, 1]
    exact = MultiModelLoops(motors, speeds, art.sample_time, art.delay_samples,
                            600).disk_margins(art)
    assert exact[0] == pytest.approx(exact[2], rel=1e-12)
    assert exact[2] == pytest.approx(M[2], rel=1e-12)
