"""pytest configuration: shared fixtures."""

from __future__ import annotations

import pytest

from tests.support import IMPLEMENTATIONS, robot_path


@pytest.fixture(params=sorted(IMPLEMENTATIONS))
def impl(request: pytest.FixtureRequest):  # type: ignore[no-untyped-def]
    """Each implementation in turn."""
    return IMPLEMENTATIONS[request.param]


@pytest.fixture(scope="session")
def default_urdf():  # type: ignore[no-untyped-def]
    return robot_path("probot_anno")
