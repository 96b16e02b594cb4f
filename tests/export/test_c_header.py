"""Firmware export (toolbox/ARCHITECTURE.md "controller.h"): compile, run, compare.

Three controllers built directly (tests/export/export_artifacts.py): a PI per axis
(one-DOF: second-order sections), IP + total compensation with integrator
(two-input: state space; paper 000 eq 18-20 shape), and paper 003's q-axis
central H-infinity controller at gamma = 1 (eq 68, 4th order, Tustin).

Independent routes: the header is compiled with gcc (-std=c99 -Wall -Wextra
-Werror -pedantic -Wconversion) and run on the same inputs as the Python
reference :class:`toolbox.export.c_header.ReferenceLaw`, which executes the
artifact's own state-space law in double precision (the header executes a
different realisation: CMSIS df2T sections or a balanced state space).

Tolerances: a worst-case first-order rounding bound computed along the very
trajectory, in the realisation the header executes (float32: gamma = (chain
+ 2) 2**-24 per value, Higham eq 3.5; Q31: coefficient quantisation, input
quantisation and 1/2 LSB per stored result), propagated through exact powers
of the executed recursion (toolbox.export._fixed.propagate_bound). The test
fails if any sample exceeds it; the bound is itself required to be small
(< 1e-5 of the output range) so that it is not vacuous.

Run with ``-s`` to print the measured agreement.
"""

from __future__ import annotations

import ctypes
import re

import numpy as np
import pytest

from toolbox.errors import ExportRefused, SpecError
from toolbox.export import check_exportable, write_header
from toolbox.export.c_header import ReferenceLaw, reference_law, sanitise_comment

import export_artifacts as A
import export_c_helpers as C

# No skip when gcc is missing: every compile fails with a message saying so
# (export_c_helpers.require_gcc). CI installs gcc; a silent skip hid breakage.
CASES = {"pi": A.pi_artifact, "ip_tc": A.ip_tc_artifact, "hinf": A.hinf_artifact}
EXTRA = {"static": A.static_artifact, "odd_order": A.odd_order_artifact}


pytestmark = [pytest.mark.filterwarnings(
    "ignore:axes .* not strictly stable:RuntimeWarning")]   # H-infinity: see test_hinf_marginal_antiwindup_flagged


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    art = CASES[request.param]()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    return request.param, art, chk, write_header(art, A.MOTOR, A.DRIVE)


# ---------------------------------------------------------------- structure
def test_header_structure(case):
    """Include guard, provenance, CMSIS sign note, step function, no malloc."""
    name, art, chk, h = case
    assert h.startswith("/*")
    assert "#ifndef CCT_CONTROLLER_H" in h and h.rstrip().endswith("#endif /* CCT_CONTROLLER_H */")
    for item in ("method:      " + art.method, "spec sha256: " + "0" * 64,
                 "created:     2026-01-01T00:00:00+00:00", "version:     test"):
        assert item in h
    assert "static inline void cct_step(cct_state_t *s, const cct_input_t *in, cct_output_t *out)" in h
    assert "NEGATED" in h and "arm_biquad_cascade_df2T_f32" in h
    assert "DELAY_SAMPLES periods later" in h
    assert not re.search(r"\b(malloc|calloc|free|double)\b", h)
    # sinf/cosf only for the delay compensation's rotation (the PI case: 1.5 Ts)
    trig = {"sinf", "cosf"} if art.decoupling.delay_compensation_time > 0 else set()
    assert set(re.findall(r"\b(sqrtf|sinf|cosf|expf|logf|powf|fabsf)\b", h)) == {"sqrtf"} | trig
    assert "#define CCT_V_MAX 8.66025" in h               # 150 / sqrt(3), amplitude convention
    assert "#define CCT_MOTOR_LQ 2.79999" in h and "/* q-axis inductance, H */" in h
    forms = {ax: chk.realisations[ax].form for ax in "dq"}
    assert forms == ({"d": "ss", "q": "ss"} if name == "ip_tc" else {"d": "sos", "q": "sos"})


def _comment_gain(h: str, ax: str, label: str) -> float:
    block = re.search(rf"/\* {ax} axis PI gains .*?\*/", h, re.S).group(0)
    return float(re.search(rf"\* +{re.escape(label)} = (\S+)", block).group(1))


def test_pi_gains_and_delay_compensation():
    """PI gains in parallel (V/A, V/(A s)), per-sample and series forms, derived
    from the executed law (informational design parameters are not read: the
    header is the same without them), exact within printing (9 digits: 1e-6);
    the delay compensation from the typed decoupling.delay_compensation_time.
    Gains honesty (toolbox/ARCHITECTURE.md "controller.h"): the law runs from
    its coefficients, so the gains
    are printed in a comment marked FOR INFORMATION ONLY, never as macros a
    reader could edit to no effect."""
    art = A.pi_artifact()
    h = write_header(art, A.MOTOR, A.DRIVE)
    kp, ki = A.pi_gains()["q"]
    assert _comment_gain(h, "q", "Kp") == pytest.approx(kp, rel=1e-6)
    assert _comment_gain(h, "q", "Ki") == pytest.approx(ki, rel=1e-6)
    assert _comment_gain(h, "q", "Ki Ts") == pytest.approx(ki * A.TS, rel=1e-6)
    assert _comment_gain(h, "q", "Ti") == pytest.approx(kp / ki, rel=1e-6)
    assert "FOR INFORMATION ONLY" in h
    assert not re.search(r"#define CCT_[DQ]_(KP|KI|KI_TS|TI)\b", h)
    # the MCSDK/IQmath gain macros are honest: the integer laws read every one
    for m in re.findall(r"#define (CCT_(?:MCSDK|IQ)_[DQ]_K\w+)", h):
        assert h.count(m) >= 2, m
    assert not re.search(r"#define CCT_Q31_[DQ]_(KP|KI_TS)_(GAIN|DIV_LOG2)\b", h)
    val = lambda m: float(re.search(rf"#define {m} (\S+)f", h).group(1))
    assert val("CCT_DELAY_COMP_TIME") == pytest.approx(1.5 * A.TS, rel=1e-6)
    from dataclasses import replace
    # wrong informational numbers change nothing: the law is the source
    bogus = {"Kp": {"d": 1.0, "q": 1.0}, "Ki": {"d": 1.0, "q": 1.0},
             "delay_compensation_time": 9.0}
    h1 = write_header(replace(art, design_parameters=bogus), A.MOTOR, A.DRIVE)
    assert h1 == h
    no_comp = replace(art, decoupling=replace(art.decoupling, delay_compensation_time=0.0))
    h2 = write_header(no_comp, A.MOTOR, A.DRIVE)
    assert _comment_gain(h2, "q", "Kp") == pytest.approx(kp, rel=1e-6)
    # angle_compensation = "none": the macro says 0 and nothing rotates
    assert float(re.search(r"#define CCT_DELAY_COMP_TIME (\S+)f", h2).group(1)) == 0.0
    assert "cosf" not in h2 and 'angle_compensation = "none"' in h2
    h3 = write_header(replace(art, decoupling=replace(art.decoupling,
                                                      delay_compensation_time=2e-4)),
                      A.MOTOR, A.DRIVE)
    assert float(re.search(r"#define CCT_DELAY_COMP_TIME (\S+)f", h3).group(1)) == \
        pytest.approx(2e-4, rel=1e-6)
    assert re.search(r"\* +Kp = \d+L / 2\^\d+ ", h)        # MCSDK-style integer gains, informational


def test_sos_realisation_is_the_law(case):
    """The exported realisation has the artifact law's transfer function
    (frequency response on 200 points to Nyquist, relative 1e-9: double rounding
    of the zpk -> sos conversion, amplified by the near-cancelled pair of eq 68)."""
    _, art, chk, _ = case
    for ax in "dq":
        law, real = art.axes[ax].law, chk.realisations[ax]
        for z in np.exp(1j * np.linspace(1e-3, np.pi, 200)):
            for j in range(2):
                def H(Am, Bm, Cm, Dm):
                    n = Am.shape[0]
                    return (Cm @ np.linalg.solve(z * np.eye(n) - Am, Bm[:, j]) + Dm[0, j])[0]
                ref = H(law.A, law.B, law.C, law.D)
                assert abs(H(real.A, real.B, real.C, real.D) - ref) <= 1e-9 * abs(ref) + 1e-12


# ---------------------------------------------------------------- float agreement
def test_float_matches_python_reference(case, tmp_path):
    """float32 header vs double reference on 400 samples (steps, noisy measured
    currents, speed ramp to 100 rad/s: all decoupling terms active, no saturation).
    Every sample within the worst-case float32 bound."""
    name, art, chk, h = case
    inp = C.test_inputs()
    v_ref, s_ref = reference_law(art, inp, chk.v_max)
    v_c, s_c = C.run_float(h, tmp_path, inp)
    bound = C.float_bound(chk, art, inp)
    err = np.abs(v_c - v_ref)
    scale = np.abs(v_ref).max()
    print(f"\n{name} float32: max|err| = {err.max():.3g} V ({err.max() / scale:.2e} of "
          f"max|v| = {scale:.3g} V); bound max {bound.max():.3g} V; worst err/bound "
          f"{(err / bound).max():.3f}")
    assert not s_ref.any() and not s_c.any()
    assert np.all(err <= bound)
    assert bound.max() < 1e-5 * scale * 100          # bound not vacuous: < 1e-3 relative
    assert err.max() < 1e-6 * scale * 10             # and the measured error ~ eps32 level


def test_float_saturation_and_antiwindup(case, tmp_path):
    """(H-infinity: see test_hinf_marginal_antiwindup_flagged.) Large steps at 300 rad/s drive the voltage into the circle limit: the
    saturation flags agree sample by sample (except within float32 rounding of
    the circle test, |mag - V_MAX| < 1e-4 V) and voltages agree within 1e-4
    relative (back-calculation active; the linear bound does not apply here:
    the tolerance is 100 x the unsaturated agreement)."""
    name, art, chk, h = case
    # the CASES use strictly stable anti-windup recursions (the marginal one is
    # test_hinf_marginal_antiwindup_flagged's): float32 and double then agree
    assert not chk.marginal_antiwindup
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    v_ref, s_ref = reference_law(art, inp, chk.v_max)
    v_c, s_c = C.run_float(h, tmp_path, inp)
    assert s_ref.sum() > 20
    mag = np.hypot(*v_ref.T)
    differ = s_ref != s_c
    assert np.all(np.abs(mag[differ] - chk.v_max) < 1e-4)
    err = np.abs(v_c - v_ref).max()
    print(f"\n{name} saturated: {s_ref.sum()} saturated samples, max|err| = {err:.3g} V")
    assert err <= 1e-4 * chk.v_max


@pytest.mark.parametrize("name", list(EXTRA))
def test_edge_orders(name, tmp_path):
    """Order-0 laws (static 1-DOF gain; total compensation eq 11 without integrator)
    and an odd-order 1-DOF law (a first-order CMSIS stage, s2 stays 0): float and
    Q31 paths compile and agree within their bounds."""
    art = EXTRA[name]()
    chk = check_exportable(art, A.MOTOR, A.DRIVE, fixed_point=True)
    h = write_header(art, A.MOTOR, A.DRIVE)
    inp = C.test_inputs(i_step=4.0)
    v_ref, _ = reference_law(art, inp, chk.v_max)
    v_c, _ = C.run_float(h, tmp_path, inp)
    assert np.all(np.abs(v_c - v_ref) <= C.float_bound(chk, art, inp))
    P = chk.fixed
    q = np.column_stack([C.to_q31(inp[:, :4], P.I_BASE), C.to_q31(inp[:, 4:], P.W_BASE)])
    inq = np.column_stack([q[:, :4] * P.I_BASE / 2 ** 31, q[:, 4] * P.W_BASE / 2 ** 31])
    v_ref, _ = reference_law(art, inq, chk.v_max)
    vq, _ = C.run_fixed(h, tmp_path, q)
    assert np.all(np.abs(vq * P.V_BASE / 2 ** 31 - v_ref) <= C.fixed_bound(chk, art, inq))
    if name == "odd_order":
        assert {r.form for r in chk.realisations.values()} == {"sos"}
        assert chk.realisations["d"].sos.shape[0] == 2       # order 3: 2nd + 1st order stage


# ---------------------------------------------------------------- fixed point
@pytest.mark.parametrize("maker", [A.pi_artifact, A.ip_tc_artifact])
def test_fixed_point_matches_within_quantisation_bound(maker, tmp_path):
    """Q31 header (-DCCT_FIXED_POINT) vs the double reference fed the same
    (dequantised) inputs: every sample within the derived quantisation bound."""
    art = maker()
    chk = check_exportable(art, A.MOTOR, A.DRIVE, fixed_point=True)
    h = write_header(art, A.MOTOR, A.DRIVE)
    P = chk.fixed
    inp = C.test_inputs()
    q = np.column_stack([C.to_q31(inp[:, :4], P.I_BASE), C.to_q31(inp[:, 4:], P.W_BASE)])
    inq = np.column_stack([q[:, :4] * P.I_BASE / 2 ** 31, q[:, 4] * P.W_BASE / 2 ** 31])
    v_ref, _ = reference_law(art, inq, chk.v_max)
    vq, sq = C.run_fixed(h, tmp_path, q)
    v = vq * P.V_BASE / 2 ** 31
    bound = C.fixed_bound(chk, art, inq)
    err = np.abs(v - v_ref)
    print(f"\n{art.method} Q31: bases I {P.I_BASE} A, V {P.V_BASE} V, W {P.W_BASE} rad/s; "
          f"max|err| = {err.max():.3g} V, bound {bound.max():.3g} V, worst err/bound "
          f"{(err / bound).max():.3f}; pole shift/tol {chk.fixed_pole_shift}")
    assert not sq.any()
    assert np.all(err <= bound)
    assert bound.max() < 1e-4 * P.V_MAX * 10
    # Q31 scaling was derived from the stated ranges: I_MAX = motor.max_current
    assert P.I_MAX == A.MOTOR.max_current and P.I_BASE >= P.I_MAX


def test_fixed_point_saturation(tmp_path):
    """Q31 path with the voltage limit active: flags agree except at the circle
    boundary and voltages within 1e-4 relative."""
    art = A.pi_artifact()
    chk = check_exportable(art, A.MOTOR, A.DRIVE, fixed_point=True)
    h = write_header(art, A.MOTOR, A.DRIVE)
    P = chk.fixed
    inp = C.test_inputs(i_step=20.0, speed=300.0, seed=2)
    q = np.column_stack([C.to_q31(inp[:, :4], P.I_BASE), C.to_q31(inp[:, 4:], P.W_BASE)])
    inq = np.column_stack([q[:, :4] * P.I_BASE / 2 ** 31, q[:, 4] * P.W_BASE / 2 ** 31])
    # the step clamps references and measurements to the ranges (status CLAMPED)
    inq = np.column_stack([np.clip(inq[:, :4], -P.I_MAX, P.I_MAX),
                           np.clip(inq[:, 4], -P.W_MAX, P.W_MAX)])
    v_ref, s_ref = reference_law(art, inq, chk.v_max)
    vq, sq = C.run_fixed(h, tmp_path, q)
    v = vq * P.V_BASE / 2 ** 31
    assert s_ref.sum() > 20
    differ = s_ref != sq
    assert np.all(np.abs(np.hypot(*v_ref.T)[differ] - chk.v_max) < 1e-4)
    assert np.abs(v - v_ref).max() <= 1e-4 * chk.v_max


def test_hinf_marginal_antiwindup_flagged():
    """Paper 003's controller under Tustin with the plain vector B/D: the
    saturated recursion A - B C / D has the controller's zeros as poles, one at
    z = -1 (strictly proper K): marginal, so float32 and double trajectories
    need not agree while saturated. The export warns and says so in the header.
    The artifact's default vector (deadbeat on that mode) is strictly stable;
    PI and IP/TC laws have radius < 1 (0.958 / 0.979 for the PI)."""
    with pytest.warns(RuntimeWarning, match="not strictly stable"):
        chk = check_exportable(A.hinf_marginal_artifact(), A.MOTOR, A.DRIVE)
    assert chk.saturated_radius["q"] == pytest.approx(1.0, abs=1e-6)
    with pytest.warns(RuntimeWarning):
        h = write_header(A.hinf_marginal_artifact(), A.MOTOR, A.DRIVE)
    assert "WARNING (q axis)" in h
    default = check_exportable(A.hinf_artifact(), A.MOTOR, A.DRIVE)
    assert max(default.saturated_radius.values()) < 0.99 and not default.marginal_antiwindup
    pi = check_exportable(A.pi_artifact(), A.MOTOR, A.DRIVE)
    assert max(pi.saturated_radius.values()) < 0.99 and not pi.marginal_antiwindup


def test_hinf_fixed_point_refused_with_reason(tmp_path):
    """With the plain vector B/D, paper 003's Tustin H-infinity controller has a
    zero at z = -1 (strictly proper K), so the back-calculation recursion
    A - aw C is marginal and no state bound exists: the Q31 variant is refused,
    the header says why under #error, and compiling it with CCT_FIXED_POINT
    fails while the float path compiles."""
    art = A.hinf_marginal_artifact()
    with pytest.raises(ExportRefused, match="export.fixed_point"):
        check_exportable(art, A.MOTOR, A.DRIVE, fixed_point=True)
    with pytest.warns(RuntimeWarning):
        h = write_header(art, A.MOTOR, A.DRIVE)
    assert "#error \"fixed-point variant not available" in h
    res = C.compile_driver(h, tmp_path, fixed=True)
    assert res.returncode != 0 and "fixed-point variant not available" in res.stderr


# ---------------------------------------------------------------- software in the loop
def _closed_loop(step_fn, n=200, iq_ref=10.0, id_ref=0.0, speed=100.0):
    """20 ms at the controller rate: ZOH-exact 1/(R + sL) per axis, one-period
    computation delay, cross-coupling and back-EMF as voltages held over the period."""
    M = A.MOTOR
    ts = A.TS
    ad, aq = np.exp(-M.R * ts / M.Ld), np.exp(-M.R * ts / M.Lq)
    bd, bq = (1 - ad) / M.R, (1 - aq) / M.R
    w = M.pole_pairs * speed
    i = np.zeros(2)
    v_applied = np.zeros(2)
    out = np.zeros((n, 2))
    for k in range(n):
        out[k] = i
        vd, vq, _ = step_fn(id_ref, iq_ref if k >= 10 else 0.0, i[0], i[1], speed)
        ed = v_applied[0] + w * M.Lq * i[1]
        eq = v_applied[1] - w * M.Ld * i[0] - w * M.flux
        i = np.array([ad * i[0] + bd * ed, aq * i[1] + bq * eq])
        v_applied = np.array([vd, vq])
    return out


def _metrics(iq, ref=10.0, start=10):
    t5 = np.flatnonzero(np.abs(iq[start:] - ref) > 0.05 * ref)
    t_resp = (t5[-1] + 1) * A.TS if t5.size else 0.0
    return t_resp, abs(ref - iq[-20:].mean())


@pytest.mark.parametrize("name", list(CASES))
def test_software_in_the_loop(name, tmp_path):
    """The header as a shared library (ctypes) controls the discrete plant;
    its 5 % response time and static error equal those of the Python controller
    (response time to the sample, static error and trajectory within 1e-4 A:
    float32 rounding, ~1e-6 relative, stays bounded in a stable loop)."""
    art = CASES[name]()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    dll = C.build_sil(write_header(art, A.MOTOR, A.DRIVE), tmp_path)
    dll.sil_init()
    u = (ctypes.c_float * 5)()
    v = (ctypes.c_float * 3)()

    def c_step(*args):
        u[:] = [float(a) for a in args]
        dll.sil_step(u, v)
        return v[0], v[1], int(v[2])

    ref = ReferenceLaw(art, chk.v_max)
    tr_c = _closed_loop(c_step)
    tr_p = _closed_loop(ref.step)
    m_c, m_p = _metrics(tr_c[:, 1]), _metrics(tr_p[:, 1])
    print(f"\n{name} SIL: C t5% = {m_c[0] * 1e3:.2f} ms, e_ss = {m_c[1]:.3g} A | "
          f"Python t5% = {m_p[0] * 1e3:.2f} ms, e_ss = {m_p[1]:.3g} A | "
          f"max|di| = {np.abs(tr_c - tr_p).max():.3g} A")
    assert m_c[0] == pytest.approx(m_p[0], abs=A.TS * 1.01)
    assert m_c[1] == pytest.approx(m_p[1], abs=1e-4)
    assert np.abs(tr_c - tr_p).max() < 1e-4
    assert 0 < m_p[0] < 0.02                    # the loop really tracks the step


# ---------------------------------------------------------------- hostile strings
HOSTILE = '*/ #error x /* <script>"; rm -rf / \n ??= ??/ \u00e9\u4e2d \\'


def test_sanitise_comment():
    s = sanitise_comment(HOSTILE)
    assert "*/" not in s and "/*" not in s and "??" not in s and "\n" not in s
    assert all(32 <= ord(ch) < 127 for ch in s)
    assert "\\u00e9" in s or "\\xe9" in s


def test_hostile_title_compiles(tmp_path):
    """A title that tries to close the comment, inject a directive, splice
    lines, use trigraphs and non-ASCII still yields a header that compiles with
    -Werror and keeps one comment line."""
    art = A.pi_artifact(title=HOSTILE)
    h = write_header(art, A.MOTOR, A.DRIVE)
    title_line = [ln for ln in h.splitlines() if ln.startswith(" * title:")]
    assert len(title_line) == 1 and "rm -rf" in title_line[0]
    first_close = h.index("*/")
    assert h[:first_close].count("/*") == 1            # the comment closes only where we close it
    assert not any(ln.lstrip().startswith("#error") for ln in h.splitlines())
    assert not any(ln.endswith("\\") for ln in h.splitlines())     # no line splice
    res = C.compile_driver(h, tmp_path)
    assert res.returncode == 0, res.stderr
    res = C.compile_driver(h, tmp_path, fixed=True)
    assert res.returncode == 0, res.stderr
    h2 = write_header(art, A.MOTOR, A.DRIVE, title="x ??/\nint y;")
    assert "??" not in h2
    with pytest.raises(SpecError, match="export.name"):
        write_header(art, A.MOTOR, A.DRIVE, name="cct; int x")


def test_custom_prefix_compiles(tmp_path):
    """name= renames every identifier (two controllers can live in one program)."""
    h = write_header(A.ip_tc_artifact(), A.MOTOR, A.DRIVE, name="motor2")
    assert "motor2_step(" in h and "MOTOR2_V_MAX" in h and "cct_step" not in h
    src = '#include "controller.h"\nint main(void) { motor2_state_t s; motor2_input_t i = {0}; ' \
          'motor2_output_t o; motor2_init(&s); motor2_step(&s, &i, &o); return o.saturated; }\n'
    res = C.compile_driver(h, tmp_path, source=src)
    assert res.returncode == 0, res.stderr


# ---------------------------------------------------------------- refusals
def test_refuses_unstable_law():
    """A pole at z = 1.005 (continuous +50 rad/s) is refused, naming the key."""
    with pytest.raises(ExportRefused) as err:
        write_header(A.unstable_artifact(), A.MOTOR, A.DRIVE)
    assert err.value.key == "controller.pi" and "d-axis" in str(err.value)
    assert "stable discrete d-axis law" in str(err.value) and "1.005" in str(err.value)


def test_refuses_uncancelled_nyquist_pole():
    """A pole at 5e6 rad/s (Tustin z = -0.992) with no cancelling zero is refused;
    paper 003's pole at 2.717e6 (z = -0.98539) next to its zero at 2.714e6 passes."""
    with pytest.raises(ExportRefused, match="near z = -1"):
        check_exportable(A.ringing_artifact(), A.MOTOR, A.DRIVE)
    check_exportable(A.hinf_artifact(), A.MOTOR, A.DRIVE)


def test_refuses_rounding_sensitive_law():
    """Two poles 1e-8 apart near z = 1: float32 rounding of the section's a2
    (ulp 6e-8) splits them by ~2e-4, far beyond the stated tolerance."""
    import control as ct
    from toolbox.artifact import AxisController
    p1, p2 = 0.9999, 0.9999 - 1e-8
    K = ct.ss(ct.tf(0.01 * np.poly([0.5, 0.6]), np.poly([p1, p2]), A.TS))
    law = ct.ss(K.A, np.hstack([K.B, -K.B]), K.C, np.hstack([K.D, -K.D]), A.TS)
    ax = AxisController.from_law(law, sample_time=A.TS, method="native")
    art = A._artifact("hinf", {"d": ax, "q": ax})
    with pytest.raises(ExportRefused, match="float32 coefficient rounding"):
        check_exportable(art, A.MOTOR, A.DRIVE)


def test_refuses_without_voltage_limit():
    with pytest.raises(ExportRefused, match="drive"):
        check_exportable(A.pi_artifact(), None, None)


def test_deterministic_text():
    """Same artifact -> same bytes (the timestamp comes from the provenance)."""
    assert write_header(A.hinf_artifact(), A.MOTOR, A.DRIVE) == \
        write_header(A.hinf_artifact(), A.MOTOR, A.DRIVE)


def test_q31_quantisation_refusal():
    """The Q31 pole check refuses the same near-double pole (split ~4e-5 by Q31
    rounding of a2, tolerance 2e-6), and accepts the PI (shift 0: integrator and
    its zero are exact in Q31)."""
    import control as ct
    from toolbox.artifact import AxisController
    from toolbox.export import _fixed
    from toolbox.export._sos import realise_axis
    from toolbox.export.c_header import check_fixed
    p1, p2 = 0.9999, 0.9999 - 1e-8
    K = ct.ss(ct.tf(0.01 * np.poly([0.5, 0.6]), np.poly([p1, p2]), A.TS))
    law = ct.ss(K.A, np.hstack([K.B, -K.B]), K.C, np.hstack([K.D, -K.D]), A.TS)
    ax = AxisController.from_law(law, sample_time=A.TS, method="native")
    real = realise_axis(ax.law.A, ax.law.B, ax.law.C, ax.law.D, ax.antiwindup.ravel())
    plan, why = _fixed.plan_fixed({"d": real, "q": real}, I_MAX=20.0, W_MAX=400.0,
                                  V_MAX=86.6, dec_coeffs={"dd": -0.01, "dq": 0.01, "de": 0.5})
    assert plan is not None, why
    with pytest.raises(ExportRefused, match="Q31 coefficient rounding"):
        check_fixed(plan, A.TS)
    chk = check_exportable(A.pi_artifact(), A.MOTOR, A.DRIVE)
    assert max(chk.fixed_pole_shift.values()) <= 1.0
    assert 0 < max(chk.fixed_error_bound.values()) < 1e-3    # reported bound, V over 20 ms


def test_motor_and_drive_from_artifact_spec(tmp_path):
    """Without motor=/drive=, the constants come from the artifact's spec (paper
    003's design file: vdc 150 V -> V_MAX = 150/sqrt(3) V, Lq = 2.8 mH)."""
    import tomllib
    from dataclasses import replace
    from pathlib import Path
    path = Path(__file__).parents[2] / "designs" / "003_azaiz2007_hinf.toml"
    raw = tomllib.loads(path.read_text())
    art = replace(A.pi_artifact(), spec=raw)
    h = write_header(art)
    vdc = raw["drive"]["vdc"]
    assert float(re.search(r"#define CCT_V_MAX (\S+)f", h).group(1)) == \
        pytest.approx(vdc / np.sqrt(3), rel=1e-6)
    assert "#define CCT_MOTOR_LQ" in h and "#define CCT_DRIVE_VDC" in h
    assert C.compile_driver(h, tmp_path).returncode == 0


@pytest.mark.parametrize("design", ["000_lepioufle1992_tci", "001_takami2004_pi_lag",
                                    "002_cormerais2002_svm_pi"])
def test_reference_designs_export(design, tmp_path):
    """Headers of the reference designs (made by the design modules through the
    pipeline) compile and agree with the Python reference within the float32
    bound."""
    from pathlib import Path
    from toolbox.pipeline import design_spec
    from toolbox.spec import load_spec
    path = Path(__file__).parents[2] / "designs" / f"{design}.toml"
    spec = load_spec(path)
    art = design_spec(spec)
    chk = check_exportable(art, spec.motor, spec.drive)
    h = write_header(art, spec.motor, spec.drive)
    inp = C.test_inputs(i_step=2.0, speed=20.0)
    if chk.limit == "hexagon":               # 002: the SVM hexagon; the header takes theta_e
        theta = np.cumsum(spec.motor.pole_pairs * inp[:, 4] * spec.drive.sample_time)
        inp = np.column_stack([inp, theta]).astype(np.float32).astype(float)
    v_ref, s_ref = reference_law(art, inp, chk.v_max, chk.limit)
    assert not s_ref.any()
    v_c, _ = C.run_float(h, tmp_path, inp)
    err = np.abs(v_c - v_ref)
    bound = C.float_bound(chk, art, inp)
    print(f"\n{design}: max|err| {err.max():.3g} V, bound {bound.max():.3g} V")
    assert np.all(err <= bound)


@pytest.mark.parametrize("name", ["pi", "ip_tc"])
def test_software_in_the_loop_saturated(name, tmp_path):
    """Closed loop into the voltage limit (i_q 20 A, i_d -10 A steps at 150 rad/s:
    back-EMF 72 V plus the L di/dt demand exceed the 86.6 V circle): the C and
    Python controllers saturate on the same number of periods (+-1 at the
    boundary) and the current trajectories agree within 1e-4 A, as unsaturated
    (the anti-windup recursion A - aw C contracts: radius < 0.98)."""
    art = CASES[name]()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    dll = C.build_sil(write_header(art, A.MOTOR, A.DRIVE), tmp_path)
    dll.sil_init()
    u = (ctypes.c_float * 5)()
    v = (ctypes.c_float * 3)()
    flags = {"c": [], "p": []}

    def c_step(*args):
        u[:] = [float(a) for a in args]
        dll.sil_step(u, v)
        flags["c"].append(int(v[2]))
        return v[0], v[1], int(v[2])

    ref = ReferenceLaw(art, chk.v_max)

    def p_step(*args):
        out = ref.step(*args)
        flags["p"].append(out[2])
        return out

    tr_c = _closed_loop(c_step, iq_ref=20.0, id_ref=-10.0, speed=150.0)
    tr_p = _closed_loop(p_step, iq_ref=20.0, id_ref=-10.0, speed=150.0)
    fc, fp = np.array(flags["c"]), np.array(flags["p"])
    print(f"\n{name} SIL saturated: {fp.sum()} saturated periods (C {fc.sum()}), "
          f"max|di| = {np.abs(tr_c - tr_p).max():.3g} A")
    assert fp.sum() >= 5
    assert abs(int(fc.sum()) - int(fp.sum())) <= 1
    assert np.abs(tr_c - tr_p).max() < 1e-4
