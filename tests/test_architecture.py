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


def _family(module: str, root: Path = PACKAGE) -> str:
    """The root module a root module's part belongs to: ``toolbox._m_<part>``
    (split out of ``toolbox._m``, which re-exports its names) is one module
    with ``toolbox._m`` for the privacy rule; any other module is its own."""
    pkg, _, name = module.partition(".")
    if name.startswith("_") and "." not in name:
        stem = name
        while "_" in stem[1:]:
            stem = stem[:stem.rindex("_")]
            if root.joinpath(stem + ".py").is_file():
                return f"{pkg}.{stem}"
    return module


def _owner_of_private(target: str, root: Path = PACKAGE) -> str | None:
    """Package owning the first private component of a ``toolbox.*`` target.

    A private module ``toolbox.x._m`` belongs to ``toolbox.x``; a private name
    ``_n`` of a module ``toolbox.x.m`` belongs to the module's package
    ``toolbox.x`` too (siblings in one package may share helpers). The root
    package's modules (``toolbox._lti``, ``toolbox._io``, ...) serve every
    package through their public names: a private name of one of them
    belongs to that module alone (otherwise every package would be its
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
                # toolbox._m._n, toolbox.m._n: the module's (its parts' too)
                return _family(".".join(parts[:2]), root)
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
            if owner is not None and not (_family(me) == owner or me.startswith(owner + ".")):
                bad.append(f"{me}:{line} imports {target} (private to {owner})")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("source, expected", [
    ("from ..spec._load import _motor\n", "toolbox.spec._load._motor"),
    ("from ..analysis.margins import _electrical_max_speed\n",
     "toolbox.analysis.margins._electrical_max_speed"),
    ("import toolbox.design._common\n", "toolbox.design._common"),
    ("from toolbox.design import _hinf_riccati as H\n", "toolbox.design._hinf_riccati"),
    ("from .._lti import _zeros\n", "toolbox._lti._zeros"),
])
def test_checker_catches_reach_ins(tmp_path, source, expected):
    """The checker flags the reach-ins issue 11 item 8 removed (so it can fail)."""
    root = tmp_path / "toolbox"
    for sub in ("export", "spec", "analysis", "design"):
        (root / sub).mkdir(parents=True)
    (root / "_lti.py").write_text("")
    f = root / "export" / "c_header.py"
    f.write_text(source)
    (line, target), = _imports(f, root)
    assert target == expected
    owner = _owner_of_private(target, root)
    assert owner is not None and not _module_name(f, root).startswith(owner + ".")


def test_parts_of_a_root_module_share_its_private_names():
    """``_lti_linalg`` (a part of ``_lti``) and ``_lti`` share private names;
    other packages may not use them."""
    assert _owner_of_private("toolbox._lti_linalg._eig") == "toolbox._lti"
    assert _family("toolbox._lti_systems") == "toolbox._lti"
    assert _family("toolbox._lti") == "toolbox._lti"
    assert _family("toolbox.design._common") == "toolbox.design._common"
    assert not "toolbox.design.hinf".startswith(_owner_of_private("toolbox._lti_poly._poly"))


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
