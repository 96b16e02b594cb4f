"""Session fixtures: hand-built artifacts (see analysis_helpers)."""
import pytest

from analysis_helpers import hinf_artifact, pi_artifact, tc_artifact


@pytest.fixture(scope="session")
def hinf():
    return hinf_artifact()


@pytest.fixture(scope="session")
def pi():
    return pi_artifact()


@pytest.fixture(scope="session")
def tc():
    return tc_artifact()
