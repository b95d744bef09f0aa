"""Stateful fault-injected variants of the Python twin: bugs that need a live group.

Each variant is ``python_impl`` with exactly one behaviour changed, like those of
``benchmarks/zoo/bugs.py``, but none of them shows in one call on a fresh group
(``--op move``: set a joint target, ``go()``, read the final state): each needs a
second call on the same group, or shows only in a planned or executed trajectory
(``--op scenario``). ``benchmarks/zoo/__init__.py`` lists them with a one-line
description, the public source of their bug class, and the robot they need
(``--targets native,benchmarks.zoo.stateful:NAME``).
"""

from __future__ import annotations

from collections.abc import Sequence
from types import SimpleNamespace

import numpy as np

import python_impl
from python_impl import convert
from python_impl.angles import normalize_angle
from python_impl.trajectory import plan_trajectory
from robot_api.errors import ErrorCode, InvalidInputError
from robot_api.protocol import JointTarget, JointValues, PoseLike
from robot_api.records import JointType, PlanResult, Pose, RobotTrajectory

Model = python_impl.RobotModel
Group = python_impl.MoveGroup


def _impl(group: type[Group]) -> SimpleNamespace:
    return SimpleNamespace(RobotModel=Model, MoveGroup=group)


# -- 1. continuous joints accumulate across moves (no wrap into (-pi, pi]) ---------------------


class _ContinuousAccumulates(Group):
    """The state of a continuous joint is the previous state plus the (shortest) move.

    From home (0) one move lands on the normalized target exactly; a second move
    across +-pi leaves the joint outside (-pi, pi] (e.g. 3.0 then -3.0 gives 3.28).
    """

    def _execute(self, names: list[str], times: Sequence[float] | np.ndarray, positions: np.ndarray) -> None:
        before = list(self._current)
        super()._execute(names, times, positions)
        self._current = [
            a + normalize_angle(b - a) if lim.type == JointType.CONTINUOUS else b
            for a, b, lim in zip(before, self._current, self._limits, strict=True)
        ]


continuous_accumulates = _impl(_ContinuousAccumulates)


# -- 2. the planner starts from home, not from the current state ------------------------------


class _StartStateHome(Group):
    """plan() and go() plan from the home state; execution then refuses a start that is off.

    On a fresh group the current state is home, so the first move is right; after
    it, plan() returns a trajectory that starts at home and go() fails ("start point
    deviates from current robot state"), returning False as moveit_commander does.
    """

    def _plan(self) -> RobotTrajectory:
        return plan_trajectory(
            self._limits,
            list(self._model.home_values),
            self._goal(),
            self._velocity_scaling,
            self._acceleration_scaling,
        )

    def go(self, joints: JointTarget | None = None, wait: bool = True) -> bool:
        try:
            return super().go(joints, wait)
        except InvalidInputError as exc:
            if exc.code == ErrorCode.INVALID_TRAJECTORY:
                return False  # the controller rejected the trajectory: CONTROL_FAILED
            raise


start_state_home = _impl(_StartStateHome)


# -- 3. a cached forward kinematics result not invalidated by a move ---------------------------


class _CachedPose(Group):
    """get_current_pose() caches the pose per link on first use and never recomputes it."""

    def __init__(self, model: Model) -> None:
        super().__init__(model)
        self._pose_cache: dict[str | None, Pose] = {}

    def get_current_pose(self, link: str | None = None) -> Pose:
        if link not in self._pose_cache:
            self._pose_cache[link] = super().get_current_pose(link)
        return self._pose_cache[link]


cached_pose = _impl(_CachedPose)


# -- 4. compute_cartesian_path ignores the scaling factors -------------------------------------


class _CartesianIgnoresScaling(Group):
    """The Cartesian path is timed at full speed (scaling factors 1.0) whatever was set.

    A bug against the contract, which scales it; MoveIt 1 itself times it so (docs/api.md,
    "Where the contract departs from MoveIt 1")."""

    def compute_cartesian_path(
        self, waypoints: Sequence[PoseLike], eef_step: float, jump_threshold: float = 0.0
    ) -> tuple[RobotTrajectory, float]:
        scaling = self._velocity_scaling, self._acceleration_scaling
        self._velocity_scaling = self._acceleration_scaling = 1.0
        try:
            return super().compute_cartesian_path(waypoints, eef_step, jump_threshold)
        finally:
            self._velocity_scaling, self._acceleration_scaling = scaling


cartesian_ignores_scaling = _impl(_CartesianIgnoresScaling)


# -- 5. the acceleration scaling factor checked but not applied --------------------------------


class _AccelerationScalingIgnored(Group):
    """Trajectories are timed with acceleration scaling 1.0 (after the checks with the real one).

    The move is first planned with the factor in effect, so a move that would last too
    long still fails as it should; the trajectory returned is the unscaled one: the
    same end point (``--op move`` sees the same final state) but faster, with
    accelerations above ``ACCELERATION_LIMIT`` x the factor.

    A bug against the contract; on a URDF-only robot (no acceleration limits configured)
    MoveIt 1's time parameterization ignores the factor too (docs/api.md, "Where the contract
    departs from MoveIt 1").
    """

    def _plan(self) -> RobotTrajectory:
        super()._plan()  # raises PlanningError exactly when the contract's plan does
        return plan_trajectory(self._limits, self._current, self._goal(), self._velocity_scaling, 1.0)


acceleration_scaling_ignored = _impl(_AccelerationScalingIgnored)


# -- 6. plan() duplicates the start point at time 0 -------------------------------------------


class _DuplicateStartPoint(Group):
    """plan() prepends the start state again at time 0: times are not strictly increasing.

    go() is unaffected (it executes its own plan), so one move ends where it should;
    executing the plan of plan() is rejected.
    """

    def plan(self, joints: JointTarget | None = None) -> PlanResult:
        result = super().plan(joints)
        t = result.trajectory
        if not result.success or len(t) == 0:
            return result
        doubled = RobotTrajectory(
            t.joint_names,
            np.concatenate([t.time_from_start[:1], t.time_from_start]),
            np.vstack([t.positions[:1], t.positions]),
            np.vstack([np.zeros_like(t.velocities[:1]), t.velocities]),
            np.vstack([np.zeros_like(t.accelerations[:1]), t.accelerations]),
        )
        return result._replace(trajectory=doubled)


duplicate_start_point = _impl(_DuplicateStartPoint)


# -- 7. execute() stops at the second-to-last point -------------------------------------------


class _ExecuteStopsShort(Group):
    """execute(plan) leaves the state at the plan's second-to-last point (go() is right)."""

    def execute(self, plan: RobotTrajectory, wait: bool = True) -> bool:
        if isinstance(plan, RobotTrajectory) and len(plan.time_from_start) > 1:
            plan = RobotTrajectory(
                plan.joint_names,
                plan.time_from_start[:-1],
                plan.positions[:-1],
                plan.velocities[:-1],
                plan.accelerations[:-1],
            )
        return super().execute(plan, wait)


execute_stops_short = _impl(_ExecuteStopsShort)


# -- 8. remember_joint_values stores the live state list, not a copy --------------------------


class _RememberAliasesState(Group):
    """remember_joint_values(name) keeps a reference to the state list, which moves update
    in place: the remembered state follows the arm."""

    def remember_joint_values(self, name: str, values: JointValues | None = None) -> None:
        super().remember_joint_values(name, values)
        if values is None:
            self._named[convert.to_string(name, "named target")] = self._current  # no copy

    def _execute(self, names: list[str], times: Sequence[float] | np.ndarray, positions: np.ndarray) -> None:
        state = self._current
        super()._execute(names, times, positions)
        state[:] = self._current  # updated in place
        self._current = state


remember_aliases_state = _impl(_RememberAliasesState)


# -- 9. plans to a pose goal take the velocity scaling twice ----------------------------------


class _PoseGoalScaledTwice(Group):
    """A plan to a pose or position goal is timed with the velocity scaling factor applied
    twice (its square); a joint goal is timed right.

    The plan ends at the same IK answer and stays within every limit, only slower: no bound
    on a trajectory's own values sees it, and ``--op move`` (joint goals) never does. On a
    7-joint arm the two IK solvers answer one pose with configurations far apart, which the
    oracle explains (a ``known_limitation``); until the sixty-ninth session that explanation
    hid this fault at every such step (docs/engine.md).
    """

    def _plan(self) -> RobotTrajectory:
        if self._pose_goal is None:
            return super()._plan()
        scaling = self._velocity_scaling
        return plan_trajectory(
            self._limits, self._current, self._goal(), scaling * scaling, self._acceleration_scaling
        )


pose_goal_scaled_twice = _impl(_PoseGoalScaledTwice)


__all__ = [
    "acceleration_scaling_ignored",
    "cached_pose",
    "cartesian_ignores_scaling",
    "continuous_accumulates",
    "duplicate_start_point",
    "execute_stops_short",
    "pose_goal_scaled_twice",
    "remember_aliases_state",
    "start_state_home",
]
