"""The header's second-order sections run by the real CMSIS-DSP (toolbox/ARCHITECTURE.md
"controller.h").

The coefficients are read back from the controller.h TEXT (the
``static const float c[]`` of each one-degree-of-freedom axis and its
``<P>_<AX>_GAIN``) and run through CMSIS-DSP's own
``arm_biquad_cascade_df2T_f32`` (the ``cmsisdsp`` package: ARM's C sources
compiled for the host, a test dependency). The result, times the gain, is
compared with the Python law in double precision
(:class:`toolbox.export.c_header.ReferenceLaw` at zero speed, small steps:
no decoupling term and no saturation, so the output is the linear law
``K(z) (i_ref - i_meas)`` of the artifact's own state space, an independent
realisation).

Tolerances:

* CMSIS vs Python law: the worst-case float32 bound of the executed
  realisation along the very trajectory (tests/export/export_c_helpers.float_bound,
  the bound tests/export/test_c_header.py uses for the compiled header);
  additionally the measured error must stay below 1e-5 of the largest output
  (it is ~1e-7: float32 rounding).
* CMSIS vs the compiled header: the same df2T recursion in float32 but
  summed in another order (CMSIS: ``s1 = (b1 x + s2) + a1 y``; the header:
  ``s1 = (b1 x + a1 y) + s2``), so the rounding differs and accumulates
  through the integrator (measured 2 to 13 ulps of the output's scale).
  Both have the same number of roundings per value, so each lies within the
  float32 bound of the exact law and they differ by at most twice it.
A sign error in a1/a2 (the CMSIS negation), a swapped stage or a missing
gain fails both by orders of magnitude: checked below by negating a1.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from toolbox.export import check_exportable, write_header
from toolbox.export.c_header import reference_law

import export_artifacts as A
import export_c_helpers as C

try:
    import cmsisdsp as dsp
except ImportError:          # fail, never skip: it is a declared test dependency
    dsp = None

CASES = {"pi": A.pi_artifact, "hinf": A.hinf_artifact, "odd_order": A.odd_order_artifact}


def header_sos(h: str, ax: str, prefix: str = "CCT_") -> tuple[np.ndarray, float]:
    """(stages, 5) coefficients and the output gain of one axis, from the header text."""
    gain = float(re.search(rf"#define {prefix}{ax.upper()}_GAIN (\S+)f", h).group(1))
    body = re.search(rf"/\* {ax} axis linear law.*?static const float c\[(\d+)\] = \{{(.*?)\}};",
                     h, re.S)
    vals = [float(v.strip().rstrip("f")) for v in body.group(2).split(",") if v.strip()]
    assert len(vals) == int(body.group(1))
    return np.array(vals, dtype=np.float32).reshape(-1, 5), gain


def cmsis_run(co: np.ndarray, gain: float, e: np.ndarray) -> np.ndarray:
    """gain x arm_biquad_cascade_df2T_f32 over the error sequence (float32)."""
    inst = dsp.arm_biquad_cascade_df2T_instance_f32()
    state = np.zeros(2 * co.shape[0], dtype=np.float32)
    dsp.arm_biquad_cascade_df2T_init_f32(inst, co.shape[0], co.ravel().astype(np.float32), state)
    y = np.asarray(dsp.arm_biquad_cascade_df2T_f32(inst, e.astype(np.float32)), dtype=np.float32)
    return (np.float32(gain) * y).astype(float)


def _inputs():
    inp = C.test_inputs(i_step=2.0)
    inp[:, 4] = 0.0                         # zero speed: no decoupling term
    return inp


@pytest.mark.parametrize("name", list(CASES))
def test_cmsis_biquads_match_python_law(name, tmp_path):
    if dsp is None:
        pytest.fail("cmsisdsp not installed: it is in the test extras "
                    "(pip install -e '.[test]'; an sdist built with gcc)", pytrace=False)
    art = CASES[name]()
    chk = check_exportable(art, A.MOTOR, A.DRIVE)
    h = write_header(art, A.MOTOR, A.DRIVE)
    inp = _inputs()
    v_ref, sat = reference_law(art, inp, chk.v_max)
    assert not sat.any()
    v_c, _ = C.run_float(h, tmp_path, inp)
    bound = C.float_bound(chk, art, inp)
    for j, ax in enumerate("dq"):
        assert chk.realisations[ax].form == "sos"
        co, gain = header_sos(h, ax)
        e = (inp[:, j].astype(np.float32) - inp[:, 2 + j].astype(np.float32))
        v_cmsis = cmsis_run(co, gain, e)
        err = np.abs(v_cmsis - v_ref[:, j])
        scale = np.abs(v_ref[:, j]).max()
        d_hdr = np.abs(v_cmsis - v_c[:, j]).max()
        ulp = float(np.spacing(np.float32(scale)))
        print(f"\n{name} {ax}: {co.shape[0]} stage(s); CMSIS vs Python law max|err| "
              f"{err.max():.3g} V ({err.max() / scale:.2e} of {scale:.3g} V), bound "
              f"{bound[:, j].max():.3g} V; CMSIS vs header {d_hdr:.3g} V ({d_hdr / ulp:.1f} ulp)")
        assert np.all(err <= bound[:, j])
        assert err.max() <= 1e-5 * scale
        assert np.all(np.abs(v_cmsis - v_c[:, j]) <= 2.0 * bound[:, j])
        # the test can fail: a1 with the scipy sign (not negated) is far off
        wrong = co.copy()
        wrong[:, 3] = -wrong[:, 3]
        assert np.abs(cmsis_run(wrong, gain, e) - v_ref[:, j]).max() > 1e3 * bound[:, j].max()
