"""Uniform random scripts (``--op scenario``): the uniform baseline's scripts and the full engine's
dry run of them (``fuzzer.dry_run``).

A script has a uniform number of steps (1 to the campaign's ``max_steps``), each kind drawn with
the scenario generator's weights (``fuzzer.input.mapping.SCENARIO_WEIGHTS``); joint targets are
uniform inside the limits (a continuous joint's: -pi, pi), pose and position targets and
Cartesian waypoints the tip's poses at uniform configurations, settings uniform in the
generator's ranges. ``with_start`` runs a script from a given configuration (the full engine's
dry run: ``fuzzer.generation.corpus.literal_scripts``). The only source of randomness is the
injected ``random.Random``.
"""

from __future__ import annotations

import math
import random
from typing import Any, Final

from fuzzer.execution.session import Session
from fuzzer.input.mapping import REMEMBERED, SCENARIO_WEIGHTS
from fuzzer.scenario.steps import KINDS

SETTINGS: Final = {
    "velocity_scaling": (0.05, 1.0),
    "acceleration_scaling": (0.05, 1.0),
    "goal_tolerance": (0.0, 1e-2),
    "eef_step": (0.01, 0.1),
    "jump_threshold": (0.0, 10.0),
}
"""A uniform script's settings: each uniform in the range of ``scenario_strategy``'s values (its
discrete choices, such as the goal tolerance's five values, spread over their range)."""
WAYPOINTS: Final = (1, 3)
"""A uniform script's Cartesian paths have this many waypoints (``scenario_strategy``'s range)."""


def header() -> dict[str, Any]:
    """An empty std_msgs/Header (a new one per message: messages never share a dict)."""
    return {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}


def configuration(session: Session, rng: random.Random) -> list[float]:
    """Uniform joint values inside the limits (rad, m), shape (n_joints,); continuous in (-pi, pi]."""
    q = []
    for lim in session.reference.joint_limits:
        lo = -math.pi if math.isinf(lim.lower) else lim.lower
        hi = math.pi if math.isinf(lim.upper) else lim.upper
        q.append(rng.uniform(lo, hi))
    return q


def pose(session: Session, rng: random.Random) -> dict[str, dict[str, float]]:
    """The tip's pose (m, unit quaternion) at a uniform configuration, as a geometry_msgs/Pose."""
    tip = session.reference.forward_kinematics(configuration(session, rng))
    return {
        "position": dict(zip("xyz", tip.position, strict=True)),
        "orientation": dict(zip("xyzw", tip.orientation, strict=True)),
    }


def uniform_step(session: Session, rng: random.Random, kind: str, remembered: list[str]) -> dict[str, Any]:
    """One step's message of a uniform script (``remembered``: the names stored so far; a
    ``remember`` step adds its name)."""
    if kind == "joint_target":
        names = list(session.reference.joint_names)
        return {
            "header": header(),
            "name": names,
            "position": configuration(session, rng),
            "velocity": [],
            "effort": [],
        }
    if kind == "pose_target":
        return {"header": header(), "pose": pose(session, rng)}
    if kind == "position_target":
        return {"header": header(), "point": pose(session, rng)["position"]}
    if kind == "cartesian_path":
        return {"header": header(), "poses": [pose(session, rng) for _ in range(rng.randint(*WAYPOINTS))]}
    if kind == "remember":
        remembered.append(rng.choice(REMEMBERED))
        return {"data": remembered[-1]}
    if kind == "named_target":
        return {"data": rng.choice(["home", *remembered])}
    if kind in SETTINGS:
        return {"data": rng.uniform(*SETTINGS[kind])}
    return {}  # std_msgs/Empty: /plan, /execute, /go, /stop, /clear_pose_targets


def uniform_script(session: Session, rng: random.Random) -> dict[str, Any]:
    """A uniform script of 1..``max_steps`` steps (the module's docstring), as a scenario message
    ``{"steps": [{"topic": ..., "msg": ...}, ...]}``."""
    kinds, weights = list(SCENARIO_WEIGHTS), list(SCENARIO_WEIGHTS.values())
    remembered: list[str] = []
    steps = []
    for _ in range(rng.randint(1, session.config.max_steps)):
        kind = rng.choices(kinds, weights)[0]
        steps.append({"topic": KINDS[kind], "msg": uniform_step(session, rng, kind, remembered)})
    return {"steps": steps}


START_STEPS: Final = 3
"""Steps ``with_start`` puts before a script: a joint target, ``/go``, a Cartesian path."""


def with_start(
    session: Session, script: dict[str, Any], values: list[float], rng: random.Random
) -> dict[str, Any] | None:
    """``script`` run from ``values`` (rad, m; shape (n_joints,)): first a joint target at them
    and ``/go``, then a ``/cartesian_path`` to the tip's pose at a uniform configuration (IK
    seeded with the state just reached, and a plan that a later ``/execute`` runs), then the
    script's steps, as many as ``max_steps`` leaves room for. None when ``max_steps`` is below
    ``START_STEPS``. A fault that reads the current state (an IK seed, a plan's start) is met
    from there; the script's own steps go on from a state other than home."""
    if session.config.max_steps < START_STEPS:
        return None
    target = {
        "header": header(),
        "name": list(session.reference.joint_names),
        "position": [float(v) for v in values],
        "velocity": [],
        "effort": [],
    }
    start = [
        {"topic": KINDS["joint_target"], "msg": target},
        {"topic": KINDS["go"], "msg": {}},
        {"topic": KINDS["cartesian_path"], "msg": {"header": header(), "poses": [pose(session, rng)]}},
    ]
    return {"steps": [*start, *script["steps"]][: session.config.max_steps]}
