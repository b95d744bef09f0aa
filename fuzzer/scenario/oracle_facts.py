"""What the scenario oracle knows: the robot's joints, and what is in effect before each step.

The settings in effect on one target are derived by walking the scenario's steps with that
target's own step statuses (a step that raised changes nothing, as the contract says): the
scaling factors (default 1.0) and the goal joint tolerance (``GOAL_JOINT_TOLERANCE``) from
their steps that succeeded, the joint goal (``home_values`` first, then the ``joint_target``
each successful ``/joint_target`` or ``/named_target`` reports), whether a pose or position
target is active, the last plan (the trajectory of a successful ``/plan`` or of a
``/cartesian_path`` that returned), and the state (the previous step's ``joint_values``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

from fuzzer.execution.records import Outcome, Status
from fuzzer.scenario.steps import ScenarioCall, Step
from robot_api.constants import DEFAULT_VELOCITY_LIMIT, GOAL_JOINT_TOLERANCE
from robot_api.records import JointType

DEFAULT_EEF_STEP = 0.01
"""eef_step (m) until an ``/eef_step`` step sets another (``fuzzer.scenario.execute``)."""

Forward = Callable[[Sequence[float], str | None], tuple[tuple[float, ...], tuple[float, ...]]]
"""FK of a configuration at a link (None: the tip): ((x, y, z) m, (x, y, z, w))."""


@dataclass(frozen=True)
class JointSpec:
    """One joint variable as the properties need it.

    Attributes
    ----------
    type : str
        ``revolute``, ``continuous`` or ``prismatic``.
    lower, upper : float
        Position limits (rad or m; infinite for continuous joints).
    velocity : float
        Planning velocity limit before scaling (rad/s or m/s): the URDF ``velocity`` if it is
        ``> 0``, else ``DEFAULT_VELOCITY_LIMIT`` (docs/api.md, "The model").
    """

    type: str
    lower: float
    upper: float
    velocity: float

    @property
    def continuous(self) -> bool:
        return self.type == JointType.CONTINUOUS

    @property
    def prismatic(self) -> bool:
        return self.type == JointType.PRISMATIC


def planning_velocity(velocity: float) -> float:
    """The contract's rule: ``velocity`` if it is > 0, else ``DEFAULT_VELOCITY_LIMIT``."""
    return velocity if velocity > 0.0 else DEFAULT_VELOCITY_LIMIT


@dataclass(frozen=True)
class ScenarioFacts:
    """The robot as the scenario oracle sees it (from the reference target's model).

    Attributes
    ----------
    joints : tuple of JointSpec
        Per joint variable, in order (dof entries).
    targets : (str, str)
        The two targets' names (a property violation names its target).
    home : tuple of float or None
        ``home_values``: the state and the joint goal a new group starts with.
    forward : Forward or None
        FK for the IK rules (same pose, half turn, knife edge); None disables them.
    """

    joints: tuple[JointSpec, ...]
    targets: tuple[str, str] = ("a", "b")
    home: tuple[float, ...] | None = None
    forward: Forward | None = None

    @property
    def prismatic(self) -> tuple[bool, ...]:
        return tuple(j.prismatic for j in self.joints)

    @property
    def continuous(self) -> tuple[bool, ...]:
        return tuple(j.continuous for j in self.joints)

    @classmethod
    def of(cls, model: Any, targets: tuple[str, str] = ("a", "b")) -> ScenarioFacts:
        """The facts of a loaded ``RobotModel`` (its ``joint_limits``, ``home_values``, FK)."""
        joints = tuple(
            JointSpec(
                str(lim.type), float(lim.lower), float(lim.upper), planning_velocity(float(lim.velocity))
            )
            for lim in model.joint_limits
        )

        def forward(q: Sequence[float], link: str | None) -> tuple[tuple[float, ...], tuple[float, ...]]:
            pose = model.forward_kinematics(list(q), link)
            return tuple(map(float, pose.position)), tuple(map(float, pose.orientation))

        return cls(joints, targets, tuple(float(x) for x in model.home_values), forward)


@dataclass(frozen=True)
class PoseGoal:
    """An active pose or position target: its link (None: the tip), orientation (None for a
    position target, whose orientation is the link's at planning time) and position (m; None
    when the message has none the oracle can read)."""

    link: str | None
    orientation: tuple[float, ...] | None
    position: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Context:
    """What is in effect on one target just before a step."""

    velocity_scaling: float = 1.0
    acceleration_scaling: float = 1.0
    goal_tolerance: float = GOAL_JOINT_TOLERANCE
    eef_step: float = DEFAULT_EEF_STEP
    joint_goal: tuple[float, ...] | None = None
    pose_goal: PoseGoal | None = None
    last_plan: tuple[float, ...] | None = None
    """The last point of this target's last plan (what ``/execute`` executes)."""
    state: tuple[float, ...] | None = None
    """The current joint values (None before the first step when ``home`` is unknown)."""


def _float(message: dict[str, Any]) -> float | None:
    value = message.get("data")
    return float(value) if isinstance(value, int | float) and math.isfinite(value) else None


def _link(message: dict[str, Any]) -> str | None:
    header = message.get("header")
    frame = header.get("frame_id") if isinstance(header, dict) else None
    return frame if isinstance(frame, str) and frame else None


def _orientation(message: dict[str, Any]) -> tuple[float, ...] | None:
    try:
        q = message["pose"]["orientation"]
        return tuple(float(q[k]) for k in "xyzw")
    except (KeyError, TypeError, ValueError):
        return None


def _point(message: dict[str, Any], kind: str) -> tuple[float, ...] | None:
    """A pose target's position, or a position target's point (m), if finite."""
    try:
        p = message["pose"]["position"] if kind == "pose_target" else message["point"]
        point = tuple(float(p[k]) for k in "xyz")
    except (KeyError, TypeError, ValueError, OverflowError):
        return None
    return point if all(math.isfinite(x) for x in point) else None


def _last_row(outcome: Outcome, dof: int) -> tuple[float, ...] | None:
    positions = outcome.values.get("trajectory.positions", ())
    if dof <= 0 or not positions or len(positions) % dof:
        return None
    return tuple(positions[-dof:])


def advance(ctx: Context, step: Step, outcome: Outcome, dof: int) -> Context:
    """What is in effect after ``step`` ended with ``outcome`` on one target."""
    state = outcome.values.get("joint_values")
    after = replace(ctx, state=tuple(state)) if state is not None else ctx
    if outcome.status is not Status.OK:
        return after
    kind, msg = step.kind, step.message
    number = _float(msg)
    if kind == "velocity_scaling" and number is not None:
        return replace(after, velocity_scaling=number)
    if kind == "acceleration_scaling" and number is not None:
        return replace(after, acceleration_scaling=number)
    if kind == "goal_tolerance" and number is not None:
        return replace(after, goal_tolerance=number)
    if kind == "eef_step" and number is not None:
        return replace(after, eef_step=number)
    if kind in ("joint_target", "named_target"):
        goal = outcome.values.get("joint_target")
        return replace(after, joint_goal=None if goal is None else tuple(goal), pose_goal=None)
    if kind == "pose_target":
        return replace(after, pose_goal=PoseGoal(_link(msg), _orientation(msg), _point(msg, kind)))
    if kind == "position_target":
        return replace(after, pose_goal=PoseGoal(_link(msg), None, _point(msg, kind)))
    if kind == "clear_pose_targets":
        return replace(after, pose_goal=None)
    if kind in ("plan", "cartesian_path"):
        return replace(after, last_plan=_last_row(outcome, dof))
    return after


def contexts(call: ScenarioCall, outcome: Outcome, facts: ScenarioFacts) -> list[Context]:
    """What is in effect before each executed step of one target's run (one per step)."""
    ctx = Context(joint_goal=facts.home, state=facts.home)
    out = []
    for step, result in zip(call.steps, outcome.steps, strict=False):
        out.append(ctx)
        ctx = advance(ctx, step, result, len(facts.joints))
    return out
