"""Robot descriptions: the shipped default arm and real robots by name.

Named robots come from the ``example-robot-data`` PyPI package (a data-only
package that installs URDF files under ``cmeel.prefix/share``).
"""

from __future__ import annotations

import importlib.metadata
import os
from pathlib import Path

from robot_api.errors import ErrorCode, URDFError

DEFAULT_ROBOT = "probot_anno"

_SHIPPED = {"probot_anno": Path(__file__).with_name("robots") / "probot_anno.urdf"}

# name -> path inside example-robot-data's ``robots`` folder
EXAMPLE_ROBOTS: dict[str, str] = {
    "ur3": "ur_description/urdf/ur3_robot.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "ur5_limited": "ur_description/urdf/ur5_joint_limited_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "z1": "z1_description/urdf/z1.urdf",
    "so100": "so_arm_description/urdf/so100.urdf",
    "so101": "so_arm_description/urdf/so101.urdf",
    "double_pendulum_continuous": "double_pendulum_description/urdf/double_pendulum_continuous.urdf",
    "baxter": "baxter_description/urdf/baxter.urdf",
}


def default_robot_path() -> Path:
    """Path of the shipped default arm (PROBOT Anno kinematics)."""
    return _SHIPPED[DEFAULT_ROBOT]


def example_robot_data_root() -> Path:
    """Folder of ``example-robot-data``'s robots.

    Raises
    ------
    URDFError
        If the package is not installed.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise URDFError(
            "named robots need the 'example-robot-data' package (pip install example-robot-data)",
            ErrorCode.URDF_INVALID,
        ) from exc
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))


def known_robots() -> list[str]:
    """Names accepted by :func:`resolve`."""
    return sorted([*_SHIPPED, *EXAMPLE_ROBOTS])


def resolve(spec: str | os.PathLike[str]) -> Path:
    """Turn a robot name or a URDF path into a path.

    Parameters
    ----------
    spec : str or path
        A name from :func:`known_robots` or the path of a URDF file.

    Raises
    ------
    URDFError
        If ``spec`` is neither an existing file nor a known name (nor a str or path at all).
    """
    if not isinstance(spec, str | os.PathLike):
        raise URDFError(f"robot: expected a name or a path, got {type(spec).__name__}")
    try:
        text = os.fspath(spec)
    except TypeError as exc:  # a PathLike whose __fspath__ returns bytes or anything else
        raise URDFError(f"robot: {exc}") from None
    if not text:  # Path("") is the working folder: "not a regular file" hid what was wrong
        raise URDFError("robot: an empty name (an unset variable?); give a robot name or a URDF path")
    if text in _SHIPPED:
        return _SHIPPED[text]
    if text in EXAMPLE_ROBOTS:
        path = example_robot_data_root() / EXAMPLE_ROBOTS[text]
        if not path.is_file():
            raise URDFError(f"robot {text!r}: {path} is missing from example-robot-data")
        return path
    path = Path(text)
    if path.is_file():
        return path
    if path.exists():  # a FIFO, device or folder: never opened (a FIFO would block)
        raise URDFError(f"robot {text!r} is not a regular file (a URDF must be one)")
    raise URDFError(f"robot {text!r} is neither a URDF file nor a known robot ({', '.join(known_robots())})")
