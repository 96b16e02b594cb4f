"""The on-disk cache's size bound (toolbox/_cache.py; toolbox/ARCHITECTURE.md
"Caches and lazy imports"): a family keeps its most recently used entries."""

from __future__ import annotations

import os

from toolbox import _cache


def test_a_family_keeps_its_most_recently_used_entries(tmp_path, monkeypatch):
    """Three entries allowed: after four writes with a hit on the oldest in
    between, the least recently used one is gone (it is computed again),
    the others are read, and another family is left alone."""
    monkeypatch.setenv("CCT_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_cache, "MAX_ENTRIES", 3)
    src = tmp_path / "source.py"
    src.write_text("x = 1\n")
    calls = []

    def get(name: str, i: int):
        return _cache.cached(f"{name}-{i}", src, lambda: calls.append((name, i)) or i,
                             lambda v: v == i, packages=())

    get("other", 0)
    for i in range(3):
        get("fam", i)
    for i in range(3):   # an explicit order of use (coarse file-system time stamps)
        (path,) = tmp_path.glob(f"fam-{i}-*.pickle")
        os.utime(path, (1e9 + i, 1e9 + i))
    assert get("fam", 0) == 0     # a hit: now the most recently used
    get("fam", 3)                 # a fourth entry: fam-1 goes
    assert sorted(p.name.split("-")[1] for p in tmp_path.glob("fam-*.pickle")) == ["0", "2", "3"]
    assert len(list(tmp_path.glob("other-*.pickle"))) == 1
    assert calls == [("other", 0), ("fam", 0), ("fam", 1), ("fam", 2), ("fam", 3)]
    assert get("fam", 1) == 1 and calls[-1] == ("fam", 1)      # computed again ...
    assert get("fam", 3) == 3 and calls[-1] == ("fam", 1)      # ... a recent one read
    assert not list(tmp_path.glob("fam-2-*.pickle"))            # the oldest, fam-2, went
