"""Debian's ROS 1 Python packages, imported into the project's interpreter.

Debian's ``python3-rospy`` & co. live in ``/usr/lib/python3/dist-packages``,
built for Debian's CPython 3.11 (the project's venv is a CPython 3.11 too, so
the few C extensions, ``tf2_py`` and ``netifaces``, load). That folder is never
put on ``sys.path``: a finder appended to the end of ``sys.meta_path`` serves
only the top-level names of :data:`ROS_MODULES`, and only when the venv has no
module of that name, so no package of the venv is ever shadowed.

The ROS packages come from apt (``scripts/ros-ensure.sh``); :func:`require`
names that command when they are missing.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import shutil
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

DIST_PACKAGES = Path("/usr/lib/python3/dist-packages")
"""Where Debian installs the ROS Python packages."""

ROS_MODULES = frozenset(
    {
        # rospy and what it imports
        "rospy", "rosgraph", "roslib", "rospkg", "genpy", "genmsg", "roscpp", "rosgraph_msgs",
        "std_msgs", "std_srvs", "catkin", "catkin_pkg", "pyparsing", "docutils", "netifaces", "yaml",
        "_yaml", "defusedxml", "dateutil",
        # messages, tf2, bags, master tools
        "sensor_msgs", "geometry_msgs", "tf2_ros", "tf2_py", "tf2_msgs", "actionlib", "actionlib_msgs",
        "rosbag", "roslz4", "gnupg", "Cryptodome", "rosnode", "rosparam", "rostopic", "rosmaster",
    }
)  # fmt: skip
"""Top-level names served from :data:`DIST_PACKAGES` when the venv has none."""

RSP_EXECUTABLE = Path("/usr/lib/robot_state_publisher/robot_state_publisher")
"""Debian's ``robot_state_publisher`` node (``ros-robot-state-publisher``)."""

INSTALL_HINT = "install ROS 1 from apt with scripts/ros-ensure.sh (make test runs it)"


class RosUnavailableError(RuntimeError):
    """ROS 1 is not installed (the message names the command that installs it)."""


class _DebianRosFinder(importlib.abc.MetaPathFinder):
    """Finds the allow-listed ROS packages in Debian's dist-packages, last."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if path is not None or fullname not in ROS_MODULES:
            return None  # submodules are found through their package's __path__
        return importlib.machinery.PathFinder.find_spec(fullname, [str(DIST_PACKAGES)])


_FINDER = _DebianRosFinder()


def missing() -> list[str]:
    """What of ROS 1 is not installed (empty when everything is)."""
    out = []
    for package in ("rospy", "rosgraph", "tf2_ros", "sensor_msgs", "rosbag"):
        if not (DIST_PACKAGES / package).is_dir():
            out.append(f"python3-{package.replace('_', '-')}")
    if shutil.which("rosmaster") is None:
        out.append("rosmaster (python3-rosmaster)")
    if not RSP_EXECUTABLE.is_file():
        out.append("robot_state_publisher (ros-robot-state-publisher)")
    return out


def require() -> None:
    """Make Debian's ROS packages importable.

    Raises
    ------
    RosUnavailableError
        ROS 1 is not installed; the message says what is missing and how to install it.
    """
    gone = missing()
    if gone:
        raise RosUnavailableError(f"ROS 1 is not installed (missing: {', '.join(gone)}): {INSTALL_HINT}")
    if _FINDER not in sys.meta_path:
        sys.meta_path.append(_FINDER)


def import_module(name: str) -> Any:
    """Import a ROS module (``rospy``, ``tf2_ros``, ``sensor_msgs.msg``...) after :func:`require`."""
    require()
    import importlib

    return importlib.import_module(name)


def loopback_environment(master_uri: str, log_dir: str) -> dict[str, str]:
    """Environment variables of a ROS process on this machine's loopback only."""
    return {
        "ROS_MASTER_URI": master_uri,
        "ROS_IP": "127.0.0.1",
        "ROS_HOSTNAME": "127.0.0.1",
        "ROS_LOG_DIR": log_dir,
        "ROS_HOME": log_dir,
        "ROSCONSOLE_STDOUT_LINE_BUFFERED": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
    }


def apply_environment(env: dict[str, str]) -> None:
    """Set ``env`` in this process (rospy reads it when the node starts)."""
    os.environ.update(env)
