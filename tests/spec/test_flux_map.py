"""``[motor] flux_map`` and ``[motor.saturation]`` (toolbox/spec/_flux_map.py;
README "Saturated motors (flux maps)"): the CSV format, its validation with
located errors, and the nominal parameters the spec derives."""

from __future__ import annotations

import numpy as np
import pytest

import toolbox
from toolbox.errors import SpecError

LD, LQ, FLUX = 2e-3, 5e-3, 0.1


def _rows(ids=(-20.0, 0.0, 20.0), iqs=(-20.0, 0.0, 20.0), scale=1.0):
    out = []
    for a in ids:
        for b in iqs:
            out.append([a, b, (LD * a + FLUX) * scale, LQ * b * scale])
    return out


def _write(path, rows, header="i_d,i_q,psi_d,psi_q"):
    path.write_text(header + "\n" + "\n".join(",".join(str(c) for c in r) for r in rows) + "\n")


def _spec(tmp_path, motor_extra):
    text = ('title = "m"\n[motor]\nR = 0.1\npole_pairs = 4\nJ = 0.01\nmax_current = 20\n'
            + motor_extra
            + '\n[drive]\nvdc = 300\nsample_time = 1e-4\n[controller]\nmethod = "pi"\n')
    (tmp_path / "s.toml").write_text(text)
    return toolbox.load_spec(tmp_path / "s.toml")


def test_map_relative_to_spec_units_and_any_order(tmp_path):
    """Columns in another order with units (mWb, kA), rows shuffled: the same
    SI grid; the nominal Ld, Lq, flux are the map's at i = 0; the path is
    relative to the spec file and stored absolute in the raw spec, which reloads."""
    (tmp_path / "maps").mkdir()
    rows = _rows(scale=1e3)
    rng = np.random.default_rng(0)
    rows = [rows[i] for i in rng.permutation(len(rows))]
    rows = [[r[3], r[2], r[1] / 1e3, r[0] / 1e3] for r in rows]
    _write(tmp_path / "maps" / "m.csv", rows,
           header="psi_q [mWb], psi_d [mWb], i_q [kA], i_d [kA]")
    spec = _spec(tmp_path, 'flux_map = "maps/m.csv"')
    m = spec.motor
    assert (m.Ld, m.Lq, m.flux) == pytest.approx((LD, LQ, FLUX), rel=1e-12)
    assert m.magnetics.kind == "map"
    np.testing.assert_array_equal(m.magnetics.data.i_d, [-20.0, 0.0, 20.0])
    raw = spec.raw["motor"]
    assert "Ld" not in raw and raw["flux_map"] == str(tmp_path / "maps" / "m.csv")
    again = toolbox.spec_from_dict({k: v for k, v in spec.raw.items() if v is not None})
    assert again.motor.Lq == m.Lq


@pytest.mark.parametrize("mutate, where, expected", [
    (lambda r: r[:-1], "m.csv", "complete rectangular grid"),
    (lambda r: r + [r[0]], "m.csv", "one row per (i_d, i_q) grid point"),
    (lambda r: [r[0], [r[1][0], r[1][1], "x", r[1][3]]] + r[2:], "line 3 column psi_d",
     "a finite number"),
    (lambda r: [[a, b, (0.05 if (a, b) == (20.0, 0.0) else c), d] for a, b, c, d in r],
     "between i_d = 0 and 20 A at i_q = 0 A", "psi_d strictly increasing in i_d"),
], ids=["missing-point", "duplicate", "non-number", "non-monotone"])
def test_map_errors_are_located(tmp_path, mutate, where, expected):
    _write(tmp_path / "m.csv", mutate(_rows()))
    with pytest.raises(SpecError) as err:
        _spec(tmp_path, 'flux_map = "m.csv"')
    text = str(err.value)
    assert "motor.flux_map" in text and where in text and expected in text, text
    assert str(tmp_path / "m.csv") in text


def test_map_header_and_unit_errors(tmp_path):
    _write(tmp_path / "m.csv", _rows(), header="i_d,i_q,psi_d,flux_q")
    with pytest.raises(SpecError, match="line 1.*columns i_d, i_q, psi_d, psi_q.*flux_q"):
        _spec(tmp_path, 'flux_map = "m.csv"')
    _write(tmp_path / "m.csv", _rows(), header="i_d [A],i_q,psi_d [T],psi_q")
    with pytest.raises(SpecError, match="column psi_d.*a unit of.*got \"?t"):
        _spec(tmp_path, 'flux_map = "m.csv"')
    with pytest.raises(SpecError, match="readable"):
        _spec(tmp_path, 'flux_map = "nowhere.csv"')


def test_map_excludes_constant_parameters(tmp_path):
    _write(tmp_path / "m.csv", _rows())
    with pytest.raises(SpecError, match="motor.Ld.*come from its flux map"):
        _spec(tmp_path, 'flux_map = "m.csv"\nLd = 1e-3')


def test_nominal_point_needs_a_current(tmp_path):
    """The nominal inductances are taken at the MTPA point of the rated (else
    maximum) current: a saturated motor without either is refused."""
    _write(tmp_path / "m.csv", _rows())
    (tmp_path / "s.toml").write_text(
        'title = "m"\n[motor]\nR = 0.1\npole_pairs = 4\nJ = 0.01\nflux_map = "m.csv"\n'
        '[drive]\nvdc = 300\nsample_time = 1e-4\n[controller]\nmethod = "pi"\n')
    with pytest.raises(SpecError, match="motor.rated_current.*MTPA point"):
        toolbox.load_spec(tmp_path / "s.toml")


def test_saturation_table_errors(tmp_path):
    base = ("[motor.saturation]\na_d0 = 3.96\na_dd = 28.46\nS = 4\na_q0 = 5.89\na_qq = 2.672\n"
            "T = 6\na_dq = 41.52\nU = 1\nV = 1\n")
    with pytest.raises(SpecError, match="motor.saturation.current_range.*required"):
        _spec(tmp_path, "flux = 0.1\n" * 0 + base)
    with pytest.raises(SpecError, match="motor.saturation.a_x.*one of"):
        _spec(tmp_path, base + "current_range = 20\na_x = 1\n")
    with pytest.raises(SpecError, match="motor.saturation.a_dd.*>= 0"):
        _spec(tmp_path, base.replace("a_dd = 28.46", "a_dd = -1") + "current_range = 20\n")


def test_resolved_spec_of_a_saturated_motor_reloads(tmp_path):
    """``cct check``'s resolved TOML keeps the magnetics (the absolute map
    path, the saturation table) and gives the derived Ld, Lq, flux as
    comments: it reloads to the same motor."""
    from toolbox.spec import spec_to_toml
    _write(tmp_path / "m.csv", _rows())
    spec = _spec(tmp_path, 'flux_map = "m.csv"')
    text = spec_to_toml(spec)
    assert "# Lq = 0.005" in text and "\nLq =" not in text
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "r.toml").write_text(text)
    again = toolbox.load_spec(tmp_path / "elsewhere" / "r.toml")
    assert (again.motor.Ld, again.motor.Lq, again.motor.flux) == (spec.motor.Ld, spec.motor.Lq,
                                                                  spec.motor.flux)
