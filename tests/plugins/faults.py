"""Targets with one planted fault each, for the engine's tests.

Each is the Python twin with one behaviour changed, exposed as an object with
``RobotModel`` and ``MoveGroup``: pass it as ``--targets native,tests.plugins.faults:NAME``.
"""

from __future__ import annotations

import math
import os
from types import SimpleNamespace

import python_impl
from robot_api.records import JointType


class _WrapToPositive(python_impl.MoveGroup):
    """Continuous joints reported in [0, 2pi) instead of (-pi, pi].

    (Wrapping only the target would be invisible: execution normalizes the state.)
    """

    def get_current_joint_values(self) -> list[float]:
        values = super().get_current_joint_values()
        return [
            v % (2 * math.pi) if lim.type == JointType.CONTINUOUS else v
            for v, lim in zip(values, self._limits, strict=True)
        ]


class _TightTolerance(python_impl.MoveGroup):
    """A goal tolerance ten times tighter than the contract's (1e-5 instead of 1e-4)."""

    def __init__(self, model: python_impl.RobotModel) -> None:
        super().__init__(model)
        self._tolerance = 1e-5


class _Noisy(python_impl.MoveGroup):
    """The twin, writing a line to file descriptor 2 on every read of the state (a target's own
    output, which libFuzzer's ``-close_fd_mask=2`` silences)."""

    def get_current_joint_values(self) -> list[float]:
        os.write(2, b"noisy target says hello\n")
        return super().get_current_joint_values()


wrap_continuous = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_WrapToPositive)
tight_tolerance = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_TightTolerance)
not_a_target = SimpleNamespace(RobotModel=python_impl.RobotModel)
noisy = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_Noisy)


class _HangsBeyondThree(python_impl.MoveGroup):
    """Never returns from go() when joint_1's target is above 3 rad."""

    def go(self, joints=None, wait=True):  # type: ignore[no-untyped-def]
        if self.get_joint_value_target()[0] > 3.0:
            while True:
                pass
        return super().go(joints, wait)


class _AbortsBeyondThree(python_impl.MoveGroup):
    """Kills the process (SIGABRT, as a native crash would) when joint_1's target is above 3 rad."""

    def go(self, joints=None, wait=True):  # type: ignore[no-untyped-def]
        if self.get_joint_value_target()[0] > 3.0:
            import os

            os.abort()
        return super().go(joints, wait)


class _ExitsBeyondThree(python_impl.MoveGroup):
    """Ends the process with status 3 and no crash file (as a library calling ``exit()`` would)
    when joint_1's target is above 3 rad."""

    def go(self, joints=None, wait=True):  # type: ignore[no-untyped-def]
        if self.get_joint_value_target()[0] > 3.0:
            import os

            os._exit(3)
        return super().go(joints, wait)


hangs = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_HangsBeyondThree)
aborts = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_AbortsBeyondThree)
exits = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_ExitsBeyondThree)


class _AlwaysHangs(python_impl.MoveGroup):
    """Never returns from go() (a target stuck on every input: -timeout and -fork tests)."""

    def go(self, joints=None, wait=True):  # type: ignore[no-untyped-def]
        while True:
            pass


always_hangs = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_AlwaysHangs)


class _AlwaysAborts(python_impl.MoveGroup):
    """Kills the process (SIGABRT) in every go(): the dry run's first input, evaluated in the
    campaign's process (fuzzer/execution/guard.py), takes the campaign with it."""

    def go(self, joints=None, wait=True):  # type: ignore[no-untyped-def]
        import faulthandler
        import os

        faulthandler.disable()  # no "Fatal Python error" stack for this intended abort
        os.abort()


always_aborts = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_AlwaysAborts)


def _model_without_arguments() -> None:
    """A RobotModel that takes no URDF: calling it as the API does raises TypeError."""


wrong_constructor = SimpleNamespace(RobotModel=_model_without_arguments, MoveGroup=python_impl.MoveGroup)
