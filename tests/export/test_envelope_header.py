"""The operating envelope's references in controller.h
(toolbox/export/_envelope_table.py) against the Python ones.

* the table's nodes are :class:`toolbox.plant.OperatingEnvelope`'s references
  (5 % voltage headroom, as the verification grid) rounded to float32;
* the header's ``cct_envelope_ref`` (compiled with gcc -std=c99 -Wall -Wextra
  -Werror, float32 arithmetic) equals the Python mirror
  ``EnvelopeTable.reference`` (double) at 400 random (torque, speed) requests,
  both signs, including beyond the torque limit and the table's top speed,
  to 2e-5 x the current limit (float32 interpolation of values up to I:
  a few ulp of 20 A, 2.4e-6 A each) with the same status;
* between the nodes the table is an interpolation of the envelope: at the
  cell centres it gives the requested torque within 0.5 % of the limit and
  stays within the drive's voltage and the current limit
  (test_interpolation_between_nodes states what is measured);
* the header states the table's memory cost (1 564 bytes).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np

import toolbox
from toolbox.export import write_header
from toolbox.export._envelope_table import N_SPEED, N_TORQUE, TABLE_BYTES, envelope_table
from toolbox.plant import OperatingEnvelope

import export_c_helpers as C

ROOT = Path(__file__).resolve().parents[2]

DRIVER = r"""
#include <stdio.h>
#include "controller.h"
int main(void)
{
    float t, w;
    while (scanf("%f %f", &t, &w) == 2) {
        float d, q;
        const int s = cct_envelope_ref(t, w, &d, &q);
        printf("%.9e %.9e %d\n", (double)d, (double)q, s);
    }
    return 0;
}
"""


def _spec():
    return toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")


def test_table_nodes_are_the_envelope():
    spec = _spec()
    tb = envelope_table(spec.motor, spec.drive)
    env = OperatingEnvelope(spec.motor, v_max=(1 - OperatingEnvelope.HEADROOM)
                            * spec.drive.max_voltage(spec.motor.convention))
    assert tb.i_d.shape == (N_SPEED, N_TORQUE) and TABLE_BYTES == 1564
    assert tb.v_max == env.V and tb.i_max == env.I
    for k in range(N_SPEED):
        w = k * tb.speed_step
        lim = env.max_torque_point(w)
        assert abs(tb.t_max[k] - lim.torque) <= 1e-6 * abs(lim.torque) + 1e-6
        for j in (0, 3, N_TORQUE - 1):
            op = env.operating_point(tb.t_max[k] * j / (N_TORQUE - 1), w)
            assert abs(tb.i_d[k, j] - op.i_d) <= 1e-6 * env.I
            assert abs(tb.i_q[k, j] - op.i_q) <= 1e-6 * env.I
            d, q, _ = tb.reference(tb.t_max[k] * j / (N_TORQUE - 1), w)
            assert abs(d - op.i_d) <= 1e-5 * env.I and abs(q - op.i_q) <= 1e-5 * env.I
    # the top row: the torque limit has fallen to ~0 (the highest speed a current fits)
    assert tb.t_max[-1] < 1e-3 * tb.t_max[0]


def test_header_references_equal_python(tmp_path):
    spec = _spec()
    art = toolbox.design_spec(spec)
    h = write_header(art, spec.motor, spec.drive)
    assert f"= {TABLE_BYTES} bytes of constants" in h
    tb = envelope_table(spec.motor, spec.drive)
    header_equals_python(h, tb, tmp_path, seed=5, n=400,
                         fixed=[[0.0, 0.0], [tb.t_max[0], 0.0], [-tb.t_max[0], 50.0],
                                [3.0, 1e4], [1.0, 140.0]])


def header_equals_python(h: str, tb, tmp_path, *, seed: int, n: int, fixed) -> None:
    """The compiled ``cct_envelope_ref`` of header ``h`` against the Python
    mirror ``tb.reference`` at ``n`` random requests (torque to 1.3 x the
    standstill limit, speed to 1.1 x the table's top, both signs), the first
    ones ``fixed`` (``[torque N m, speed rad/s]``): currents to 2e-5 x I,
    statuses equal, all three statuses met."""
    rng = np.random.default_rng(seed)
    req = np.column_stack([rng.uniform(-1.3, 1.3, n) * tb.t_max[0],
                           rng.uniform(-1.1, 1.1, n) * tb.top_speed])
    req[:len(fixed)] = fixed
    req = req.astype(np.float32).astype(float)
    res = C.compile_driver(h, tmp_path, source=DRIVER)
    assert res.returncode == 0, res.stderr
    text = "\n".join(f"{t:.9e} {w:.9e}" for t, w in req) + "\n"
    out = subprocess.run([str(tmp_path / "drv")], input=text, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    got = np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])
    ref = np.array([tb.reference(t, w) for t, w in req])
    err = np.abs(got[:, :2] - ref[:, :2]).max()
    print(f"\nheader vs Python: max|di| {err:.3g} A; statuses {np.bincount(ref[:, 2].astype(int))}")
    assert err <= 2e-5 * tb.i_max
    assert (got[:, 2] == ref[:, 2]).all()
    assert set(ref[:, 2].astype(int)) == {0, 1, 2}


def cell_centres(tb):
    """``(speed, torque, i_d, i_q)`` at the centre of every cell of the table
    ``tb`` (the torque a fraction of the mean of the cell's two speed rows'
    limits), with the table's interpolated reference there."""
    for k in range(N_SPEED - 1):
        w = (k + 0.5) * tb.speed_step
        t_lim = 0.5 * (tb.t_max[k] + tb.t_max[k + 1])
        for j in range(N_TORQUE - 1):
            t = t_lim * (j + 0.5) / (N_TORQUE - 1)
            d, q, _ = tb.reference(t, w)
            yield w, t, d, q


def test_interpolation_between_nodes():
    """At the 160 cell centres the interpolated reference gives the requested
    torque within 0.5 % of the standstill limit (0.15 % measured), needs at
    most the drive's full voltage (the envelope's limit is 95 % of it; 100.13 %
    of the envelope's measured) and stays within the current limit (+0.1 %).
    The current vector itself may differ from the exact envelope's by up to
    1.75 A (8.8 % of I, median 0.012 A) in the cells that cross base speed:
    there the interpolation mixes MTPA and field-weakening points of the same
    torque curve."""
    spec = _spec()
    tb = envelope_table(spec.motor, spec.drive)
    env = OperatingEnvelope(spec.motor, v_max=tb.v_max)
    t_err = v_rel = i_rel = di = 0.0
    for w, t, d, q in cell_centres(tb):
        op = env.operating_point(t, w)
        t_err = max(t_err, abs(float(env.torque(d, q)) - t))
        v_rel = max(v_rel, float(np.hypot(*env.voltage(d, q, w))) / env.V)
        i_rel = max(i_rel, float(np.hypot(d, q)) / env.I)
        di = max(di, float(np.hypot(d - op.i_d, q - op.i_q)))
    print(f"\ncell centres: torque error {t_err:.3g} N m of {tb.t_max[0]:.4g}, |v| <= "
          f"{v_rel:.4f} V_env, |i| <= {i_rel:.4f} I, |di| <= {di:.3g} A")
    assert t_err <= 5e-3 * tb.t_max[0]
    assert v_rel <= 1.0 / (1.0 - OperatingEnvelope.HEADROOM)
    assert i_rel <= 1.001
