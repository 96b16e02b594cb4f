"""Paper 003's reference artifact: figures and tabled margins are of the executed law.

reports/003_azaiz2007_hinf (``cct design designs/003_azaiz2007_hinf.toml``)
runs the 3rd-order reduced controllers of eq (71)-(72). Schema 1 stored the
4th-order design as ``discrete``/``continuous`` next to the 3rd-order ``law``,
so the Bode plot was not the loop whose margins were tabled. Here every view of
each axis has the law's order, the full-order design sits apart under
``full_order``, and the stored Bode data and margins are those of the law.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from toolbox.analysis import compute_margins
from toolbox.analysis.margins import make_axis_loop
from toolbox.artifact import ControllerArtifact
from toolbox.spec import load_spec

ROOT = Path(__file__).resolve().parents[2]
REPORT = ROOT / "reports" / "003_azaiz2007_hinf"


@pytest.fixture(scope="module")
def stored():
    art = ControllerArtifact.loads((REPORT / "controller.json").read_text(),
                                   file=str(REPORT / "controller.json"))
    analysis = json.loads((REPORT / "analysis.json").read_text())
    motor = load_spec(ROOT / "designs" / "003_azaiz2007_hinf.toml").motor
    return art, analysis, motor


@pytest.mark.parametrize("axis", ["d", "q"])
def test_every_view_is_the_third_order_executed_law(stored, axis):
    art, _, _ = stored
    ax = art.axes[axis]
    assert ax.law.order == ax.continuous.order == ax.discrete.order == 3   # eq (71)-(72)
    assert len(ax.zpk.poles) == 3
    assert ax.full_order.law.order == 4 and ax.reduced is None            # eq (68), not run


def test_design_margins_are_named_apart(stored):
    """The continuous reduction-guard margins are design_margins_continuous; the
    only key named margins is the sampled executed loop."""
    art, _, _ = stored
    params = art.design_parameters
    assert "loop_margins" not in params
    assert set(params["design_margins_continuous"]["q"]) == {"full", "reduced"}


@pytest.mark.parametrize("axis", ["d", "q"])
def test_tabled_margins_are_of_the_executed_law(stored, axis):
    """margins (artifact and analysis.json) recomputed from the law with the one
    margins API: equal to 1e-9 relative (same code, same law; JSON keeps 17 digits)."""
    art, analysis, motor = stored
    fresh = compute_margins(art, motor)[axis]
    for table in (art.margins[axis], analysis["margins"]["discrete"][axis]):
        for key in ("gain_margin_db", "phase_margin_deg", "stability_margin"):
            assert table[key] == pytest.approx(getattr(fresh, key), rel=1e-9)


@pytest.mark.parametrize("axis", ["d", "q"])
def test_stored_bode_is_of_the_executed_law(stored, axis):
    """analysis.json's loop response equals L = K G z^-d of the 3rd-order law at
    the stored frequencies, to the 6 significant digits it is stored with
    (relative 1e-5 on |L| in dB away from 0 dB, absolute 1e-4 dB near it). The
    reduction is so faithful on the d axis (the 4th-order loop differs by
    < 0.002 dB there) that the magnitude alone cannot tell the two apart; the
    stored closed-loop poles can: law order + 1 (ZOH plant) + delay periods,
    5 for the executed law against 6 for the unreduced design."""
    art, analysis, motor = stored
    r = analysis["responses"][axis]
    w = np.asarray(r["omega"], float)
    L_axis = motor.Ld if axis == "d" else motor.Lq
    loop = make_axis_loop(art.axes[axis], motor.R, L_axis, art.sample_time, art.delay_samples)
    stored_db = np.asarray(r["loop"]["mag_db"], float)
    np.testing.assert_allclose(stored_db, 20 * np.log10(np.abs(loop.loop(w))),
                               rtol=1e-5, atol=1e-4)
    assert len(r["pz"]["poles"]) == art.axes[axis].law.order + 1 + art.delay_samples == 5
