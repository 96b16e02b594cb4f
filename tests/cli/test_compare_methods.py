"""``cct compare SPEC --method all``: every method on one corpus motor, side
by side. On the NEMA 23 servo of tests/corpus/datasheets robust_pi is
infeasible at its default 0.5 disk margin: it is listed as refused with its
file, key and reason, the ten others are designed, verified and ranked, and
the exit code is 1 (a refused design fails the comparison)."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from toolbox.cli import main
from toolbox.spec import METHODS

SPEC = Path(__file__).parents[1] / "corpus" / "datasheets" / "nema23_teknic_hudson_2311.toml"


def test_compare_all_methods_on_one_motor(tmp_path):
    out = tmp_path / "cmp.json"
    res = CliRunner().invoke(main, ["compare", str(SPEC), "--method", "all", "--json",
                                    str(out), "-q"])
    assert res.exit_code == 1, res.output
    lines = res.output.splitlines()
    assert lines[0].split()[:3] == ["rank", "method", "BW"]
    table = lines[1:1 + len(METHODS) - 1]
    ranks = [int(line.split()[0]) for line in table]
    assert ranks == list(range(1, len(METHODS)))          # ranked, one row per design
    methods = [line.split()[1] for line in table]
    assert sorted(methods) == sorted(m for m in METHODS if m != "robust_pi")
    assert "rank: passing designs first" in res.output
    refused = res.output[res.output.index("REFUSED"):]
    assert f"{SPEC}: controller.robust_pi.disk_margin:" in refused.replace("\n      ", " ")
    rows = json.loads(out.read_text())
    designed = [r for r in rows if "rank" in r]
    assert {r["spec"] for r in rows if "refused" in r} == {f"{SPEC} --method robust_pi"}
    # the ranking criterion holds: passing rows first, then by drift disk margin
    keys = [(not r["passed"], -(r["robustness"]["worst_disk_margin"] or 0.0))
            for r in sorted(designed, key=lambda r: r["rank"])]
    assert keys == sorted(keys)
