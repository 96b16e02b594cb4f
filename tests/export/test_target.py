"""Target in the loop: every gallery header, cross-compiled for a Cortex-M4F
and executed on an emulated one, gives the host's outputs bit for bit along a
closed-loop trajectory; its size, instructions per step and share of a PWM
period are measured.

For every design of the gallery (``designs/*.toml``, designed here as
``tests/export/test_sil.py`` does), the header is compiled with
``arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16
-mfloat-abi=hard`` and the export tests' strict flags plus
``-Wdouble-promotion`` (``-O2``), linked with newlib's libm, and loaded on
unicorn's Cortex-M4 (:mod:`target_m4`: the startup routine enables the FPU
through CPACR first; a float instruction before it is a NOCP fault). The same
translation unit is built for the host with gcc (float32 arithmetic on SSE,
glibc's libm).

Trajectory: the inputs of each period (``i_d_ref, i_q_ref``, the measured
``i_d, i_q`` at ``t_k``, ``omega_m`` and ``theta_e = p omega_m t_k`` wrapped
to [-pi, pi)) are recorded from :func:`toolbox.sim.simulate` in closed loop
(``test_sil``'s cases "30 % base" and "saturating": a step to I = half the
current scale, the voltage limit acting in the second; stationary-frame
hold; the bus of the case given once through ``<p>set_vdc``). Both builds
step along it from ``<p>init``.

Bound: 0 (bit-equality), except after the hexagon limit first acts. The
output struct (``v_d, v_q, v_d_comp, v_q_comp``, the saturation flags,
``status``) and the whole state struct are compared byte for byte after every
period. Both sides compute in IEEE binary32 with round-to-nearest, without
contraction into fused multiply-adds (``-std=c99`` implies
``-ffp-contract=off`` in GCC) and in the same operation order; ``sqrtf`` is
correctly rounded on both (VSQRT.F32, SSE sqrtss). What can differ is the
last bit of ``sinf``/``cosf``: newlib's (fdlibm's, < 1 ulp) against glibc's
(``fcs_mpc``'s predicted currents, which pass through them at the rotor's
angle, are compared within ``LIBM_BOUND`` of ``I_PLAUSIBLE``).
At the constant angle of the voltage placement they agree on every gallery
trajectory; at the hexagon's angle, which turns with the rotor, they do not
always, and a 1-ulp change of the projection changes the scale factor of the
limit and, through the anti-windup, the state. From the first period in which
the hexagon acts, the outputs are therefore compared within
``LIBM_BOUND = 2e-6 V_MAX`` (17 ulp of V_MAX: a few ulp per period through a
stable recursion; measured 2.3e-7 V_MAX, on 000_tc and 002_svm_pi), the flags
and status exactly. A mismatch otherwise means the target computes something
else than the host (a double promotion, a contraction, a miscompiled
construct), which is what this test is for.

Measured per design (``-s`` prints the table; README "Firmware header"
holds firmware.json's figures, which this test bounds: every closed-loop
period within firmware.json's worst path, the same object size): object sizes (``arm-none-eabi-size``: ``text`` = code and constant
coefficients of init, set_vdc, step and the other entry points; ``bss`` the
state and the I/O structs of the wrapper), the step code alone, the libm code
the link pulls in, instructions per ``<p>step`` (typical: the median over
unsaturated periods; worst: the maximum, saturated and with the hexagon
where the design has one), the VDIV/VSQRT among them, the stack depth, and
the share of a 20 kHz PWM period (8500 cycles) on a 170 MHz Cortex-M4 for
1.0 and 1.3 cycles per instruction plus 13 extra cycles per VDIV/VSQRT (14
cycles each on the M4). Flash wait states are not modelled: at 170 MHz an
STM32G4 needs 8 wait states, hidden by its ART cache/prefetch on a warm
loop; place the ISR in CCM SRAM (or count ~1.5-2 cycles per instruction on a
cold cache) for a bound.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

import target_m4 as T
import test_sil as S

#: slow: cross-compiled headers on the emulated Cortex-M4F
pytestmark = pytest.mark.slow

CASES = ("30% base", "saturating")
F_PWM = 20e3
F_CPU = 170e6
CYCLES = F_CPU / F_PWM
CPI = (1.0, 1.3)
LIBM_BOUND = 2e-6 
SLOW_EXTRA = 13                      # VDIV.F32 / VSQRT.F32: 14 cycles instead of 1
_RESULTS: dict[str, dict] = {}


@pytest.fixture(scope="module", autouse=True)
def table():
    yield
    if not _RESULTS:
        return
    lines = ["", "Cortex-M4F (arm-none-eabi-gcc 12.2 -O2, unicorn): per design",
             f"{'design':<30} {'method':<9} {'text':>5} {'bss':>4} {'step':>5} {'libm':>5} "
             f"{'instr typ':>9} {'instr worst':>11} {'div/sqrt':>8} {'stack':>5} "
             f"{'% of 50 us @170 MHz':>20}"]
    for name, r in sorted(_RESULTS.items()):
        lo, hi = (100 * (r['worst'] * c + SLOW_EXTRA * r['slow']) / CYCLES for c in CPI)
        lines.append(f"{name:<30} {r['method']:<9} {r['text']:5d} {r['bss']:4d} {r['step']:5d} "
                     f"{r['libm']:5d} {r['typical']:9d} {r['worst']:11d} {r['slow']:8d} "
                     f"{r['stack']:5d} {lo:9.1f} - {hi:4.1f} %")
    print("\n".join(lines))


def _trajectory(spec, art, label: str) -> tuple[np.ndarray, float]:
    """(N, 6) inputs per period from the closed-loop simulation, and the bus (V)."""
    i_step, speeds = S._scales(spec)
    omega_m, vdc = speeds[label]
    i_s, _ = S.run_simulator(spec, art, "stationary", omega_m, vdc, i_step)
    refs = S._references(i_step)
    k = np.arange(len(refs))
    w_e = spec.motor.pole_pairs * omega_m
    theta = np.mod(w_e * k * spec.drive.sample_time + math.pi, 2 * math.pi) - math.pi
    u = np.column_stack([refs, i_s, np.full(len(k), omega_m), theta])
    return u.astype(np.float32), vdc


def _saturated(out: bytes, method: str) -> bool:
    return method != "fcs_mpc" and struct.unpack_from("<i", out, 16)[0] != 0


@pytest.mark.parametrize("name", S.DESIGNS)
def test_target_matches_host_in_closed_loop(name, tmp_path):
    T.require()
    spec, art, header = S._designed(name)
    b = T.build(header, "cct_", tmp_path)
    assert not [s for s in b.symbols if s.startswith(("__aeabi_d", "__adddf", "__muldf"))], \
        f"{name}: the step links soft-float double routines"
    tgt, host = T.Target(b), T.Host(b)
    with pytest.raises(T.UsageFault):               # the FPU is off until startup enables it
        tgt.call("tgt_init")
        tgt.call("tgt_step")
    tgt.call("tgt_startup")
    assert (tgt.cpacr >> 20) & 0xF == 0xF
    n_in = b.symbols["tgt_in"][1] // 4
    counts, sat_counts, slow, stack = [], [], 0, 0
    hexagon = art.method != "fcs_mpc" and n_in == 6
    v_max = S._macro(header, "CCT_V_MAX") if art.method != "fcs_mpc" else 0.0
    exact, differ, worst_dv = 0, 0, 0.0
    for label in CASES:
        u, vdc = _trajectory(spec, art, label)
        for side in (tgt, host):
            side.call("tgt_init")
            side.write("tgt_vdc", struct.pack("<f", vdc))
            side.call("tgt_set_vdc")
            assert side.read("tgt_ret") == bytes(4), f"{name}: set_vdc({vdc}) refused"
        saturated, hex_acted = 0, False
        for k, row in enumerate(u):
            data = row[:n_in].tobytes()
            tgt.write("tgt_in", data)
            host.write("tgt_in", data)
            n, n_slow, depth = tgt.call("tgt_step")
            host.call("tgt_step")
            out_t, out_h = tgt.read("tgt_out"), host.read("tgt_out")
            sat = _saturated(out_t, art.method)
            hex_acted |= hexagon and sat
            if hex_acted:       # libm's last bit may differ from here on: within LIBM_BOUND
                dv = np.abs(np.frombuffer(out_t[:16], np.float32).astype(float)
                            - np.frombuffer(out_h[:16], np.float32).astype(float)).max()
                worst_dv = max(worst_dv, dv)
                assert dv <= LIBM_BOUND * v_max and out_t[16:] == out_h[16:], (
                    f"{name} {label} period {k}: target and host differ by {dv:.3g} V "
                    f"> {LIBM_BOUND:g} V_MAX, or in the flags")
                differ += out_t != out_h
            else:
                assert out_t == out_h, (f"{name} {label} period {k}: target output "
                                        f"{out_t.hex()} != host {out_h.hex()}")
                st_t, st_h = tgt.read("tgt_state"), host.read("tgt_state")
                if art.method == "fcs_mpc":
                    # the predicted currents (state bytes 8..16) come through sinf/cosf at
                    # the rotating angle: libm's last bit, within LIBM_BOUND of I_PLAUSIBLE
                    p_t, p_h = (np.frombuffer(x[8:16], np.float32).astype(float)
                                for x in (st_t, st_h))
                    i_pl = S._macro(header, "CCT_I_PLAUSIBLE")
                    assert np.abs(p_t - p_h).max() <= LIBM_BOUND * i_pl, \
                        f"{name} {label} period {k}: the predictions part"
                    st_t, st_h = st_t[:8] + st_t[16:], st_h[:8] + st_h[16:]
                assert st_t == st_h, f"{name} {label} period {k}: the states part"
                exact += 1
            assert out_t[-4:] == bytes(4), f"{name} {label} period {k}: status != 0"
            saturated += sat
            (sat_counts if sat else counts).append(n)
            slow = max(slow, n_slow)
            stack = max(stack, depth)
        if label == "saturating" and art.method != "fcs_mpc":
            assert saturated > 0, f"{name}: the saturating case never saturated on the target"
    # firmware.json's figures (toolbox.export.firmware, its own fixed input set) against
    # this closed loop: every period within its worst path, the sizes of the same build
    from toolbox.export.firmware import measure_firmware
    fw = measure_firmware(header, "cct_")
    assert fw["measured"] and fw["code_bytes"] == b.obj_size["text"], fw
    assert max(counts + sat_counts) <= fw["instructions"]["worst"], (
        f"{name}: a closed-loop period took {max(counts + sat_counts)} instructions, more than "
        f"firmware.json's worst path {fw['instructions']['worst']}")
    entry = {"tgt_startup", "tgt_init", "tgt_set_vdc", "tgt_preset"}
    _RESULTS[name] = dict(
        method=art.method, text=b.obj_size["text"], bss=b.obj_size["bss"],
        step=sum(v for k, v in b.functions.items() if k not in entry),
        libm=b.elf_text - b.obj_size["text"],
        typical=int(np.median(counts)), worst=max(counts + sat_counts), slow=slow, stack=stack,
        exact=exact, differ=differ, dv=worst_dv / v_max if v_max else 0.0)
    print(f"\n{name}: {exact} periods bit-equal; after the hexagon first acted {differ} "
          f"differ, worst {worst_dv:.3g} V = {worst_dv / v_max if v_max else 0:.3g} V_MAX")
