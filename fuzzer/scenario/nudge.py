"""Small moves of a scenario's state or goal just before one step, for the oracle's
ill-conditioning checks (``fuzzer.execution.evaluate``; ``run_scenario``'s ``nudge``)."""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from fuzzer.execution.oracle import wrap
from fuzzer.scenario.steps import Step
from robot_api.records import JointType

Axis = tuple[float, float, float]
AXIS: Axis = (1.0, -1.0, 1.0)
"""Default direction of a goal nudge (positions move along it, orientations turn about it)."""


class Moved(enum.Enum):
    """What a :class:`Nudge` moves."""

    STATE = "state"
    """The current state: every joint by the shift (rad, m), minus on odd indices."""
    POSITION = "position"
    """The goal's positions (m, along the nudge's axis): a ``/cartesian_path`` step's waypoints,
    or else the pose or position target in effect, set again moved."""
    ORIENTATION = "orientation"
    """The goal's orientations, turned by the shift (rad, :func:`turned`): a ``/cartesian_path``
    step's waypoints, or else the pose target in effect, set again turned."""
    TO = "to"
    """The current state, moved to the nudge's ``state`` (the shift is not used): both targets
    then start the step from one state (``fuzzer.scenario.common_start``)."""


@dataclass(frozen=True)
class Nudge:
    """A small move just before one step, for the oracle's ill-conditioning checks.

    Attributes
    ----------
    index : int
        The step it comes before.
    shift : float
        How far (rad or m): joints alternate in sign (``+shift`` on even indices), positions
        move by ``shift * axis``, orientations turn by ``shift`` about ``axis``.
    moved : Moved
        The state, or the goal's positions or orientations.
    """

    index: int
    shift: float
    moved: Moved = Moved.STATE
    axis: Axis = AXIS
    """Direction of a goal nudge (``Moved.POSITION``, ``Moved.ORIENTATION``)."""
    state: tuple[float, ...] = ()
    """Where ``Moved.TO`` puts the state (rad, m; one value per joint variable)."""


@dataclass(frozen=True)
class Retry:
    """One of the oracle's ill-conditioning re-runs (``Evaluator._scenario_ik``): the nudge
    before the divergent step and the slack (rad, m) added to the campaign tolerance when its
    answer is compared with the divergent run's. ``label`` names it across inputs."""

    label: str
    nudge: Nudge
    slack: float = 0.0


@dataclass
class Explainers:
    """Labels of the re-runs that explained a divergence, most recent first (move to front).

    A divergence is ``ill_conditioned`` when any one re-run moves a target's answer; which one
    does decides only how many run before it. In a campaign one re-run tends to explain
    divergence after divergence (in a 30-s ``ik_seed_band`` campaign, 65 of 69 were explained
    by the fourth, the state moved by the tolerance), so the last one to explain goes first:
    the same verdicts from fewer re-runs (docs/engine.md, "Ill-conditioning")."""

    recent: list[str] = field(default_factory=list)

    def ordered(self, tries: Sequence[Retry]) -> list[Retry]:
        """``tries`` with the recent explainers first (most recent first), the rest as given."""
        rank = {label: i for i, label in enumerate(self.recent)}
        return sorted(tries, key=lambda t: rank.get(t.label, len(rank)))

    def explained(self, label: str) -> None:
        """The re-run named ``label`` explained a divergence: it goes first next time."""
        if label in self.recent:
            self.recent.remove(label)
        self.recent.insert(0, label)


def turned(q: tuple[float, ...], angle: float, axis: Axis = AXIS) -> tuple[float, ...]:
    """Quaternion ``q`` (x, y, z, w, any norm) followed by a turn of ``angle`` (rad) about the
    unit vector along ``axis`` in its own frame (``q * dq``); the norm is kept."""
    x, y, z, w = q
    k = math.sin(angle / 2.0) / math.sqrt(sum(v * v for v in axis))
    a, b, c, d = k * axis[0], k * axis[1], k * axis[2], math.cos(angle / 2.0)
    return (
        w * a + x * d + y * c - z * b,
        w * b - x * c + y * d + z * a,
        w * c + x * b - y * a + z * d,
        w * d - x * a - y * b - z * c,
    )


def shifted_goal(step: Step, shift: float, moved: Moved = Moved.POSITION, axis: Axis = AXIS) -> Step:
    """``step`` (a ``/pose_target``, ``/position_target`` or ``/cartesian_path``) with every
    position it names moved by ``shift * axis`` (m), or with every orientation turned by
    ``shift`` (rad) about ``axis`` (:func:`turned`); other steps unchanged.

    Raises
    ------
    LookupError
        ``Moved.ORIENTATION`` of a ``/position_target`` (it has no orientation).
    """

    def point_moved(point: dict[str, Any]) -> dict[str, Any]:
        return {k: point[k] + shift * a for k, a in zip("xyz", axis, strict=True)}

    def pose_moved(pose: dict[str, Any]) -> dict[str, Any]:
        if moved is Moved.POSITION:
            return {**pose, "position": point_moved(pose["position"])}
        o = pose["orientation"]
        q = turned((o["x"], o["y"], o["z"], o["w"]), shift, axis)
        return {**pose, "orientation": dict(zip("xyzw", q, strict=True))}

    msg = step.message
    if step.kind == "pose_target":
        return Step(step.kind, {**msg, "pose": pose_moved(msg["pose"])})
    if step.kind == "position_target":
        if moved is Moved.ORIENTATION:
            raise LookupError("a position target has no orientation to turn")
        return Step(step.kind, {**msg, "point": point_moved(msg["point"])})
    if step.kind == "cartesian_path":
        return Step(step.kind, {**msg, "poses": [pose_moved(pose) for pose in msg["poses"]]})
    return step


def shifted_state(state: list[float], shift: float, limits: Any) -> list[float]:
    """``state`` moved by ``shift`` on every joint (minus on odd indices), clamped into the
    limits, continuous joints normalized into (-pi, pi] (the contract's rule)."""
    out = []
    for j, (value, lim) in enumerate(zip(state, limits, strict=True)):
        moved = value + (shift if j % 2 == 0 else -shift)
        out.append(wrap(moved) if lim.type == JointType.CONTINUOUS else min(max(moved, lim.lower), lim.upper))
    return out
