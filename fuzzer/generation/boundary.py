"""Boundary probes: space-filling points with one joint put on an edge, once per process.

Space-filling points (``fuzzer.generation.spacefill``) lie inside the limits and never on a round
number, while many real faults sit exactly there: a bounds check with the wrong tolerance, a
target outside the limits clamped or set anyway, a continuous joint at exactly pi, a missing
``lower`` read as unlimited. Mutation reaches them only when an ``interesting`` mutation picks
the right value for the right joint (about one in a hundred of those mutations). This is AFL's
deterministic interesting-value stage, done once per process and carried by space-filling
points: a probe replaces one joint of a point with an edge value, round by round (every joint
and side at the first offset, then every joint at the next...), so each probe is otherwise an
ordinary in-limits configuration.

The space-filling seeds (``fuzzer.generation.corpus``) carry the first round: 5e-5 past a
limit, inside MoveIt's goal tolerance, so a correct target still accepts the input and the
seed's other joints still count. The rest come during the campaign
(``fuzzer.generation.spacefill.fresh_inputs``) as inputs of their own, every other fresh input,
each on the last plain point: a probe past the tolerance is rejected as a whole, so it must not
use up a point of the space-filling sequence. An input that carries one has the lineage
``spacefill:boundary`` (``fuzzer.selection.state.BOUNDARY``).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

OFFSETS = (5e-5, 1.5e-4, 0.0, 1e-4, 1e-6, 1e-9)
"""How far past a finite limit each round puts a joint (rad or m), in round order: inside
MoveIt's default goal tolerance (1e-4: accepted by a correct bounds check, rejected by one with
a tighter tolerance), just beyond it (rejected, or clamped, or set anyway), exactly on the limit,
on the tolerance itself, and the float-noise distances."""

CONTINUOUS = (math.pi, -math.pi, 0.0, math.pi / 2, -math.pi / 2, 2 * math.pi)
"""The values of a joint without limits (a continuous joint) in the same rounds: the wrap
points first (``(-pi, pi]`` against ``[-pi, pi)``)."""

ORIENTATION_SCALES = (0.5, 2.0, 1e-6, 0.0)
"""The lengths a pose target's quaternion gets in the orientation probes (``scale_orientation``):
a pose's precondition is a unit quaternion, as a joint's is its limits. Half and twice unit length
(a quaternion written by hand, or averaged without renormalizing: MoveIt warns and goes on), a
tiny but valid length (the normalization's precision; ``QUATERNION_NORM_EPS`` is 1e-9), and zero
(rejected as an invalid argument by a correct target)."""

REACH_FACTOR = 4.0
"""The reach probe's distance from the base (``beyond_reach``), in multiples of the farthest tip
of ``REACH_SAMPLES`` uniform configurations: a pose goal out of reach, where an IK solver takes
its failure path (iterations run out; a status code to report, a classic place to misread one).
The sampled farthest tip of a serial arm is more than a quarter of its reach."""

REACH_SAMPLES = 64


POSE_TYPES = ("geometry_msgs/PoseStamped", "geometry_msgs/Pose")
"""Message types with a pose ``beyond_reach`` can move."""


def beyond_reach(msg_type: str, message: dict[str, Any], distance: float) -> dict[str, Any] | None:
    """A copy of a pose message with its position moved along its direction from the base's
    origin (x if it is the origin) to ``distance`` m; None for a type without a pose."""
    out = copy.deepcopy(message)
    pose = out.get("pose") if msg_type == "geometry_msgs/PoseStamped" else out
    if msg_type not in POSE_TYPES or not isinstance(pose, dict):
        return None
    position = pose.get("position")
    if not isinstance(position, dict):
        return None
    xyz = [float(position.get(k, 0.0)) for k in "xyz"]
    norm = math.sqrt(sum(v * v for v in xyz))
    direction = [v / norm for v in xyz] if norm > 0.0 and math.isfinite(norm) else [1.0, 0.0, 0.0]
    pose["position"] = {k: distance * d for k, d in zip("xyz", direction, strict=True)}
    return out


def probes(
    lower: Sequence[float], upper: Sequence[float], rounds: int = len(OFFSETS)
) -> list[tuple[int, float]]:
    """The probes of the first ``rounds`` rounds as (joint index, value), in the order they are used.

    Parameters
    ----------
    lower, upper : sequence of float, length dof
        Joint limits (rad, m); infinite on a side without a limit.
    rounds : int
        How many rounds (default all; the seeds take one).

    Returns
    -------
    list of (int, float)
        Round ``k`` holds, joint by joint, ``upper + OFFSETS[k]`` and ``lower - OFFSETS[k]``
        for each finite bound, and ``CONTINUOUS[k]`` for a joint with neither bound.
    """
    if len(lower) != len(upper):
        raise ValueError("probes need lower and upper limits of the same length")
    out: list[tuple[int, float]] = []
    for k, offset in enumerate(OFFSETS[: max(0, rounds)]):
        for j, (lo, hi) in enumerate(zip(lower, upper, strict=True)):
            values = [hi + offset] if math.isfinite(hi) else []
            if math.isfinite(lo):
                values.append(lo - offset)
            if not values:
                values = [CONTINUOUS[k]]
            out.extend((j, v) for v in values)
    return out


@dataclass
class Boundary:
    """The probes of one process, handed out in order until they run out.

    Parameters
    ----------
    lower, upper : sequence of float, length dof
        Joint limits (see :func:`probes`).
    start : int
        Probes already used elsewhere (by the space-filling seeds this campaign wrote).
    rounds : int
        How many rounds to hand out at most (default all; the seeds take one).
    """

    lower: Sequence[float]
    upper: Sequence[float]
    start: int = 0
    rounds: int = len(OFFSETS)
    items: list[tuple[int, float]] = field(init=False, repr=False)
    used: int = field(init=False)

    def __post_init__(self) -> None:
        self.items = probes(self.lower, self.upper, self.rounds)
        self.used = max(0, self.start)

    @property
    def left(self) -> int:
        """Probes not handed out yet."""
        return max(0, len(self.items) - self.used)

    def apply(self, values: Sequence[float]) -> tuple[tuple[float, ...], bool]:
        """``values`` with the next probe's joint set to its value, and whether a probe was
        left to apply (if not, ``values`` unchanged)."""
        if self.used >= len(self.items):
            return tuple(values), False
        j, value = self.items[self.used]
        self.used += 1
        out = list(values)
        if j < len(out):
            out[j] = value
        return tuple(out), True


def scale_orientation(msg_type: str, message: dict[str, Any], scale: float) -> dict[str, Any] | None:
    """A copy of a pose message with its orientation quaternion's components times ``scale``.

    Parameters
    ----------
    msg_type : str
        ``geometry_msgs/PoseStamped`` or ``geometry_msgs/Pose``; any other type has no pose
        target (None).
    message : dict
        A valid message of ``msg_type``.
    scale : float
        The factor (``ORIENTATION_SCALES``): a unit quaternion gets this length.
    """
    out = copy.deepcopy(message)
    pose = out.get("pose") if msg_type == "geometry_msgs/PoseStamped" else out
    if msg_type not in POSE_TYPES or not isinstance(pose, dict):
        return None
    orientation = pose.get("orientation")
    if not isinstance(orientation, dict):
        return None
    pose["orientation"] = {k: float(orientation.get(k, 0.0)) * scale for k in "xyzw"}
    return out
