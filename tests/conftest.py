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


@pytest.fixture(scope="session", autouse=True)
def ros_logs(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """ROS masters, nodes and RViz started by the tests log into the session's temporary
    folder (``ROS_LOG_DIR``, which pytest clears with its old runs), not a new /tmp folder each."""
    folder = str(tmp_path_factory.mktemp("ros-logs"))
    with pytest.MonkeyPatch.context() as patch:  # restores what was there before
        patch.setenv("ROS_LOG_DIR", folder)
        yield folder
