"""This process as a ROS node (rospy), on a master it starts or joins.

One per process (rospy's rule): :func:`context` starts or joins the master
(``ROS_MASTER_URI`` when a master answers there, else a new one on a free
loopback port), puts the ROS environment in ``os.environ`` (so ``-fork``
children and spawned nodes join the same master) and calls
``rospy.init_node`` once, without rospy's signal handlers.
"""

from __future__ import annotations

import contextlib
import os
import threading
from dataclasses import dataclass
from typing import Any

from fuzzer.ros import env, processes

_lock = threading.Lock()
_context: RosContext | None = None


@dataclass
class RosContext:
    """The master this process talks to, and rospy, initialized."""

    master: processes.Master
    rospy: Any
    name: str

    @property
    def environment(self) -> dict[str, str]:
        """Environment of a process that joins this master (loopback only)."""
        return self.master.environment

    def set_param(self, name: str, value: Any) -> None:
        self.rospy.set_param(name, value)

    def delete_param(self, name: str) -> None:
        with contextlib.suppress(KeyError):
            self.rospy.delete_param(name)


def context() -> RosContext:
    """This process's ROS node, created on first use.

    Raises
    ------
    RosUnavailableError
        ROS is not installed or no master could be started.
    """
    global _context
    with _lock:
        if _context is not None:
            return _context
        env.require()
        master = processes.join_or_start_master()  # logs: processes.log_folder()
        env.apply_environment(master.environment)
        import rospy

        name = f"rrosfuzz_{os.getpid()}"
        rospy.init_node(
            name, anonymous=False, disable_signals=True, disable_rosout=True, log_level=rospy.WARN
        )
        _context = RosContext(master, rospy, rospy.get_name())
        return _context
