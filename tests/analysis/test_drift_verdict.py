"""The default drift box a design is judged on (toolbox/analysis/_drift.py,
toolbox/ARCHITECTURE.md "Robustness verdict"): its values follow from the
cited coefficients, and the verdict runs the sweep and the multiloop disk
margin over that box."""

import math

import pytest

import toolbox
from toolbox.analysis import DRIVE_DRIFT, drift_ranges, drift_verdict
from toolbox.analysis._drift import (ALPHA_CU, DEFAULT_DRIFT_SETS, FLUX_TEMPERATURE_COEFF, SPEED_OFFSET_FRACTION,
                                     WINDING_TEMPERATURE_C, box_text)


def test_default_box_values_and_sources():
    # copper, IEC 60028: 0.00393 /K around 20 degC, winding -20..150 degC
    assert ALPHA_CU == 0.00393 and WINDING_TEMPERATURE_C == (20.0, -20.0, 150.0)
    assert DRIVE_DRIFT["R"] == (0.843, 1.511)
    assert DRIVE_DRIFT["R"][0] == pytest.approx(1 - 0.00393 * 40, abs=5e-4)
    assert DRIVE_DRIFT["R"][1] == pytest.approx(1 + 0.00393 * 130, abs=5e-4)
    # +-10 % tolerance, saturation another -10 % at peak current
    assert DRIVE_DRIFT["Ld"] == DRIVE_DRIFT["Lq"] == (0.8, 1.1)
    # NdFeB about -0.12 %/K over the same temperatures
    assert FLUX_TEMPERATURE_COEFF == -0.0012
    assert DRIVE_DRIFT["flux"] == (0.844, 1.048)
    assert DRIVE_DRIFT["speed_gain"] == (0.98, 1.02)
    assert SPEED_OFFSET_FRACTION == 0.01


def test_ranges_default_and_spec_box():
    spec = toolbox.spec_from_dict({"motor": {"catalog": "azaiz2007"},
                                   "drive": {"vdc": 150, "sample_time": 1e-4,
                                             "max_speed": 230.0},
                                   "controller": {"method": "pi"}})
    source, r = drift_ranges(spec.motor, spec.drive)
    assert source == "default"
    assert r["speed_offset"] == pytest.approx([-2.3, 2.3])    # 1 % of 230 rad/s
    assert r["delay_samples"] is None                          # the design's own delay
    assert r["R"] == [0.843, 1.511] and r["flux"] == [0.844, 1.048]
    source, r = drift_ranges(spec.motor, spec.drive, {"R": (0.5, 2.0)})
    assert source == "parameter_drift" and r["R"] == [0.5, 2.0]
    assert all(r[k] is None for k in r if k != "R")
    text = box_text("default", drift_ranges(spec.motor, spec.drive)[1], 920.0)
    assert text == ("default drift box: R x0.843..1.511, Ld/Lq x0.8..1.1, flux x0.844..1.048, "
                    "speed sensor +-2 %, +-1 % offset, 0..920 rad/s electrical")


def test_verdict_of_a_sound_and_a_hot_pi():
    base = {"motor": {"catalog": "azaiz2007"},
            "drive": {"vdc": 150, "sample_time": 1e-4, "delay_samples": 1, "max_speed": 230.0}}
    sound = toolbox.spec_from_dict({**base, "controller": {"method": "pi",
                                                           "pi": {"bandwidth": 1000.0}}})
    v = drift_verdict(toolbox.design_spec(sound), sound.motor, sound.drive)
    assert v.passed and v.n_unstable == 0 and v.first_unstable is None
    assert v.n_sets == 1 + 2 ** 6 + DEFAULT_DRIFT_SETS and v.delay_samples == 1
    assert 0 < v.worst_disk_margin < 2 and v.max_speed_rad_s == pytest.approx(920.0)
    assert v.summary().startswith("robustness (default drift box: R x0.843..1.511")
    # 8800 rad/s: stable at nominal, past the sampled limit once L drops by 20 %
    hot = toolbox.spec_from_dict({**base, "controller": {"method": "pi",
                                                         "pi": {"bandwidth": 8800.0}}})
    v = drift_verdict(toolbox.design_spec(hot), hot.motor, hot.drive)
    assert not v.passed and v.worst_disk_margin == 0.0
    f = v.first_unstable
    assert f["Ld"] == pytest.approx(0.8) and f["Lq"] == pytest.approx(0.8)
    assert f["spectral_radius"] > 1 and math.isfinite(f["speed_rad_s"])
    assert "first: R x0.843, Ld x0.8, Lq x0.8" in v.failure()
    assert f"at {f['speed_rad_s']:.4g} rad/s electrical" in v.failure()


def test_a_zero_disk_margin_fails_even_without_an_unstable_sample():
    """The multiloop disk-margin check runs the box's R, Ld, Lq corners with an
    exact speed sensor; a corner unstable there (margin 0) fails the verdict
    even when no sampled set of the sweep is, and the reason names it."""
    from toolbox.analysis._drift import DriftVerdict
    v = DriftVerdict(source="default", box={"R": [0.843, 1.511]}, box_text="default drift box: R",
                     max_speed_rad_s=920.0, delay_samples=1, n_sets=565, n_unstable=0,
                     first_unstable=None, worst_spectral_radius=0.99, worst_disk_margin=0.0,
                     worst_disk_margin_at={"R": 0.843, "Ld": 0.8, "Lq": 1.1, "speed_rad_s": 920.0})
    assert not v.passed
    assert "R x0.843, Ld x0.8, Lq x1.1" in v.failure() and "920 rad/s" in v.failure()
    ok = DriftVerdict(**{**v.__dict__, "worst_disk_margin": 0.2})
    assert ok.passed and ok.failure() is None
