"""Every public name of every stage is documented, and every documented
function names each of its parameters (as python-control's docstrings_test)."""

import importlib
import inspect

import pytest

PACKAGES = ["toolbox", "toolbox.spec", "toolbox.plant", "toolbox.artifact", "toolbox.design",
            "toolbox.analysis", "toolbox.sim", "toolbox.verify", "toolbox.metrics",
            "toolbox.export", "toolbox.report"]


def public_objects():
    for name in PACKAGES:
        module = importlib.import_module(name)
        for attr in getattr(module, "__all__", []):
            obj = getattr(module, attr)
            if inspect.isfunction(obj) or inspect.isclass(obj):
                yield f"{name}.{attr}", obj


OBJECTS = dict(public_objects())


@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_documented(name):
    obj = OBJECTS[name]
    doc = inspect.getdoc(obj)
    assert doc and len(doc.strip()) > 10, f"{name} has no docstring"
    if inspect.isfunction(obj):
        params = [p for p in inspect.signature(obj).parameters.values()
                  if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
        missing = [p.name for p in params if p.name not in doc]
        assert not missing, f"{name}: parameters not documented: {missing}"
