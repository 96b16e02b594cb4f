"""The d-axis priority guard (``drive.voltage_priority = "d_axis"``): ``|v_d|``
is capped at ``sqrt(1 - min(|e_q| / V, 1)^2)`` of the limit's d extent, ``e_q
= w (Ld_c i_d + psi_c)`` the speed voltage of the controller's model, so that
``v_q`` keeps the back-EMF (toolbox/ARCHITECTURE.md "Operating envelope").

* the formula: the simulator kernel's ``d_priority_cap`` equals the Python
  reference's bit for bit, and on the circle the limited ``v_q`` reaches
  ``min(|e_q|, V)`` whenever it is asked (60 random cases, 1e-12 V).
* the simulator: paper 003's motor, a flying start from zero current into the
  field-weakening reference at 1.5 x base speed (back-EMF 100 V against an
  86.6 V limit): without the guard the H-infinity law's d loop took the voltage
  (its decoupling ``-w Lq i_q`` grows as ``i_q`` brakes) and ``|i|`` ran to
  94 A (measured before the guard, 4.7 x the 20 A limit); with it 27.4 A
  (radial: 16.4 A); bound 1.5 x the limit. The PI stays at the reference's
  amplitude (15.94 A) either way.
* the header: tests/export/test_voltage_priority.py compares the float header
  with the reference (which carries the guard) to 1e-4 x V_MAX; here the
  guard is shown to bind in that comparison (circle, 300 rad/s ramp).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import toolbox
from toolbox.export import check_exportable, write_header
from toolbox.export.c_header import d_priority_limit, reference_law
from toolbox.sim import DriveParams, control_law, simulate
from toolbox.sim._kernel import d_priority_cap as kernel_cap
from toolbox.export._reference import d_priority_cap as reference_cap
from toolbox.spec import Scenario
from toolbox.verify._envelope_grid import grid_envelope

import export_artifacts as A
import export_c_helpers as C

ROOT = Path(__file__).resolve().parents[2]


def test_guard_formula():
    rng = np.random.default_rng(7)
    vm = 100.0
    for _ in range(60):
        e = rng.uniform(-2.0 * vm, 2.0 * vm)
        assert kernel_cap(vm, e) == reference_cap(vm, e)
        vd, vq = rng.uniform(-2 * vm, 2 * vm, 2)
        d, q = d_priority_limit(vd, vq, vm, "circle", 0.0, e)
        keep = min(abs(e), vm)
        assert abs(d) <= math.sqrt(vm * vm - keep * keep) + 1e-12
        assert math.hypot(d, q) <= vm * (1 + 1e-12)
        if abs(vq) >= keep:
            assert abs(q) >= keep - 1e-12
        if abs(vd) <= math.sqrt(max(vm * vm - keep * keep, 0.0)):
            assert d == vd   # inside the guard v_d is kept
    # no speed voltage: the plain d priority
    assert d_priority_limit(150.0, 10.0, vm, "circle", 0.0, 0.0) == (100.0, 0.0)


@pytest.mark.parametrize("design, bound", [("003_azaiz2007_hinf.toml", 30.0),
                                           ("003_azaiz2007_pi.toml", 16.0)])
def test_flying_start_above_base_speed(design, bound):
    spec = toolbox.load_spec(ROOT / "designs" / design)
    law = control_law(toolbox.design_spec(spec))
    peaks = {}
    for prio in ("d_axis", "radial"):
        drive = DriveParams(vdc=spec.drive.vdc, sample_time=spec.drive.sample_time,
                            delay_samples=spec.drive.delay_samples, voltage_priority=prio)
        env = grid_envelope(spec.motor, drive)
        speed = 1.5 * env.base_speed()
        op = env.operating_point(0.0, speed)
        sc = Scenario(kind="current_step", duration=0.2, id_ref0=op.i_d, iq_ref0=op.i_q,
                      id_ref=op.i_d, iq_ref=op.i_q, initial_speed=speed, keep_traces=True,
                      trace_step=drive.sample_time)
        r = simulate(law, spec.motor, sc, drive)
        peaks[prio] = float(np.hypot(r.id, r.iq).max())
        # settles on the field-weakening reference (-15.9 A) either way
        assert abs(r.id[-1] - op.i_d) < 0.01 * env.I and abs(r.iq[-1]) < 0.01 * env.I
    print(f"\n{design}: flying start at 1.5 x base, peak |i| {peaks} A")
    assert peaks["d_axis"] <= bound and peaks["radial"] <= 17.0


def test_header_guard_binds(tmp_path):
    """The circle header test's inputs (PI, 20 A steps, 0..300 rad/s): the
    reference's |v_d| sits on the guard (below the circle) in saturated
    periods, and the header agrees there."""
    art = A.pi_artifact()
    drive = replace(A.DRIVE, voltage_limit="circle", voltage_priority="d_axis")
    chk = check_exportable(art, A.MOTOR, drive)
    h = write_header(art, A.MOTOR, drive)
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    v_ref, s_ref = reference_law(art, inp, chk.v_max, "circle", "d_axis")
    dec = art.decoupling
    e_q = dec.pole_pairs * inp[:, 4] * (dec.Ld_c * inp[:, 2] + dec.flux_c)
    cap = np.array([reference_cap(chk.v_max, e) for e in e_q]) * chk.v_max
    on_guard = (np.abs(np.abs(v_ref[:, 0]) - cap) < 1e-9 * chk.v_max) & (cap < 0.99 * chk.v_max)
    v_c, _ = C.run_float(h, tmp_path, inp)
    print(f"\nguard binds in {on_guard.sum()} of {len(inp)} periods; header max|err| "
          f"{np.abs(v_c - v_ref)[on_guard].max():.3g} V")
    assert on_guard.sum() >= 5
    assert np.abs(v_c - v_ref)[on_guard].max() <= 1e-4 * chk.v_max
