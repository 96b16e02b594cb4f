"""Target-size figures of a header as data: ``firmware.json``.

:func:`measure_firmware` cross-compiles a ``controller.h`` for a Cortex-M4F
(``arm-none-eabi-gcc 12.2 -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16
-mfloat-abi=hard -O2``, the export tests' strict flags plus
``-Wdouble-promotion``, newlib's libm) and executes ``<p>step`` on an
emulated Cortex-M4F (:mod:`toolbox.export._m4`, unicorn) over a fixed set of
inputs, and returns the figures a firmware engineer budgets with: code and
data size, instructions per step (typical and worst path) and the share of a
PWM period at a stated clock. Without the cross toolchain or the emulator it
returns ``measured = false`` and the reason ("not measured: toolchain absent
(...)"); the report's firmware card and the README table read this data
(:func:`firmware_table_row`).

Inputs (deterministic, no simulation): after ``<p>init`` and ``<p>set_vdc``
at the nominal bus, ``ANGLES`` sampled angles over [-pi, pi) at each of
three mechanical speeds (0, 0.3 and 1 x the header's speed range
``W_PLAUSIBLE / 2``), each once at zero error with 10 % of the current range
(the typical path: no limit acts at zero speed and 30 %) and once with the
references at the current range, the measured currents at -0.5 x it (the
voltage limit acts: the worst path, with the hexagon where the design has
one). Typical = the median over the zero-error periods at 0 and 0.3 x the
range; worst = the maximum over every period. The share of the PWM period
counts ``CPI`` cycles per instruction plus ``SLOW_EXTRA`` per VDIV/VSQRT
(14 cycles each on the M4); flash wait states are not modelled (an STM32G4
at 170 MHz hides its 8 wait states behind the ART cache on a warm loop; run
the ISR from CCM SRAM for a hard bound).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import struct
import tempfile
from pathlib import Path

from .._cache import cached

__all__ = ["FIRMWARE_JSON", "SCHEMA", "measure_firmware", "firmware_json", "firmware_table_row",
           "load_firmware", "firmware_table", "F_CPU", "F_PWM", "CPI"]

FIRMWARE_JSON = "firmware.json"
SCHEMA = "cct.firmware/1"
F_CPU = 170e6                      # Hz, an STM32G4-class Cortex-M4F
F_PWM = 20e3                       # Hz, the PWM (and controller) rate the share refers to
CPI = (1.0, 1.3)                   # cycles per instruction, the range quoted
SLOW_EXTRA = 13                    # VDIV.F32 / VSQRT.F32: 14 cycles instead of 1
ANGLES = 24
TARGET = ("Cortex-M4F, arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 "
          "-mfloat-abi=hard -std=c99 -O2, newlib libm; executed on unicorn's Cortex-M4")


def _macro(header: str, name: str) -> float | None:
    m = re.search(rf"#define {name} \(?([-+0-9.eE]+)f?\)?", header)
    return float(m.group(1)) if m else None


def _inputs(header: str, P: str, n_in: int) -> list[tuple[bool, list[float]]]:
    """(typical?, input row) of the measurement (module docstring)."""
    i_rng = (_macro(header, f"{P}I_PLAUSIBLE") or 0.0) / 2.0
    w_rng = (_macro(header, f"{P}W_PLAUSIBLE") or 0.0) / 2.0
    rows = []
    for frac in (0.0, 0.3, 1.0):
        for k in range(ANGLES):
            th = -math.pi + 2.0 * math.pi * k / ANGLES
            w = frac * w_rng
            i = 0.1 * i_rng
            rows.append((frac < 1.0, [-0.25 * i, i, -0.25 * i, i, w, th]))
            rows.append((False, [-i_rng, i_rng, 0.5 * i_rng, -0.5 * i_rng, w, th]))
    return [(t, r[:n_in]) for t, r in rows]


def measure_firmware(header: str, prefix: str = "cct_", *, f_cpu: float = F_CPU,
                     f_pwm: float = F_PWM) -> dict:
    """The target figures of ``header`` (its C prefix ``prefix``) as the
    ``firmware.json`` dict (module docstring). Never raises for a missing
    toolchain: ``{"measured": false, "reason": ...}`` instead.

    Keys when measured: ``schema``, ``measured``, ``target``, ``toolchain``,
    ``clock_hz``, ``pwm_hz``, ``cycles_per_period``, ``code_bytes`` (text of
    the object: init, set_vdc, step, coefficients), ``data_bytes`` (data +
    bss: the state and the I/O structs), ``step_code_bytes``, ``libm_bytes``
    (what the link adds), ``stack_bytes``, ``instructions`` (``typical``,
    ``worst``), ``div_sqrt`` (VDIV/VSQRT on the worst path), ``saturated``
    (periods in which the limit acted), ``period_share`` (fraction of the PWM
    period, ``low`` at CPI 1.0 and ``high`` at 1.3), ``inputs``.
    """
    from . import _m4
    base = {"schema": SCHEMA, "target": TARGET, "clock_hz": f_cpu, "pwm_hz": f_pwm}
    why = _m4.available()
    if why is not None:
        return {**base, "measured": False, "reason": f"not measured: toolchain absent ({why})"}
    # The figures depend only on the header, the clocks, this code and the
    # toolchain: a repeated design (same header) reads them from the on-disk
    # cache instead of paying the cross build and emulation again (~0.5-1.7 s).
    # (the header's creation time stamp, a comment, is not part of the key)
    code = re.sub(r"^ \* created: .*$", "", header, flags=re.M)
    key = hashlib.sha256(f"{prefix}\0{f_cpu!r}\0{f_pwm!r}\0{_m4.toolchain_version()}\0"
                         f"{code}".encode()).hexdigest()[:16]
    return cached(f"firmware-{key}", [__file__, _m4.__file__],
                  lambda: _measure(header, prefix, base, f_cpu, f_pwm),
                  lambda v: isinstance(v, dict) and v.get("measured") is True,
                  packages=("unicorn",))


def _measure(header: str, prefix: str, base: dict, f_cpu: float, f_pwm: float) -> dict:
    """:func:`measure_firmware` without the cache (toolchain present)."""
    from . import _m4
    P = prefix.upper()
    fcs = f"{P}FCS_ALPHA" in header
    with tempfile.TemporaryDirectory(prefix="cct-m4-") as tmp:
        b = _m4.build(header, prefix, Path(tmp), with_host=False)
        tgt = _m4.Target(b)
        tgt.call("tgt_startup")
        n_in = b.symbols["tgt_in"][1] // 4
        vdc = _macro(header, f"{P}DRIVE_VDC")
        tgt.call("tgt_init")
        if vdc is not None:
            tgt.write("tgt_vdc", struct.pack("<f", vdc))
            tgt.call("tgt_set_vdc")
        typical, counts, slow, stack, saturated = [], [], 0, 0, 0
        for is_typical, row in _inputs(header, P, n_in):
            tgt.write("tgt_in", struct.pack(f"<{n_in}f", *row))
            n, n_slow, depth = tgt.call("tgt_step")
            out = tgt.read("tgt_out")
            if not fcs and struct.unpack_from("<i", out, 16)[0]:
                saturated += 1
            counts.append(n)
            if is_typical:
                typical.append(n)
            slow = max(slow, n_slow)
            stack = max(stack, depth)
        toolchain = _m4.toolchain_version()
    entry = {"tgt_startup", "tgt_init", "tgt_set_vdc", "tgt_preset"}
    cycles = f_cpu / f_pwm
    worst = max(counts)
    typical.sort()
    return {**base, "measured": True, "toolchain": toolchain,
            "cycles_per_period": cycles,
            "code_bytes": b.obj_size["text"], "data_bytes": b.obj_size["data"] + b.obj_size["bss"],
            "step_code_bytes": sum(v for k, v in b.functions.items() if k not in entry),
            "libm_bytes": b.elf_text - b.obj_size["text"], "stack_bytes": stack,
            "instructions": {"typical": typical[len(typical) // 2], "worst": worst},
            "div_sqrt": slow, "saturated": saturated,
            "period_share": {"cpi": list(CPI),
                             "low": (worst * CPI[0] + SLOW_EXTRA * slow) / cycles,
                             "high": (worst * CPI[1] + SLOW_EXTRA * slow) / cycles},
            "inputs": (f"{len(counts)} steps: {ANGLES} angles x speeds 0, 0.3, 1 x the speed "
                       "range, at zero error (typical: speeds 0 and 0.3) and with the voltage "
                       "limit acting (worst)")}


def firmware_json(data: dict) -> str:
    """The ``firmware.json`` text of :func:`measure_firmware`'s dict (deterministic)."""
    return json.dumps(data, indent=1, sort_keys=True, allow_nan=False) + "\n"


def firmware_table_row(name: str, method: str, data: dict) -> str:
    """One row of the README's firmware table from a ``firmware.json`` dict."""
    if not data.get("measured"):
        return f"| {name} | {method} | {data.get('reason', 'not measured')} |" + " |" * 8
    ins, sh = data["instructions"], data["period_share"]
    return (f"| {name} | {method} | {data['code_bytes']} | {data['data_bytes']} | "
            f"{data['step_code_bytes']} | {data['libm_bytes']} | {ins['typical']} | "
            f"{ins['worst']} | {data['div_sqrt']} | {data['stack_bytes']} | "
            f"{100 * sh['low']:.1f}-{100 * sh['high']:.1f} |")


def load_firmware(out_dir: str | Path) -> dict | None:
    """``out_dir/firmware.json`` as a dict, or None when the file is absent.

    Raises :class:`toolbox.errors.ArtifactError` (naming the file) for a file
    that is not a JSON object of schema :data:`SCHEMA` with a boolean
    ``measured``."""
    from .._io import read_limited
    from ..errors import ArtifactError
    path = Path(out_dir) / FIRMWARE_JSON
    if not path.exists():
        return None
    raw = read_limited(path, ArtifactError, what="firmware.json file")
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as err:
        raise ArtifactError("", "a UTF-8 JSON object", str(err), file=str(path)) from None
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        raise ArtifactError("schema", f'"{SCHEMA}"', data.get("schema") if isinstance(data, dict)
                            else type(data).__name__, file=str(path))
    if not isinstance(data.get("measured"), bool):
        raise ArtifactError("measured", "true or false", data.get("measured"), file=str(path))
    return data


TABLE_HEAD = ("| design | method | code B | data B | step code B | libm B | instr typ | "
              "instr worst | div/sqrt | stack B | % of 50 us |\n"
              "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")


def firmware_table(reports_dir: str | Path) -> str:
    """The README's firmware table: one row per ``<reports_dir>/<name>/firmware.json``
    (name order), the method read from the directory's ``controller.json``
    (with "(hexagon)" for ``drive.voltage_limit = "hexagon"``)."""
    rows = [TABLE_HEAD]
    for d in sorted(p for p in Path(reports_dir).iterdir() if p.is_dir()):
        data = load_firmware(d)
        if data is None:
            continue
        art = json.loads((d / "controller.json").read_text())
        method = art.get("method", "?")
        if (art.get("spec") or {}).get("drive", {}).get("voltage_limit") == "hexagon" \
                and method != "fcs_mpc":
            method += " (hexagon)"
        rows.append(firmware_table_row(d.name, method, data))
    return "\n".join(rows)
