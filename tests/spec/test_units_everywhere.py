"""Units wherever a spec holds a physical quantity (README "Spec files"):
method parameters, requirements, scenarios, campaigns, with datasheet
spellings; KV recognised; a motor-relative bound on the inertia that names
the likely unit slip; every error of a file in one run.

Expected values are computed here by hand from the unit definitions (1 rpm =
2 pi / 60 rad/s, 1 Hz of bandwidth = 2 pi rad/s, rms -> peak x sqrt(2) in
the amplitude-invariant dq frame, x sqrt(3) in the power-invariant one), not
by pint, so a wrong conversion table fails them.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from toolbox.errors import SpecError
from toolbox.spec import load_spec, spec_from_dict
from toolbox.spec._bounds import INERTIA_ACCELERATION

REL = 1e-12
RPM = 2 * math.pi / 60
SQRT2, SQRT3 = math.sqrt(2), math.sqrt(3)
DRIVE = {"vdc": 150, "sample_time": 1e-4}
MOTOR = {"catalog": "azaiz2007"}


def spec(**sections):
    data = {"motor": MOTOR, "drive": DRIVE, "controller": {"method": "pi"}}
    data.update(sections)
    return spec_from_dict(data)


def error(**sections) -> SpecError:
    with pytest.raises(SpecError) as info:
        spec(**sections)
    return info.value


# ------------------------------------------------------------ datasheet spellings
@pytest.mark.parametrize("key, text, si", [
    ("R", "0.6 Ohm", 0.6), ("R", "0.6 Ω", 0.6), ("R", "600 mOhm", 0.6),
    ("Ld", "2.8 mH", 2.8e-3),
    ("J", "11.1 kg·cm²", 11.1e-4), ("J", "11.1 kg*cm^2", 11.1e-4), ("J", "11100 g cm^2", 11.1e-4),
    ("rated_speed", "3000 1/min", 3000 * RPM), ("rated_speed", "3000 min⁻¹", 3000 * RPM),
    ("rated_speed", "3000 rpm", 3000 * RPM),
    ("rated_current", "10 Arms", 10 * SQRT2), ("rated_current", "10 A rms", 10 * SQRT2),
    ("rated_current", "10 A_rms", 10 * SQRT2), ("rated_current", "10 Apk", 10.0),
    ("max_current_rms", "10 Arms", 10 * SQRT2),  # a key named rms: the marker scales nothing
])
def test_datasheet_spelling(key, text, si):
    m = spec(motor={**MOTOR, key: text}).motor
    model_key = {"max_current_rms": "max_current"}.get(key, key)
    assert getattr(m, model_key) == pytest.approx(si, rel=REL)


@pytest.mark.parametrize("text", ["0.5 N·m/A", "0.5 Nm/A", "0.5 N m/A", "500 mNm/A"])
def test_torque_constant_spellings(text):
    """kt_peak = 1.5 p flux (N m per A peak): flux = 0.5 / (1.5 x 4)."""
    m = spec(motor={"R": 0.6, "Ld": 1.4e-3, "Lq": 2.8e-3, "pole_pairs": 4, "J": 1.11e-3,
                    "kt_peak": text}).motor
    assert m.flux == pytest.approx(0.5 / 6, rel=REL)


def test_torque_constant_per_rms_ampere_in_a_peak_key():
    """kt_peak = "0.5 N m/Arms": per A rms = per sqrt(2) A peak, so
    kt_peak = 0.5 / sqrt(2) N m/A and flux = kt_peak / (1.5 p)."""
    m = spec(motor={"R": 0.6, "Ld": 1.4e-3, "Lq": 2.8e-3, "pole_pairs": 4, "J": 1.11e-3,
                    "kt_peak": "0.5 Nm/Arms"}).motor
    assert m.flux == pytest.approx(0.5 / SQRT2 / 6, rel=REL)


def test_v_per_krpm_line_rms():
    """ke_ll_rms = "49.8 V/krpm": 49.8 V rms line-line per 1000 rpm;
    flux = sqrt(2) ke / (sqrt(3) p) with ke in V s/rad."""
    m = spec(motor={"R": 0.6, "Ld": 1.4e-3, "Lq": 2.8e-3, "pole_pairs": 4, "J": 1.11e-3,
                    "ke_ll_rms": "49.8 V/krpm"}).motor
    assert m.flux == pytest.approx(SQRT2 * 49.8 / (1000 * RPM) / (SQRT3 * 4), rel=REL)


def test_rms_current_in_the_power_invariant_convention():
    m = spec(motor={**MOTOR, "convention": "power", "flux": 0.12 * math.sqrt(1.5),
                    "rated_current": "10 Arms"}).motor
    assert m.rated_current == pytest.approx(10 * SQRT3, rel=REL)


def test_kv_is_recognised_with_the_constant_it_stands_for():
    err = error(motor={"R": 0.1, "Ld": 1e-4, "Lq": 1e-4, "pole_pairs": 7, "J": 1e-5,
                       "ke_ll_peak": "380 rpm/V"})
    ke = 1 / (380 * RPM)  # V s/rad
    assert f"{ke:.4g}" == "0.02513"
    text = str(err)
    assert text.startswith("motor.ke_ll_peak: expected a back-EMF constant")
    assert "this is a KV" in text and f"ke = 1/KV = {ke:.4g} V s/rad" in text


# ---------------------------------------------------------- method parameters
@pytest.mark.parametrize("text", ["12566.370614359172 rad/s", "2 kHz", "2000 Hz"])
def test_pi_bandwidth_with_units(text):
    cfg = spec(controller={"method": "pi", "pi": {"bandwidth": text}}).controller.cfg
    wc = 2 * math.pi * 2000
    assert cfg.details["bandwidth_rad_s"]["q"] == pytest.approx(wc, rel=1e-9)
    assert cfg.Kp[1] == pytest.approx(2.8e-3 * wc, rel=1e-9)  # cancellation: Kp = L wc


def test_pi_response_time_in_ms_equals_seconds():
    a = spec(controller={"method": "pi", "pi": {"response_time": "2 ms"}}).controller.cfg
    b = spec(controller={"method": "pi", "pi": {"response_time": 0.002}}).controller.cfg
    assert a.Kp == b.Kp and a.Ki == b.Ki


def test_per_axis_and_other_methods_with_units():
    a = spec(controller={"method": "ilq", "ilq": {"poles": {"d": "-2 krad/s",
                                                            "q": "-2000 rad/s"}}})
    b = spec(controller={"method": "ilq", "ilq": {"poles": -2000.0}})
    assert a.controller.cfg == b.controller.cfg
    a = spec(controller={"method": "lq", "lq": {"current_limit": "10 Arms"}})
    b = spec(controller={"method": "lq", "lq": {"current_limit": 10 * SQRT2}})
    assert a.controller.cfg == b.controller.cfg


def test_method_parameter_unit_errors_name_the_key():
    err = error(controller={"method": "pi", "pi": {"bandwidth": "2 kV"}})
    assert str(err) == ('controller.pi.bandwidth: expected an angular rate (rad/s, or Hz '
                        '(x 2 pi)), got a voltage ("2 kV")')
    err = error(controller={"method": "robust_pi", "robust_pi": {"max_speed": "50 Hz"}})
    assert str(err).startswith("controller.robust_pi.max_speed: expected a speed")


# --------------------------------------------------------------- requirements
def test_requirements_with_units():
    req = spec(requirements={"min_phase_margin_deg": "45 deg", "min_gain_margin_db": "6 dB",
                             "max_response_time": "2 ms", "max_settling_time": "0.01 s",
                             "max_static_speed_error": "10 rpm",
                             "max_commutations_per_s": "4 kHz",
                             "min_bandwidth_rad_s": "1 kHz"}).requirements.bounds
    assert req == pytest.approx({"min_phase_margin_deg": 45.0, "min_gain_margin_db": 6.0,
                                 "max_response_time": 2e-3, "max_settling_time": 0.01,
                                 "max_static_speed_error": 10 * RPM,
                                 "max_commutations_per_s": 4000.0,
                                 "min_bandwidth_rad_s": 2000 * math.pi}, rel=1e-12)
    rad = spec(requirements={"min_phase_margin_deg": f"{math.pi / 4!r} rad"})
    assert rad.requirements.bounds["min_phase_margin_deg"] == pytest.approx(45.0, rel=1e-12)


def test_requirement_plausibility():
    err = error(requirements={"min_phase_margin_deg": "200 deg"})
    assert str(err) == ("requirements.min_phase_margin_deg: expected a plausible phase "
                        "margin between 0 and 180 deg, got 200.0")


# ------------------------------------------------------------------ scenarios
def test_scenario_with_units():
    sc = spec(scenario=[{"kind": "current_step", "duration": "20 ms", "iq_ref": "5 Arms",
                         "step_time": "1 ms", "initial_speed": "1000 rpm",
                         "plant_values": {"R": "700 mOhm"}}]).scenarios[0]
    assert (sc.duration, sc.step_time) == pytest.approx((0.02, 1e-3), rel=REL)
    assert sc.iq_ref == pytest.approx(5 * SQRT2, rel=REL)
    assert sc.initial_speed == pytest.approx(1000 * RPM, rel=REL)
    assert sc.plant_values["R"] == pytest.approx(0.7, rel=REL)


def test_campaign_with_units():
    cmp = spec(scenario=[{"name": "s", "kind": "current_step", "duration": 0.02,
                          "iq_ref": 5.0}],
               campaign={"motors": 10, "seed": 1, "parameters": {"R": {
                   "distribution": "uniform", "mode": "value", "low": "500 mOhm",
                   "high": "0.8 ohm"}},
                   "operating_points": {"speed": ["0 rpm", "1000 rpm"]}}).campaign
    assert cmp.parameters[0].low == pytest.approx(0.5, rel=REL)
    assert dict(cmp.operating_points)["speed"] == pytest.approx((0.0, 1000 * RPM), rel=REL)


# -------------------------------------------------------------------- inertia
def test_bare_inertia_in_kg_cm2_names_the_slip():
    """paper 003's motor: T_char = 1.5 p flux^2 / Lq = 30.86 N m, so J = 1.2
    (meant kg cm^2) gives 25.7 rad/s^2, under the 100 rad/s^2 bound."""
    err = error(motor={**MOTOR, "J": 1.2})
    text = str(err)
    t_char = 1.5 * 4 * 0.12 ** 2 / 2.8e-3
    assert f"{t_char:.3g} N m" in text
    assert f"between {t_char / 3e7:.3g} and {t_char / 100:.3g} kg m^2" in text
    assert 'kg·cm² written as kg·m²? write J = "1.2 kg cm^2"' in text


CORPUS = sorted((Path(__file__).parents[1] / "corpus" / "motors").glob("*.toml"))


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_corpus_inertia_slip_is_caught(path):
    """Each corpus motor passes the bound as written; its J typed as a bare
    number in kg cm^2 (x 1e4) is refused with the kg·cm² hint unless the motor
    is faster than 1e6 rad/s^2 (the bound's stated blind spot: the slip
    leaves it above 100 rad/s^2)."""
    s = load_spec(path)
    m = s.motor
    ratio = 1.5 * m.pole_pairs * m.flux ** 2 / max(m.Ld, m.Lq) / m.J
    assert INERTIA_ACCELERATION[0] <= ratio <= INERTIA_ACCELERATION[1]
    data = tomllib.loads(path.read_text())
    data["motor"]["J"] = m.J * 1e4
    if ratio * 1e-4 >= INERTIA_ACCELERATION[0]:
        assert ratio > 1e6
        return
    with pytest.raises(SpecError) as info:
        spec_from_dict(data, file=str(path))   # a flux_map path is relative to the file
    assert "kg·cm² written as kg·m²?" in str(info.value)


# ------------------------------------------------------------ all errors at once
BAD = """
[motor]
R = -1
Ld = "0.5 mH"
Lq = "0.5 mH"
flux = "380 rpm/V"
pole_pairs = 4
J = 1e-3
[drive]
vdc = "150 V"
sample_time = "100 us"
[controller]
method = "pi"
[controller.pi]
bandwidth = "2 kV"
[requirements]
min_phase_margin_deg = "45 ohm"
max_response_time = "2 mss"
[[scenario]]
kind = "current_step"
duration = "20 kg"
[[scenario]]
kind = "current_step"
duration = "20 ms"
iq_ref = "5 V"
"""


def test_every_section_reported_when_the_motor_fails(tmp_path):
    """The motor fails; the controller's motor-independent error, the
    requirements' and both scenarios' are still reported, each located."""
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    with pytest.raises(SpecError) as info:
        load_spec(path)
    keys = [e.key for e in info.value.errors]
    assert sorted(keys) == sorted([
        "motor.R", "motor.flux", "controller.pi.bandwidth",
        "requirements.min_phase_margin_deg", "requirements.max_response_time",
        "scenario[0].duration", "scenario[1].iq_ref"])
    assert all(e.file == str(path) and e.expected and e.has_got for e in info.value.errors)
