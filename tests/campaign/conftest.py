"""Fixtures of the campaign tests (the spec is in campaign_helpers.py)."""

from __future__ import annotations

import pytest
from campaign_helpers import write_spec


@pytest.fixture(scope="session")
def designed(tmp_path_factory):
    """``(spec, artifact)`` of the 400-sample test campaign (designed once)."""
    from toolbox.pipeline import design_spec
    from toolbox.spec import load_spec

    spec = load_spec(write_spec(tmp_path_factory.mktemp("spec")))
    return spec, design_spec(spec)


@pytest.fixture(scope="session")
def serial_run(designed, tmp_path_factory):
    """The uninterrupted in-process run: the reference table."""
    from toolbox.campaign import run_campaign

    spec, artifact = designed
    return run_campaign(spec, tmp_path_factory.mktemp("serial"), scheduler="serial",
                        artifact=artifact)
