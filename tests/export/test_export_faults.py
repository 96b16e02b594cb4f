"""controller.h under hostile numbers: range-checked constants, NaN/inf recovery.

* Every constant the header emits is checked before the text exists: floats
  within float32 (no ``inff``, no ``nan``, no subnormal), integers within the
  C range they are used in. A value out of range is refused with
  :class:`toolbox.errors.ExportRefused` naming the spec key (vdc =
  1e39 once gave a header with ``inff`` that did not compile).
* The float step function rejects non-finite inputs, holds the last good
  output, leaves its state unchanged and reports ``out.status`` (1 bad input,
  2 non-finite result); valid samples afterwards continue as if the bad one
  had been skipped.
"""

from __future__ import annotations

import re
import subprocess
from dataclasses import replace

import numpy as np
import pytest

from toolbox.errors import ExportRefused
from toolbox.export import check_exportable, write_header
from toolbox.export.c_header import ReferenceLaw, reference_law

import export_artifacts as A
import export_c_helpers as C

DRIVER_STATUS = r"""
#include <stdio.h>
#include "controller.h"
int main(void)
{
    cct_state_t s;
    cct_input_t in;
    cct_output_t out;
    cct_init(&s);
    while (scanf("%f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q, &in.omega_m) == 5) {
        cct_step(&s, &in, &out);
        printf("%.9e %.9e %d %d\n", (double)out.v_d, (double)out.v_q, out.saturated, out.status);
    }
    return 0;
}
"""


def run_status(header: str, tmp, inputs: np.ndarray) -> np.ndarray:
    """Rows ``v_d v_q saturated status`` of the compiled header (gcc -Werror)."""
    res = C.compile_driver(header, tmp, source=DRIVER_STATUS)
    assert res.returncode == 0, res.stderr
    text = "\n".join(" ".join(repr(float(v)) if np.isfinite(v) else str(v) for v in row)
                     for row in inputs) + "\n"
    out = subprocess.run([str(tmp / "drv")], input=text, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    return np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])


# ------------------------------------------------------------------ ranges
BAD = [
    # (what is changed, value, spec key named, words in the message)
    ("drive.vdc", 1e39, "drive.vdc", "float32 range"),
    ("drive.vdc", 1e20, "drive.vdc", "square fits float32"),
    ("motor.R", 1e39, "motor.R", "float32 range"),
    ("motor.J", 1e-45, "motor.J", "normal float32"),
    ("motor.pole_pairs", 10 ** 6, "motor.pole_pairs", "integer in [1, 32767]"),
    ("drive.switching_frequency", 1e39, "drive.switching_frequency", "float32 range"),
]


def _with(change: str, value):
    motor, drive = A.MOTOR, A.DRIVE
    table, attr = change.split(".")
    if table == "motor":
        motor = replace(motor, **{attr: value})
    else:
        drive = replace(drive, **{attr: value})
    return motor, drive


@pytest.mark.parametrize("change,value,key,words", BAD)
def test_out_of_range_constant_is_refused(change, value, key, words):
    """Refused before any text exists, naming the key (and what was expected)."""
    motor, drive = _with(change, value)
    art = A.pi_artifact()
    if change == "motor.pole_pairs":
        art = replace(art, decoupling=replace(art.decoupling, pole_pairs=value))
    with pytest.raises(ExportRefused) as err:
        write_header(art, motor, drive)
    assert err.value.key == key and words in str(err.value)


def test_vdc_1e39_through_the_cli(tmp_path):
    """The vdc = 1e39 case end to end: cct design with vdc = 1e39 never leaves a
    header with inff behind. Either the design stage refuses it first or the
    export does; exit 2 and no controller.h in both cases."""
    from click.testing import CliRunner
    from toolbox.cli import main
    spec = tmp_path / "big.toml"
    spec.write_text('[motor]\ncatalog = "azaiz2007"\n[drive]\nvdc = 1e39\nsample_time = 1e-4\n'
                    '[controller]\nmethod = "pi"\n[controller.pi]\nbandwidth = 500\n')
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["design", str(spec), "--out", str(out), "-q"])
    print(res.output)
    assert res.exit_code == 2, res.output
    assert not (out / "controller.h").exists()


@pytest.mark.parametrize("scale", [1e-30, 1e30])
def test_extreme_but_representable_values_compile(scale, tmp_path):
    """Inertia and friction far from physical but within float32 are emitted
    (they are informative #defines) and the header compiles; no inf/nan token."""
    motor = replace(A.MOTOR, J=A.MOTOR.J * scale, friction=A.MOTOR.friction * scale)
    h = write_header(A.pi_artifact(), motor, A.DRIVE)
    code = "\n".join(ln for ln in h.splitlines() if not ln.lstrip().startswith(("*", "/*")))
    assert not re.search(r"\b(inff?|nanf?|INFINITY|NAN)\b", code)
    assert C.compile_driver(h, tmp_path).returncode == 0


def test_q31_constant_out_of_range_disables_only_q31(tmp_path):
    """A current range beyond float32 (motor.max_current = 1e39 A would make the
    Q31 base inff) cannot reach the float header either: MOTOR_MAX_CURRENT is
    refused naming motor.max_current."""
    motor = replace(A.MOTOR, max_current=1e39)
    with pytest.raises(ExportRefused) as err:
        write_header(A.pi_artifact(), motor, A.DRIVE)
    assert err.value.key == "motor.max_current"


# ------------------------------------------------------------------ NaN / inf
@pytest.mark.parametrize("name", ["pi", "ip_tc", "hinf"])
def test_nan_input_is_held_and_skipped(name, tmp_path):
    """A NaN measured current at k = 100 and an infinite speed at k = 150: the
    header reports status 1 there, repeats the previous output and keeps its
    state; every other sample equals the Python reference run on the sequence
    WITHOUT those two samples, within the worst-case float32 bound of
    export_c_helpers.float_bound. Nothing latches NaN."""
    art = {"pi": A.pi_artifact, "ip_tc": A.ip_tc_artifact, "hinf": A.hinf_artifact}[name]()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    h = write_header(art, A.MOTOR, A.DRIVE)
    clean = C.test_inputs()
    bad_rows = [100, 150]
    inp = np.insert(clean, [100, 149], clean[[99, 148]], axis=0)    # placeholders
    inp[100, 3] = np.nan
    inp[150, 4] = np.inf
    out = run_status(h, tmp_path, inp)
    assert np.all(np.isfinite(out[:, :2]))
    status = out[:, 3].astype(int)
    assert list(np.flatnonzero(status)) == bad_rows and np.all(status[bad_rows] == 1)
    for k in bad_rows:                                        # held output
        np.testing.assert_array_equal(out[k, :2], out[k - 1, :2])
    good = np.delete(out[:, :2], bad_rows, axis=0)
    v_ref, _ = reference_law(art, clean, chk.v_max)
    bound = C.float_bound(chk, art, clean)
    assert np.all(np.abs(good - v_ref) <= bound)
    # the Python reference law behaves the same way (held output, status 1)
    v_hold, _ = reference_law(art, inp, chk.v_max)
    np.testing.assert_array_equal(np.delete(v_hold, bad_rows, axis=0), v_ref)
    for k in bad_rows:
        np.testing.assert_array_equal(v_hold[k], v_hold[k - 1])


def test_overflow_reports_status_2_and_keeps_state(tmp_path):
    """A finite but absurd reference (3e38 A) overflows float32 inside the law:
    status 2, the last output held, the state untouched, so the following
    samples are bit-identical to a run in which that sample never happened
    (same binary, same operations: tolerance 0)."""
    art = A.pi_artifact()
    h = write_header(art, A.MOTOR, A.DRIVE)
    clean = C.test_inputs(n=200)
    inp = np.insert(clean, 80, clean[79], axis=0)
    inp[80, 1] = 3e38
    out = run_status(h, tmp_path, inp)
    ref = run_status(h, tmp_path / "ref", clean)
    assert out[80, 3] == 2 and np.count_nonzero(out[:, 3]) == 1
    np.testing.assert_array_equal(out[80, :2], out[79, :2])
    np.testing.assert_array_equal(np.delete(out, 80, axis=0), ref)


def test_reference_law_status():
    """ReferenceLaw reports status 1 on a non-finite input and 0 otherwise."""
    law = ReferenceLaw(A.pi_artifact(), 86.6)
    law.step(0.0, 1.0, 0.0, 0.5, 10.0)
    assert law.status == 0
    v = law.step(0.0, float("nan"), 0.0, 0.5, 10.0)
    assert law.status == 1 and np.isfinite(v[:2]).all()


def test_status_api_documented():
    """The header comment documents the status codes and the hold behaviour."""
    h = write_header(A.pi_artifact(), A.MOTOR, A.DRIVE)
    top = h[:h.index("*/")]
    for words in ("out->status", "CCT_STATUS_BAD_INPUT", "CCT_STATUS_BAD_STATE",
                  "last good output", "state"):
        assert words in top


@pytest.mark.parametrize("coefficient", [1e25, 1e39])
def test_cli_export_names_the_design_file(tmp_path, coefficient):
    """`cct export DIR` refusing a controller names DIR/controller.json, the key
    and what was expected; exit 2 and no header written.

    The spec bounds refuse an absurd drive (vdc <= 1e5 V) before any design, so
    the refusal is provoked by a tampered law: one reference-channel coefficient
    set to an absurd value. The loop stays stable (B_r is outside the loop), so
    it is the exportability check that refuses it; before the minimal
    realisation guarded SLICOT, these values aborted the process in TB01PD."""
    import json
    import toolbox
    from click.testing import CliRunner
    from toolbox.cli import main
    data = {"motor": {"catalog": "azaiz2007"}, "drive": {"vdc": 150, "sample_time": 1e-4},
            "controller": {"method": "pi", "pi": {"bandwidth": 500}}}
    stored = json.loads(toolbox.design_spec(toolbox.spec_from_dict(data)).dumps())
    stored["axes"]["q"]["law"]["B"][0][0] = coefficient
    out = tmp_path / "out"
    out.mkdir()
    (out / "controller.json").write_text(json.dumps(stored))
    res = CliRunner().invoke(main, ["export", str(out), "--format", "c"])
    assert res.exit_code == 2, res.output
    msg = res.output.strip().splitlines()[-1]
    assert msg.startswith(f"cct: error: {out / 'controller.json'}: controller.pi: expected ")
    assert "dynamic range" in msg
    assert not (out / "controller.h").exists()


def test_nan_detected_under_fast_math(tmp_path):
    """Firmware is often built with -ffast-math, under which gcc may fold
    isfinite() to 1; the header tests the IEEE bits instead, so a NaN input is
    still reported (status 1) and the output stays finite."""
    h = write_header(A.pi_artifact(), A.MOTOR, A.DRIVE)
    tmp_path.mkdir(exist_ok=True)
    (tmp_path / "controller.h").write_text(h)
    (tmp_path / "driver.c").write_text(DRIVER_STATUS)
    exe = tmp_path / "drv"
    cmd = [C.require_gcc(), *C.CFLAGS, "-ffast-math", "-I", str(tmp_path),
           str(tmp_path / "driver.c"), "-o", str(exe), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    out = subprocess.run([str(exe)], input="0 1 0 0.5 10\n0 nan 0 0.5 10\n0 1 0 0.5 10\n",
                         capture_output=True, text=True, timeout=60, check=True).stdout
    rows = np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])
    assert list(rows[:, 3]) == [0, 1, 0] and np.all(np.isfinite(rows[:, :2]))
    np.testing.assert_array_equal(rows[1, :2], rows[0, :2])
