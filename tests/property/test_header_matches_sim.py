"""The exported C header replays the simulator through saturation (toolbox/ARCHITECTURE.md
"controller.h": one law in every executor).

For every linear method and random plausible motors (the draws of
:mod:`test_random_motors`), a saturating q-current step is simulated by the
toolbox (``run_verification``, traces kept at every controller period); the
float ``controller.h`` of the same artifact is compiled with
``gcc -std=c99 -Wall -Wextra -Werror`` and driven open loop with the *same*
sequence the simulated controller saw: references, measured currents, measured
speed (and, for the SVM hexagon, the electrical angle). Its voltages must equal
the simulator's applied voltages sample by sample, saturated periods included.

Alignment: the trace row ``k`` holds the voltage *applied* over period ``k``
(``toolbox.sim._kernel``: ``vd_app = vd_buf[k - delay]``), i.e. the law's
output computed at sample ``k - delay``; with ``delay_samples = 1`` the header's
output for input row ``k`` is compared with trace row ``k + 1``, and trace row 0
must be zero.

Tolerance (float32 header vs float64 simulator), per sample::

    |v_C - v_sim| <= 1e-3 V_max + (4 + N_sat) eps32 |D_y| I_scale

* ``1e-3 V_max``: the header realises a one-degree-of-freedom law as CMSIS
  df2T second-order sections (``toolbox.export._sos``). For a PI the section
  state holds the integral in *error* units and its update
  ``x+ = b1 e + (e + x)`` cancels two terms of the size of the error ``e``: in
  saturation ``e`` is the whole step while ``x`` is small, so each period
  rounds at ``eps32 |e|`` (not ``eps32 |x|``), times the section gain. Over
  the ~1000 saturated periods of a long L/R this random walk reaches
  ~2e-4 V_max (measured: 2.4 mV of 11.6 V, R = 1, L = 50 mH, Ts = 45 us,
  pi); 1e-3 V_max covers it with a factor 3 and stays two orders below what
  a broken law produces. Measured on R = 1, L = 50 mH, Ts = 100 us at speed
  (pi, tci, lq): the anti-windup vector halved in the header gives 0.14 to
  0.56 V_max, no anti-windup 0.48 to 0.56 V_max, one period of misalignment
  is asserted to exceed 10 x the tolerance in every example. The plain float32
  rounding of the output terms (2**-24 relative, a few terms bounded by
  V_max) is 1e-7 V_max and negligible against it.
* ``4 eps32 |D_y| I_scale``: the inputs themselves are rounded to float32 in
  the header (a real firmware's ADC path); the proportional path amplifies that
  rounding by the law's direct feedthrough ``|D_y|`` (V/A) of the measured
  current, up to ``L wc`` which is thousands of times ``V_max / I_scale`` for
  slow, high-inductance motors. ``I_scale`` is the largest current magnitude of
  the run; 4 eps32 covers the rounding of reference and measurement (2 eps32)
  and of the resulting error (2 eps32). This term is the physics of float32
  inputs, not a loosening for the law.
* ``N_sat eps32 |D_y| I_scale``: while saturated the error ``e`` is constant
  (the whole step), so the section updates round the same way every period
  and their rounding adds up linearly instead of as a random walk: at most
  one ``eps32 |D_y e|`` (the largest term of the update) per saturated period.
  Seen on H-infinity laws with long saturation (1246 of 2000 periods
  saturated: 1.1e-3 V_max, above the 1e-3 term alone). Open-loop replay
  keeps that drift; in closed loop the integral action removes it. Even with
  a few thousand saturated periods the bound stays two orders below a broken
  law's error.
"""

from __future__ import annotations

import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from toolbox.export import check_exportable, write_header
from toolbox.pipeline import design_spec, run_verification
from toolbox.spec import spec_from_dict

from hypothesis import HealthCheck, settings

from test_random_motors import METHODS, WC_TS, _spec, motors

sys.path.insert(0, str(Path(__file__).parents[1] / "export"))
import export_c_helpers as C  # noqa: E402  (tests/export helper: gcc flags and driver)

#: slow: compiled headers against long simulations, many random motors
pytestmark = pytest.mark.slow

EPS32 = 2.0 ** -24
#: float32 df2T rounding through saturation, relative to V_max (module docstring)
REL_TOL = 1e-3
#: at most this many controller periods: the C driver reads text, and the
#: saturated phase plus the linear settling fits well inside
MAX_ROWS = 2000

DRIVER = r"""
#include <stdio.h>
#include "controller.h"
int main(void)
{
    cct_state_t s;
    cct_input_t in = {0};
    cct_output_t out;
    cct_init(&s);
#ifdef CCT_HEX
    while (scanf("%f %f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q,
                 &in.omega_m, &in.theta_e) == 6) {
#else
    while (scanf("%f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q,
                 &in.omega_m) == 5) {
#endif
        cct_step(&s, &in, &out);
        printf("%.9e %.9e %d %d\n", (double)out.v_d, (double)out.v_q, out.saturated,
               out.status);
    }
    return 0;
}
"""


#: electrical time constant over the sample time for the draws here: a step
#: that R i can still sustain (R i <= 0.6 V_max) then asks the linear law for
#: about L wc i = 0.5 x 0.15 x 45 V_max = 3.4 V_max, so every method (the IP
#: and LQ servo laws too, whose voltage ramps instead of jumping) saturates
TAU_OVER_TS = 45.0


def saturating_motors():
    """motors() whose L/R is long enough for a reachable step to saturate."""
    return motors().filter(
        lambda c: min(c[0]["Ld"], c[0]["Lq"]) / c[0]["R"] >= TAU_OVER_TS * c[1]["sample_time"])


def _step(motor: dict, drive: dict, speed_frac: float) -> tuple[float, float, float]:
    """A q step into the voltage limit that R i and the EMF still leave reachable.

    The step is fixed first (R i = 0.5 V_max, so that with L/R >= 45 Ts the
    linear law asks several V_max); the speed is then bounded so that the
    EMF stays below ``speed_frac`` V_max, the d-axis voltage ``w Lq i`` below
    0.2 V_max and the rotation below 3 deg per period.

    Returns (iq_step A, mechanical speed rad/s, q voltage left for L di/dt V).
    """
    v_max = drive["vdc"] / math.sqrt(3)        # inscribed circle, amplitude-invariant
    i_step = 0.5 * v_max / motor["R"]
    w_e = min(speed_frac * v_max / motor["flux"], 0.05 / drive["sample_time"],
              0.2 * v_max / (motor["Lq"] * i_step))
    v_d = w_e * motor["Lq"] * i_step
    v_q_avail = math.sqrt(v_max ** 2 - v_d ** 2) - motor["R"] * i_step - w_e * motor["flux"]
    return i_step, w_e / motor["pole_pairs"], v_q_avail


def _profile(max_examples: int):
    return settings(max_examples=max_examples, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow,
                                           HealthCheck.filter_too_much])


#: examples per method: 10 (the H-infinity design with gamma iteration costs
#: up to ~30 s per motor, so 3), about 1.5 min for the module on one core
EXAMPLES = {m: (3 if m == "hinf" else 10) for m in METHODS}


def _run_header(header: str, inputs: np.ndarray) -> np.ndarray:
    """Compile once (tests/export CFLAGS: -std=c99 -Wall -Wextra -Werror ...) and
    run; rows ``v_d v_q saturated status``."""
    with tempfile.TemporaryDirectory(prefix="cct_prop_") as tmp:
        res = C.compile_driver(header, Path(tmp), source=DRIVER,
                               hexagon=inputs.shape[1] == 6)
        assert res.returncode == 0, f"controller.h does not compile:\n{res.stderr}"
        text = "\n".join(" ".join(f"{v:.9e}" for v in row) for row in inputs) + "\n"
        out = subprocess.run([str(Path(tmp) / "drv")], input=text, capture_output=True,
                             text=True, timeout=60, check=True).stdout
    return np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])


def _feedthrough(artifact) -> dict[str, float]:
    """|D| of the measured-current input of each axis's executed law (V/A)."""
    return {ax: float(abs(np.asarray(artifact.axes[ax].law.D)[0, 1])) for ax in ("d", "q")}


def _given(method: str):
    return _profile(EXAMPLES[method])(given(case=saturating_motors(), at_speed=st.booleans(),
                                            hexagon=st.booleans())(
        lambda case, at_speed, hexagon: _check_header(method, case, at_speed, hexagon)))


@pytest.mark.parametrize("method", METHODS)
def test_header_matches_simulator_through_saturation(method):
    _given(method)()


def _check_header(method: str, case, at_speed: bool, hexagon: bool) -> None:
    motor, drive = case
    drive = {**drive, "voltage_limit": "hexagon" if hexagon else "circle"}
    Ts = drive["sample_time"]
    i_step, speed, v_q_avail = _step(motor, drive, 0.3 if at_speed else 0.0)
    assume(v_q_avail > 0.1 * drive["vdc"] / math.sqrt(3))
    # long enough for the saturated rise (L di / V_avail) and the linear tail,
    # bounded for the text round trip
    t_rise = motor["Lq"] * i_step / v_q_avail + 3.0 * math.log(20) / (WC_TS / Ts)
    rows = int(min(MAX_ROWS, max(200, 2.0 * t_rise / Ts)))
    spec = spec_from_dict(_spec(method, motor, drive, i_step, speed, rows * Ts))
    artifact = design_spec(spec)
    (outcome,) = run_verification(artifact, spec).scenarios
    tr = outcome.result
    n = len(tr.t)
    cols = [tr.id_ref, tr.iq_ref, tr.id, tr.iq, tr.speed_measured]
    if hexagon:
        # the imposed constant speed: theta_k = p Omega k Ts, as the kernel's
        # plant angle (toolbox.sim._kernel state s[3], starting at 0)
        cols.append(motor["pole_pairs"] * np.asarray(tr.speed_measured) * np.arange(n) * Ts)
    inputs = np.column_stack(cols).astype(np.float32).astype(float)
    chk = check_exportable(artifact, spec.motor, spec.drive)
    header = write_header(artifact, spec.motor, spec.drive)
    out = _run_header(header, inputs)
    assert out.shape == (n, 4)
    assert not out[:, 3].any(), f"{method}: header reported a fault status on finite inputs"
    v_sim = np.column_stack([tr.vd, tr.vq])
    assert np.all(v_sim[0] == 0.0), "trace row 0 is before the first applied voltage"
    v_c = out[:-1, :2]                     # computed at k, applied over k + 1
    # the comparison can tell: aligned without the delay, it must fail
    unaligned = np.abs(v_c - v_sim[:-1]).max()
    v_sim = v_sim[1:]
    saturated = out[:-1, 2].astype(bool)
    # the property is about saturation: the step must have hit the limit
    assert saturated.sum() >= 2, (f"{method}: the step never saturated "
                                  f"(max |v| {np.hypot(*v_sim.T).max():.4g} of {chk.v_max:.4g} V)")
    i_scale = float(np.abs(inputs[:, :4]).max())
    D = _feedthrough(artifact)
    n_sat = int(saturated.sum())
    tol = np.array([REL_TOL * chk.v_max + (4 + n_sat) * EPS32 * D[ax] * i_scale
                    for ax in ("d", "q")])
    err = np.abs(v_c - v_sim)
    worst = int(np.argmax((err / tol).max(axis=1)))
    print(f"\n{method} {'hexagon' if hexagon else 'circle'} {speed:.3g} rad/s: "
          f"{int(saturated.sum())} of {n} periods saturated, max |dv| / V_max "
          f"{(err.max(axis=0) / chk.v_max).max():.2g}, max |dv| / tol {(err / tol).max():.2g}")
    assert unaligned > 10 * tol.max(), f"{method}: the check cannot see a period of delay"
    assert np.all(err <= tol), (
        f"{method} ({'hexagon' if hexagon else 'circle'}, speed {speed:.4g} rad/s): C vs "
        f"simulator at period {worst} of {n} (saturated: {bool(saturated[worst])}): "
        f"|dv| = {err[worst]} V > tol {tol} V (V_max {chk.v_max:.4g} V)")
