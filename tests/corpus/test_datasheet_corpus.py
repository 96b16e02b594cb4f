"""Six motors written the way their datasheets print them, units in every
section (``tests/corpus/datasheets/*.toml``: drone outrunner, small maxon EC,
NEMA 23 servo, 560 V industrial servo, e-bike hub, traction IPMSM; each
file cites its source and marks what it assumed).

Each is designed with every method from its one spec through ``--method``
(``load_spec(path, overrides=...)``, what ``cct design SPEC --method M``
does), the design stage only (``cct design --only-controller``): each
outcome is either a controller artifact or a refusal located in the spec
(``DesignInfeasible``/``SpecError`` naming the file and a ``controller.*``
key, with what was expected). Verification of the same designs is the
corpus grid's job (tests/corpus/test_corpus.py).

Time (shared 2-core machine): 60 (motor, method) cases without ``tune``
about 40 s; ``tune`` (an optimisation over the drift box) takes 46-146 s a
motor, so it runs on the NEMA 23 servo only (the suite has no ``slow``
marker). Measured outcome: every method designs on every motor except
``robust_pi`` on the drone, maxon, NEMA 23 and 560 V servos, refused with
``controller.robust_pi.disk_margin`` and a computed, re-checked advice.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from toolbox.errors import SpecError
from toolbox.pipeline import design_spec
from toolbox.spec import load_spec
from toolbox.spec import METHODS

DIR = Path(__file__).parent / "datasheets"
FILES = sorted(DIR.glob("*.toml"))
CATEGORIES = ("drone", "maxon", "nema23", "560v", "hub", "traction")


def test_six_categories_with_units_in_every_section():
    """One file per category; every section holds unit strings; the source is
    cited and the assumptions are marked."""
    import tomllib

    names = [p.stem for p in FILES]
    assert all(any(c in n for n in names) for c in CATEGORIES), names
    for path in FILES:
        text = path.read_text()
        assert text.startswith("#") and "assumed" in text, path.name
        data = tomllib.loads(text)
        method = data["controller"]["method"]
        for section in (data["motor"], data["drive"], data["controller"][method],
                        data["requirements"], data["scenario"][0]):
            assert any(isinstance(v, str) and any(ch.isdigit() for ch in v)
                       and " " in v.strip() for v in section.values()), (path.name, section)


def _design(path: Path, method: str):
    spec = load_spec(path, overrides=[("--method", f'controller.method="{method}"')])
    return spec, design_spec(spec)


def _cases():
    for path in FILES:
        for method in METHODS:
            if method == "tune" and "nema23" not in path.stem:
                continue
            # slow: the robust methods search over model sets (7-150 CPU-s per motor)
            marks = pytest.mark.slow if method in ("tune", "robust_pi") else ()
            yield pytest.param(path, method, id=f"{method}-{path.stem}", marks=marks)


@pytest.mark.parametrize("path, method", list(_cases()))
def test_every_method_designs_or_refuses_with_a_located_reason(path, method):
    try:
        spec, art = _design(path, method)
    except SpecError as err:
        # a refusal names the file, a controller key, what was expected
        assert err.file == str(path), err
        if method == "robust_pi":  # computed advice, never a bare "lower it"
            assert "passes" in err.hint or "cannot pass" in err.hint, err.hint
        assert err.key.startswith("controller"), err
        assert err.expected, err
        assert str(err).startswith(f"{path}: {err.key}: expected "), err
        return
    assert art.method == method
    assert art.sample_time == pytest.approx(spec.drive.sample_time, rel=1e-12)
    for ax in ("d", "q"):
        disc = art.axes[ax].discrete
        assert all(math.isfinite(v) for row in disc.A for v in row)
