"""Compile and run exported headers; error bounds of the executed arithmetic."""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

from toolbox.export import _fixed
from toolbox.export.c_header import AXES

GCC = shutil.which("gcc")
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wconversion", "-O2"]

DRIVER = r"""
#include <stdio.h>
#include <stdint.h>
#include "controller.h"
int main(void)
{
#ifdef CCT_FIXED_POINT
    cct_state_q31_t s;
    cct_input_q31_t in;
    cct_output_q31_t out;
    long a, b, c, d, e;
    cct_init_q31(&s);
    while (scanf("%ld %ld %ld %ld %ld", &a, &b, &c, &d, &e) == 5) {
        in.i_d_ref = (int32_t)a; in.i_q_ref = (int32_t)b;
        in.i_d = (int32_t)c; in.i_q = (int32_t)d; in.omega_m = (int32_t)e;
        cct_step_q31(&s, &in, &out);
        printf("%ld %ld %d\n", (long)out.v_d, (long)out.v_q, out.saturated);
    }
#else
    cct_state_t s;
    cct_input_t in = {0};
    cct_output_t out;
    cct_init(&s);
#ifdef CCT_HEX
    while (scanf("%f %f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q, &in.omega_m,
                 &in.theta_e) == 6) {
#else
    while (scanf("%f %f %f %f %f", &in.i_d_ref, &in.i_q_ref, &in.i_d, &in.i_q, &in.omega_m) == 5) {
#endif
        cct_step(&s, &in, &out);
        printf("%.9e %.9e %d\n", (double)out.v_d, (double)out.v_q, out.saturated);
    }
#endif
    return 0;
}
"""

SIL = r"""
#include "controller.h"
static cct_state_t st;
void sil_init(void);
void sil_step(const float *u, float *v);
void sil_init(void) { cct_init(&st); }
void sil_step(const float *u, float *v)
{
    cct_input_t in = {0};
    cct_output_t o;
    in.i_d_ref = u[0]; in.i_q_ref = u[1]; in.i_d = u[2]; in.i_q = u[3]; in.omega_m = u[4];
    cct_step(&st, &in, &o);
    v[0] = o.v_d; v[1] = o.v_q; v[2] = (float)o.saturated;
}
"""


def require_gcc() -> str:
    """gcc's path; fails (never skips) when it is missing: the export tests
    exist to compile the header, and CI installs gcc."""
    if GCC is None:
        import pytest
        pytest.fail("gcc not found on PATH: tests/export compile controller.h with gcc "
                    "(install it: apt-get install gcc; CI installs it)", pytrace=False)
    return GCC


#: Directory shared by the session's processes (all pytest-xdist workers of one
#: run) holding each clean gcc build once, keyed by its inputs; set by
#: tests/export/conftest.py, None (no sharing) outside a session.
BUILD_CACHE: Path | None = None


def _gcc(cmd: list[str], inputs: tuple[str, ...], out: Path) -> subprocess.CompletedProcess:
    """Run the gcc command ``cmd`` writing ``out``, once per session for equal inputs.

    The key is gcc's path, every argument that is not a path of the test's
    directory and the text of every compiled file (``inputs``): equal keys
    are the same translation unit with the same options, so the binary is
    the same and is copied (a copy, not a link: ctypes would share one
    loaded library, and its static state, between tests). Only a build with
    exit 0 and no diagnostics is shared; any other is run every time."""
    if BUILD_CACHE is None:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    flags = [a for a in cmd if not a.startswith(str(out.parent))]
    h = hashlib.sha256("\0".join(flags).encode())
    for text in inputs:
        h.update(b"\0" + hashlib.sha256(text.encode()).digest())
    cached = BUILD_CACHE / h.hexdigest()[:32]
    if cached.is_file():
        shutil.copyfile(cached, out)
        out.chmod(0o755)
        return subprocess.CompletedProcess(cmd, 0, "", "")
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    if res.returncode == 0 and not res.stdout and not res.stderr:
        BUILD_CACHE.mkdir(parents=True, exist_ok=True)
        part = cached.with_name(f"{cached.name}.{os.getpid()}")
        shutil.copyfile(out, part)
        os.replace(part, cached)            # atomic: another worker may write it too
    return res


def compile_driver(header: str, tmp: Path, fixed: bool = False, source: str = DRIVER,
                   hexagon: bool = False) -> subprocess.CompletedProcess:
    require_gcc()
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "controller.h").write_text(header)
    (tmp / "driver.c").write_text(source)
    exe = tmp / ("drv_q31" if fixed else "drv")
    cmd = [GCC, *CFLAGS, *(["-DCCT_FIXED_POINT"] if fixed else []),
           *(["-DCCT_HEX"] if hexagon else []), "-I", str(tmp),
           str(tmp / "driver.c"), "-o", str(exe), "-lm"]
    return _gcc(cmd, (header, source), exe)


def run_float(header: str, tmp: Path, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outputs and saturation flags of the float header; inputs (N, 5), or
    (N, 6) with theta_e for a hexagon header."""
    res = compile_driver(header, tmp, hexagon=inputs.shape[1] == 6)
    assert res.returncode == 0, res.stderr
    text = "\n".join(" ".join(f"{v:.9e}" for v in row) for row in inputs) + "\n"
    out = subprocess.run([str(tmp / "drv")], input=text, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    arr = np.array([[float(x) for x in ln.split()] for ln in out.strip().splitlines()])
    return arr[:, :2], arr[:, 2].astype(int)


def run_fixed(header: str, tmp: Path, q_inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    res = compile_driver(header, tmp, fixed=True)
    assert res.returncode == 0, res.stderr
    text = "\n".join(" ".join(str(int(v)) for v in row) for row in q_inputs) + "\n"
    out = subprocess.run([str(tmp / "drv_q31")], input=text, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    arr = np.array([[int(x) for x in ln.split()] for ln in out.strip().splitlines()])
    return arr[:, :2], arr[:, 2]


def build_sil(header: str, tmp: Path) -> ctypes.CDLL:
    require_gcc()
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "controller.h").write_text(header)
    (tmp / "sil.c").write_text(SIL)
    lib = tmp / "libsil.so"
    cmd = [GCC, *CFLAGS, "-shared", "-fPIC", "-I", str(tmp), str(tmp / "sil.c"), "-o",
           str(lib), "-lm"]
    res = _gcc(cmd, (header, SIL), lib)
    assert res.returncode == 0, res.stderr
    dll = ctypes.CDLL(str(lib))
    dll.sil_step.argtypes = [ctypes.POINTER(ctypes.c_float), ctypes.POINTER(ctypes.c_float)]
    dll.sil_step.restype = None
    return dll


def test_inputs(n: int = 400, seed: int = 1, i_step: float = 8.0, speed: float = 100.0,
                ) -> np.ndarray:
    """Reference steps, measured currents lagging them (1 ms) plus noise, a speed ramp.

    Rounded to float32 so that C and Python see identical numbers.
    """
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    idr = np.where(k >= 50, -0.3 * i_step, 0.0)
    iqr = np.where(k >= 20, i_step, 0.0) - np.where(k >= 250, 0.5 * i_step, 0.0)
    alpha = np.exp(-1e-4 / 1e-3)
    i_d = np.zeros(n)
    i_q = np.zeros(n)
    for j in range(1, n):
        i_d[j] = alpha * i_d[j - 1] + (1 - alpha) * idr[j - 1]
        i_q[j] = alpha * i_q[j - 1] + (1 - alpha) * iqr[j - 1]
    i_d += 0.05 * rng.standard_normal(n)
    i_q += 0.05 * rng.standard_normal(n)
    om = speed * k / n
    return np.column_stack([idr, iqr, i_d, i_q, om]).astype(np.float32).astype(float)


def _dec_terms(dec, inputs):
    w = dec.pole_pairs * inputs[:, 4]
    td = np.abs(dec.cross * w * dec.Lq_c * inputs[:, 3])
    tq = np.abs(dec.cross * w * dec.Ld_c * inputs[:, 2]) + np.abs(dec.emf * w * dec.flux_c)
    return {"d": td, "q": tq}


def realisation_trajectory(real, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """States (N, n) and outputs (N,) of a realisation in double (no saturation)."""
    n = real.order
    x = np.zeros(n)
    X = np.zeros((len(u), n))
    y = np.zeros(len(u))
    for k, uk in enumerate(u):
        X[k] = x
        y[k] = float((real.C @ x + real.D @ uk)[0])
        x = real.A @ x + real.B @ uk
    return X, y


def float_bound(check, artifact, inputs) -> np.ndarray:
    """(N, 2) worst-case |v_float32 - v_exact| (V) of the header's float path."""
    dec = _dec_terms(artifact.decoupling, inputs)
    out = []
    for j, ax in enumerate(AXES):
        real = check.realisations[ax]
        u = inputs[:, [j, 2 + j]]
        X, _ = realisation_trajectory(real, u)
        dx, dy = _fixed.float32_local_errors(real, X, u, dec[ax])
        out.append(_fixed.propagate_bound(real.A, real.C, dx, dy))
    return np.column_stack(out)


def to_q31(values: np.ndarray, base: float) -> np.ndarray:
    q = np.round(np.asarray(values) / base * 2.0 ** 31)
    return np.clip(q, -(2 ** 31 - 1), 2 ** 31 - 1).astype(np.int64)


def fixed_bound(check, artifact, inputs) -> np.ndarray:
    """(N, 2) worst-case |v_Q31 - v_exact| (V) of the fixed-point path."""
    plan = check.fixed
    lsb = 2.0 ** -31
    wn = np.abs(inputs[:, 4]) / plan.W_BASE
    idn = np.abs(inputs[:, 2]) / plan.I_BASE
    iqn = np.abs(inputs[:, 3]) / plan.I_BASE
    dec_err = {}
    for ax, terms in (("d", [("dd", wn * iqn)]), ("q", [("dq", wn * idn), ("de", wn)])):
        e = np.zeros(len(inputs))
        for name, prod in terms:
            m, F, val = plan.dec[name]
            e += abs(m / 2.0 ** F - val) * prod + abs(m / 2.0 ** F) * 0.5 * lsb + 0.5 * lsb
        dec_err[ax] = e
    out = []
    for j, ax in enumerate(AXES):
        real = check.realisations[ax]
        fa = plan.axes[ax]
        u = inputs[:, [j, 2 + j]]
        X, _ = realisation_trajectory(real, u)
        xn = X / fa.S[None, :] if fa.S.size else X
        un = u / plan.I_BASE
        dx, dy = _fixed.fixed_local_errors(fa, xn, un, dec_err[ax])
        out.append(plan.V_BASE * _fixed.propagate_bound(fa.Aq, fa.Cq, dx, dy))
    return np.column_stack(out)
