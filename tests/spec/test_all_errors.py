"""Every error of a spec file in one run (README: "all at once"), not only the
first of each section; each names the key path, what was expected and what
was found (the file heads the list)."""

from __future__ import annotations

import pytest

from toolbox.errors import SpecError
from toolbox.spec import load_spec

SPEC = """
title = "multi"
[motor]
R = -1
Ld = 0
Lq = "x"
flux = 0.1
pole_pairs = 4
J = 1e-3
bogus = 1
[drive]
vdc = -5
sample_time = 0
extra = 2
[controller]
method = "pi"
[requirements]
min_phase_margin_deg = -4
max_overshoot_pct = "a"
nope = 1
[requirements.parameter_drift]
R = [1.2, 1.5]
Q = [0.9, 1.1]
"""


def test_every_error_of_each_section_is_reported(tmp_path):
    path = tmp_path / "multi.toml"
    path.write_text(SPEC)
    with pytest.raises(SpecError) as info:
        load_spec(path)
    errors = {e.key: e for e in info.value.errors}
    assert set(errors) == {
        "motor.bogus", "motor.R", "motor.Ld", "motor.Lq", "drive.vdc", "drive.sample_time",
        "drive.extra", "requirements.nope", "requirements.min_phase_margin_deg",
        "requirements.max_overshoot_pct", "requirements.parameter_drift.R",
        "requirements.parameter_drift.Q"}, sorted(errors)
    text = str(info.value)
    assert text.startswith(f"{path}: 12 errors:")
    assert "motor.R: expected a number > 0 (ohm), got -1" in text
    assert 'requirements.max_overshoot_pct: expected a number >= 0 (%), got "a"' in text
    assert all(e.file == str(path) and e.expected for e in info.value.errors)
    assert all(e.has_got for k, e in errors.items() if not k.endswith(("bogus", "extra",
                                                                         "nope", "Q")))
