"""A deliberately faulty target for the ROS transport's tests (python_impl with three faults).

FK with the first joint value exactly ``DIE`` ends the process (``os._exit``: a node that
dies), ``HANG`` blocks (a node that never answers), ``RAISE`` raises ``RuntimeError``
(a crash that replays in-process the same way), ``EXIT_ONCE`` ends the first node that meets it
with status 0, as a node shut down from outside ends (a marker in ``ROS_LOG_DIR`` says it did).
Everything else is python_impl.
"""

from __future__ import annotations

import os
import threading
from types import SimpleNamespace

import python_impl
from robot_api.records import Pose

DIE = 0.125
HANG = 0.25
RAISE = 0.375
EXIT_ONCE = 0.5


class RobotModel(python_impl.RobotModel):
    __slots__ = ()

    def pose_of(self, values: list[float], link: int) -> Pose:
        if values[0] == DIE:
            os._exit(3)
        if values[0] == HANG:
            threading.Event().wait()
        if values[0] == RAISE:
            raise RuntimeError("injected fault")
        if values[0] == EXIT_ONCE:
            marker = os.path.join(os.environ.get("ROS_LOG_DIR", "."), "rrosfuzz-exited-once")
            if not os.path.exists(marker):
                open(marker, "w").close()
                os._exit(0)
        return super().pose_of(values, link)


api = SimpleNamespace(RobotModel=RobotModel, MoveGroup=python_impl.MoveGroup)
