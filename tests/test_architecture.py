"""Layering and privacy rules of the package, checked on the source (AST).

toolbox/ARCHITECTURE.md "Layers" and "Privacy rule":

* ``toolbox.spec`` is data: it never imports ``toolbox.design`` (the design
  methods register their parameter readers with the spec stage instead);
* a private module or name (``_x``) of a package is used only inside that
  package; other packages import the package's public face, which re-exports
  the public names in ``__all__``.

Every import statement counts, including those inside functions.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "toolbox"


def _module_name(path: Path, root: Path = PACKAGE) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, root: Path = PACKAGE) -> list[tuple[int, str]]:
    """``(line, dotted target)`` of every import in ``path``; ``from A import b``
    yields ``A.b`` (b may be a module or a name: both are checked alike)."""
    name = _module_name(path, root)
    is_pkg = path.name == "__init__.py"
    package = name if is_pkg else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out += [(node.lineno, f"{mod}.{a.name}") for a in node.names if a.name != "*"]
    return out


def _owner_of_private(target: str, root: Path = PACKAGE) -> str | None:
    """Package owning the first private component of a ``toolbox.*`` target.

    A private module ``toolbox.x._m`` belongs to ``toolbox.x`` (so
    ``toolbox.lti._systems`` and every name in it belong to ``toolbox.lti``);
    a private name ``_n`` of a module ``toolbox.x.m`` belongs to the module's
    package ``toolbox.x`` too (siblings in one package may share helpers).
    The root package's modules (``toolbox._io``, ``toolbox._cache``, ...)
    serve every package through their public names: a private name of one of
    them belongs to that module alone (otherwise every package would be its
    sibling and no reach-in into them would ever be flagged).
    """
    parts = target.split(".")
    if parts[0] != "toolbox":
        return None
    for i, part in enumerate(parts[1:], start=1):
        if part.startswith("_") and not part.startswith("__"):
            root_module = root.joinpath(parts[1] + ".py").is_file()
            name_private = i == 2 or (len(parts) > 2 and parts[2].startswith("_")
                                      and not parts[2].startswith("__"))
            if root_module and name_private:
                return ".".join(parts[:2])       # toolbox._m._n, toolbox.m._n: the module's
            prefix = parts[:i]
            is_package = root.parent.joinpath(*prefix).is_dir()
            return ".".join(prefix if is_package else prefix[:-1])
    return None


SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_sources_found():
    """The walk sees the package (a wrong path would make every check vacuous)."""
    names = {_module_name(p) for p in SOURCES}
    assert {"toolbox.spec._load", "toolbox.design.hinf", "toolbox.analysis.margins"} <= names


def test_spec_does_not_import_design():
    """spec -> design would re-create the import cycle of issue 11 item 5."""
    bad = [f"{_module_name(p)}:{line} imports {t}" for p in SOURCES
           if _module_name(p).startswith("toolbox.spec")
           for line, t in _imports(p) if t == "toolbox.design" or t.startswith("toolbox.design.")]
    assert not bad, "\n".join(bad)


def test_no_private_reach_ins():
    """No module uses another package's private module or name."""
    bad = []
    for p in SOURCES:
        me = _module_name(p)
        for line, target in _imports(p):
            owner = _owner_of_private(target)
            if owner is not None and not (me == owner or me.startswith(owner + ".")):
                bad.append(f"{me}:{line} imports {target} (private to {owner})")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("source, expected", [
    ("from ..spec._load import _motor\n", "toolbox.spec._load._motor"),
    ("from ..analysis.margins import _electrical_max_speed\n",
     "toolbox.analysis.margins._electrical_max_speed"),
    ("import toolbox.design._common\n", "toolbox.design._common"),
    ("from toolbox.design import _hinf_riccati as H\n", "toolbox.design._hinf_riccati"),
    ("from ..lti._linalg import invariant_zeros\n", "toolbox.lti._linalg.invariant_zeros"),
    ("from ..lti import _systems\n", "toolbox.lti._systems"),
    ("from toolbox.lti import _eig\n", "toolbox.lti._eig"),
    ("from .._io import _tmp\n", "toolbox._io._tmp"),
])
def test_checker_catches_reach_ins(tmp_path, source, expected):
    """The checker flags reach-ins into another package's private modules and
    names, toolbox.lti's included (so it can fail)."""
    root = tmp_path / "toolbox"
    for sub in ("export", "spec", "analysis", "design", "lti"):
        (root / sub).mkdir(parents=True)
    (root / "lti" / "__init__.py").write_text("")
    (root / "lti" / "_linalg.py").write_text("")
    (root / "_io.py").write_text("")
    f = root / "export" / "c_header.py"
    f.write_text(source)
    (line, target), = _imports(f, root)
    assert target == expected
    owner = _owner_of_private(target, root)
    assert owner is not None and not _module_name(f, root).startswith(owner + ".")


def test_lti_private_names_belong_to_lti():
    """``toolbox.lti``'s private modules and names are its own: its modules
    may share them, other packages may not (they import ``toolbox.lti``'s
    public face)."""
    assert _owner_of_private("toolbox.lti._linalg._eig") == "toolbox.lti"
    assert _owner_of_private("toolbox.lti._systems") == "toolbox.lti"
    assert _owner_of_private("toolbox.lti._poly") == "toolbox.lti"
    assert _owner_of_private("toolbox.lti.StateSpace") is None
    assert "toolbox.lti._norms".startswith(_owner_of_private("toolbox.lti._systems") + ".")
    assert not "toolbox.design.hinf".startswith(_owner_of_private("toolbox.lti._poly._poly"))


def test_no_root_level_lti_modules():
    """The linear-system layer is the package ``toolbox.lti`` alone: no
    ``toolbox/_lti*.py`` module (nor a shim of one) is left at the root."""
    assert (PACKAGE / "lti" / "__init__.py").is_file()
    assert not sorted(PACKAGE.glob("_lti*.py"))


def test_method_readers_registered():
    """Every method the spec accepts has a reader registered by toolbox.design."""
    import toolbox  # noqa: F401  (imports toolbox.design, which registers)
    from toolbox.spec import METHODS, registered_methods
    assert set(registered_methods()) == set(METHODS)


def test_unregistered_method_is_a_located_spec_error():
    """A method without a reader is refused naming controller.method and the remedy."""
    from toolbox.errors import SpecError
    from toolbox.spec import read_method_cfg
    with pytest.raises(SpecError, match=r"controller\.method: expected a method with a "
                                        r"registered parameter reader .*got \"nope\""):
        read_method_cfg("nope", None, None, None)


def test_test_module_basenames_are_unique():
    """pytest's default (prepend) import mode imports test modules by basename:
    two ``test_x.py`` in different folders stop the whole run at collection,
    which a run of one folder does not show."""
    tests = Path(__file__).parent
    names = [p.name for p in tests.rglob("test_*.py")]
    assert len(names) == len(set(names)), sorted({n for n in names if names.count(n) > 1})
