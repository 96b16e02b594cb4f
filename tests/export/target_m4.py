"""Cortex-M4F target for the export tests: the toolbox's own cross build and
emulated Cortex-M4F (:mod:`toolbox.export._m4`: toolchain, FPU gate,
instruction counting), and the same translation unit built for the host, to
compare the two bit for bit.
"""

from __future__ import annotations

import ctypes
import os

from toolbox.export._m4 import (ARM_GCC, ARM_NM, ARM_SIZE, MCU, STRICT, TARGET_C,  # noqa: F401
                                Build, BuildError, Target, UsageFault, available, build)


def require() -> None:
    """Skip when the target toolchain is missing, unless CCT_REQUIRE_TARGET=1
    (set by .ci/run, which installs it): then fail."""
    import pytest
    why = available()
    if why is None:
        return
    msg = (f"target toolchain missing: {why} (apt-get install gcc-arm-none-eabi "
           "libnewlib-arm-none-eabi; pip install unicorn; see .ci/target-deps.sh)")
    if os.environ.get("CCT_REQUIRE_TARGET") == "1":
        pytest.fail(msg, pytrace=False)
    pytest.skip(msg)


class Host:
    """The same translation unit in a host shared library (ctypes)."""

    def __init__(self, b: Build) -> None:
        self.b = b
        self.lib = ctypes.CDLL(str(b.host))

    def call(self, name: str) -> None:
        getattr(self.lib, name)()

    def _addr(self, sym: str) -> int:
        return ctypes.addressof(ctypes.c_char.in_dll(self.lib, sym))

    def write(self, sym: str, data: bytes, offset: int = 0) -> None:
        ctypes.memmove(self._addr(sym) + offset, data, len(data))

    def read(self, sym: str, n: int | None = None) -> bytes:
        n = self.b.symbols[sym][1] if n is None else n
        return ctypes.string_at(self._addr(sym), n)
