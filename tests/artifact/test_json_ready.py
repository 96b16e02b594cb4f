"""json_ready, the one encoder of the toolbox's JSON (toolbox/ARCHITECTURE.md
"controller.json": non-finite floats as strings, floats round-trip)."""

import math
from types import MappingProxyType

import numpy as np

from toolbox.artifact import json_ready


def test_plain_and_numpy_values_convert_by_the_same_rules():
    """The exact-type fast path of plain values (a speed-up) and the general
    rules for everything else give one result: plain JSON types only, bools
    kept bools, non-finite floats as strings, in lists, tuples and mappings."""
    doc = {"f": [1.5, math.inf, -math.inf, math.nan, -0.0],
           "n": (np.float64(2.5), np.float32(0.5), np.int64(3), np.bool_(True), np.float64("nan")),
           "b": [True, False, None, 1, "s"],
           "c": [1 + 2j, np.complex128(3 - 4j)],
           "a": np.array([[1.0, np.inf], [2.0, 3.0]]),
           "m": MappingProxyType({1: (2.0, [math.nan])}),
           "nested": [[1.0, 2.0], [], {}, ({"x": [np.float64(1.0), 2.0]},)]}
    out = json_ready(doc)
    assert out == {"f": [1.5, "inf", "-inf", "nan", -0.0],
                   "n": [2.5, 0.5, 3, True, "nan"],
                   "b": [True, False, None, 1, "s"],
                   "c": [[1.0, 2.0], [3.0, -4.0]],
                   "a": [[1.0, "inf"], [2.0, 3.0]],
                   "m": {"1": [2.0, ["nan"]]},
                   "nested": [[1.0, 2.0], [], {}, [{"x": [1.0, 2.0]}]]}

    def types(x):
        if isinstance(x, dict):
            return all(type(k) is str and types(v) for k, v in x.items())
        if isinstance(x, list):
            return all(types(v) for v in x)
        return type(x) in (float, int, str, bool, type(None))

    assert types(out)
    assert type(out["n"][3]) is bool and math.copysign(1.0, out["f"][4]) == -1.0


def test_controller_matrices_are_read_only_copies():
    """An artifact's matrices cannot be edited in place (the analysis keeps
    results keyed on a live controller, which such an edit would leave stale)
    and do not alias the caller's arrays."""
    import pytest

    from toolbox.artifact import StateSpaceData

    A = np.array([[1.0]])
    s = StateSpaceData(A, np.ones((1, 2)), np.ones((1, 1)), np.zeros((1, 2)), 1e-4, "zoh")
    A[0, 0] = 5.0
    assert s.A[0, 0] == 1.0
    for m in (s.A, s.B, s.C, s.D):
        assert m.dtype == float
        with pytest.raises(ValueError, match="read-only"):
            m[...] = 0.0
