"""Targets that misbehave in ways a crash must not hide (tests/test_hostile_files.py).

``exits``: the Python twin whose ``go()`` calls ``sys.exit(3)``; replaying an
input on it must report a crash outcome, not end the replay with status 0.
"""

from __future__ import annotations

import sys
from types import SimpleNamespace
from typing import Any

import python_impl


class _ExitingGroup(python_impl.MoveGroup):
    def go(self, *args: Any, **kwargs: Any) -> Any:
        sys.exit(3)


exits = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_ExitingGroup)
