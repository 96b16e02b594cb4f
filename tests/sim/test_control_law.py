"""The simulator's inputs (toolbox/ARCHITECTURE.md "Parameters and models"): the true plant is a
``toolbox.spec.Motor`` and the law carries the artifact's ``Decoupling`` (what
the controller believes), not copies of their numbers."""

import dataclasses

import numpy as np
import pytest

from toolbox.artifact import Decoupling
from toolbox.design import design
from toolbox.errors import SpecError
from toolbox.sim import DriveParams, control_law, simulate, simulate_batch
from toolbox.spec import Scenario
from toolbox.spec import spec_from_dict

from sim_helpers import PAPER000 as M, tc_law, tci_law

Ts = 1e-4
DRIVE = DriveParams(vdc=150, sample_time=Ts, delay_samples=1)
STEP = Scenario(kind="current_step", duration=0.005, iq_ref=5.0, initial_speed=200.0)


def _same(a: dict, b: dict) -> bool:
    """Bit-equal metrics (a metric NaN in both, e.g. an unsettled time, is equal)."""
    return a.keys() == b.keys() and all(
        (np.isnan(a[k]) and np.isnan(b[k])) or a[k] == b[k] for k in a)


def test_control_law_holds_the_artifacts_decoupling():
    """control_law keeps the artifact's Decoupling object itself (identity)."""
    spec = spec_from_dict({
        "motor": {"R": 0.6, "Ld": 1.4e-3, "Lq": 2.8e-3, "flux": 0.12, "pole_pairs": 4,
                  "J": 1.11e-3},
        "drive": {"vdc": 150, "sample_time": 1e-4, "delay_samples": 1},
        "controller": {"method": "pi", "pi": {"bandwidth": 1000.0}}})
    art = design(spec)
    assert control_law(art).decoupling is art.decoupling


def test_the_law_predicts_with_its_own_model_not_the_plants():
    """The decoupling uses the controller's belief: a law whose Lq_c is wrong by
    a factor 2 gives another run on the same true motor (the kernel reads
    Decoupling, not the plant), while a Decoupling equal to the motor's gives
    exactly the run of the nominal law (same numbers in, same bits out)."""
    law = tc_law(M, 800, 800, Ts)
    base = simulate(law, M, STEP, DRIVE).metrics
    same = dataclasses.replace(law, decoupling=Decoupling.from_motor(
        M, delay_compensation_time=law.decoupling.delay_compensation_time))
    assert _same(simulate(same, M, STEP, DRIVE).metrics, base)
    wrong = dataclasses.replace(law, decoupling=dataclasses.replace(law.decoupling,
                                                                    Lq_c=2 * M.Lq))
    assert simulate(wrong, M, STEP, DRIVE).metrics["mse_id"] != base["mse_id"]


def test_batch_of_motors_equals_single_runs():
    """simulate_batch with Motor.with_overrides variants == simulate on each
    (same kernel, same packed arrays: bit-identical, compared with ==)."""
    law = tc_law(M, 800, 800, Ts)
    motors = [M.with_overrides(scale={"R": s, "Lq": 1 / s}) for s in (0.7, 1.0, 1.4)]
    out = simulate_batch(law, motors, STEP, DRIVE)
    for i, m in enumerate(motors):
        single = simulate(law, m, STEP, DRIVE).metrics
        assert _same(single, {k: out.metrics[k][i] for k in single}), m


def test_batch_columns_refuse_an_unknown_torque_factor():
    cols = {"R": M.R, "Ld": M.Ld, "Lq": M.Lq, "flux": M.flux, "pole_pairs": M.pole_pairs,
            "J": M.J, "torque_factor": np.array([1.0, 1.2])}
    with pytest.raises(SpecError, match=r"plants\.torque_factor\[1\]"):
        simulate_batch(tc_law(M, 800, 800, Ts), cols, STEP, DRIVE)


@pytest.mark.parametrize("axis, field, value", [("d", "A", np.nan), ("q", "antiwindup", np.inf),
                                                ("q", "D", -np.inf)])
def test_non_finite_law_matrices_are_refused(axis, field, value):
    """A NaN or inf anywhere in a law's matrices (including the anti-windup
    gain) raises SpecError before the kernel runs."""
    law = tci_law(M, 800, 200, 800, 200, Ts)
    ax = getattr(law, axis)
    bad = np.array(getattr(ax, field), float, copy=True)
    bad.flat[-1] = value
    law = dataclasses.replace(law, **{axis: dataclasses.replace(ax, **{field: bad})})
    with pytest.raises(SpecError, match="finite controller matrices"):
        simulate(law, M, STEP, DRIVE)
