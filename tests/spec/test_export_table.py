"""``[export]`` table of the spec: the C prefix of controller.h (toolbox/ARCHITECTURE.md
"controller.h", Names)."""

import pytest

from toolbox.errors import SpecError
from toolbox.spec import spec_from_dict
from toolbox.spec._render import spec_to_toml

BASE = {"motor": {"catalog": "azaiz2007"}, "drive": {"vdc": 150, "sample_time": 1e-4},
        "controller": {"method": "pi"}}


def test_default_and_given_prefix():
    assert spec_from_dict(BASE).export_prefix == "cct_"
    spec = spec_from_dict({**BASE, "export": {"prefix": "motor1_"}})
    assert spec.export_prefix == "motor1_"
    # cct check prints it, and what it prints reads back the same
    import tomllib
    text = spec_to_toml(spec)
    assert '[export]\nprefix = "motor1_"' in text
    assert spec_from_dict(tomllib.loads(text)).export_prefix == "motor1_"
    assert "[export]" not in spec_to_toml(spec_from_dict(BASE))


@pytest.mark.parametrize("table, key, words", [
    ({"prefix": "1m"}, "export.prefix", "C identifier prefix"),
    ({"prefix": "_"}, "export.prefix", "C identifier prefix"),
    ({"prefix": "a" * 32}, "export.prefix", "C identifier prefix"),
    ({"prefix": "m\n"}, "export.prefix", "C identifier prefix"),   # re.match's $ took it
    ({"prefix": "motor1_\n"}, "export.prefix", "C identifier prefix"),
    ({"prefix": 3}, "export.prefix", "a string"),
    ({"prefx": "m_"}, "export.prefx", "did you mean"),
])
def test_bad_prefix_refused(table, key, words):
    with pytest.raises(SpecError) as err:
        spec_from_dict({**BASE, "export": table})
    assert key in str(err.value) and words in str(err.value)
