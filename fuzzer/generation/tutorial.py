"""Seed scenarios written as MoveIt's own tutorials use the API (``--op scenario``).

Hypothesis' first examples are its simplest ones, so many generated seed scenarios are short
lists of settings (``/eef_step`` three times) without a move: of the 32 of ``-seed`` 0, 2 and 6
on the default robot, 3-16 have a ``/plan`` and 1-3 set a scaling factor below 1 before a
``/plan`` or a ``/cartesian_path``. Users, though, start from the tutorials, and the faults
reported against MoveIt's scaling factors were reported against exactly these scripts
(moveit/moveit#1065: a Cartesian path after ``setMaxVelocityScalingFactor``). Each script here
follows one tutorial's sequence of calls, with the robot's own configurations instead of the
Panda's numbers:

``joint_goal``
    moveit2_tutorials ``move_group_interface_tutorial.cpp``, "Planning to a joint-space goal":
    a joint target, both scaling factors 0.05, ``plan``, then executing the plan.
``pose_goal``
    moveit_tutorials ``move_group_python_interface_tutorial.py``: ``go_to_joint_state``
    (``go``, ``stop``), ``go_to_pose_goal`` (``set_pose_target``, ``go``, ``stop``,
    ``clear_pose_targets``), then ``plan_cartesian_path`` and ``execute_plan``.
``cartesian_slow``
    moveit_tutorials ``move_group_interface_tutorial.cpp``, "Cartesian Paths": the velocity
    scaling factor 0.05 ("Cartesian motions are frequently required to be slow"), a path
    through three waypoints at ``eef_step`` 0.01 and ``jump_threshold`` 0.0, then executing it.
``pick_and_place``
    the remember / named-target round trip of pick-and-place scripts: both scaling factors
    0.2, a move, ``remember_joint_values``, another move, back to the remembered state.

Configurations come from a seeded uniform stream inside the joint limits (a continuous
joint's: -pi, pi); pose goals and waypoints are the tip at configurations a tenth of the way
from the state the script stands in toward another one (``GOAL_STEP``), so they are reachable
and near enough for an iterative IK from that state. A straight Cartesian line between two
reachable poses may still leave the workspace or pass a singularity: over seeds 0-29 on
PROBOT Anno, Kinova and UR5, 9 of the 360 scripts have a path that stops short (both targets
alike; numpy's PCG64 stream, used until 2026-12-05, 15). Nothing here runs a target.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any, Final

from fuzzer.generation.spacefill import (
    GOAL_STEP,
    Reachable,
    Uniform,
    configuration_message,
    joint_target_step,
    toward,
)

Step = dict[str, Any]

TUTORIAL: Final = "tutorial"
"""Origin and lineage name of a tutorial script's seed file."""
SLOW: Final = 0.05
"""The tutorials' scaling factor for a slow move (both MoveIt tutorials use 0.05)."""
PICK_SCALING: Final = 0.2
"""The scaling factors of the pick-and-place script."""
EEF_STEP: Final = 0.01
"""The tutorials' Cartesian interpolation step (m): "a resolution of 1 cm"."""
JUMP_THRESHOLD: Final = 0.0
"""The tutorials' jump threshold (disabled)."""
WAYPOINTS: Final = 3
"""Waypoints of a tutorial Cartesian path (down, right, up and left in the C++ tutorial)."""
NAMES: Final = ("joint_goal", "pose_goal", "cartesian_slow", "pick_and_place")
"""The scripts, in the order :func:`tutorial_scenarios` returns them."""
_HEADER: Final[dict[str, Any]] = {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}


def _float(topic: str, value: float) -> Step:
    return {"topic": topic, "msg": {"data": float(value)}}


def _call(topic: str) -> Step:
    return {"topic": topic, "msg": {}}


def _pose(values: tuple[float, ...], reachable: Reachable) -> dict[str, Any]:
    stamped = configuration_message("geometry_msgs/PoseStamped", {"header": _HEADER}, values, (), reachable)
    assert stamped is not None  # a PoseStamped always carries a pose
    pose: dict[str, Any] = stamped["pose"]
    return pose


def tutorial_scenarios(
    lower: Sequence[float],
    upper: Sequence[float],
    joint_names: Sequence[str],
    reachable: Reachable,
    seed: int,
    max_steps: int,
) -> list[tuple[str, dict[str, Any]]]:
    """The tutorial scripts for one robot, as scenario messages.

    Parameters
    ----------
    lower, upper : sequence of float, shape (dof,)
        Joint limits (rad, m); an infinite bound (a continuous joint's) becomes -pi / pi.
    joint_names : sequence of str, shape (dof,)
        The robot's joints in order (the joint targets name every joint).
    reachable : callable
        The robot's FK: a configuration (dof,) -> the tip's position (3,) in m and unit
        quaternion (4,) as (x, y, z, w).
    seed : int
        Seed of the configurations (equal seeds give equal scripts).
    max_steps : int
        A script with more steps is left out.

    Returns
    -------
    list of (str, dict)
        ``(name, {"steps": [...]})`` in the order of :data:`NAMES`, the ones that fit.
        Empty for a robot without joints.
    """
    if not len(lower):
        return []
    # six configurations uniform in the box, Python's Mersenne Twister seeded with ``seed``
    # (``spacefill.Uniform``): numpy's generators cost ``numpy.random``'s import, 11 ms on one
    # CPU, which a scenario campaign's first input waited for (its start-up 11-17 ms behind
    # uniform sampling's on every scenario bug; docs/benchmarks-log.md, fifty-third session)
    q = [tuple(map(float, row)) for row in Uniform(lower, upper, seed).block(6)]
    names = list(joint_names)
    path = [_pose(toward(q[2], q[3], GOAL_STEP * k / WAYPOINTS), reachable) for k in range(1, WAYPOINTS + 1)]
    cartesian = {"header": copy.deepcopy(_HEADER), "poses": path}
    scripts: list[tuple[str, list[Step]]] = [
        (
            "joint_goal",
            [
                joint_target_step(q[0], names),
                _float("/velocity_scaling", SLOW),
                _float("/acceleration_scaling", SLOW),
                _call("/plan"),
                _call("/execute"),
            ],
        ),
        (
            "pose_goal",
            [
                joint_target_step(q[1], names),
                _call("/go"),
                _call("/stop"),
                {
                    "topic": "/pose_target",
                    "msg": {
                        "header": copy.deepcopy(_HEADER),
                        "pose": _pose(toward(q[1], q[4]), reachable),
                    },
                },
                _call("/go"),
                _call("/stop"),
                _call("/clear_pose_targets"),
                {
                    "topic": "/cartesian_path",
                    "msg": {
                        "header": copy.deepcopy(_HEADER),
                        "poses": [_pose(toward(q[1], q[5]), reachable)],
                    },
                },
                _call("/execute"),
            ],
        ),
        (
            "cartesian_slow",
            [
                joint_target_step(q[2], names),
                _call("/go"),
                _float("/velocity_scaling", SLOW),
                _float("/eef_step", EEF_STEP),
                _float("/jump_threshold", JUMP_THRESHOLD),
                {"topic": "/cartesian_path", "msg": cartesian},
                _call("/execute"),
            ],
        ),
        (
            "pick_and_place",
            [
                _float("/velocity_scaling", PICK_SCALING),
                _float("/acceleration_scaling", PICK_SCALING),
                joint_target_step(q[3], names),
                _call("/go"),
                {"topic": "/remember", "msg": {"data": "pick"}},
                joint_target_step(q[4], names),
                _call("/go"),
                {"topic": "/named_target", "msg": {"data": "pick"}},
                _call("/go"),
            ],
        ),
    ]
    return [(name, {"steps": steps}) for name, steps in scripts if len(steps) <= max_steps]
