"""STM32 MCSDK-style and TI IQmath-style integer variants of the PI law
(toolbox/ARCHITECTURE.md "controller.h", integer variants).

The PI artifact (tests/export/export_artifacts.pi_artifact: Kp = L wc,
Ki = R wc, Tustin, back-calculation anti-windup) is exported once; the same
header is compiled with ``-DCCT_MCSDK`` (int16 digits, int16 gains with
power-of-two divisors) and ``-DCCT_IQMATH`` (_IQ24 per unit) and run on the
inputs of tests/export/test_c_header.py (steps, noisy measured currents, a
speed ramp to 100 rad/s: every decoupling term active, no saturation). The
reference is the float law in double precision
(:class:`toolbox.export.c_header.ReferenceLaw`) fed the *dequantised* integer
inputs, so input quantisation is not counted against the variant.

Bounds (derived here from the integer gains printed in the header, not from
the generator's own numbers), per sample k, in output LSBs:

* proportional path: ``|dKp| |e_k| + 1`` (gain quantisation, one floor shift);
* integral path: ``sum_{j<k} (|dKi| |e_j| + r)`` (gain quantisation; ``r`` = 0
  for the MCSDK, whose int32 integral is an exact sum of ``KI e``, and 1 LSB
  per step for IQmath's floored _IQmpy) plus 1 for the output shift;
* each decoupling term: ``|dc| |w i| + |c| + 1`` (coefficient quantisation,
  the floored product ``w i``, the final floor).

The test fails when one sample exceeds its bound; the bound itself must be
below 1e-3 of the largest voltage (not vacuous). Saturation and clamping
are tested separately below.
"""

from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest

from toolbox.export import check_exportable, write_header
from toolbox.export.c_header import ReferenceLaw

import export_artifacts as A
import export_c_helpers as C

#: slow: the vendor integer variants compiled and run per design (cross-checks of the
#: float law the everyday set checks)
pytestmark = pytest.mark.slow

DRIVER = r"""
#include <stdio.h>
#include <stdint.h>
#include "controller.h"
int main(void)
{
    long a, b, c, d, e;
#ifdef CCT_MCSDK
    cct_state_s16_t s;
    cct_input_s16_t in;
    cct_output_s16_t out;
    cct_init_s16(&s);
#ifdef RETUNE
    s.gd.kp_gain = D_KP_G; s.gd.kp_div = D_KP_S; s.gd.ki_gain = D_KI_G; s.gd.ki_div = D_KI_S;
    s.gd.kaw_gain = D_KAW_G; s.gd.kaw_div = D_KAW_S;
    s.gq.kp_gain = Q_KP_G; s.gq.kp_div = Q_KP_S; s.gq.ki_gain = Q_KI_G; s.gq.ki_div = Q_KI_S;
    s.gq.kaw_gain = Q_KAW_G; s.gq.kaw_div = Q_KAW_S;
#endif
#else
    cct_state_iq_t s;
    cct_input_iq_t in;
    cct_output_iq_t out;
    cct_init_iq(&s);
#ifdef RETUNE
    s.gd.kp = D_KP; s.gd.ki = D_KI; s.gd.kaw = D_KAW;
    s.gq.kp = Q_KP; s.gq.ki = Q_KI; s.gq.kaw = Q_KAW;
#endif
#endif
    while (scanf("%ld %ld %ld %ld %ld", &a, &b, &c, &d, &e) == 5) {
#ifdef CCT_MCSDK
        in.i_d_ref = (int16_t)a; in.i_q_ref = (int16_t)b; in.i_d = (int16_t)c;
        in.i_q = (int16_t)d; in.omega_m = (int16_t)e;
        cct_step_s16(&s, &in, &out);
#else
        in.i_d_ref = (int32_t)a; in.i_q_ref = (int32_t)b; in.i_d = (int32_t)c;
        in.i_q = (int32_t)d; in.omega_m = (int32_t)e;
        cct_step_iq(&s, &in, &out);
#endif
        printf("%ld %ld %d %d\n", (long)out.v_d, (long)out.v_q, out.saturated, out.status);
    }
    return 0;
}
"""


def _macro(h: str, name: str) -> float:
    m = re.search(rf"#define CCT_{name} \(?(?:\(int32_t\))?(-?[0-9.e+]+)[fL]?\)?", h)
    assert m, name
    return float(m.group(1))


def _compile_run(h: str, tmp, variant: str, q_inputs: np.ndarray) -> np.ndarray:
    gcc = C.require_gcc()
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "controller.h").write_text(h)
    (tmp / "drv.c").write_text(DRIVER)
    res = subprocess.run([gcc, *C.CFLAGS, f"-DCCT_{variant}", "-I", str(tmp), str(tmp / "drv.c"),
                          "-o", str(tmp / "drv"), "-lm"], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    text = "\n".join(" ".join(str(int(v)) for v in row) for row in q_inputs) + "\n"
    out = subprocess.run([str(tmp / "drv")], input=text, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    return np.array([[int(x) for x in ln.split()] for ln in out.strip().splitlines()])


def _scales(h: str, variant: str):
    """(full scale of one integer unit: current A, speed rad/s, voltage V; units per full scale)."""
    if variant == "MCSDK":
        return _macro(h, "MCSDK_I_FS"), _macro(h, "MCSDK_W_FS"), _macro(h, "MCSDK_V_FS"), 32768.0
    return _macro(h, "IQ_I_BASE"), _macro(h, "IQ_W_BASE"), _macro(h, "IQ_V_BASE"), 2.0 ** 24


def _range(variant: str) -> float:
    """The current and speed ranges as fractions of the scales of :func:`_scales`
    (the MCSDK's full scales are twice the ranges, the plausible ranges)."""
    return 0.5 if variant == "MCSDK" else 1.0


def _gain(h: str, variant: str, name: str) -> float:
    """A coefficient of the header in output units per (input unit) (as executed)."""
    if variant == "MCSDK":
        return _macro(h, f"MCSDK_{name}_GAIN") / 2.0 ** _macro(h, f"MCSDK_{name}_DIV")
    return _macro(h, f"IQ_{name}") / 2.0 ** 24


def _quantise(inp, I, W, full):
    q = np.column_stack([np.round(inp[:, :4] / I * full), np.round(inp[:, 4] / W * full)])
    lim = full - 1 if full == 32768.0 else full
    return np.clip(q, -lim, lim).astype(np.int64)


def _bound(h, variant, art, q, I, W, V, full):
    """(N, 2) bound in volts (module docstring)."""
    dec = art.decoupling
    p = dec.pole_pairs
    gI = I / V                                    # V units per A unit, per V/A
    out = np.zeros((len(q), 2))
    law = {ax: (art.axes[ax].law.D[0, 0], art.axes[ax].law.C[0, 0] * art.axes[ax].law.B[0, 0])
           for ax in "dq"}
    w = q[:, 4].astype(float)
    cross, emf = float(dec.cross), float(dec.emf)
    exact_dec = {"DD": -cross * p * dec.Lq_c * W * I / V, "DQ": cross * p * dec.Ld_c * W * I / V,
                 "DE": emf * p * dec.flux_c * W / V}
    for j, ax in enumerate("dq"):
        e = (q[:, j] - q[:, 2 + j]).astype(float)
        dkp = abs(_gain(h, variant, f"{ax.upper()}_KP") - law[ax][0] * gI)
        dki = abs(_gain(h, variant, f"{ax.upper()}_KI") - law[ax][1] * gI)
        r = 0.0 if variant == "MCSDK" else 1.0
        integ = np.concatenate([[0.0], np.cumsum(dki * np.abs(e) + r)[:-1]])
        b = dkp * np.abs(e) + 1.0 + integ + 1.0
        terms = [("DD", q[:, 3])] if ax == "d" else [("DQ", q[:, 2]), ("DE", None)]
        for name, cur in terms:
            c = _gain(h, variant, name)
            if cur is None:                       # e term: c w, one floor
                b += abs(c - exact_dec[name]) * np.abs(w) + 1.0
            else:                                 # (c ((w i) >> shift)) >> div
                b += abs(c - exact_dec[name]) * np.abs(w * cur) / full + abs(c) + 1.0
        out[:, j] = b * V / full
    return out


@pytest.mark.parametrize("variant", ["MCSDK", "IQMATH"])
def test_vendor_variant_matches_float_law(variant, tmp_path):
    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    h = write_header(art, A.MOTOR, A.DRIVE)
    I, W, V, full = _scales(h, variant)
    # the drive's ranges: 1 p.u. for IQmath; MCSDK digits of twice them (the plausible ranges)
    k = 2.0 if variant == "MCSDK" else 1.0
    assert I == k * A.MOTOR.max_current and W == k * A.DRIVE.max_speed
    inp = C.test_inputs()
    q = _quantise(inp, I, W, full)
    deq = np.column_stack([q[:, :4] * I / full, q[:, 4] * W / full])
    ref = ReferenceLaw(art, chk.v_max)
    v_ref = np.array([ref.step(*row)[:2] for row in deq])
    out = _compile_run(h, tmp_path, variant, q)
    v = out[:, :2] * V / full
    err = np.abs(v - v_ref)
    bound = _bound(h, variant, art, q, I, W, V, full)
    scale = np.abs(v_ref).max()
    print(f"\n{variant}: max|err| {err.max():.3g} V, bound max {bound.max():.3g} V "
          f"({bound.max() / scale:.2e} of max|v| {scale:.3g} V), worst err/bound "
          f"{(err / bound).max():.3f}")
    assert not out[:, 2].any() and not out[:, 3].any()
    assert np.all(err <= bound)
    assert bound.max() < 1e-3 * scale


@pytest.mark.parametrize("variant", ["MCSDK", "IQMATH"])
def test_vendor_variant_saturation(variant, tmp_path):
    """20 A steps at 300 rad/s: the voltage limit acts (> 20 periods); flags
    agree with the float law except within 2 output LSBs of the limit, the
    magnitude never exceeds the limit by more than 1 LSB (integer division
    truncates towards zero), and voltages agree within 2e-3 V_MAX (0.17 V).
    That tolerance (20 x the float path's) is the MCSDK's: its integral and
    anti-windup gains are int16 with divisors <= 2^15 (Ki = 0.0035
    digit/digit is 113 / 2^15, 0.4 % off), which the unsaturated bound above
    already grows to 5e-4 V_MAX over these 400 periods, and while saturated
    the back-calculation integrates the Kaw quantisation as well: 4 x that
    (measured 2.9e-4 V_MAX; IQmath 1.1e-5 V_MAX)."""
    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    h = write_header(art, A.MOTOR, A.DRIVE)
    I, W, V, full = _scales(h, variant)
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    rng_i = _range(variant) * I
    inp[:, :4] = np.clip(inp[:, :4], -0.999 * rng_i, 0.999 * rng_i)
    q = _quantise(inp, I, W, full)
    deq = np.column_stack([q[:, :4] * I / full, q[:, 4] * W / full])
    ref = ReferenceLaw(art, chk.v_max)
    res = np.array([ref.step(*row) for row in deq])
    out = _compile_run(h, tmp_path, variant, q)
    v = out[:, :2] * V / full
    lsb = V / full
    vmax = chk.v_max
    assert res[:, 2].sum() > 20
    differ = res[:, 2] != out[:, 2]
    assert np.all(np.abs(np.hypot(*res[differ, :2].T) - vmax) < 2 * lsb + 1e-3 * vmax)
    assert np.hypot(*v.T).max() <= vmax + 2 * lsb
    err = np.abs(v - res[:, :2]).max()
    print(f"\n{variant} saturated: {int(res[:, 2].sum())} saturated, max|err| {err:.3g} V "
          f"({err / vmax:.2e} V_MAX)")
    assert err <= 2e-3 * vmax
    assert not out[:, 3].any()


def test_inputs_beyond_range_are_clamped_and_flagged(tmp_path):
    """A 30 A measurement with a 20 A range (motor.max_current): IQmath
    clamps it to 1.0 p.u. and says so (status CLAMPED) and its output equals
    the float law fed 20 A (within the linear bound's few LSBs). A 100 A
    measurement (beyond the plausible 2 p.u.) is refused (status IMPLAUSIBLE):
    the law runs on the last plausible sample without an integral update, so
    the next period equals the float law that never saw it. The MCSDK's
    amps-to-s16A helper maps the plausible range (40 A) to the rail and a NaN
    to 0, each with its flag; its step clamps beyond the range (16384 digits)
    and refuses the rail likewise."""
    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    h = write_header(art, A.MOTOR, A.DRIVE)
    I, W, V, full = _scales(h, "IQMATH")
    assert I == 20.0
    rows = np.array([[0.0, 5.0, 0.0, 4.0, 50.0], [0.0, 5.0, 0.0, 30.0, 50.0],
                     [0.0, 5.0, 0.0, 4.5, 50.0], [0.0, 5.0, 0.0, 100.0, 50.0],
                     [0.0, 5.0, 0.0, 4.2, 50.0]])
    q = np.column_stack([np.round(rows[:, :4] / I * full), np.round(rows[:, 4] / W * full)])
    out = _compile_run(h, tmp_path, "IQMATH", q.astype(np.int64))
    assert list(out[:, 3]) == [0, 3, 0, 4, 0]
    clipped = rows.copy()
    clipped[1, 3] = I
    ref = ReferenceLaw(art, chk.v_max)
    v_ref = np.array([ref.step(*row)[:2] for row in np.delete(clipped, 3, axis=0)])
    np.testing.assert_array_less(np.abs(np.delete(out[:, :2], 3, axis=0) * V / full - v_ref),
                                 1e-5 * V)
    # the refused period: the law on the last plausible sample (4.5 A), state unchanged
    ref2 = ReferenceLaw(art, chk.v_max)
    for row in clipped[:3]:
        ref2.step(*row)
    v_sub = ref2.step(*[0.0, 5.0, 0.0, 4.5, 50.0])[:2]
    assert np.abs(out[3, :2] * V / full - v_sub).max() < 1e-5 * V
    src = ('#include <stdio.h>\n#include "controller.h"\nint main(void)\n{\n'
           '    int f = 0, g = 0, n = 0;\n'
           '    const int16_t a = cct_to_s16a(100.0f, &f);\n'
           '    const int16_t b = cct_to_s16a(10.0f, &g);\n'
           '    const volatile float z = 0.0f;\n'
           '    const int16_t c = cct_to_s16a(z / z, &n);\n'
           '    cct_state_s16_t s;\n    cct_input_s16_t in = {0, 1000, 0, 0, 100};\n'
           '    cct_output_s16_t o1, o2, o3;\n    cct_init_s16(&s);\n'
           '    in.i_q = 20000; cct_step_s16(&s, &in, &o1);\n'
           '    in.i_q = a; cct_step_s16(&s, &in, &o2);\n'
           '    in.i_q = -32768; cct_step_s16(&s, &in, &o3);\n'
           '    printf("%d %d %d %d %d %d %d %d %d\\n", (int)a, f, (int)b, g, (int)c, n,'
           ' o1.status, o2.status, o3.status);\n    return 0;\n}\n')
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "controller.h").write_text(h)
    (tmp_path / "c" / "m.c").write_text(src)
    res = subprocess.run([C.require_gcc(), *C.CFLAGS, "-DCCT_MCSDK", "-I", str(tmp_path / "c"),
                          str(tmp_path / "c" / "m.c"), "-o", str(tmp_path / "c" / "m"), "-lm"],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    got = list(map(int, subprocess.run([str(tmp_path / "c" / "m")], capture_output=True,
                                       text=True, timeout=30).stdout.split()))
    # 10 A of a 40 A full scale (twice the 20 A range) = 8192 digits
    assert got == [32767, 1, 8192, 0, 0, 1, 3, 4, 4], got


def test_vendor_variants_refused_for_other_laws(tmp_path):
    """A law that is not a one-DOF PI (paper 003's 4th-order H-infinity) has no
    MCSDK/IQmath variant: the header says why under #error, the float path is
    unaffected."""
    h = write_header(A.hinf_artifact(), A.MOTOR, A.DRIVE)
    for variant in ("MCSDK", "IQMATH"):
        tmp = tmp_path / variant
        tmp.mkdir()
        (tmp / "controller.h").write_text(h)
        (tmp / "m.c").write_text('#include "controller.h"\nint main(void) { return 0; }\n')
        res = subprocess.run([C.require_gcc(), *C.CFLAGS, f"-DCCT_{variant}", "-I", str(tmp),
                              str(tmp / "m.c"), "-o", str(tmp / "m"), "-lm"],
                             capture_output=True, text=True, timeout=60)
        assert res.returncode != 0 and "run a PI (one integrator)" in res.stderr


@pytest.mark.parametrize("design", ["000_lepioufle1992_pi", "003_azaiz2007_pi"])
@pytest.mark.parametrize("variant", ["MCSDK", "IQMATH"])
def test_reference_pi_designs(design, variant, tmp_path):
    """The PI reference designs (made by the design module through the
    pipeline) have both variants, and they agree with the float law within
    the same derived bound (steps of 0.3 x the current range, speed ramp to
    0.2 x the speed range, 400 periods); the bound stays below 2e-3 of the
    largest voltage."""
    from pathlib import Path
    from toolbox.pipeline import design_spec
    from toolbox.spec import load_spec
    spec = load_spec(Path(__file__).parents[2] / "designs" / f"{design}.toml")
    art = design_spec(spec)
    chk = check_exportable(art, spec.motor, spec.drive)
    h = write_header(art, spec.motor, spec.drive)
    I, W, V, full = _scales(h, variant)
    inp = C.test_inputs(i_step=0.3 * _range(variant) * I, speed=0.2 * _range(variant) * W)
    q = _quantise(inp, I, W, full)
    deq = np.column_stack([q[:, :4] * I / full, q[:, 4] * W / full])
    ref = ReferenceLaw(art, chk.v_max)
    res = np.array([ref.step(*row) for row in deq])
    out = _compile_run(h, tmp_path, variant, q)
    err = np.abs(out[:, :2] * V / full - res[:, :2])
    bound = _bound(h, variant, art, q, I, W, V, full)
    print(f"\n{design} {variant}: max|err| {err.max():.3g} V, bound {bound.max():.3g} V, "
          f"max|v| {np.abs(res[:, :2]).max():.3g} V, {int(res[:, 2].sum())} saturated")
    assert not res[:, 2].any()
    assert np.all(err <= bound)
    # not vacuous: the MCSDK's 16-bit LSB alone is 2.4e-4 of 003's max|v| (21.9 V),
    # its bound 1.1e-3; a wrong gain or decoupling term errs by > 1e-2
    assert bound.max() < 2e-3 * np.abs(res[:, :2]).max()


@pytest.mark.parametrize("variant", ["MCSDK", "IQMATH"])
def test_gains_retunable_at_run_time(variant, tmp_path):
    """Gains honesty for the integer variants: the step reads the gains from
    the state (as the MCSDK's PI handle), so writing the gains of a PI tuned
    for wc = 1000 rad/s into a controller exported for wc = 500 rad/s gives
    exactly (bit for bit) the outputs of the controller exported for 1000
    rad/s, and outputs that differ from the untuned one (saturating steps at
    300 rad/s: anti-windup gains exercised too)."""
    h500 = write_header(A.pi_artifact(wc=500.0), A.MOTOR, A.DRIVE)
    h1000 = write_header(A.pi_artifact(wc=1000.0), A.MOTOR, A.DRIVE)
    I, W, V, full = _scales(h500, variant)
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    rng_i = _range(variant) * I
    inp[:, :4] = np.clip(inp[:, :4], -0.999 * rng_i, 0.999 * rng_i)
    q = _quantise(inp, I, W, full)
    defs = []
    for ax in "DQ":
        for k in ("KP", "KI", "KAW"):
            if variant == "MCSDK":
                defs += [f"-D{ax}_{k}_G={int(_macro(h1000, f'MCSDK_{ax}_{k}_GAIN'))}",
                         f"-D{ax}_{k}_S={int(_macro(h1000, f'MCSDK_{ax}_{k}_DIV'))}"]
            else:
                defs.append(f"-D{ax}_{k}={int(_macro(h1000, f'IQ_{ax}_{k}'))}")
    runs = {}
    for name, h, extra in (("500", h500, []), ("1000", h1000, []),
                           ("retuned", h500, ["-DRETUNE", *defs])):
        tmp = tmp_path / name
        tmp.mkdir()
        (tmp / "controller.h").write_text(h)
        (tmp / "r.c").write_text(DRIVER)
        res = subprocess.run([C.require_gcc(), *C.CFLAGS, f"-DCCT_{variant}", *extra, "-I", str(tmp),
                              str(tmp / "r.c"), "-o", str(tmp / "r"), "-lm"],
                             capture_output=True, text=True, timeout=60)
        assert res.returncode == 0, res.stderr
        text = "\n".join(" ".join(str(int(v)) for v in row) for row in q) + "\n"
        runs[name] = subprocess.run([str(tmp / "r")], input=text, capture_output=True,
                                    text=True, timeout=60, check=True).stdout
    assert runs["retuned"] == runs["1000"]
    assert runs["retuned"] != runs["500"]


def test_vendor_plan_of_a_check_without_its_minimal_laws():
    """An ExportCheck built without the minimal laws (its field's default) gets
    the plan made from the artifact's, the same as check_exportable's."""
    from dataclasses import replace

    from toolbox.export.c_header import vendor_plan

    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    plan, why = vendor_plan(art, A.MOTOR, A.DRIVE, chk)
    assert plan is not None, why
    again, _ = vendor_plan(art, A.MOTOR, A.DRIVE, replace(chk, minimal={}))
    assert again == plan
