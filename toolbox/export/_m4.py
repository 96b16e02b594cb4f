"""Cortex-M4F target of the header: cross-compile a header's entry points
with arm-none-eabi-gcc and execute them on an emulated Cortex-M4F (unicorn),
counting instructions (:mod:`toolbox.export.firmware` measures with it;
``tests/export/test_target.py`` compares it with the host bit for bit).

Toolchain: Debian's ``gcc-arm-none-eabi`` (GCC 12.2, the Arm GNU toolchain
12.2.rel1) with ``libnewlib-arm-none-eabi`` (newlib's libm: ``sinf``,
``cosf``, ``sqrtf``), installed by ``.ci/target-deps.sh``. Emulator:
``unicorn`` (PyPI; QEMU's ARMv7E-M core with the model
``UC_CPU_ARM_CORTEX_M4``: Thumb-2, DSP extension and the FPv4-SP
single-precision FPU; QEMU's softfloat implements IEEE-754 binary32 exactly,
including the fused VFMA and subnormals, as the M4's FPU does with the reset
FPSCR: round to nearest, no flush-to-zero, no default NaN).

The FPU enable. On silicon the FPU is off at reset and the startup code
(CMSIS ``SystemInit``) sets CP10/CP11 full access in ``SCB->CPACR``
(0xE000ED88); a float instruction before that raises a UsageFault (NOCP).
unicorn 2.1 maps no System Control Space and gives the core FPU access from
reset (it ignores CPACR). The harness models the gate itself: the SCS page
is an MMIO region whose CPACR word the firmware's own startup routine writes
(``tgt_startup`` below, the ``SystemInit`` line), and the instruction hook
refuses any coprocessor-10/11 (VFP) instruction while CPACR lacks CP10/CP11
full access, as a NOCP UsageFault would.

Counting: a code hook counts the instructions executed from the entry of the
wrapper ``tgt_step`` (a call of ``<p>step`` on global structs) to its return,
libm calls included, and separately the VDIV.F32 / VSQRT.F32 among them
(14 cycles each on the M4, against 1 for most FPU operations), and the stack
depth (stack painted with 0xA5 before the call, the deepest changed word
after it).
"""

from __future__ import annotations

import functools
import shutil
import struct
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

ARM_GCC = shutil.which("arm-none-eabi-gcc")
ARM_SIZE = shutil.which("arm-none-eabi-size")
ARM_NM = shutil.which("arm-none-eabi-nm")
#: Cortex-M4F with the single-precision FPU, hard-float ABI
MCU = ["-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard"]
#: the export tests' strict flags, plus -Wdouble-promotion: on an M4F a double
#: operation is a soft-float library call (tens of times slower), so the
#: header must have none
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wconversion",
          "-Wdouble-promotion", "-O2"]
FLASH, FLASH_SIZE = 0x08000000, 0x100000      # STM32G4-like map
RAM, RAM_SIZE = 0x20000000, 0x20000
SCS = 0xE000E000                               # System Control Space page
CPACR = 0xE000ED88
RET = 0x1FFF0000                               # return trap (system memory)
STACK_PAINT = 0xA5

LINKER_SCRIPT = """\
MEMORY { FLASH (rx) : ORIGIN = 0x08000000, LENGTH = 1024K
         RAM (rwx)  : ORIGIN = 0x20000000, LENGTH = 128K }
SECTIONS {
  .text : { KEEP(*(.text.tgt_*)) *(.text*) *(.rodata*) } > FLASH
  .ARM.exidx : { *(.ARM.exidx*) } > FLASH
  .data : { *(.data*) } > RAM
  .bss : { *(.bss*) *(COMMON) } > RAM
}
"""

#: the firmware side: startup's FPU enable, then init / set_vdc / step on
#: global structs (the host build of the same file skips the CPACR write)
TARGET_C = r"""
#include <stdint.h>
#include "controller.h"
{p}state_t tgt_state;
{p}input_t tgt_in;
{p}output_t tgt_out;
float tgt_vdc;
int tgt_ret;
float tgt_preset_v[2];
void tgt_startup(void);
void tgt_init(void);
void tgt_set_vdc(void);
void tgt_step(void);
void tgt_preset(void);
void tgt_startup(void)
{{
#ifdef __arm__
    /* CMSIS SystemInit: SCB->CPACR |= CP10, CP11 full access */
    *(volatile uint32_t *)0xE000ED88u |= (0xFu << 20);
    __asm__ volatile ("dsb\n\tisb");
#endif
}}
void tgt_init(void) {{ {p}init(&tgt_state); }}
void tgt_set_vdc(void) {{ tgt_ret = {p}set_vdc(&tgt_state, tgt_vdc); }}
void tgt_step(void) {{ {p}step(&tgt_state, &tgt_in, &tgt_out); }}
void tgt_preset(void)
{{
#ifdef TGT_PRESET
    {p}preset(&tgt_state, tgt_preset_v[0], tgt_preset_v[1]);
#endif
}}
"""


def available() -> str | None:
    """None when the cross toolchain and the emulator are there, else what is missing."""
    missing = [n for n, p in (("arm-none-eabi-gcc", ARM_GCC), ("arm-none-eabi-size", ARM_SIZE),
                              ("arm-none-eabi-nm", ARM_NM)) if p is None]
    try:
        import unicorn  # noqa: F401
    except ImportError:
        missing.append("unicorn (PyPI)")
    return ", ".join(missing) or None


class BuildError(RuntimeError):
    """A cross or host compilation step failed (the command and its messages)."""


@functools.lru_cache(maxsize=1)
def toolchain_version() -> str:
    """First line of ``arm-none-eabi-gcc --version`` (keys the firmware figures)."""
    return _run([ARM_GCC, "--version"]).stdout.splitlines()[0]


def _run(cmd, **kw) -> subprocess.CompletedProcess:
    res = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=120, **kw)
    if res.returncode != 0:
        raise BuildError(f"{' '.join(map(str, cmd))}\n{res.stderr}")
    return res


@dataclass
class Build:
    """A header built for the target (ELF, object) and the host (shared library)."""
    elf: Path
    obj: Path
    host: Path
    symbols: dict[str, tuple[int, int]]        # name -> (address, size) in the ELF
    obj_size: dict[str, int]                   # text, data, bss of the object (arm-none-eabi-size)
    elf_text: int                              # .text + .rodata of the linked ELF (libm included)
    functions: dict[str, int] = field(default_factory=dict)   # object's function sizes


def build(header: str, prefix: str, tmp: Path, defines=(), extra: str = "",
          with_host: bool = True) -> Build:
    """Cross-compile (strict flags, -O2) and link; build the same file for the
    host (a shared library, gcc) unless ``with_host`` is false."""
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "controller.h").write_text(header)
    (tmp / "tgt.c").write_text(TARGET_C.format(p=prefix) + extra)
    (tmp / "link.ld").write_text(LINKER_SCRIPT)
    defs = [f"-D{d}" for d in defines]
    obj, elf = tmp / "tgt.o", tmp / "tgt.elf"
    _run([ARM_GCC, *MCU, *STRICT, *defs, "-ffunction-sections", "-fdata-sections",
          "-I", tmp, "-c", tmp / "tgt.c", "-o", obj])
    _run([ARM_GCC, *MCU, "-nostartfiles", "-T", tmp / "link.ld", "-Wl,--gc-sections",
          "-Wl,-e,tgt_step", obj, "-lm", "-o", elf])
    host = tmp / "libtgt.so"
    if with_host:
        _run([shutil.which("gcc"), *STRICT, *defs, "-shared", "-fPIC", "-I", tmp, tmp / "tgt.c",
              "-o", host, "-lm"])
    syms = {}
    for ln in _run([ARM_NM, "-S", elf]).stdout.splitlines():
        f = ln.split()
        if len(f) == 4:
            syms[f[3]] = (int(f[0], 16), int(f[1], 16))
    text, data, bss = (int(x) for x in _run([ARM_SIZE, obj]).stdout.splitlines()[1].split()[:3])
    elf_text = int(_run([ARM_SIZE, elf]).stdout.splitlines()[1].split()[0])
    funcs = {}
    for ln in _run([ARM_NM, "-S", "--size-sort", obj]).stdout.splitlines():
        f = ln.split()
        if len(f) == 4 and f[2] in "tT":
            funcs[f[3]] = int(f[1], 16)
    return Build(elf, obj, host, syms, {"text": text, "data": data, "bss": bss}, elf_text, funcs)


def _is_vfp(hw1: int, hw2: int) -> bool:
    """A 32-bit Thumb-2 coprocessor instruction on CP10/CP11 (every FPv4 instruction)."""
    return (hw1 & 0xEC00) == 0xEC00 and (hw2 & 0x0E00) == 0x0A00


def _is_slow(hw1: int, hw2: int) -> bool:
    """VDIV.F32 or VSQRT.F32 (14 cycles each on the Cortex-M4)."""
    vdiv = (hw1 & 0xFFB0) == 0xEE80 and (hw2 & 0x0F50) == 0x0A00
    vsqrt = (hw1 & 0xFFBF) == 0xEEB1 and (hw2 & 0x0FD0) == 0x0AC0
    return vdiv or vsqrt


class UsageFault(RuntimeError):
    """A VFP instruction executed with the FPU disabled (NOCP)."""


class Target:
    """The ELF loaded on an emulated Cortex-M4F; ``call`` runs one function."""

    def __init__(self, b: Build) -> None:
        from unicorn import UC_ARCH_ARM, UC_HOOK_CODE, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
        from unicorn.arm_const import UC_CPU_ARM_CORTEX_M4
        self.b = b
        uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M4)
        uc.mem_map(FLASH, FLASH_SIZE)
        uc.mem_map(RAM, RAM_SIZE)
        uc.mem_map(RET, 0x1000)
        self.cpacr = 0                                # reset value: FPU off
        uc.mmio_map(SCS, 0x1000, self._scs_read, None, self._scs_write, None)
        elf = b.elf.read_bytes()
        phoff, = struct.unpack_from("<I", elf, 28)
        phentsize, phnum = struct.unpack_from("<HH", elf, 42)
        for i in range(phnum):
            p_type, off, vaddr, _, filesz, memsz, _, _ = struct.unpack_from(
                "<8I", elf, phoff + i * phentsize)
            if p_type == 1 and memsz:                 # PT_LOAD
                uc.mem_write(vaddr, elf[off:off + filesz] + bytes(memsz - filesz))
        self.flash = bytes(uc.mem_read(FLASH, b.elf_text + 64))
        self.uc = uc
        self._kind: dict[int, int] = {}
        self.count = self.slow = 0
        uc.hook_add(UC_HOOK_CODE, self._hook)
        self.stack_top = RAM + RAM_SIZE - 8

    def _scs_read(self, uc, offset, size, data):
        return self.cpacr if SCS + offset == CPACR else 0

    def _scs_write(self, uc, offset, size, value, data):
        if SCS + offset == CPACR:
            self.cpacr = value & 0xFFFFFFFF

    def _hook(self, uc, address, size, data):
        k = self._kind.get(address)
        if k is None:
            k = 0
            if size == 4:
                o = address - FLASH
                hw1, hw2 = struct.unpack_from("<HH", self.flash, o)
                k = (1 if _is_vfp(hw1, hw2) else 0) | (2 if _is_slow(hw1, hw2) else 0)
            self._kind[address] = k
        self.count += 1
        if k:
            if (self.cpacr >> 20) & 0xF != 0xF:
                uc.emu_stop()
                self.fault = UsageFault(f"VFP instruction at {address:#x} with CPACR "
                                        f"{self.cpacr:#010x} (FPU not enabled): NOCP")
            if k & 2:
                self.slow += 1

    def call(self, name: str, paint: int = 2048) -> tuple[int, int, int]:
        """Run ``name()`` to its return: (instructions, VDIV/VSQRT, stack bytes)."""
        from unicorn.arm_const import UC_ARM_REG_LR, UC_ARM_REG_SP
        uc = self.uc
        sp = self.stack_top
        uc.mem_write(sp - paint, bytes([STACK_PAINT]) * paint)
        uc.reg_write(UC_ARM_REG_SP, sp)
        uc.reg_write(UC_ARM_REG_LR, RET | 1)
        self.count = self.slow = 0
        self.fault = None
        uc.emu_start(self.b.symbols[name][0] | 1, RET, count=2_000_000)
        if self.fault is not None:
            raise self.fault
        stack = bytes(uc.mem_read(sp - paint, paint))
        used = paint - next((i for i, c in enumerate(stack) if c != STACK_PAINT), paint)
        return self.count, self.slow, used

    def write(self, sym: str, data: bytes, offset: int = 0) -> None:
        self.uc.mem_write(self.b.symbols[sym][0] + offset, data)

    def read(self, sym: str, n: int | None = None) -> bytes:
        addr, size = self.b.symbols[sym]
        return bytes(self.uc.mem_read(addr, size if n is None else n))
