"""The on-disk cache of compiled jinja2 templates (toolbox._cache.template_bytecode_cache).

A header rendered through the cache must be the same text as one compiled
afresh; the entries must be keyed by the module building the environment (its
options are not part of jinja2's own key), and a disabled cache writes nothing.
"""

from __future__ import annotations

from toolbox import _cache
from toolbox.export import c_header

from export_artifacts import DRIVE, MOTOR, hinf_artifact


def _header_fresh_env(monkeypatch) -> str:
    monkeypatch.setattr(c_header, "_ENV", None)  # a new environment, as in a new process
    return c_header.write_header(hinf_artifact(), MOTOR, DRIVE)


def test_cached_templates_render_as_a_fresh_compile(tmp_path, monkeypatch):
    monkeypatch.setenv("CCT_CACHE_DIR", "off")
    fresh = _header_fresh_env(monkeypatch)
    monkeypatch.setenv("CCT_CACHE_DIR", str(tmp_path))
    first = _header_fresh_env(monkeypatch)          # compiles, writes the entries
    entries = sorted((tmp_path / "jinja").iterdir())
    assert entries, "no compiled template was cached"
    second = _header_fresh_env(monkeypatch)         # loads the entries
    assert fresh == first == second
    assert sorted((tmp_path / "jinja").iterdir()) == entries


def test_entries_are_keyed_by_the_owning_module(tmp_path, monkeypatch):
    monkeypatch.setenv("CCT_CACHE_DIR", str(tmp_path))
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("OPTIONS = 1\n")
    b.write_text("OPTIONS = 2\n")
    pattern_a = _cache.template_bytecode_cache(a).pattern
    pattern_b = _cache.template_bytecode_cache(b).pattern
    assert pattern_a != pattern_b


def test_disabled_cache_compiles_every_time(tmp_path, monkeypatch):
    monkeypatch.setenv("CCT_CACHE_DIR", "off")
    assert _cache.template_bytecode_cache(c_header.__file__) is None
