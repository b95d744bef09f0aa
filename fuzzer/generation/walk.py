"""A walk of IK goals through joint space: a pose goal moved by moving the configuration it is
the pose of, so that the moved goal stays reachable.

Mutating a pose goal's fields moves it off the set of poses the arm can take: a position moved
a few centimetres with the orientation kept is, for a 6-joint arm, mostly a pose no
configuration reaches, and an IK fault there shows as nothing (both targets fail). Session 63's
untuned bug ``ik_ball`` (IK fails for goals within 2.54 cm of a point of the workspace;
BENCHMARKS.md, "Bugs the engine was not tuned on") is such a region: the float tracer led the
search into the ball, but by poses KDL could not reach either, so only the space-filling
inputs' share found it.

:class:`Walk` is a source of the bandit over input sources (``fuzzer.selection.state.Sources``,
arm ``walk``) for ``--op ik``. It keeps, per pose goal, a configuration whose pose it is: the
configuration a space-filling or aligned input was made from (:meth:`Walk.recording` wraps the
robot's forward kinematics that makes them), the one a walk made, or the first target's IK
solution when it converged and reaches the goal (:meth:`Walk.learn`). :meth:`Walk.make` moves
the parent's configuration (one, two or all of the joints before the goal's link, by a normal
step whose size is drawn log-uniformly between ``STEP_SHARES`` of each joint's range, clamped
to the limits) and gives
the pose of the moved configuration, of the same link, in a copy of the parent: a goal near
the parent's and reachable. A parent with no known configuration is not walked (the harness
mutates it instead).

Half the walks start from libFuzzer's parent; the other half from the walkable input that came
nearest the flip of a float comparison (``FloatCompareTracer.nearer``), a site drawn uniformly
(:meth:`Walk.offer`, :meth:`Walk.parent`). So a walk climbs toward a branch on the goal's
position (each step nearer is a new float-comparison feature) through reachable goals only,
from its best step so far.
"""

from __future__ import annotations

import math
import random
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any

from fuzzer.execution.records import Outcome, Status
from fuzzer.generation.spacefill import Reachable, configuration_message, finite_box
from fuzzer.input.mapping import MAPPINGS, IkCall
from fuzzer.input.testcase import TestCase
from fuzzer.selection.state import WALK, Made

CAPACITY = 4096
"""Pose goals whose configuration is kept (the least recently used are forgotten)."""
STEP_SHARES = (1e-4, 0.3)
"""A step's standard deviation lies between these shares of a joint's range (log-uniformly)."""
ONE_JOINT, TWO_JOINTS = 0.5, 0.25
"""How often a step moves one joint, two joints; otherwise it moves every joint."""
LEARN_SLACK = 1e-4
"""How far (m, rad) the forward kinematics of a converged IK answer may put the link from the
goal for the answer to be learned as the goal's configuration (KDL stops within about 1.7e-5)."""
FRONTIER = 1024
"""Float-comparison sites whose nearest walkable input is kept (the least recently improved
are forgotten)."""
FRONTIER_CHANCE = 0.5
"""How often a walk starts from the nearest input of a site instead of libFuzzer's parent."""

Key = tuple[tuple[float, ...], tuple[float, ...], str | None]
PoseOf = Callable[[tuple[float, ...], str | None], tuple[tuple[float, ...], tuple[float, ...]]]
"""Forward kinematics of a configuration for a link (None: the group's tip): (position, orientation)."""


class Walk:
    """The ``walk`` source of an ``ik`` campaign (the module's docstring says what it does).

    Parameters
    ----------
    msg_type : str
        The campaign's message type (``geometry_msgs/PoseStamped`` or ``geometry_msgs/Pose``).
    lower, upper : sequence of float, length dof
        Joint limits (rad, m); an infinite bound (continuous joint) becomes -pi / pi.
    pose_of : callable (values, link) -> (position, orientation)
        The robot's forward kinematics (m; quaternion x, y, z, w).
    capacity : int
        How many pose goals' configurations are kept.
    """

    def __init__(
        self,
        msg_type: str,
        lower: Sequence[float],
        upper: Sequence[float],
        pose_of: PoseOf,
        capacity: int = CAPACITY,
    ) -> None:
        self.msg_type = msg_type
        self.lower, self.upper = finite_box(lower, upper)
        self.pose_of = pose_of
        self.capacity = capacity
        self._known: OrderedDict[Key, tuple[float, ...]] = OrderedDict()
        self.frontier: OrderedDict[int, TestCase] = OrderedDict()
        """Per float-comparison site, the walkable input that came nearest its flip."""
        self._movers: dict[str | None, tuple[int, ...]] = {}

    def __len__(self) -> int:
        return len(self._known)

    def note(
        self,
        position: Sequence[float],
        orientation: Sequence[float],
        link: str | None,
        values: Sequence[float],
    ) -> None:
        """Remember that ``values`` puts ``link`` at (``position``, ``orientation``)."""
        key = (tuple(map(float, position)), tuple(map(float, orientation)), link)
        self._known[key] = tuple(map(float, values))
        self._known.move_to_end(key)
        while len(self._known) > self.capacity:
            self._known.popitem(last=False)

    def recording(self, reachable: Reachable) -> Reachable:
        """``reachable`` (forward kinematics of the group's tip), remembering each configuration
        by the pose it gives: the space-filling and aligned sources' goals become walkable."""

        def recorded(values: tuple[float, ...]) -> tuple[tuple[float, ...], tuple[float, ...]]:
            position, orientation = reachable(values)
            self.note(position, orientation, None, values)
            return position, orientation

        return recorded

    def learn(self, call: Any, outcomes: Sequence[Outcome]) -> None:
        """After an input ran: the first target's IK solution of ``call`` when it converged
        and its forward kinematics puts the link at the goal (within ``LEARN_SLACK``: a target
        that claims success wrongly is what this fuzzer looks for)."""
        if not isinstance(call, IkCall) or not outcomes or outcomes[0].status is not Status.OK:
            return
        values = tuple(outcomes[0].values.get("joint_values", ()))
        if len(values) != len(self.lower) or not all(map(math.isfinite, values)):
            return
        try:
            position, orientation = self.pose_of(values, call.link)
            goal = tuple(map(float, call.position)), tuple(map(float, call.orientation))
        except Exception:  # noqa: BLE001 - a target's error or a huge number: nothing learned
            return
        if _apart(position, orientation, *goal) <= LEARN_SLACK:
            self.note(*goal, call.link, values)

    def offer(self, site: int, case: TestCase) -> None:
        """``case`` came nearer the flip of float comparison ``site`` than any input before
        (``FloatCompareTracer.nearer``): that site's preferred parent, when its goal's
        configuration is known."""
        if self.configuration(case.message) is not None:
            self.frontier[site] = case
            self.frontier.move_to_end(site)
            while len(self.frontier) > FRONTIER:
                self.frontier.popitem(last=False)

    def parent(self, case: TestCase, rng: random.Random) -> TestCase:
        """The input to walk from: libFuzzer's parent ``case`` or, ``FRONTIER_CHANCE`` of the
        time, the input nearest the flip of a site drawn uniformly. libFuzzer draws its parent
        from the whole corpus (hundreds of inputs), so a climb toward a branch on the goal went
        on from its last step only about once per corpus size of walks; an ``ik`` campaign
        on a plugged-in target has about 15 sites."""
        if self.frontier and rng.random() < FRONTIER_CHANCE:
            return self.frontier[rng.choice(list(self.frontier))]
        return case

    def configuration(self, message: dict[str, Any]) -> tuple[tuple[float, ...], str | None] | None:
        """The known configuration of ``message``'s goal and the goal's link, or None."""
        found = self._lookup(message)
        return None if found is None else (found[1], found[0][2])

    def _lookup(self, message: dict[str, Any]) -> tuple[Key, tuple[float, ...]] | None:
        """``message``'s goal as a key and its known configuration (now the most recently
        used), or None."""
        key = self._key(message)
        values = None if key is None else self._known.get(key)
        if key is None or values is None:
            return None
        self._known.move_to_end(key)
        return key, values

    def _key(self, message: dict[str, Any]) -> Key | None:
        """``message``'s goal as a key of the known configurations, or None (not a goal)."""
        try:
            call = MAPPINGS[("ik", self.msg_type)](message)
            if not isinstance(call, IkCall):
                return None
            return (tuple(map(float, call.position)), tuple(map(float, call.orientation)), call.link)
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError):
            return None

    def movers(self, link: str | None) -> tuple[int, ...]:
        """The joints that move ``link`` (those before it in the chain), found once per link by
        moving each joint from the middle of the limits: a walk of a joint after the link
        gave its parent's goal again (every walk of a ``base_link`` goal)."""
        if link not in self._movers:
            middle = [(lo + hi) / 2.0 for lo, hi in zip(self.lower, self.upper, strict=True)]
            try:
                here = self.pose_of(tuple(middle), link)
                found = []
                for j, (lo, hi) in enumerate(zip(self.lower, self.upper, strict=True)):
                    moved = list(middle)
                    moved[j] = lo + 0.75 * (hi - lo)
                    if self.pose_of(tuple(moved), link) != here:
                        found.append(j)
                self._movers[link] = tuple(found)
            except Exception:  # noqa: BLE001 - a link a target refuses: nothing to walk
                self._movers[link] = ()
        return self._movers[link]

    def step(
        self, values: Sequence[float], rng: random.Random, joints: Sequence[int] | None = None
    ) -> tuple[float, ...]:
        """``values`` inside the limits (a boundary probe's configuration lies just past one)
        with one, two or all of ``joints`` (default: every joint) moved by a normal step,
        clamped to the limits."""
        q = [min(max(float(v), lo), hi) for v, lo, hi in zip(values, self.lower, self.upper, strict=True)]
        pool = range(len(q)) if joints is None else joints
        draw = rng.random()
        count = 1 if draw < ONE_JOINT else 2 if draw < ONE_JOINT + TWO_JOINTS else len(pool)
        share = math.exp(rng.uniform(math.log(STEP_SHARES[0]), math.log(STEP_SHARES[1])))
        for j in rng.sample(pool, min(count, len(pool))):
            lo, hi = float(self.lower[j]), float(self.upper[j])
            q[j] = min(max(q[j] + rng.gauss(0.0, share * (hi - lo)), lo), hi)
        return tuple(q)

    def make(self, message: dict[str, Any], rng: random.Random) -> Made:
        """A copy of ``message`` whose goal is the pose of its known configuration moved by
        :meth:`step` in the joints that move its link (named ``walk``); None when its
        configuration is not known, no joint moves its link, or the step gives its goal again."""
        found = self._lookup(message)
        if found is None:
            return None
        key, values = found
        link = key[2]
        joints = self.movers(link)
        if not joints:
            return None
        moved = self.step(values, rng, joints)
        position, orientation = self.pose_of(moved, link)
        if not all(map(math.isfinite, (*position, *orientation))) or (position, orientation) == key[:2]:
            return None
        self.note(position, orientation, link, moved)
        out = configuration_message(
            self.msg_type, message, moved, (), lambda _: (position, orientation), frame=None
        )
        return None if out is None else (out, WALK)


def _apart(
    position: Sequence[float],
    orientation: Sequence[float],
    goal_position: Sequence[float],
    goal_orientation: Sequence[float],
) -> float:
    """The larger of the distance (m) and the rotation angle (rad) between two poses."""
    dot = abs(sum(a * b for a, b in zip(orientation, goal_orientation, strict=True)))
    norms = math.sqrt(sum(a * a for a in orientation) * sum(b * b for b in goal_orientation))
    angle = 2.0 * math.acos(min(1.0, dot / norms)) if norms > 0.0 else math.inf
    return max(math.dist(position, goal_position), angle)
