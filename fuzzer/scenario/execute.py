"""Running a scenario on one target (docs/engine.md, "Scenarios (``--op scenario``)").

One new ``MoveGroup(model)`` per run; the steps run in order. A step that raises a
``robot_api.errors.RobotAPIError`` is ``REJECTED`` and the scenario goes on (the contract
leaves the group unchanged on error); any other exception is ``CRASHED`` and ends it.
Each target executes its *own* last plan, as a user's script would.

Per-step ``Outcome.values`` (read-only sequences of floats, ``records.Floats``):

* ``joint_values`` after every step (rad, m);
* ``position`` (m) and ``orientation`` (x, y, z, w) after ``/go`` and ``/execute``;
* ``joint_target`` after ``/joint_target`` and ``/named_target``;
* ``success`` (1.0 or 0.0) for ``/go``, ``/plan``, ``/execute``; ``error_code`` for ``/plan``;
* ``fraction`` for ``/cartesian_path``;
* ``trajectory.time_from_start`` (M,) and ``trajectory.positions``, ``.velocities``,
  ``.accelerations`` flattened row-major (M*dof,) for ``/plan`` and ``/cartesian_path``;
* ``named.<name>``: ``get_named_target_values(name)`` in joint order, after ``/remember``,
  and after ``/go`` and ``/execute`` for every name a ``/remember`` of this run stored (a move
  must leave what was remembered as it was).

What the executor knows for the oracle's per-target properties, on ``/plan``, ``/go``,
``/execute`` and ``/cartesian_path`` steps (``in_effect.*``, the settings the script made
on this target, not outputs of the target): ``in_effect.velocity_scaling``,
``in_effect.acceleration_scaling``, ``in_effect.goal_tolerance`` (the last accepted
values; the contract's defaults 1.0, 1.0 and ``GOAL_JOINT_TOLERANCE`` before any),
``in_effect.joint_goal`` (``/plan`` and ``/go`` without an
active pose target: ``get_joint_value_target()`` before the call), and for ``/execute`` of
a plan ``in_effect.plan_last`` (the executed plan's last point).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from fuzzer.execution.records import Floats, Outcome, Status, floats
from fuzzer.scenario.nudge import Axis, Moved, Nudge, shifted_goal, shifted_state
from fuzzer.scenario.steps import ScenarioCall, Step
from robot_api.constants import GOAL_JOINT_TOLERANCE
from robot_api.errors import RobotAPIError
from robot_api.records import RobotTrajectory

DEFAULT_EEF_STEP = 0.01
"""eef_step (m) of ``/cartesian_path`` until an ``/eef_step`` step sets another."""
DEFAULT_JUMP_THRESHOLD = 0.0
"""jump_threshold of ``/cartesian_path`` until a ``/jump_threshold`` step sets another."""

Values = dict[str, Sequence[float]]

_PLANS = frozenset({"plan", "go", "execute", "cartesian_path"})
_POSED = frozenset({"go", "execute"})


_TRAJECTORY = ("time_from_start", "positions", "velocities", "accelerations")


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two flat float64 arrays hold the same bits (NaN payloads and -0.0 included)."""
    return a.shape == b.shape and bool(np.array_equal(a.view(np.uint64), b.view(np.uint64)))


def _pose(values: Values, pose: Any) -> None:
    values["position"] = tuple(map(float, pose.position))
    values["orientation"] = tuple(map(float, pose.orientation))


def _pose_tuple(pose: dict[str, Any]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A ``geometry_msgs/Pose`` dict as the contract's ``((x, y, z), (qx, qy, qz, qw))``."""
    p, q = pose["position"], pose["orientation"]
    return (p["x"], p["y"], p["z"]), (q["x"], q["y"], q["z"], q["w"])


class _Run:
    """The state of one scenario run on one target: its group and the script's settings."""

    def __init__(self, runner: Any) -> None:
        self.runner = runner
        self.group = runner.impl.MoveGroup(runner.model)
        self.eef_step = DEFAULT_EEF_STEP
        self.jump_threshold = DEFAULT_JUMP_THRESHOLD
        self.velocity_scaling = 1.0
        self.acceleration_scaling = 1.0
        self.goal_tolerance = GOAL_JOINT_TOLERANCE
        self.pose_goal = False
        self.goal_step: Step | None = None
        self.last_plan: Any = None
        self.remembered: dict[str, None] = {}
        """Names a ``/remember`` of this run stored, in order."""
        self.kept: dict[str, Floats] = {}
        """The last trajectory's arrays as recorded, by value name (see ``_trajectory``)."""
        self._joint_names: tuple[str, ...] | None = None

    @property
    def joint_names(self) -> tuple[str, ...]:
        if self._joint_names is None:
            self._joint_names = tuple(self.runner.model.joint_names)
        return self._joint_names

    def _trajectory(self, values: Values, trajectory: Any) -> None:
        """Record a plan's ``trajectory.*`` values. An array with the same bits as the last
        recorded one of its name is that record again, not a copy: a script that plans the same
        path again and again (a tiny acceleration scaling makes each 10,000-60,000 points) kept
        a copy per step until the whole script was compared (BENCHMARKS.md, "Memory")."""
        for name in _TRAJECTORY:
            key = f"trajectory.{name}"
            array = np.ascontiguousarray(getattr(trajectory, name), dtype=np.float64).ravel()
            old = self.kept.get(key)
            if old is not None and _same_bits(old.array, array):
                values[key] = old
            else:
                values[key] = self.kept[key] = floats(array)

    def nudge(self, shift: float) -> None:
        """Move the current state by ``shift`` on every joint with a one-point trajectory."""
        limits = tuple(self.runner.model.joint_limits)
        point = shifted_state(list(self.group.get_current_joint_values()), shift, limits)
        zeros = np.zeros((1, len(point)))
        times, positions = np.array([0.0]), np.array([point])
        trajectory = RobotTrajectory(self.joint_names, times, positions, zeros, zeros.copy())
        self.group.execute(trajectory)

    def move_to(self, state: tuple[float, ...]) -> None:
        """Move the state to ``state`` with a two-point trajectory from the current state (1 s
        later; ``execute`` checks only the first point against the state, and every point
        against the limits)."""
        current = list(self.group.get_current_joint_values())
        if len(state) != len(current):
            raise ValueError(f"a state of {len(state)} values for {len(current)} joint variables")
        zeros = np.zeros((2, len(current)))
        times, positions = np.array([0.0, 1.0]), np.array([current, list(state)], dtype=float)
        self.group.execute(RobotTrajectory(self.joint_names, times, positions, zeros, zeros.copy()))

    def nudge_goal(self, shift: float, moved: Moved, axis: Axis) -> None:
        """Set the pose or position target in effect again, moved (``nudge.shifted_goal``);
        raises ``LookupError`` when no pose goal is in effect or it has nothing to move."""
        if not self.pose_goal or self.goal_step is None:
            raise LookupError("no pose goal in effect")
        self.step(shifted_goal(self.goal_step, shift, moved, axis))

    def step(self, step: Step) -> tuple[Status, Values]:
        """Run one step; raises what the target raises."""
        group, kind, msg = self.group, step.kind, step.message
        values: Values = {}
        status = Status.OK
        if kind in _PLANS:
            values["in_effect.velocity_scaling"] = (self.velocity_scaling,)
            values["in_effect.acceleration_scaling"] = (self.acceleration_scaling,)
            values["in_effect.goal_tolerance"] = (self.goal_tolerance,)
        if kind == "joint_target":
            if msg["name"]:
                group.set_joint_value_target(list(msg["name"]), list(msg["position"]))
            else:
                group.set_joint_value_target(list(msg["position"]))
            self.pose_goal = False
            values["joint_target"] = floats(group.get_joint_value_target())
        elif kind == "named_target":
            group.set_named_target(msg["data"])
            self.pose_goal = False
            values["joint_target"] = floats(group.get_joint_value_target())
        elif kind == "pose_target":
            group.set_pose_target(_pose_tuple(msg["pose"]), msg["header"]["frame_id"] or None)
            self.pose_goal, self.goal_step = True, step
        elif kind == "position_target":
            p = msg["point"]
            group.set_position_target([p["x"], p["y"], p["z"]], msg["header"]["frame_id"] or None)
            self.pose_goal, self.goal_step = True, step
        elif kind == "clear_pose_targets":
            group.clear_pose_targets()
            self.pose_goal = False
        elif kind == "remember":
            name = msg["data"]
            group.remember_joint_values(name)
            self.remembered[name] = None
            self._named(values, (name,))
        elif kind == "velocity_scaling":
            group.set_max_velocity_scaling_factor(msg["data"])
            self.velocity_scaling = msg["data"]
        elif kind == "acceleration_scaling":
            group.set_max_acceleration_scaling_factor(msg["data"])
            self.acceleration_scaling = msg["data"]
        elif kind == "goal_tolerance":
            group.set_goal_joint_tolerance(msg["data"])
            self.goal_tolerance = msg["data"]
        elif kind == "eef_step":
            self.eef_step = msg["data"]
        elif kind == "jump_threshold":
            self.jump_threshold = msg["data"]
        elif kind == "stop":
            group.stop()
        elif kind == "plan" or kind == "go":
            if not self.pose_goal:
                values["in_effect.joint_goal"] = floats(group.get_joint_value_target())
            status = self._plan(values) if kind == "plan" else self._go(values)
        elif kind == "execute":
            status = self._execute(values)
        elif kind == "cartesian_path":
            poses = [_pose_tuple(p) for p in msg["poses"]]
            trajectory, fraction = group.compute_cartesian_path(poses, self.eef_step, self.jump_threshold)
            self.last_plan = trajectory
            values["fraction"] = (float(fraction),)
            self._trajectory(values, trajectory)
        else:
            raise ValueError(f"unknown step kind {kind!r}")
        values["joint_values"] = floats(group.get_current_joint_values())
        if kind in _POSED:
            _pose(values, group.get_current_pose())
            self._named(values, self.remembered)
        return status, values

    def _named(self, values: Values, names: Iterable[str]) -> None:
        for name in names:
            table = self.group.get_named_target_values(name)
            values[f"named.{name}"] = tuple(float(table.get(j, math.nan)) for j in self.joint_names)

    def _plan(self, values: Values) -> Status:
        result = self.group.plan()
        success = result.success is True
        if success:
            self.last_plan = result.trajectory
        values["success"] = (1.0 if success else 0.0,)
        values["error_code"] = (float(int(result.error_code)),)
        self._trajectory(values, result.trajectory)
        return Status.OK if success else Status.FAILED

    def _go(self, values: Values) -> Status:
        moved = self.group.go() is True
        values["success"] = (1.0 if moved else 0.0,)
        return Status.OK if moved else Status.FAILED

    def _execute(self, values: Values) -> Status:
        if self.last_plan is None:
            values["success"] = (1.0,)  # no plan yet: no call, an ok step (docs/engine.md)
            return Status.OK
        positions = np.asarray(self.last_plan.positions, dtype=float)
        if positions.ndim == 2 and positions.shape[0] > 0:
            values["in_effect.plan_last"] = tuple(positions[-1].tolist())
        done = self.group.execute(self.last_plan) is True
        values["success"] = (1.0 if done else 0.0,)
        return Status.OK if done else Status.FAILED

    def final(self) -> Values:
        """The state at the end: joint values and the end effector's pose."""
        values: Values = {"joint_values": floats(self.group.get_current_joint_values())}
        _pose(values, self.group.get_current_pose())
        return values


def _failure(status: Status, exc: BaseException) -> Outcome:
    code = int(exc.code) if isinstance(exc, RobotAPIError) else None
    return Outcome(status, type(exc).__name__, code, str(exc)[:500])


NUDGE_FAILED = "nudge_failed"
"""In a scenario outcome's values when ``nudge`` could not be made (the target refused the
one-point trajectory or the moved goal, or no pose goal, or no orientation, was in effect): the run then says
nothing about ill-conditioning."""


def run_scenario(runner: Any, call: ScenarioCall, nudge: Nudge | None = None) -> Outcome:
    """Run a scenario on one target.

    Parameters
    ----------
    runner : fuzzer.execution.targets.Runner
        The target (its ``impl`` and loaded ``model``).
    call : ScenarioCall
        The steps.
    nudge : Nudge, optional
        For ill-conditioning checks of the oracle. Just before step ``nudge.index``:
        ``Moved.STATE`` moves the current state by ``shift`` (rad, m) on every joint, minus
        on odd joint indices, clamped into the limits (continuous joints normalized into
        (-pi, pi]), by executing a one-point trajectory (time 0); ``Moved.TO`` moves it to
        ``nudge.state`` (a two-point trajectory from it); ``Moved.POSITION`` moves a
        ``/cartesian_path`` step's waypoints by ``shift * axis`` (m), or sets the pose or
        position target in effect again moved so; ``Moved.ORIENTATION`` turns their
        orientations by ``shift`` (rad) about ``axis`` (``nudge.turned``). A nudge that
        cannot be made (the target refuses it, or there is no pose goal to move) is not an
        error of the step: the outcome's values then hold ``NUDGE_FAILED``.

    Returns
    -------
    Outcome
        ``steps``: one Outcome per executed step (module docstring); ``values``: the final
        state (``joint_values``, ``position``, ``orientation``); status ``OK``, or
        ``CRASHED`` with the error of the step that crashed (later steps did not run).

    Raises
    ------
    RobotAPIError and others
        Only from ``MoveGroup(model)`` itself (``Runner.run`` turns them into an outcome).
    """
    run = _Run(runner)
    outcomes: list[Outcome] = []
    crash: BaseException | None = None
    nudge_failed = False
    for index, step in enumerate(call.steps):
        if nudge is not None and nudge.index == index:
            try:
                if nudge.moved is Moved.STATE:
                    run.nudge(nudge.shift)
                elif nudge.moved is Moved.TO:
                    run.move_to(nudge.state)
                elif step.kind == "cartesian_path":
                    step = shifted_goal(step, nudge.shift, nudge.moved, nudge.axis)
                else:
                    run.nudge_goal(nudge.shift, nudge.moved, nudge.axis)
            except Exception:  # noqa: BLE001 - reported as NUDGE_FAILED, never as the step's answer
                nudge_failed = True
        try:
            status, values = run.step(step)
        except RobotAPIError as exc:
            outcomes.append(_failure(Status.REJECTED, exc))
            continue
        except KeyboardInterrupt:
            raise
        except BaseException as exc:  # noqa: BLE001 - a crash of the target ends the scenario
            outcomes.append(_failure(Status.CRASHED, exc))
            crash = exc
            break
        outcomes.append(Outcome(status, values=values))
    steps = tuple(outcomes)
    try:
        final = run.final()
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # noqa: BLE001 - a target that cannot report its state
        if crash is None:
            failed = _failure(Status.REJECTED if isinstance(exc, RobotAPIError) else Status.CRASHED, exc)
            return Outcome(failed.status, failed.error, failed.code, failed.message, {}, steps)
        final = {}
    if nudge_failed:
        final = {**final, NUDGE_FAILED: (1.0,)}
    if crash is not None:
        failed = _failure(Status.CRASHED, crash)
        return Outcome(failed.status, failed.error, failed.code, failed.message, final, steps)
    return Outcome(Status.OK, values=final, steps=steps)


def scenario_outcome(runner: Any, call: ScenarioCall, nudge: Nudge | None = None) -> Outcome:
    """``run_scenario``, never raising: a group that cannot be constructed is the outcome."""
    try:
        return run_scenario(runner, call, nudge)
    except RobotAPIError as exc:
        return Outcome(Status.REJECTED, type(exc).__name__, int(exc.code), str(exc)[:500])
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # noqa: BLE001 - a crash of the target is a finding
        return Outcome(Status.CRASHED, type(exc).__name__, None, str(exc)[:500])
