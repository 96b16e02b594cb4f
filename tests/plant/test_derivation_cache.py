"""On-disk cache of the symbolic derivation (toolbox/_cache.py; toolbox/ARCHITECTURE.md
"Caches and lazy imports").

The cached model must be *identical* to a fresh derivation: sympy
expressions are compared structurally (``==``, no simplification, no
tolerance), so any drift between the cached and the derived model fails.
"""

from __future__ import annotations

import pytest

from toolbox import _cache
from toolbox.plant import _symbolic
from toolbox.plant._symbolic import DqModel, _derive_dq_model


@pytest.fixture(scope="module")
def fresh():
    """The derivation without any cache (the reference), derived once (~2.4 s each)."""
    return {c: _derive_dq_model(c) for c in _symbolic.CONVENTIONS}


@pytest.fixture(scope="module")
def models():
    """The models as the toolbox gives them (read from the user's cache, or
    derived and cached there): what the stand-in of ``derivations`` returns.
    Equality with a derivation without any cache is asked of ``fresh``, by
    the tests marked slow (a fresh derivation costs ~2.4 s of sympy each)."""
    return {c: _symbolic.derive_dq_model(c) for c in _symbolic.CONVENTIONS}


@pytest.fixture
def derivations(models, tmp_path, monkeypatch):
    """A private cache directory, the lru_cache cleared, and the derivation
    replaced by a counting stand-in returning the model of ``models`` (so that a
    test can tell a cache hit from a recomputation, at no sympy cost)."""
    monkeypatch.delenv("CCT_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    calls: list[str] = []

    def derive(convention: str) -> DqModel:
        calls.append(convention)
        return models[convention]

    monkeypatch.setattr(_symbolic, "_derive_dq_model", derive)
    _symbolic.derive_dq_model.cache_clear()
    yield tmp_path / "current-control-toolbox", calls
    _symbolic.derive_dq_model.cache_clear()


def _fields(m: DqModel) -> tuple:
    return (m.convention, m.di_dt, m.voltage, m.torque, m.dOmega_dt, m.inductance_map)


@pytest.mark.slow
@pytest.mark.parametrize("convention", _symbolic.CONVENTIONS)
def test_cached_model_equals_fresh_derivation(derivations, fresh, convention):
    """Write, then read back from disk: structurally equal to the re-derivation."""
    cache_home, calls = derivations
    first = _symbolic.derive_dq_model(convention)
    files = list(cache_home.glob(f"dq_model-{convention}-*.pickle"))
    assert len(files) == 1
    _symbolic.derive_dq_model.cache_clear()  # force the disk read
    loaded = _symbolic.derive_dq_model(convention)
    assert loaded is not first  # really came from disk
    assert calls == [convention]  # derived once, then read
    assert _fields(loaded) == _fields(fresh[convention]) == _fields(first)
    # the symbols keep their assumptions (positive, real) through the pickle
    assert loaded.di_dt.free_symbols == fresh[convention].di_dt.free_symbols


@pytest.mark.parametrize("damage", [b"", b"garbage", "truncate", "flip"])
def test_corrupted_cache_is_ignored_and_rewritten(derivations, models, damage):
    """A damaged entry is never unpickled as is: re-derived, then rewritten."""
    cache_home, calls = derivations
    _symbolic.derive_dq_model("amplitude")
    path, = cache_home.glob("dq_model-amplitude-*.pickle")
    raw = path.read_bytes()
    if damage == "truncate":
        bad = raw[: len(raw) // 2]
    elif damage == "flip":
        bad = raw[:-10] + bytes([raw[-10] ^ 0xFF]) + raw[-9:]
    else:
        bad = damage
    path.write_bytes(bad)
    assert _cache._read(path, _cache.cache_key(_symbolic.__file__)) is None
    _symbolic.derive_dq_model.cache_clear()
    model = _symbolic.derive_dq_model("amplitude")
    assert _fields(model) == _fields(models["amplitude"])
    assert calls == ["amplitude", "amplitude"]  # the damaged entry was not used
    assert path.read_bytes() == raw  # rewritten whole


def test_key_follows_the_source(tmp_path):
    """Editing the derivation's source changes the key (a stale entry is never read)."""
    src = tmp_path / "a.py"
    src.write_text("x = 1\n")
    k1 = _cache.cache_key(src)
    src.write_text("x = 2\n")
    assert _cache.cache_key(src) != k1
    assert _cache.cache_key(_symbolic.__file__) == _cache.cache_key(_symbolic.__file__)


def test_entry_of_another_key_is_not_read(derivations):
    """A file whose header names another key is ignored."""
    cache_home, _ = derivations
    _symbolic.derive_dq_model("power")
    path, = cache_home.glob("dq_model-power-*.pickle")
    assert _cache._read(path, "0" * 16) is None


def test_cache_can_be_disabled(tmp_path, monkeypatch):
    """CCT_CACHE_DIR=off: nothing is written, the value is still computed."""
    monkeypatch.setenv("CCT_CACHE_DIR", "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert _cache.cache_dir() is None
    assert _cache.cached("x", _symbolic.__file__, lambda: 42, lambda v: True) == 42
    assert not any(tmp_path.iterdir())


def test_unwritable_cache_is_not_an_error(tmp_path, monkeypatch):
    """A cache directory that cannot be created: computed, no exception."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("CCT_CACHE_DIR", str(blocker / "sub"))
    assert _cache.cached("x", _symbolic.__file__, lambda: 7, lambda v: True) == 7


def test_wrong_type_in_cache_is_recomputed(derivations):
    """An entry that unpickles to something else (check fails) is recomputed."""
    cache_home, calls = derivations
    key = _cache.cache_key(_symbolic.__file__)
    _cache._write(cache_home / f"dq_model-amplitude-{key}.pickle", key, "not a model")
    model = _symbolic.derive_dq_model("amplitude")
    assert isinstance(model, DqModel) and model.convention == "amplitude"
    assert calls == ["amplitude"]


@pytest.mark.parametrize("convention", _symbolic.CONVENTIONS)
def test_cached_numeric_model_equals_lambdify(derivations, tmp_path, monkeypatch, convention):
    """The numeric A(omega), B, e(omega) re-created from the cached code of
    lambdify (toolbox/plant/_numeric.py) return exactly, bit for bit, what the
    functions lambdify returns do, at random parameter points; the second call
    reads the cache (the code is not generated again). The symbolic model is
    the module's reference derivation (``derivations``): the private cache
    directory is empty, so it would otherwise be derived again (2 s each)."""
    import numpy as np
    import sympy as sp

    from toolbox.plant import _numeric

    monkeypatch.setenv("CCT_CACHE_DIR", str(tmp_path))
    generated: list[str] = []
    real = _numeric._electrical_sources

    def counting(c):
        generated.append(c)
        return real(c)

    monkeypatch.setattr(_numeric, "_electrical_sources", counting)
    _numeric._electrical_matrices.cache_clear()
    first = _numeric._electrical_matrices(convention)
    _numeric._electrical_matrices.cache_clear()
    cached = _numeric._electrical_matrices(convention)
    _numeric._electrical_matrices.cache_clear()
    assert generated == [convention] and len(list(tmp_path.iterdir())) >= 1

    S = _symbolic.SYMBOLS
    model = _symbolic.derive_dq_model(convention)
    x, u = sp.Matrix([S["i_d"], S["i_q"]]), sp.Matrix([S["v_d"], S["v_q"]])
    A, B = model.di_dt.jacobian(x), model.di_dt.jacobian(u)
    e = sp.simplify(model.di_dt - A * x - B * u)
    args = (S["R"], S["L_d"], S["L_q"], S["psi_f"], S["omega"])
    ref = [sp.lambdify(args, m, "numpy") for m in (A, B, e)]
    rng = np.random.default_rng(3)
    for point in rng.uniform([0.01, 1e-4, 1e-4, 0.01, -3000], [5, 0.05, 0.05, 1, 3000],
                             size=(20, 5)):
        for f_ref, f_cached, f_first in zip(ref, cached, first):
            want = np.asarray(f_ref(*point), float)
            assert np.array_equal(np.asarray(f_cached(*point), float), want)
            assert np.array_equal(np.asarray(f_first(*point), float), want)


@pytest.mark.slow
def test_report_equations_cached_equal_derived(tmp_path, monkeypatch):
    """The report's equation rows read from the cache are those derived and
    typeset afresh (LaTeX, text and SVG strings identical)."""
    import types

    from toolbox.report import _derived_equations, _equations

    monkeypatch.setenv("CCT_CACHE_DIR", str(tmp_path))
    spec = types.SimpleNamespace(motor=types.SimpleNamespace(convention="amplitude"))
    fresh = _derived_equations("amplitude")
    assert _equations(spec) == fresh  # computed and written
    path, = tmp_path.glob("report_equations-amplitude-*.pickle")
    import toolbox.report

    def no_derivation(_):
        raise AssertionError("derived again instead of read from the cache")

    monkeypatch.setattr(toolbox.report, "_derived_equations", no_derivation)
    assert _equations(spec) == fresh  # read back
    assert len(fresh) == 6 and all(r["svg"].lstrip().startswith("<svg") for r in fresh)
