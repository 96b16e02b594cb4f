"""Firmware-grade headers: prefix, run-time bus voltage, delay
compensation, usage example. toolbox/ARCHITECTURE.md "controller.h".

Every header is compiled with gcc -std=c99 -Wall -Wextra -Werror -pedantic
-Wconversion (tests/export/export_c_helpers.CFLAGS) and run; the numbers are
compared with the double-precision reference law
(:class:`toolbox.export.c_header.ReferenceLaw`) or with a rotation done in
double. Run with ``-s`` to print the measured agreement.
"""

from __future__ import annotations

import subprocess
from dataclasses import replace

import numpy as np
import pytest

from toolbox.errors import SpecError
from toolbox.export import check_exportable, example_source, prefix_name, write_header
from toolbox.export.c_header import ReferenceLaw

import export_artifacts as A
import export_c_helpers as C

HEX_DRIVE = replace(A.DRIVE, voltage_limit="hexagon")
EPS32 = 2.0 ** -24


def _build(tmp, files: dict, main: str, defines=()) -> str:
    """Compile and link several translation units into one program."""
    gcc = C.require_gcc()
    tmp.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (tmp / name).write_text(text)
    srcs = [str(tmp / n) for n in files if n.endswith(".c")]
    exe = tmp / main
    res = subprocess.run([gcc, *C.CFLAGS, *defines, "-I", str(tmp), *srcs, "-o", str(exe), "-lm"],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    return str(exe)


def _run(exe: str, rows: np.ndarray) -> np.ndarray:
    text = "\n".join(" ".join(f"{v:.9e}" for v in row) for row in rows) + "\n"
    out = subprocess.run([exe], input=text, capture_output=True, text=True, timeout=60,
                         check=True).stdout
    return np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])


# ---------------------------------------------------------------- 1. prefix
TU = r"""
#include <stdio.h>
#include "{h}"
void {p}run(const float *u, float *v);
void {p}run(const float *u, float *v)
{{
    static {p}state_t s;
    static int started = 0;
    {p}input_t in = {{0}};
    {p}output_t out;
    if (!started) {{ {p}init(&s); started = 1; }}
    in.i_d_ref = u[0]; in.i_q_ref = u[1]; in.i_d = u[2]; in.i_q = u[3]; in.omega_m = u[4];
    {p}step(&s, &in, &out);
    v[0] = out.v_d; v[1] = out.v_q;
}}
"""

MAIN2 = r"""
#include <stdio.h>
#include "motor1.h"
#include "motor2.h"   /* both in one translation unit too: distinct guards and names */
void motor1_run(const float *u, float *v);
void motor2_run(const float *u, float *v);
int main(void)
{
    float u[5], v1[2], v2[2];
    /* the constants of both headers are visible side by side */
    if (MOTOR1_SAMPLE_TIME != MOTOR2_SAMPLE_TIME) { return 3; }
    while (scanf("%f %f %f %f %f", &u[0], &u[1], &u[2], &u[3], &u[4]) == 5) {
        motor1_run(u, v1);
        motor2_run(u, v2);
        printf("%.9e %.9e %.9e %.9e\n", (double)v1[0], (double)v1[1], (double)v2[0],
               (double)v2[1]);
    }
    return 0;
}
"""


def test_prefix_names():
    """``prefix="motor1_"`` renames guard, types, functions, macros and the
    fixed-point switch; "motor1" is the same prefix; no ``cct``/``CCT`` name is
    left. The default stays ``CCT_``/``cct_`` (the existing contract)."""
    art = A.pi_artifact()
    h = write_header(art, A.MOTOR, A.DRIVE, prefix="motor1_")
    assert h == write_header(art, A.MOTOR, A.DRIVE, prefix="motor1")
    assert "#ifndef MOTOR1_CONTROLLER_H" in h and "#ifdef MOTOR1_FIXED_POINT" in h
    for ident in ("motor1_step(", "motor1_init(", "motor1_set_vdc(", "motor1_state_t",
                  "motor1_step_q31(", "#define MOTOR1_V_MAX ", "MOTOR1_STATUS_OK"):
        assert ident in h, ident
    assert "cct_" not in h.replace("cct_step", "") and "CCT_" not in h
    default = write_header(art, A.MOTOR, A.DRIVE)
    assert "#ifndef CCT_CONTROLLER_H" in default and "#ifdef CCT_FIXED_POINT" in default
    assert "cct_step(" in default
    assert write_header(art, A.MOTOR, A.DRIVE, prefix="cct_") == default


@pytest.mark.parametrize("bad", ["1motor", "_m", "_", "mo tor", "m-1", "x" * 32, "", 5,
                                 "m\n", "motor1_\n"])
def test_prefix_refused(bad):
    """Not a C identifier starting with a letter (<= 31 characters): SpecError
    naming export.prefix, nothing rendered."""
    with pytest.raises(SpecError, match="export.prefix"):
        write_header(A.pi_artifact(), A.MOTOR, A.DRIVE, prefix=bad)
    with pytest.raises(SpecError):
        prefix_name(bad)


def test_two_prefixed_headers_in_one_program(tmp_path):
    """Two controllers in one firmware: the PI (motor1_) and the IP/TC law
    (motor2_), each header in its own translation unit and both in main.c,
    compiled and linked into one program. Each controller's output equals its
    OWN reference law within the float32 bound (tests/export/test_c_header.py
    rules), and the two differ by far more than that bound, so a program that
    silently used one header's values for both would fail."""
    arts = {"motor1": A.pi_artifact(), "motor2": A.ip_tc_artifact()}
    files = {f"{p}.h": write_header(a, A.MOTOR, A.DRIVE, prefix=p + "_") for p, a in arts.items()}
    files.update({f"{p}.c": TU.format(h=f"{p}.h", p=p + "_") for p in arts})
    files["main.c"] = MAIN2
    exe = _build(tmp_path, files, "two")
    inp = C.test_inputs()
    out = _run(exe, inp)
    worst = []
    for j, (p, art) in enumerate(arts.items()):
        chk = check_exportable(art, A.MOTOR, A.DRIVE)
        ref = ReferenceLaw(art, chk.v_max)
        v_ref = np.array([ref.step(*row)[:2] for row in inp])
        err = np.abs(out[:, 2 * j:2 * j + 2] - v_ref)
        bound = C.float_bound(chk, art, inp)
        worst.append(err.max())
        assert np.all(err <= bound), p
    gap = np.abs(out[:, :2] - out[:, 2:]).max()
    print(f"\ntwo headers: max|err| motor1 {worst[0]:.3g} V, motor2 {worst[1]:.3g} V; "
          f"outputs differ by up to {gap:.3g} V")
    assert gap > 1e3 * max(worst)


def test_two_headers_mixed_float_and_q31(tmp_path):
    """The fixed-point switch is per prefix: MOTOR2_FIXED_POINT turns on the
    Q31 variant of motor2 only; both compile in one translation unit."""
    h1 = write_header(A.pi_artifact(), A.MOTOR, A.DRIVE, prefix="motor1_")
    h2 = write_header(A.pi_artifact(), A.MOTOR, A.DRIVE, prefix="motor2_")
    main = ('#include "motor1.h"\n#include "motor2.h"\nint main(void)\n{\n'
            '    motor1_state_t a; motor2_state_q31_t b;\n'
            '    motor1_init(&a); motor2_init_q31(&b);\n'
            '    return (int)(a.d[0] != 0.0f) + (int)(b.d[0] != 0);\n}\n')
    exe = _build(tmp_path, {"motor1.h": h1, "motor2.h": h2, "main.c": main}, "mixed",
                 defines=["-DMOTOR2_FIXED_POINT"])
    assert subprocess.run([exe], timeout=30).returncode == 0
    bad = ('#include "motor1.h"\nint main(void) { motor1_state_q31_t b; (void)b; return 0; }\n')
    (tmp_path / "bad.c").write_text(bad)
    res = subprocess.run([C.require_gcc(), *C.CFLAGS, "-DMOTOR2_FIXED_POINT", "-I", str(tmp_path),
                          str(tmp_path / "bad.c"), "-o", str(tmp_path / "bad")],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode != 0          # motor1's Q31 types exist only under MOTOR1_FIXED_POINT


# ---------------------------------------------------------------- 2. run-time bus voltage
DRIVER_VDC = r"""
#include <stdio.h>
#include "controller.h"
int main(void)
{
    cct_state_t s;
    cct_input_t in = {0};
    cct_output_t out;
    float vdc;
    int st;
    cct_init(&s);
#ifdef CCT_HEX
    while (scanf("%f %f %f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q,
                 &in.omega_m, &in.theta_e, &vdc) == 7) {
#else
    while (scanf("%f %f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q,
                 &in.omega_m, &vdc) == 6) {
#endif
        st = cct_set_vdc(&s, vdc);
        cct_step(&s, &in, &out);
        printf("%.9e %.9e %d %d %.9e %.9e %d\n", (double)out.v_d, (double)out.v_q,
               out.saturated, out.status, (double)out.v_d_comp, (double)out.v_q_comp, st);
    }
    return 0;
}
"""


def _bus(n: int) -> np.ndarray:
    """Nominal 150 V, sagging to 100 V from row 150, a glitch row of 0 V and
    one NaN (both refused: the previous limit stays), recovering to 140 V at 300."""
    vdc = np.full(n, 150.0)
    vdc[150:] = 100.0
    vdc[300:] = 140.0
    vdc[200] = 0.0
    vdc[201] = np.nan
    return vdc


def _reference_with_bus(art, inp, vdc, v_per_vdc, limit):
    """ReferenceLaw with the limit updated as the header's set_vdc does."""
    ref = ReferenceLaw(art, v_per_vdc * 150.0, limit)
    out = []
    for row, vb in zip(inp, vdc):
        if np.isfinite(vb) and vb > 0:
            ref.v_max = v_per_vdc * float(np.float32(vb))
        out.append(ref.step(*row))
    return np.array(out)


@pytest.mark.parametrize("limit", ["circle", "hexagon"])
def test_runtime_bus_voltage(limit, tmp_path):
    """set_vdc() takes the measured bus: the limit is V_MAX_PER_VDC x vdc
    (1/sqrt(3) amplitude-invariant, circle radius or hexagon apothem as the
    spec's drive.voltage_limit says). Saturating inputs (20 A steps at
    300 rad/s) with the bus sagging 150 -> 100 -> 140 V: flags agree except
    within float32 rounding at the boundary (<= 3 samples), voltages within
    1e-4 V_MAX (the saturated tolerance of tests/export/test_c_header.py).
    The header holding the nominal limit instead would be off by > 10 V; the
    refused readings (0 V, NaN) return status 1 and keep the last limit."""
    drive = HEX_DRIVE if limit == "hexagon" else A.DRIVE
    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, drive)
    h = write_header(art, A.MOTOR, drive)
    assert ("float theta_e;" in h) == (limit == "hexagon")
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    if limit == "hexagon":
        theta = np.cumsum(A.MOTOR.pole_pairs * inp[:, 4] * A.TS)
        inp = np.column_stack([inp, theta]).astype(np.float32).astype(float)
    vdc = _bus(len(inp))
    res = C.compile_driver(h, tmp_path, source=DRIVER_VDC, hexagon=limit == "hexagon")
    assert res.returncode == 0, res.stderr
    out = _run(str(tmp_path / "drv"), np.column_stack([inp, vdc]))
    k = chk.v_max / A.DRIVE.vdc
    ref = _reference_with_bus(art, inp, vdc, k, limit)
    nominal = _reference_with_bus(art, inp, np.full(len(inp), 150.0), k, limit)
    err = np.abs(out[:, :2] - ref[:, :2]).max()
    miss = np.abs(out[:, :2] - nominal[:, :2]).max()
    print(f"\n{limit} run-time bus: {int(ref[:, 2].sum())} saturated, max|err| {err:.3g} V "
          f"(tolerance {1e-4 * chk.v_max:.3g} V); a fixed nominal limit would be off by "
          f"{miss:.3g} V")
    assert ref[150:300, 2].sum() > 20                 # the sagged bus limits
    assert (ref[:, 2] != out[:, 2]).sum() <= 3
    assert err <= 1e-4 * chk.v_max
    assert miss > 10.0
    st = out[:, 6].astype(int)
    assert list(np.flatnonzero(st)) == [200, 201] and not out[:, 3].any()


def test_runtime_bus_voltage_q31(tmp_path):
    """Q31: set_vdc_q31() takes the bus as Q31 of Q31_VDC_BASE, the word being
    the limit in Q31 of Q31_V_BASE. With the bus at 100 V (2/3 of nominal) the
    saturated Q31 output matches the reference law at 100 V within 1e-4 V_MAX
    (as test_fixed_point_saturation); a bus above nominal is clamped to
    Q31_V_MAX (the bases and state bounds are sized for it) and returns 1; a
    negative word returns -1."""
    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, A.DRIVE, fixed_point=True)
    h = write_header(art, A.MOTOR, A.DRIVE)
    P = chk.fixed
    import re
    vdc_base = float(re.search(r"#define CCT_Q31_VDC_BASE (\S+)f", h).group(1))
    assert vdc_base == pytest.approx(P.V_BASE * np.sqrt(3.0), rel=1e-6)
    drv = r"""
#include <stdio.h>
#include <stdint.h>
#include "controller.h"
int main(void)
{
    cct_state_q31_t s;
    cct_input_q31_t in;
    cct_output_q31_t out;
    long a, b, c, d, e, f;
    int st;
    cct_init_q31(&s);
    while (scanf("%ld %ld %ld %ld %ld %ld", &a, &b, &c, &d, &e, &f) == 6) {
        st = cct_set_vdc_q31(&s, (int32_t)f);
        in.i_d_ref = (int32_t)a; in.i_q_ref = (int32_t)b;
        in.i_d = (int32_t)c; in.i_q = (int32_t)d; in.omega_m = (int32_t)e;
        cct_step_q31(&s, &in, &out);
        printf("%ld %ld %d %d\n", (long)out.v_d, (long)out.v_q, out.saturated, st);
    }
    return 0;
}
"""
    res = C.compile_driver(h, tmp_path, fixed=True, source=drv)
    assert res.returncode == 0, res.stderr
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    n = len(inp)
    q = np.column_stack([C.to_q31(inp[:, :4], P.I_BASE), C.to_q31(inp[:, 4:], P.W_BASE)])
    wq = int(C.to_q31(np.array([100.0]), vdc_base)[0])
    wq_hi = int(C.to_q31(np.array([170.0]), vdc_base)[0])
    words = np.full(n, wq, dtype=np.int64)
    words[5] = wq_hi
    words[6] = -1
    text = "\n".join(" ".join(str(int(v)) for v in row)
                     for row in np.column_stack([q, words])) + "\n"
    out = subprocess.run([str(tmp_path / "drv_q31")], input=text, capture_output=True,
                         text=True, timeout=60, check=True).stdout
    arr = np.array([[int(x) for x in ln.split()] for ln in out.strip().splitlines()])
    assert arr[5, 3] == 1 and arr[6, 3] == -1 and not np.delete(arr[:, 3], [5, 6]).any()
    inq = np.column_stack([q[:, :4] * P.I_BASE / 2 ** 31, q[:, 4] * P.W_BASE / 2 ** 31])
    # the step clamps references and measurements to the ranges (status CLAMPED)
    inq = np.column_stack([np.clip(inq[:, :4], -P.I_MAX, P.I_MAX),
                           np.clip(inq[:, 4], -P.W_MAX, P.W_MAX)])
    ref = ReferenceLaw(art, chk.v_max)
    v_ref = []
    for kk, row in enumerate(inq):
        ref.v_max = chk.v_max if kk in (5, 6) else wq * P.V_BASE / 2 ** 31
        v_ref.append(ref.step(*row))
    v_ref = np.array(v_ref)
    v = arr[:, :2] * P.V_BASE / 2 ** 31
    err = np.abs(v - v_ref[:, :2]).max()
    print(f"\nQ31 run-time bus 100 V: {int(v_ref[:, 2].sum())} saturated, max|err| {err:.3g} V")
    assert v_ref[:, 2].sum() > 20
    assert err <= 1e-4 * chk.v_max
    assert np.hypot(*v[7:].T).max() <= 100.0 / np.sqrt(3) * (1 + 1e-6)


# ---------------------------------------------------------------- 4. delay compensation
def test_delay_compensation_applied(tmp_path):
    """The complex-vector PI assumes v_dq rotated by 1.5 Ts w_e before the
    inverse Park transform: v_d_comp + j v_q_comp = (v_d + j v_q) e^{j 1.5 Ts w_e},
    checked against that rotation done in double on the header's own v_dq.
    Tolerance 1e-6 |v| + 1e-6 V: float32 cosf/sinf and products (a few eps32
    relative) and the float32 angle (relative 2 eps32 of <= 0.18 rad). The
    angle reaches 0.18 rad at 300 rad/s, so an unrotated output misses by
    > 1e4 x the tolerance. Without compensation the outputs are equal."""
    art = A.pi_artifact()
    h = write_header(art, A.MOTOR, A.DRIVE)
    inp = C.test_inputs(i_step=8.0, speed=300.0)
    vdc = np.full(len(inp), 150.0)
    vdc[100] = np.nan                       # refused bus reading; the law still runs
    res = C.compile_driver(h, tmp_path, source=DRIVER_VDC)
    assert res.returncode == 0, res.stderr
    rows = np.column_stack([inp, vdc])
    rows[250, 0] = np.nan                   # a bad input: everything held
    out = _run(str(tmp_path / "drv"), rows)
    th = 1.5 * A.TS * A.MOTOR.pole_pairs * inp[:, 4]
    z = (out[:, 0] + 1j * out[:, 1]) * np.exp(1j * th)
    z[250] = z[249]                          # held: the previous period's rotated output
    err = np.abs(out[:, 4] + 1j * out[:, 5] - z)
    tol = 1e-6 * np.abs(z) + 1e-6
    unrot = np.abs(out[:, 4] + 1j * out[:, 5] - (out[:, 0] + 1j * out[:, 1]))
    print(f"\ndelay compensation: angle up to {th.max():.3f} rad, max|err| {err.max():.3g} V, "
          f"unrotated would miss by {unrot.max():.3g} V")
    assert out[250, 3] == 1 and out[249, 3] == 0
    assert np.all(err <= tol)
    assert unrot.max() > 1e4 * tol.max()
    art0 = replace(art, decoupling=replace(art.decoupling, delay_compensation_time=0.0))
    res = C.compile_driver(write_header(art0, A.MOTOR, A.DRIVE), tmp_path / "no", source=DRIVER_VDC)
    assert res.returncode == 0, res.stderr
    out0 = _run(str(tmp_path / "no" / "drv"), np.column_stack([inp, vdc]))
    assert np.array_equal(out0[:, 4:6], out0[:, :2])


# ---------------------------------------------------------------- 5. usage example
@pytest.mark.parametrize("prefix,drive", [("cct_", A.DRIVE), ("motor1_", HEX_DRIVE)])
def test_usage_example_compiles_and_runs(prefix, drive, tmp_path):
    """The example at the end of the header (init, set_vdc with the bus
    reading, per-period step, fault handling, v_d_comp/v_q_comp to the PWM)
    compiles as main.c with -Werror and runs (exit 0, no fault reported);
    it sits under #if 0 so the header itself is unchanged by it."""
    h = write_header(A.pi_artifact(), A.MOTOR, drive, prefix=prefix)
    src = example_source(h)
    p = prefix
    for needed in (f"{p}init(", f"{p}set_vdc(", f"{p}step(", "out.status", "v_d_comp"):
        assert needed in src
    exe = _build(tmp_path, {"controller.h": h, "main.c": src}, "example")
    res = subprocess.run([exe], capture_output=True, text=True, timeout=30)
    assert res.returncode == 0 and "status" not in res.stdout
    bare = write_header(A.pi_artifact(), A.MOTOR, drive, prefix=prefix, example=False)
    assert "EXAMPLE" not in bare and h.count("#if 0") == 1


# ---------------------------------------------------------------- CLI and spec
SPEC = ('[motor]\ncatalog = "azaiz2007"\n[drive]\nvdc = 150\nsample_time = 1e-4\n'
        'delay_samples = 1\n[controller]\nmethod = "pi"\n[controller.pi]\n')


def _design_dir(tmp_path, text: str):
    import toolbox
    spec_path = tmp_path / "s.toml"
    spec_path.write_text(text)
    art = toolbox.design_spec(toolbox.load_spec(spec_path))
    out = tmp_path / "d"
    out.mkdir()
    (out / "controller.json").write_text(art.dumps())
    return out


def test_cli_prefix_option_and_spec(tmp_path):
    """``cct export --prefix motor1_`` renames the header; without the option
    the spec's ``[export] prefix`` applies (default cct_); a bad prefix is bad
    input: exit 2, nothing written."""
    from click.testing import CliRunner
    from toolbox.cli import main

    def run(*args):
        return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)

    out = _design_dir(tmp_path, SPEC)
    res = run("export", out, "--prefix", "motor1_", "-o", out / "m1.h")
    assert res.exit_code == 0, res.output
    h = (out / "m1.h").read_text()
    assert "#ifndef MOTOR1_CONTROLLER_H" in h and "motor1_step(" in h
    assert run("export", out, "-o", out / "plain.h").exit_code == 0
    assert "#ifndef CCT_CONTROLLER_H" in (out / "plain.h").read_text()
    res = run("export", out, "--prefix", "9x", "-o", out / "bad.h")
    assert res.exit_code == 2 and "--prefix" in res.output and not (out / "bad.h").exists()
    (tmp_path / "b").mkdir()
    out2 = _design_dir(tmp_path / "b", SPEC + '[export]\nprefix = "axis2_"\n')
    assert run("export", out2, "-o", out2 / "a2.h").exit_code == 0
    assert "axis2_step(" in (out2 / "a2.h").read_text()


def test_q31_input_conversion_clamps_and_flags(tmp_path):
    """A 100 A input once overflowed a Q31 range sized to 2 x rated
    current. The Q31 variant's <p>to_q31() clamps to the stated range
    (Q31_I_MAX = motor.max_current = 20 A here) and flags it; in range it is
    exact to float32 (24-bit) rounding of the word: |word - exact| <= 2^31 x
    2^-23 (2 float32 ulps of the ratio)."""
    h = write_header(A.pi_artifact(), A.MOTOR, A.DRIVE)
    chk = check_exportable(A.pi_artifact(), A.MOTOR, A.DRIVE, fixed_point=True)
    src = ('#include <stdio.h>\n#include "controller.h"\nint main(void)\n{\n'
           '    const float x[4] = {100.0f, -100.0f, 12.5f, -3.0f};\n    int k;\n'
           '    for (k = 0; k < 4; ++k) {\n        int f = 0;\n'
           '        const int32_t w = cct_to_q31(x[k], CCT_Q31_I_MAX, CCT_Q31_I_BASE, &f);\n'
           '        printf("%ld %d\\n", (long)w, f);\n    }\n    return 0;\n}\n')
    exe = _build(tmp_path, {"controller.h": h, "m.c": src}, "q31conv", defines=["-DCCT_FIXED_POINT"])
    out = [ln.split() for ln in subprocess.run([exe], capture_output=True, text=True,
                                               timeout=30).stdout.split("\n") if ln]
    P = chk.fixed
    exact = [P.I_MAX, -P.I_MAX, 12.5, -3.0]
    for (w, f), x, flag in zip(out, exact, [1, 1, 0, 0]):
        assert int(f) == flag
        assert abs(int(w) - x / P.I_BASE * 2 ** 31) <= 2 ** 31 * 2 ** -23
