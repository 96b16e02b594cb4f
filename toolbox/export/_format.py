"""C text of the header: comment sanitising (:func:`sanitise_comment`), range-checked
literals (float32 ``_f``/``_farr``, C int ``_int``, Q31 ``_q31``, shift counts
``_shift``), ``#error`` lines (``_c_error``) and the line accumulator ``_Text``.

Out of range, a literal is refused with :class:`toolbox.errors.ExportRefused`
naming the spec key responsible, so the header never holds ``inff``/``nan``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import ExportRefused


# ---------------------------------------------------------------------------
# comment sanitising
# ---------------------------------------------------------------------------
def sanitise_comment(text: Any, max_len: int = 200) -> str:
    """Make a user string safe inside a C block comment, on one line.

    Non-ASCII and control characters become ``\\uXXXX``/``\\xXX`` escapes,
    ``*/`` and ``/*`` are broken with a space, ``??`` (trigraph opener) is
    written ``?-?``, a backslash becomes ``\\x5c`` (never a line splice), and
    the text is cut to ``max_len`` characters.

    Parameters
    ----------
    text : object
        The user string (converted with ``str``).
    max_len : int
        Longest result (characters).

    Returns
    -------
    str
        Printable ASCII, safe inside ``/* ... */`` on one line.
    """
    out = []
    for ch in str(text):
        o = ord(ch)
        if ch == "\\":
            out.append("\\x5c")
        elif 32 <= o < 127:
            out.append(ch)
        elif o < 256:
            out.append(f"\\x{o:02x}")
        elif o < 0x10000:
            out.append(f"\\u{o:04x}")
        else:
            out.append(f"\\U{o:08x}")
    s = "".join(out)
    while "*/" in s or "/*" in s:
        s = s.replace("*/", "* /").replace("/*", "/ *")
    while "??" in s:
        s = s.replace("??", "?-?")
    if len(s) > max_len:
        s = s[:max_len - 3] + "..."
    return s


F32_MAX = float(np.finfo(np.float32).max)
F32_TINY = float(np.finfo(np.float32).tiny)       # smallest normal float32
C_INT_MAX = 32767          # the C99 guaranteed range of int (INT_MAX >= 32767)
C_INT32_MAX = 2 ** 31 - 1  # Q31 words and long constants


def _f(v: float, key: str, what: str) -> str:
    """A float literal (float32-rounded, 9 significant digits, always valid C).

    Parameters
    ----------
    v : float
        The value.
    key : str
        Spec key responsible for the value (named in the refusal).
    what : str
        The constant, in words (named in the refusal).

    Raises
    ------
    ExportRefused
        ``v`` is not finite, overflows float32 (|v| > 3.40e38, C would read
        ``inff``) or is a non-zero value below the smallest normal float32
        (1.18e-38; it would lose its precision or vanish).
    """
    try:
        x = float(v)
    except (TypeError, ValueError, OverflowError):
        raise ExportRefused(key, f"{what}: a number", v) from None
    with np.errstate(over="ignore"):
        f32 = float(np.float32(x))
    if not (math.isfinite(x) and math.isfinite(f32)):
        raise ExportRefused(key, f"{what} within the float32 range (|x| <= {F32_MAX:.3g})", x,
                            hint="controller.h would not compile or would compute inf/nan")
    if f32 == 0.0 and x != 0.0 or 0.0 < abs(f32) < F32_TINY:
        raise ExportRefused(key, f"{what} representable as a normal float32 (0 or |x| >= "
                            f"{F32_TINY:.3g})", x, hint="it would vanish or lose precision")
    if f32 == 0.0:
        return "0.0f"
    return f"{f32:.9e}f"


def _farr(values, key: str, what: str) -> str:
    return ", ".join(_f(v, key, what) for v in values)


def _int(v: Any, key: str, what: str, lo: int = -C_INT_MAX, hi: int = C_INT_MAX) -> int:
    """An integer constant within ``[lo, hi]`` (default: the C99 ``int`` range).

    Raises
    ------
    ExportRefused
        ``v`` is not an integral number in range.
    """
    try:
        ok = float(v) == int(v) and lo <= int(v) <= hi
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ExportRefused(key, f"{what}: an integer in [{lo}, {hi}]", v,
                            hint="controller.h would not compile or would overflow")
    return int(v)


def _q31(v: Any, key: str, what: str) -> str:
    """An int32 literal with the ``L`` suffix (long is at least 32 bits)."""
    return f"{_int(v, key, what, -C_INT32_MAX, C_INT32_MAX)}L"


def _shift(v: Any, key: str, what: str) -> str:
    """An unsigned shift count of an int64 value (0..62)."""
    return f"{_int(v, key, what, 0, 62)}u"


class _Text:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def __call__(self, line: str = "") -> None:
        self.lines.append(line)

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


def _c_error(what: str, reason: Any) -> str:
    """An ``#error`` line ``what: reason`` (the reason sanitised, its double
    quotes made single so the C string stays one token)."""
    return f"#error \"{what}: {sanitise_comment(reason).replace(chr(34), chr(39))}\""
