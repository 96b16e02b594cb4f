"""Every error of a ``[controller.<method>]`` table in one run (README "all
at once"): each method's table below holds at least two independent
mistakes (unknown keys, wrong types, out-of-range values, cross-key
conflicts), and ``cct check`` / ``cct design`` name every one of them, with
the file, the key path, what was expected and what was found, exit 2 and
write nothing (toolbox/spec/_methods.py ``read_collecting``)."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from toolbox.cli import main
from toolbox.errors import SpecError
from toolbox.spec import SpecErrors, load_spec, spec_from_dict
from toolbox.spec._methods import MAX_METHOD_ERRORS

HEAD = ('[motor]\ncatalog = "azaiz2007"\n[drive]\nvdc = 150\nsample_time = 1e-4\n'
        '[controller]\nmethod = "{method}"\n')

# method -> (its table as TOML, [(key path, expected (part of), found as shown)])
CASES = {
    "pi": ('bandwidth = -1\ndiscretisation = "foo"\nbogus = 1\n', [
        ("controller.pi.bogus", "a known key of [controller.pi]", None),
        ("controller.pi.bandwidth", "a number > 0 (rad/s)", "-1"),
        ("controller.pi.discretisation", 'one of "tustin"', '"foo"')]),
    "pi_explicit": ('Kp = -1\nKi = "x"\n', [  # a required pair: both reported
        ("controller.pi.Kp", "a number > 0 (V/A)", "-1"),
        ("controller.pi.Ki", "a number > 0 (V/(A s))", '"x"')]),
    "ip": ('bandwidth = {d = -1, q = "x"}\ndiscretisation = 3\n', [
        ("controller.ip.bandwidth.d", "a number > 0 (rad/s)", "-1"),
        ("controller.ip.bandwidth.q", "a number > 0 (rad/s)", '"x"'),
        ("controller.ip.discretisation", 'one of "tustin"', "3")]),
    "pi_lag": ('lag_time_constant = -1\ndecoupling = 3\nbandwidth = "2 parsecs"\n', [
        ("controller.pi_lag.bandwidth", "an angular rate", '"2 parsecs"'),
        ("controller.pi_lag.lag_time_constant", "a number > 0 (s)", "-1"),
        ("controller.pi_lag.decoupling", "true or false", "3")]),
    "tc": ('response_time = -1\ndiscretisation = "x"\n[controller.tc.model]\nR = -1\n', [
        ("controller.tc.model.R", "a number > 0 (ohm)", "-1"),
        ("controller.tc.response_time", "a number > 0 (s)", "-1"),
        ("controller.tc.discretisation", 'one of "tustin"', '"x"')]),
    "tci": ('natural_frequency = -5\ndamping = -1\nbogus = 2\n', [
        ("controller.tci.bogus", "a known key of [controller.tci]", None),
        ("controller.tci.natural_frequency", "a number > 0 (rad/s)", "-5"),
        ("controller.tci.damping", "a number > 0", "-1")]),
    "ilq": ('poles = 5\nsigma = -1\n', [
        ("controller.ilq.poles", "a number < 0 (rad/s)", "5"),
        ("controller.ilq.sigma", "a number > 0 (1/s)", "-1")]),
    "lq": ('domain = "cont"\nQ = {d = [1], q = [1, 2]}\nR = -1\ncurrent_limit = 0\n', [
        ("controller.lq.domain", 'one of "continuous", "discrete"', '"cont"'),
        ("controller.lq.current_limit", "a number > 0 (A)", "0"),
        ("controller.lq.Q.d", "a list of 2 numbers", "[1]"),
        ("controller.lq.R", "a number > 0 (1/V^2)", "-1")]),
    "hinf": ('gamma = "best"\nbackoff = -1\n'
             '[controller.hinf.weights.d]\nw1 = {num = [1], den = [1, -1]}\n'
             '[controller.hinf.weights.q]\nw2 = -3\n', [
        ("controller.hinf.gamma", 'a number > 0 or "optimal"', '"best"'),
        ("controller.hinf.backoff", "a number >= 0 and <= 10", "-1"),
        ("controller.hinf.weights.d.w1", "a stable weight", '"pole at s = 1+0j"'),
        ("controller.hinf.weights.q.w2", "a constant weight > 0", "-3")]),
    "hinf_at_speed": ('margin_loss = 3\n[controller.hinf.at_speed]\nmax_speed = -1\n'
                      'inductance_box = [2, 3]\nfoo = 1\n', [
        ("controller.hinf.margin_loss", "a number >= 0 and <= 1", "3"),
        ("controller.hinf.at_speed.foo", "a known key of [controller.hinf.at_speed]", None),
        ("controller.hinf.at_speed.max_speed", "a number >= 0 (rad/s mechanical)", "-1"),
        ("controller.hinf.at_speed.inductance_box", "[lo, hi] with 0 < lo <= 1 <= hi",
         "[2.0, 3.0]")]),
    "fcs_mpc": ('alpha = -1\ngama = 1\nbeta = "x"\n', [
        ("controller.fcs_mpc.gama", 'a known key of [controller.fcs_mpc]', None),
        ("controller.fcs_mpc.alpha", "a number >= 0 and <= 1e+12", "-1"),
        ("controller.fcs_mpc.beta", "a number >= 0 and <= 1e+12", '"x"')]),
    "robust_pi": ('disk_margin = 3\nspeed_gain = [2, 3]\nsamples = -1\n', [
        ("controller.robust_pi.disk_margin", "a number > 0 and < 2", "3.0"),
        ("controller.robust_pi.speed_gain", "[lo, hi] with 0 < lo <= 1 <= hi", "[2.0, 3.0]"),
        ("controller.robust_pi.samples", "an integer >= 0 and <= 256", "-1")]),
    "tune": ('disk_margin = 3\nstarts = 100\nevaluations = 1\n', [
        ("controller.tune.disk_margin", "a number > 0 and < 2", "3.0"),
        ("controller.tune.starts", "an integer >= 1 and <= 8", "100"),
        ("controller.tune.evaluations", "an integer >= 20 and <= 5000", "1")]),
    "cv": ('bandwidth = -1\ndelay_pole = 2\nx = 1\n', [
        ("controller.cv.x", "a known key of [controller.cv]", None),
        ("controller.cv.bandwidth", "a number > 0 (rad/s)", "-1"),
        ("controller.cv.delay_pole", "a number >= 0 and <= 0.95", "2")]),
}

#: the method of each case (the case name without its variant)
METHOD_OF = {case: {"pi_explicit": "pi", "hinf_at_speed": "hinf"}.get(case, case)
             for case in CASES}


def test_every_method_has_a_case():
    """A method added without a case here fails this test."""
    from toolbox.spec import METHODS
    assert set(METHODS) == set(METHOD_OF.values())


def _spec_file(tmp_path, case: str):
    method = METHOD_OF[case]
    path = tmp_path / f"{case}.toml"  # each table's plain keys come before its sub-tables
    path.write_text(HEAD.format(method=method) + f"[controller.{method}]\n" + CASES[case][0])
    return path


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize("case", sorted(CASES))
def test_check_reports_every_error_of_the_table(tmp_path, case):
    path = _spec_file(tmp_path, case)
    expected = CASES[case][1]
    with pytest.raises(SpecErrors) as info:
        load_spec(path)
    errors = info.value.errors
    # exactly these keys, in the order found: no error lost, no follow-on invented
    assert [e.key for e in errors] == [k for k, _, _ in expected]
    for err, (key, what, got) in zip(errors, expected):
        assert err.file == str(path)
        assert what in err.expected, (key, err.expected)
        text = str(err.with_file(""))
        assert text.startswith(f"{key}: expected ")
        if got is not None:
            assert ", got " in text and got in text.split(", got ", 1)[1], text
    res = _run("check", path)
    assert res.exit_code == 2, res.output
    assert f"{path}: {len(expected)} errors:" in res.output
    for key, what, _ in expected:
        assert f"  {key}: expected {what}" in res.output


@pytest.mark.parametrize("case", ["pi", "hinf", "tci", "lq"])
def test_design_refuses_with_every_error_and_writes_nothing(tmp_path, case):
    path = _spec_file(tmp_path, case)
    out = tmp_path / "out"
    res = _run("design", path, "--out", out)
    assert res.exit_code == 2, res.output
    for key, what, _ in CASES[case][1]:
        assert f"{key}: expected {what}" in res.output
    assert not out.exists()


def _data(method, table, **motor):
    return {"motor": {"catalog": "azaiz2007", **motor},
            "drive": {"vdc": 150.0, "sample_time": 1e-4},
            "controller": {"method": method, method: table}}


def test_one_error_stays_one_line():
    """A single mistake is raised as it is (not a one-entry list)."""
    with pytest.raises(SpecError) as info:
        spec_from_dict(_data("pi", {"bandwidth": -1.0}), file="s.toml")
    assert not isinstance(info.value, SpecErrors)
    assert str(info.value) == "s.toml: controller.pi.bandwidth: expected a number > 0 " \
                              "(rad/s), got -1.0"


def test_a_key_taken_out_is_not_reported_again_as_missing():
    """Kp_normalised given without Ki_normalised, sensor_gain wrong: after the
    first reading the reader is not made to report sensor_gain's follow-on
    ("voltage_gain needs Kp_normalised") nor the missing pair."""
    with pytest.raises(SpecErrors) as info:
        spec_from_dict(_data("pi", {"Kp_normalised": -1.0, "Ki_normalised": 2.0,
                                    "sensor_gain": -3.0, "voltage_gain": 100.0}))
    assert [e.key for e in info.value.errors] == ["controller.pi.Kp_normalised",
                                                  "controller.pi.sensor_gain"]


def test_errors_of_the_table_join_those_of_the_motor():
    """With [motor] wrong too, the table's motor-independent errors are still
    all reported (read against stand-in motors, toolbox/spec/_load.py)."""
    with pytest.raises(SpecErrors) as info:
        spec_from_dict(_data("cv", {"bandwidth": -1.0, "delay_pole": 2.0}, R=-1.0))
    assert [e.key for e in info.value.errors] == [
        "motor.R", "controller.cv.bandwidth", "controller.cv.delay_pole"]


def test_a_table_with_thousands_of_mistakes_is_listed_by_its_first():
    """Reading stops after MAX_METHOD_ERRORS readings, saying more may follow."""
    table = {f"k{i}": 1 for i in range(5000)}
    with pytest.raises(SpecErrors) as info:
        spec_from_dict(_data("fcs_mpc", table))
    keys = [e.key for e in info.value.errors]
    assert keys[:-1] == [f"controller.fcs_mpc.k{i}" for i in range(MAX_METHOD_ERRORS)]
    assert keys[-1] == "controller.fcs_mpc"
    assert "more may follow" in info.value.errors[-1].expected


def test_a_valid_table_reads_as_before():
    """No error: the reader runs once, the configuration unchanged."""
    spec = spec_from_dict(_data("pi", {"Kp": {"d": 10.0, "q": 20.0}, "Ki": 1e4}))
    assert spec.controller.cfg.Kp == (10.0, 20.0)
    assert spec.controller.cfg.Ki == (1e4, 1e4)


def test_a_conflict_does_not_report_the_other_route_missing():
    """Kp and Kp_normalised both given: the conflict is the error; Ki is not
    then reported missing (it belongs to the route the user may not mean)."""
    with pytest.raises(SpecError) as info:
        spec_from_dict(_data("pi", {"Kp": 1.0, "Kp_normalised": 0.01}))
    assert not isinstance(info.value, SpecErrors)
    assert info.value.key == "controller.pi.Kp_normalised"
