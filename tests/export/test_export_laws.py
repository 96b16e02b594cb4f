"""The executed law three times: simulator kernel, Python reference, C header.

One law, three executors (toolbox/ARCHITECTURE.md "controller.h"): the numba
kernel (toolbox/sim/_kernel.py), the export's
Python reference law (:class:`toolbox.export.c_header.ReferenceLaw`) and the C
text must execute the same law, including the voltage limit (circle and the
SVM hexagon, ``voltage_limit = "hexagon"``) and back-calculation anti-windup.

* kernel vs reference: the kernel's closed loop is replayed open loop through
  the reference law (its recorded references, measured currents, measured
  speed and the electrical angle ``theta_k = p Omega k Ts`` of the imposed
  constant speed). Both run float64 with the same operations in a different
  order, so they agree to rounding: 1e-12 relative to the largest voltage
  (measured ~4e-14; a wrong limit, angle or anti-windup gives >= 1e-3).
* header vs reference: float32 header against the double reference, within
  1e-4 x V_MAX while saturated (as tests/export/test_c_header.py).
"""

from __future__ import annotations

import subprocess
from dataclasses import replace

import numpy as np
import pytest

from toolbox.errors import ExportRefused
from toolbox.export import check_exportable, write_header
from toolbox.export.c_header import ReferenceLaw, reference_law
from toolbox.sim import DriveParams, control_law, simulate
from toolbox.spec import Scenario

import export_artifacts as A
import export_c_helpers as C

CASES = {"pi": A.pi_artifact, "ip_tc": A.ip_tc_artifact, "hinf": A.hinf_artifact}
HEX_DRIVE = replace(A.DRIVE, voltage_limit="hexagon")
V_MAX = 150.0 / np.sqrt(3.0)          # amplitude convention: circle radius = hexagon apothem

DRIVER6 = r"""
#include <stdio.h>
#include "controller.h"
int main(void)
{
    cct_state_t s;
    cct_input_t in;
    cct_output_t out;
    cct_init(&s);
    while (scanf("%f %f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q,
                 &in.omega_m, &in.theta_e) == 6) {
        cct_step(&s, &in, &out);
        printf("%.9e %.9e %d %d\n", (double)out.v_d, (double)out.v_q, out.saturated, out.status);
    }
    return 0;
}
"""


def run_c(header: str, tmp, inputs: np.ndarray, driver: str) -> np.ndarray:
    """Compile (gcc -Werror, tests/export/export_c_helpers.CFLAGS) and run; rows v_d v_q sat status."""
    res = C.compile_driver(header, tmp, source=driver)
    assert res.returncode == 0, res.stderr
    text = "\n".join(" ".join(f"{v:.9e}" for v in row) for row in inputs) + "\n"
    out = subprocess.run([str(tmp / "drv")], input=text, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    return np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])


def _kernel_run(art, limit: str, speed: float):
    scen = Scenario(kind="current_step", duration=0.02, id_ref=-100.0, iq_ref=250.0,
                    step_time=0.002, initial_speed=speed, keep_traces=True, trace_step=A.TS)
    drive = DriveParams(vdc=A.DRIVE.vdc, sample_time=A.TS, delay_samples=1, v_limit=limit)
    return simulate(control_law(art), A.MOTOR, scen, drive)


@pytest.mark.parametrize("limit", ["circle", "hexagon"])
@pytest.mark.parametrize("speed", [0.0, 150.0])
@pytest.mark.parametrize("name", list(CASES))
def test_kernel_matches_reference_law(name, speed, limit):
    """250 A / -100 A steps into the voltage limit at standstill and at 150 rad/s
    (back-EMF 72 V of 86.6 V): the kernel's applied voltage (one period of
    delay) equals the reference law's output to 1e-12 relative, saturated
    periods included. For the hexagon at speed the replayed angle p Omega k Ts
    differs from the kernel's RK4-integrated one by at most n_steps x eps x
    theta_max (20,000 plant steps, theta <= 12 rad: 5e-11 rad), which moves
    the hexagon's edge by |v| x 2 dtheta: that term is added to the tolerance."""
    art = CASES[name]()
    r = _kernel_run(art, limit, speed)
    ref = ReferenceLaw(art, V_MAX, limit)
    p = A.MOTOR.pole_pairs
    v = np.array([ref.step(r.id_ref[k], r.iq_ref[k], r.id[k], r.iq[k], r.speed_measured[k],
                           p * r.speed_measured[k] * k * A.TS) for k in range(len(r.t))])
    kernel = np.column_stack([r.vd, r.vq])[1:]            # applied one period later
    err = np.abs(v[:-1, :2] - kernel).max()
    scale = np.abs(v[:, :2]).max()
    print(f"\n{name} {limit} {speed:g} rad/s: {int(v[:, 2].sum())} saturated periods, "
          f"max|dv| {err:.3g} V of {scale:.3g} V")
    assert v[:, 2].sum() >= 5                              # the limit really acted
    n_steps = round(0.02 / 1e-6)                           # plant steps of 1 us (default)
    dtheta = n_steps * np.finfo(float).eps * p * speed * 0.02 if limit == "hexagon" else 0.0
    assert err <= scale * (1e-12 + 2.0 * dtheta)


def test_hexagon_is_not_the_circle():
    """The hexagon lets |v| reach the vertex radius 2/sqrt(3) V_MAX in the corners:
    the reference law exceeds V_MAX by more than 5 % somewhere, the circle never
    (so the kernel test above can tell the two apart)."""
    art = A.pi_artifact()
    r = _kernel_run(art, "hexagon", 150.0)
    inp = np.column_stack([r.id_ref, r.iq_ref, r.id, r.iq, r.speed_measured,
                           A.MOTOR.pole_pairs * r.speed_measured * np.arange(len(r.t)) * A.TS])
    v_hex, _ = reference_law(art, inp, V_MAX, "hexagon")
    v_cir, _ = reference_law(art, inp[:, :5], V_MAX, "circle")
    assert np.hypot(*v_hex.T).max() > 1.05 * V_MAX
    assert np.hypot(*v_cir.T).max() <= V_MAX * (1 + 1e-12)


@pytest.mark.parametrize("name", list(CASES))
def test_hexagon_header_matches_reference(name, tmp_path):
    """voltage_limit = "hexagon": the header takes theta_e and limits on the SVM
    hexagon like the simulator. Saturated inputs (20 A steps at 300 rad/s, the
    angle turning 12 electrical rad/ms): flags agree except within float32
    rounding of the edge test, voltages within 1e-4 x V_MAX (float32 sin/cos
    of angles up to 50 rad: ~1e-5 rad)."""
    art = CASES[name]()
    chk = check_exportable(art, A.MOTOR, HEX_DRIVE)
    assert chk.limit == "hexagon"
    h = write_header(art, A.MOTOR, HEX_DRIVE)
    assert "float theta_e;" in h and "cosf(" in h
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    theta = np.cumsum(A.MOTOR.pole_pairs * inp[:, 4] * A.TS)
    inp = np.column_stack([inp, theta]).astype(np.float32).astype(float)
    v_ref, s_ref = reference_law(art, inp, chk.v_max, "hexagon")
    out = run_c(h, tmp_path, inp, DRIVER6)
    assert s_ref.sum() > 20 and not out[:, 3].any()
    differ = s_ref != out[:, 2]
    assert differ.sum() <= 3
    err = np.abs(out[:, :2] - v_ref).max()
    print(f"\n{name} hexagon: {s_ref.sum()} saturated, max|err| {err:.3g} V")
    assert err <= 1e-4 * chk.v_max


def test_hexagon_q31_refused_with_reason(tmp_path):
    """The Q31 variant does not implement the hexagon (it needs sin/cos of the
    angle): asked for, it is refused naming drive.voltage_limit; the header
    carries the reason under #error and compiles only without CCT_FIXED_POINT."""
    art = A.pi_artifact()
    with pytest.raises(ExportRefused) as err:
        check_exportable(art, A.MOTOR, HEX_DRIVE, fixed_point=True)
    assert err.value.key == "drive.voltage_limit" and "float path only" in str(err.value)
    h = write_header(art, A.MOTOR, HEX_DRIVE)
    res = C.compile_driver(h, tmp_path, fixed=True, source=DRIVER6)
    assert res.returncode != 0 and "float path only" in res.stderr
    assert C.compile_driver(h, tmp_path, source=DRIVER6).returncode == 0
