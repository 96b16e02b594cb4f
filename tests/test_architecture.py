"""Layering and privacy rules of the package, checked on the source (AST).

toolbox/ARCHITECTURE.md "Layers" and "Privacy rule":

* the layer order written in ARCHITECTURE.md (its "Layers" block): a
  package imports only packages of lower layers, so the package graph has
  no cycle;
* ``toolbox.spec`` is data: it never imports ``toolbox.design`` (the design
  methods register their parameter readers with the spec stage instead);
* a private module or name (``_x``) of a package is used only inside that
  package; other packages import the package's public face, which re-exports
  the public names in ``__all__``.

Every import statement counts, including those inside functions, and so do
the names ``toolbox._lazy.lazy_attributes`` imports on first use and
``importlib.import_module`` of a literal name.
"""

from __future__ import annotations

import ast
import functools
import gc
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "toolbox"


@functools.lru_cache(maxsize=None)
def _parsed(path: Path, text: str) -> ast.Module:
    """The parsed source (cached: the checks below walk every file several times).

    The cyclic garbage collector is off while parsing: the parser allocates
    a million nodes, none of them garbage, and the collections they trigger
    were half of the parse's time."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        return ast.parse(text, str(path))
    finally:
        if enabled:
            gc.enable()


def _parse(path: Path) -> ast.Module:
    return _parsed(path, path.read_text())


@functools.lru_cache(maxsize=None)
def _walk(tree: ast.AST) -> tuple[ast.AST, ...]:
    """Every node of a (cached) parsed tree, as ``ast.walk`` yields them; cached
    with the parse: walking was most of these checks' cost."""
    return tuple(ast.walk(tree))


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
    for node in _walk(_parse(path)):
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
    """spec -> design would re-create an import cycle (the method readers register instead)."""
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


# ---------------------------------------------------------------- layer order

DOC = PACKAGE / "ARCHITECTURE.md"
#: The PEP 562 helper (``lazy_attributes``): the submodules it imports are read
#: from the mapping each package passes it (:func:`_dynamic_imports`).
LAZY_HELPER = "toolbox._lazy"


def _layers(doc: Path = DOC) -> list[tuple[str, ...]]:
    """The layer order of ARCHITECTURE.md "Layers" (its first fenced block),
    lowest layer first; each layer a tuple of package names."""
    text = doc.read_text()
    section = text[text.index("## Layers\n"):]
    block = re.search(r"```\n(.*?)```", section, flags=re.S).group(1)
    rows = [tuple(n.strip() for n in line.split(",")) for line in block.splitlines()
            if line.strip()]
    return rows[::-1]


def _unit(module: str, root: Path = PACKAGE) -> str:
    """The package a module belongs to for the layer rule: ``toolbox.x.y`` ->
    ``x`` (a subpackage, or a root module ``toolbox/x.py``), ``toolbox``
    itself (the public face ``toolbox/__init__.py``, or a name imported from
    it) -> ``toolbox``."""
    parts = module.split(".")
    if len(parts) == 1:
        return "toolbox"
    head = parts[1]
    if root.joinpath(head).is_dir() or root.joinpath(head + ".py").is_file():
        return head
    return "toolbox"   # ``from toolbox import name``: a name of the public face


def _dynamic_imports(tree: ast.AST, name: str, package: str) -> list[tuple[int, str]]:
    """Imports made by name at run time: the values of the mapping passed to
    ``lazy_attributes(__name__, MAPPING, globals())`` (submodules of the
    package) and ``importlib.import_module("literal")``; a call whose target
    cannot be read off the source yields ``"?"`` (reported, never ignored)."""
    assigns = {t.id: node.value for node in _walk(tree) if isinstance(node, ast.Assign)
               for t in node.targets if isinstance(t, ast.Name)}
    out = []
    for node in _walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        fname = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
        if fname == "lazy_attributes" and len(node.args) >= 2:
            mapping = node.args[1]
            if isinstance(mapping, ast.Name):
                mapping = assigns.get(mapping.id)
            if not isinstance(mapping, ast.Dict):
                out.append((node.lineno, "?"))
                continue
            for value in mapping.values:
                ok = isinstance(value, ast.Constant) and isinstance(value.value, str)
                out.append((value.lineno, f"{name}.{value.value}" if ok else "?"))
        elif fname == "import_module" and node.args:
            arg = node.args[0]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                out.append((node.lineno, arg.value))
            elif (isinstance(arg, ast.JoinedStr) and arg.values
                  and isinstance(arg.values[0], ast.FormattedValue)
                  and getattr(arg.values[0].value, "id", None) in ("__package__", "__name__")):
                out.append((node.lineno, package))   # a module of the caller's own package
            else:
                out.append((node.lineno, "?"))
    return out


def _package_imports(path: Path, root: Path = PACKAGE) -> list[tuple[int, str]]:
    """``(line, imported package)`` of every import of another package in
    ``path``: static imports (any scope) and :func:`_dynamic_imports`."""
    name = _module_name(path, root)
    me = _unit(name, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = _parse(path)
    # the lazy helper's own import_module is read at its call sites instead
    dynamic = [] if name == LAZY_HELPER else _dynamic_imports(tree, name, package)
    out = []
    for line, target in _imports(path, root) + dynamic:
        if target == "?":
            out.append((line, "?"))
            continue
        if target.split(".")[0] != "toolbox":
            continue
        unit = _unit(target, root)
        if unit != me:
            out.append((line, unit))
    return out


def layer_violations(root: Path = PACKAGE, doc: Path = DOC) -> list[str]:
    """``file:line: a imports b ...`` for every import of a package of the same
    or a higher layer, of a package the layer order does not place, or made
    by a name the checker cannot read; empty when the order holds."""
    layers = _layers(doc)
    rank = {unit: k for k, layer in enumerate(layers) for unit in layer}
    bad = []
    for path in sorted(root.rglob("*.py")):
        me = _unit(_module_name(path, root), root)
        where = path.relative_to(root.parent)
        if me not in rank:
            bad.append(f"{where}:1: package {me!r} is not placed in the layer order")
            continue
        for line, unit in sorted(set(_package_imports(path, root))):
            if unit == "?":
                bad.append(f"{where}:{line}: {me} imports a module named at run time "
                           "that the checker cannot read (use a literal name)")
            elif unit not in rank:
                bad.append(f"{where}:{line}: {me} imports {unit}, which the layer "
                           "order does not place")
            elif rank[unit] >= rank[me]:
                bad.append(f"{where}:{line}: {me} (layer {rank[me]}) imports {unit} "
                           f"(layer {rank[unit]}): only lower layers may be imported")
    return bad


def package_cycles(root: Path = PACKAGE) -> list[list[str]]:
    """The cycles of the package import graph (strongly connected components
    of more than one package, or a package importing itself through a name)."""
    graph: dict[str, set[str]] = {}
    for path in sorted(root.rglob("*.py")):
        me = _unit(_module_name(path, root), root)
        graph.setdefault(me, set()).update(u for _, u in _package_imports(path, root)
                                           if u != "?")
    index, low, stack, on_stack, out = {}, {}, [], set(), []

    def visit(v: str) -> None:   # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_layer_order_holds():
    """Every package imports only lower layers (ARCHITECTURE.md "Layers")."""
    bad = layer_violations()
    assert not bad, "\n".join(bad)


def test_no_package_cycle():
    """The package graph, every import counted, has no cycle."""
    assert package_cycles() == []


def test_layer_order_covers_the_packages():
    """The walk sees the stages and the root face's lazy names (a wrong parse
    would make the layer check vacuous)."""
    layers = _layers()
    assert layers[0] == ("errors",) and layers[-1] == ("toolbox",)
    units = {_unit(_module_name(p)) for p in SOURCES}
    assert {"spec", "plant", "artifact", "sim", "analysis", "design", "verify", "pipeline",
            "cli", "toolbox"} <= units
    root_face = {u for _, u in _package_imports(PACKAGE / "__init__.py")}
    assert {"design", "spec", "artifact", "pipeline"} <= root_face   # artifact, pipeline: lazy


def _tree(tmp_path: Path, files: dict[str, str]) -> tuple[Path, Path]:
    """A synthetic ``toolbox`` with this repository's layer order and ``files``."""
    root = tmp_path / "toolbox"
    for rel, text in files.items():
        f = root / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
    doc = root / "ARCHITECTURE.md"
    doc.write_text(DOC.read_text())
    return root, doc


@pytest.mark.parametrize("files, expected", [
    # an in-function import of a higher layer (the spec -> sim scenario import of old)
    ({"spec/__init__.py": "", "sim/__init__.py": "from ..spec import Motor\n",
      "spec/_load.py": "def f():\n    x = 1\n    from ..sim import Scenario\n"},
     "toolbox/spec/_load.py:3: spec (layer 3) imports sim (layer 5)"),
    # ``from . import`` at the root, in a function
    ({"spec/__init__.py": "def f():\n    from .. import verify\n", "verify/__init__.py": ""},
     "toolbox/spec/__init__.py:2: spec (layer 3) imports verify (layer 8)"),
    # same layer
    ({"plant/__init__.py": "import toolbox.artifact\n", "artifact/__init__.py": ""},
     "toolbox/plant/__init__.py:1: plant (layer 4) imports artifact (layer 4)"),
    # a name of the public face
    ({"sim/_x.py": "from toolbox import design_spec\n", "__init__.py": ""},
     "toolbox/sim/_x.py:1: sim (layer 5) imports toolbox (layer 12)"),
    # a lazily exported name of a package placed below it
    ({"_io.py": "from ._lazy import lazy_attributes\n", "_lazy.py": "",
      "metrics.py": "import importlib\n\ndef f():\n    importlib.import_module('toolbox.sim')\n",
      "sim/__init__.py": ""},
     "toolbox/metrics.py:4: metrics (layer 1) imports sim (layer 5)"),
    # a run-time name the checker cannot read
    ({"design/_registry.py": "import importlib\nM = 'x'\n\ndef f():\n"
      "    return importlib.import_module(M)\n"},
     "toolbox/design/_registry.py:5: design imports a module named at run time"),
    # a package the order does not place
    ({"newstage/__init__.py": "from ..spec import Motor\n", "spec/__init__.py": ""},
     "toolbox/newstage/__init__.py:1: package 'newstage' is not placed"),
])
def test_layer_checker_fails_on_violations(tmp_path, files, expected):
    """Fed violating sources, the checker names the file and line."""
    root, doc = _tree(tmp_path, files)
    bad = layer_violations(root, doc)
    assert any(b.startswith(expected) for b in bad), bad


def test_layer_checker_reads_lazy_attributes(tmp_path):
    """The names ``lazy_attributes`` loads count as imports of their package."""
    root, doc = _tree(tmp_path, {
        "__init__.py": "from ._lazy import lazy_attributes\n"
                       "_LAZY = {'design_spec': 'pipeline'}\n"
                       "__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, globals())\n",
        "_lazy.py": "", "pipeline.py": "", "spec/__init__.py": "def f():\n    import toolbox\n"})
    assert (2, "pipeline") in _package_imports(root / "__init__.py", root)
    assert any(b.startswith("toolbox/spec/__init__.py:2: spec (layer 3) imports toolbox")
               for b in layer_violations(root, doc))


def test_cycle_checker_finds_a_cycle(tmp_path):
    """Two packages importing each other (inside functions) are a cycle."""
    root, _ = _tree(tmp_path, {"spec/__init__.py": "def f():\n    from ..sim import S\n",
                               "sim/__init__.py": "def g():\n    from ..spec import M\n",
                               "plant/__init__.py": "from ..spec import M\n"})
    assert package_cycles(root) == [["sim", "spec"]]
