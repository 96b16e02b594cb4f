"""``cct compare SPEC --method all``: every method on one corpus motor, side
by side. On the NEMA 23 servo of tests/corpus/datasheets robust_pi is
infeasible at its default 0.5 disk margin: it is listed as refused with its
file, key and reason, the ten others are designed, verified and ranked, and
the exit code is 1 (a refused design fails the comparison)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from toolbox.cli import main
from toolbox.spec import METHODS

SPEC = Path(__file__).parents[1] / "corpus" / "datasheets" / "nema23_teknic_hudson_2311.toml"


@pytest.mark.slow   # every method on one motor, robust searches included
def test_compare_all_methods_on_one_motor(tmp_path):
    out = tmp_path / "cmp.json"
    res = CliRunner().invoke(main, ["compare", str(SPEC), "--method", "all", "--json",
                                    str(out), "-q"])
    assert res.exit_code == 1, res.output
    lines = res.output.splitlines()
    assert lines[0].split()[:3] == ["rank", "method", "BW"]
    end = next(k for k, x in enumerate(lines) if x.startswith("worst axis throughout"))
    table = lines[1:end]
    ranks = [int(line.split()[0]) for line in table]
    assert ranks == list(range(1, len(table) + 1))          # ranked, one row per design
    assert "rank: passing designs first" in res.output
    rows = json.loads(out.read_text())
    designed = [r for r in rows if "rank" in r]
    refused = {r["spec"].rpartition(" --method ")[2]: r["refused"] for r in rows
               if "refused" in r}
    # every method is either in the table or refused, and robust_pi is refused
    assert sorted([line.split()[1] for line in table] + list(refused)) == sorted(METHODS)
    assert "robust_pi" in refused and len(table) >= len(METHODS) // 2
    text = res.output.replace("\n      ", " ")
    for method, reason in refused.items():
        assert reason.startswith(f"{SPEC}: controller"), reason   # located: file and key
        assert f"REFUSED  {reason[:60]}" in text
    assert f"{SPEC}: controller.robust_pi.disk_margin: expected" in refused["robust_pi"]
    # the ranking criterion holds: passing rows first, then by drift disk margin
    keys = [(not r["passed"], -(r["robustness"]["worst_disk_margin"] or 0.0))
            for r in sorted(designed, key=lambda r: r["rank"])]
    assert keys == sorted(keys)
