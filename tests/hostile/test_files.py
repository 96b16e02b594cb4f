"""Files that are not what they claim: FIFOs, devices, huge files, deep nesting.

``cct check /dev/zero`` ran out of memory, a FIFO blocked forever, and a
100,000-deep nested TOML raised RecursionError inside tomllib. Each is now an
exit 2 with a message naming the file.
"""

from __future__ import annotations

import json
import os

import pytest

from toolbox._io import (_TOKEN, MAX_DEPTH, MAX_INPUT_BYTES, check_data_depth,
                         check_text_depth)
from toolbox.errors import ArtifactError, SpecError
from toolbox.spec import load_spec, spec_from_dict

from hostile_helpers import cct_subprocess, run_cli, spec_dict, to_toml


def test_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "spec.toml"
    os.mkfifo(fifo)
    # a child process: if the reader blocked on open(), the timeout (60 s, far
    # above the ~2 s start-up of the CLI) turns the hang into a test failure
    res = cct_subprocess("check", fifo, timeout=60)
    assert res.returncode == 2, res.stderr
    assert f"cct: error: {fifo}: expected a regular spec file, got \"a FIFO\"" in res.stderr


def test_fifo_in_process_returns_at_once(tmp_path):
    fifo = tmp_path / "controller.json"
    os.mkfifo(fifo)
    # open() on a FIFO without a writer blocks: it returning at all is the check
    # (the subprocess test above turns such a hang into a failure)
    res = run_cli("verify", tmp_path)
    assert res.exit_code == 2
    assert f"{fifo}: expected a regular controller.json file, got \"a FIFO\"" in res.output


def test_dev_zero_is_refused():
    with pytest.raises(SpecError) as info:
        load_spec("/dev/zero")
    assert str(info.value) == '/dev/zero: expected a regular spec file, got "a device"'
    res = run_cli("check", "/dev/zero")
    assert res.exit_code == 2 and "MemoryError" not in res.output


def test_directory_is_refused(tmp_path):
    with pytest.raises(SpecError) as info:
        load_spec(tmp_path)
    assert str(info.value) == f'{tmp_path}: expected a regular spec file, got "a directory"'
    assert run_cli("check", tmp_path).exit_code == 2  # click's own check says it first


def test_file_over_the_size_cap(tmp_path):
    path = tmp_path / "big.toml"
    path.write_bytes(b"#" * (MAX_INPUT_BYTES + 1))  # a comment: valid TOML but too big
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert str(info.value) == (f"{path}: expected a spec file of at most 1048576 bytes, "
                               f'got "{MAX_INPUT_BYTES + 1} bytes"')


def test_file_at_the_size_cap_is_read(tmp_path):
    text = to_toml(spec_dict())
    path = tmp_path / "full.toml"
    path.write_text(text + "#" * (MAX_INPUT_BYTES - len(text.encode())))
    assert path.stat().st_size == MAX_INPUT_BYTES
    assert load_spec(path).motor.R == 0.6


def test_missing_file(tmp_path):
    with pytest.raises(SpecError) as info:
        load_spec(tmp_path / "nope.toml")
    assert str(info.value) == (f"{tmp_path / 'nope.toml'}: expected a readable spec file, "
                               f'got "No such file or directory"')


DEEP = 100_000


@pytest.mark.parametrize("name, text", [
    ("arrays", "x = " + "[" * DEEP + "]" * DEEP + "\n"),
    ("inline_tables", "x = " + "{a = " * DEEP + "1" + "}" * DEEP + "\n"),
    ("dotted_key", "a" + ".a" * DEEP + " = 1\n"),
    ("table_header", "[" + "a." * DEEP + "a]\nx = 1\n"),
    ("unclosed", "x = " + "[" * DEEP + "\n"),
], ids=lambda v: v if len(v) < 20 else "")
def test_deeply_nested_toml_is_refused_before_parsing(tmp_path, name, text, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("tomllib parsed the text")

    # refused by the linear pre-scan; tomllib itself went quadratic on the dotted key
    monkeypatch.setattr("toolbox.spec._load.tomllib.loads", never)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert str(info.value) == (f"{path}: expected nesting at most 32 levels deep, "
                               'got "deeper nesting at line 1"')


def test_deep_toml_cli_exit_2(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("x = " + "[" * DEEP + "]" * DEEP + "\n")
    res = run_cli("check", path)
    assert res.exit_code == 2
    assert "RecursionError" not in res.output and "nesting at most 32" in res.output


def test_nesting_limit_counts_levels_exactly():
    ok = "x = " + "[" * MAX_DEPTH + "]" * MAX_DEPTH
    check_text_depth(ok, SpecError)  # 32 levels: accepted
    with pytest.raises(SpecError):
        check_text_depth("x = " + "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1), SpecError)


@pytest.mark.parametrize("text", [
    'x = "' + "[" * 1000 + '"',                 # brackets inside a string
    "x = '" + "{" * 1000 + "'",                 # literal string
    'x = """\n' + "[" * 1000 + '\n"""',         # multi-line string
    "# " + "[" * 1000 + "\nx = 1",              # comment
    "x = [" + ", ".join(["1.5"] * 1000) + "]",  # many floats, one level
    'a."b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r.s.t.u.v.w.x.y.z.1.2.3.4.5.6.7.8" = 1',
], ids=["string", "literal", "multiline", "comment", "floats", "quoted_key"])
def test_nesting_scan_ignores_what_is_not_nesting(text):
    check_text_depth(text, SpecError)


def test_data_depth_is_checked_without_recursion():
    data: dict = {}
    node = data
    for _ in range(DEEP):  # deeper than Python's recursion limit
        node["a"] = {}
        node = node["a"]
    with pytest.raises(SpecError) as info:
        spec_from_dict({**spec_dict(), "title": data})
    assert "expected nesting at most 32 levels deep" in str(info.value)
    with pytest.raises(ArtifactError):
        check_data_depth([[[[]]]], ArtifactError, limit=2)  # the innermost list is level 3
    check_data_depth([[[[]]]], ArtifactError, limit=3)


def test_deep_json_controller_is_an_artifact_error(tmp_path):
    (tmp_path / "controller.json").write_text("[" * DEEP + "]" * DEEP)
    res = run_cli("export", tmp_path)
    assert res.exit_code == 2
    path = tmp_path / "controller.json"
    assert (f'cct: error: {path}: expected nesting at most 32 levels deep, got "deeper '
            f'nesting at line 1"') in res.output


def test_oversized_controller_json(tmp_path):
    (tmp_path / "controller.json").write_text(json.dumps({"pad": "x" * MAX_INPUT_BYTES}))
    res = run_cli("verify", tmp_path)
    assert res.exit_code == 2
    assert "expected a controller.json file of at most 1048576 bytes" in res.output


def test_python_m_toolbox_cli_runs():
    res = cct_subprocess("--help", timeout=60)
    assert res.returncode == 0 and "Usage: cct" in res.stdout


@pytest.mark.parametrize("text", [
    '"' + '\\"' * (MAX_INPUT_BYTES // 2),            # one unterminated string of escapes
    '"""' + "x" * (MAX_INPUT_BYTES - 3),             # unterminated multi-line string
    ("'" * 7 + "\n") * (MAX_INPUT_BYTES // 8),
    # a lone backslash at the end failed every string match (quadratic; found
    # by the growth check below on a quarter of "escaped_quotes")
    '"' + '\\"' * (MAX_INPUT_BYTES // 2 - 1) + "\\",
    '"""' + '\\"' * (MAX_INPUT_BYTES // 2 - 2) + "\\",
], ids=["escaped_quotes", "open_multiline", "quote_runs", "trailing_backslash",
        "multiline_trailing_backslash"])
def test_nesting_scan_is_linear_on_pathological_strings(text):
    """A scan that re-tried each quote went quadratic (16 kB took 4 s; a lone
    backslash at the end, 1.8 s at 16 kB): a string token that fails to match
    at a quote is re-attempted at the next quote, each attempt running to the
    end. The scan is linear when the string alternative matches at every quote,
    checked here at each quote of the text's first 2 kB, cut at three offsets
    (the cut decides whether a lone backslash ends it); then the whole 1 MiB
    text is scanned."""
    for cut in (2048, 2049, 2050):
        part = text[:cut]
        for i, ch in enumerate(part):
            if ch in "\"'":
                assert _TOKEN.match(part, i).lastgroup == "string", (cut, i)
    check_text_depth(text, SpecError)
