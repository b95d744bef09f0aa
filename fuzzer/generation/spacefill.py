"""Space-filling joint configurations: a scrambled Sobol sequence inside the joint limits.

Mutation clusters inputs around the corpus and around interesting values; a fault confined
to a narrow band of one joint's range, away from every round number, is then rarely visited.
A low-discrepancy sequence covers the whole box evenly: every joint's range is stratified
(each of the first ``2^k`` points falls in its own ``1/2^k`` slice of every joint's range),
and the points keep coming for the whole campaign. ``SpaceFill`` draws them in blocks of
``BLOCK`` from :class:`scipy.stats.qmc.Sobol` (scrambled, seeded: the same seed gives the
same points) and scales them into the limits; continuous joints use ``(-pi, pi]``.

``configuration_message`` puts one configuration into a message of the campaign's type
(``sensor_msgs/JointState`` positions, ``std_msgs/Float64MultiArray`` data, and for IK a
pose: forward kinematics of the configuration, so the pose is reachable).
"""

from __future__ import annotations

import copy
import math
import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.stats import qmc

BLOCK = 256
"""Points drawn at a time (a power of two keeps Sobol's balance properties per block)."""


@dataclass
class SpaceFill:
    """An endless stream of joint configurations covering the box ``[lower, upper]``.

    Parameters
    ----------
    lower, upper : sequence of float, length dof
        Joint limits (rad, m); an infinite bound (continuous joint) becomes -pi / pi.
    seed : int
        Scrambling seed: equal seeds give equal streams.
    """

    lower: Sequence[float]
    upper: Sequence[float]
    seed: int = 0
    drawn: int = 0
    """Points handed out so far."""
    _engine: Any = field(init=False, repr=False)
    _block: list[tuple[float, ...]] = field(init=False, default_factory=list, repr=False)

    def __post_init__(self) -> None:
        if len(self.lower) != len(self.upper) or not self.lower:
            raise ValueError("SpaceFill needs lower and upper limits of the same non-zero length")
        lo = [(-math.pi if not math.isfinite(x) else float(x)) for x in self.lower]
        hi = [(math.pi if not math.isfinite(x) else float(x)) for x in self.upper]
        self._lo, self._hi = np.array(lo), np.array(hi)
        self._fixed = self._hi <= self._lo  # a joint with lower == upper: always that value
        self._engine = qmc.Sobol(d=len(lo), scramble=True, seed=np.random.default_rng(self.seed))
        self._rows = np.empty((0, len(lo)))

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) as arrays, infinite bounds replaced by -pi / pi."""
        return self._lo.copy(), self._hi.copy()

    def block(self, n: int) -> np.ndarray:
        """The next ``n`` points at once, shape (n, dof), inside the box. Drawn from Sobol in
        power-of-two blocks (its balance needs them) kept in a buffer; a separate sequence
        from ``next``'s (use one of the two per stream)."""
        while len(self._rows) < n:
            size = max(BLOCK, 1 << max(0, n - len(self._rows) - 1).bit_length())
            span = np.where(self._fixed, 0.0, self._hi - self._lo)
            self._rows = np.vstack([self._rows, self._lo + self._engine.random(size) * span])
        out, self._rows = self._rows[:n], self._rows[n:]
        self.drawn += n
        return out

    def next(self) -> tuple[float, ...]:
        """The next configuration (a tuple of dof floats inside the limits)."""
        if not self._block:
            unit = self._engine.random(BLOCK)
            span = np.where(self._fixed, 0.0, self._hi - self._lo)
            points = self._lo + unit * span
            self._block = [tuple(map(float, row)) for row in points[::-1]]
        self.drawn += 1
        return self._block.pop()


def configuration_message(
    msg_type: str,
    base: dict[str, Any],
    values: tuple[float, ...],
    joint_names: Sequence[str],
    reachable: Callable[[tuple[float, ...]], tuple[tuple[float, ...], tuple[float, ...]]] | None = None,
) -> dict[str, Any] | None:
    """A copy of ``base`` (a message of ``msg_type``) carrying configuration ``values``.

    Returns None for a message type without a joint-space or pose field (the source then does
    not apply). A JointState keeps its other fields, with ``name`` set to the robot's joints in
    order when it held names.
    """
    out = copy.deepcopy(base)
    if msg_type == "sensor_msgs/JointState":
        out["position"] = list(values)
        if out.get("name"):
            out["name"] = list(joint_names)
        return out
    if msg_type == "std_msgs/Float64MultiArray":
        out["data"] = list(values)
        return out
    if reachable is None or msg_type not in ("geometry_msgs/PoseStamped", "geometry_msgs/Pose"):
        return None
    position, orientation = reachable(values)
    pose = {
        "position": dict(zip("xyz", map(float, position), strict=True)),
        "orientation": dict(zip("xyzw", map(float, orientation), strict=True)),
    }
    if msg_type == "geometry_msgs/PoseStamped":
        out["pose"] = pose
        return out
    out.update(pose)
    return out


Reachable = Callable[[tuple[float, ...]], tuple[tuple[float, ...], tuple[float, ...]]]


def scenario_with_configuration(
    message: dict[str, Any],
    values: tuple[float, ...],
    joint_names: Sequence[str],
    rng: random.Random,
    max_steps: int,
) -> dict[str, Any] | None:
    """A copy of a scenario (``--op scenario``) whose joint target goes to ``values``: one of
    its ``/joint_target`` steps (picked by ``rng``) gets the configuration (all joints, by
    name), or, when it has none and there is room, a ``/joint_target`` + ``/go`` pair is
    inserted at a random place. None when neither applies."""
    steps = message.get("steps")
    if not isinstance(steps, list):
        return None
    out = copy.deepcopy(message)
    targets = [
        i for i, step in enumerate(steps) if isinstance(step, dict) and step.get("topic") == "/joint_target"
    ]
    if targets:
        msg = out["steps"][rng.choice(targets)]["msg"]
        msg["name"], msg["position"] = list(joint_names), list(values)
        return out
    if len(steps) + 2 > max_steps:
        return None
    state = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": list(joint_names),
        "position": list(values),
        "velocity": [],
        "effort": [],
    }
    at = rng.randint(0, len(steps))
    out["steps"][at:at] = [{"topic": "/joint_target", "msg": state}, {"topic": "/go", "msg": {}}]
    return out


def fresh_inputs(
    op: str,
    msg_type: str,
    stream: SpaceFill,
    joint_names: Sequence[str],
    reachable: Reachable | None = None,
    max_steps: int = 16,
) -> Callable[[dict[str, Any], random.Random], dict[str, Any] | None]:
    """The harness's ``Sources.fresh``: the parent message carrying the stream's next point."""

    def fresh(message: dict[str, Any], rng: random.Random) -> dict[str, Any] | None:
        values = stream.next()
        if op == "scenario":
            return scenario_with_configuration(message, values, joint_names, rng, max_steps)
        return configuration_message(msg_type, message, values, joint_names, reachable)

    return fresh
