"""A deliberately faulty target for the ROS transport's tests (python_impl with three faults).

FK with the first joint value exactly ``DIE`` ends the process (``os._exit``: a node that
dies), ``HANG`` blocks (a node that never answers), ``RAISE`` raises ``RuntimeError``
(a crash that replays in-process the same way). Everything else is python_impl.
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


class RobotModel(python_impl.RobotModel):
    __slots__ = ()

    def pose_of(self, values: list[float], link: int) -> Pose:
        if values[0] == DIE:
            os._exit(3)
        if values[0] == HANG:
            threading.Event().wait()
        if values[0] == RAISE:
            raise RuntimeError("injected fault")
        return super().pose_of(values, link)


api = SimpleNamespace(RobotModel=RobotModel, MoveGroup=python_impl.MoveGroup)
