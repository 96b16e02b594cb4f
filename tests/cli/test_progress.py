"""Progress bars on stderr; ``-q`` silences the bar, never the result summary
(README.md "Commands").

Under the test runner stderr is not a terminal, so the bar is one line per
step (``  - [k/N] step ...``), recognised by its counter; the redrawn tqdm
bar of a terminal (``k/N steps``) is checked on :class:`StepBar` directly.
The summary is recognised the summary by the ``requirements:`` verdict line
(``cct design``) and the table header (``cct compare``). Only the
``--only-controller`` design (a fraction of a second) runs here, plus one
two-spec comparison: the checks are on what is printed, never on time.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from toolbox.cli import main
from toolbox.cli._progress import StepBar, design_stages

DESIGNS = Path(__file__).resolve().parents[2] / "designs"
BAR = re.compile(r"\[\d+/\d+\]|\d+/\d+ steps")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.mark.parametrize("quiet", [False, True])
def test_design_bar_and_summary(tmp_path, quiet):
    """Bar (with the stage name) on stderr unless -q; the verdict line on stdout always."""
    res = run("design", DESIGNS / "000_lepioufle1992_tc.toml", "--out", tmp_path,
              "--only-controller", *(["-q"] if quiet else []))
    assert res.exit_code == 0, res.output
    assert "requirements:" in res.stdout
    if quiet:
        assert res.stderr == ""  # nothing at all: no bar, no "wrote" lines
    else:
        assert "  - [1/1] design ..." in res.stderr
        assert "wrote" in res.stderr
    assert not BAR.search(res.stdout)  # stdout stays clean for pipes


def test_compare_quiet_keeps_table(tmp_path):
    """cct compare -q: no bar, the table and the FAIL lines are still printed."""
    specs = [DESIGNS / "000_lepioufle1992_pi.toml", DESIGNS / "000_lepioufle1992_tc.toml"]
    res = CliRunner().invoke(main, ["compare", *map(str, specs), "-q"])
    assert res.exit_code == 1, res.output  # paper 000's PI fails its requirements
    assert not BAR.search(res.stderr) and not BAR.search(res.stdout)
    assert "GM dB" in res.stdout and "FAIL" in res.stdout


@pytest.mark.parametrize("tty", [True, False])
def test_step_bar_protocol(capsys, tty):
    """Named steps advance the bar; other strings are messages; quiet prints nothing."""
    with StepBar(["a", "b"], quiet=False, desc="t", tty=tty) as bar:
        bar("a")
        bar("note: something")
        bar("b")
        assert bar._started == 2  # "a" done, "b" running
    err = capsys.readouterr().err
    assert "  - note: something" in err
    if tty:
        assert "t: b" in err and "1/2 steps" in err  # redrawn tqdm bar
    else:
        assert err.splitlines() == ["  - [1/2] a ...", "  - note: something",
                                    "  - [2/2] b ..."]
    with StepBar(["a"], quiet=True, tty=tty) as bar:
        bar("a")
        bar("message")
    assert capsys.readouterr() == ("", "")


def test_design_stages_follow_flags():
    """The planned stages are the ones build_outputs reports, in its order."""
    assert design_stages(True, True, True, True) == (
        "design", "analysis", "verification", "firmware header", "report")
    assert design_stages(False, False, False, False) == ("design",)
