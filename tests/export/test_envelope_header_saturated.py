"""The header's envelope table of a saturated motor (the corpus PM-SyRM,
``[motor.saturation]``): its nodes are :class:`toolbox.plant.SaturatedEnvelope`'s
references (the motor's magnetic model, 5 % voltage headroom) rounded to
float32 (1e-6 x I: float32 of 25 A is exact to 1e-6 A), the header says so,
and the compiled ``cct_envelope_ref`` equals the Python mirror
``EnvelopeTable.reference`` at 300 random requests to 2e-5 x I with the same
status (as for a constant-parameter motor, tests/export/test_envelope_header.py).
Between the nodes the interpolated reference gives the requested torque
within 1 % of the standstill limit (the saturated torque curves bend more
than the constant ones; measured 0.71 %, 0.50 N m of 71.0 N m).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

import toolbox
from toolbox.export import write_header
from toolbox.export._envelope_table import N_SPEED, N_TORQUE, envelope_table
from toolbox.plant import OperatingEnvelope, SaturatedEnvelope, envelope_of

from test_envelope_header import cell_centres, header_equals_python

ROOT = Path(__file__).resolve().parents[2]


def _spec():
    path = ROOT / "tests" / "corpus" / "motors" / "baldor_ecs101m0h7ef4_pmsyrm.toml"
    return toolbox.spec_from_dict(tomllib.loads(path.read_text()))


def test_saturated_table_nodes_are_the_saturated_envelope():
    spec = _spec()
    tb = envelope_table(spec.motor, spec.drive)
    env = envelope_of(spec.motor, v_max=(1 - OperatingEnvelope.HEADROOM)
                      * spec.drive.max_voltage(spec.motor.convention))
    assert isinstance(env, SaturatedEnvelope) and "SaturatedEnvelope" in tb.source
    assert tb.v_max == env.V and tb.i_max == env.I
    # no drive.max_speed: the table spans 2 x base speed
    assert abs(tb.top_speed - 2 * env.base_speed()) <= 1e-6 * tb.top_speed
    for k in range(N_SPEED):
        w = k * tb.speed_step
        lim = env.max_torque_point(w)
        assert abs(tb.t_max[k] - lim.torque) <= 1e-6 * abs(lim.torque) + 1e-6
        for j in range(N_TORQUE):
            op = env.operating_point(tb.t_max[k] * j / (N_TORQUE - 1), w)
            assert abs(tb.i_d[k, j] - op.i_d) <= 1e-6 * env.I
            assert abs(tb.i_q[k, j] - op.i_q) <= 1e-6 * env.I
    # the constant-parameter table of the nominal Ld, Lq, flux differs (by amps)
    lin = OperatingEnvelope(spec.motor, v_max=env.V)
    op_lin = lin.operating_point(0.5 * tb.t_max[0], tb.top_speed)
    op_sat = env.operating_point(0.5 * tb.t_max[0], tb.top_speed)
    assert np.hypot(op_lin.i_d - op_sat.i_d, op_lin.i_q - op_sat.i_q) > 1.0


def test_saturated_header_references_equal_python(tmp_path):
    spec = _spec()
    art = toolbox.design_spec(spec)
    h = write_header(art, spec.motor, spec.drive)
    assert "toolbox.plant.SaturatedEnvelope, the motor's magnetic model" in h
    tb = envelope_table(spec.motor, spec.drive)
    header_equals_python(h, tb, tmp_path, seed=7, n=300,
                         fixed=[[0.0, 0.0], [tb.t_max[0], 0.0],
                                [-tb.t_max[0], 0.7 * tb.top_speed]])


def test_saturated_interpolation_between_nodes():
    spec = _spec()
    tb = envelope_table(spec.motor, spec.drive)
    env = envelope_of(spec.motor, v_max=tb.v_max)
    t_err = i_rel = 0.0
    for _w, t, d, q in cell_centres(tb):
        t_err = max(t_err, abs(float(env.torque(d, q)) - t))
        i_rel = max(i_rel, float(np.hypot(d, q)) / env.I)
    print(f"\ncell centres: torque error {t_err:.3g} N m of {tb.t_max[0]:.4g}, "
          f"|i| <= {i_rel:.4f} I")
    assert t_err <= 1e-2 * tb.t_max[0]
    assert i_rel <= 1.001
