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

from fuzzer.generation.boundary import Boundary
from fuzzer.selection.state import BOUNDARY, SPACEFILL, Made, Maker

BLOCK = 256
"""Points drawn at a time (a power of two keeps Sobol's balance properties per block)."""


WIDEST = 1e300
"""The widest bound a sampler uses (rad, m): a URDF may write +-1e308 for "unbounded", and the
span of such a box overflowed to inf, so every sample was inf."""


def finite_box(lower: Sequence[float], upper: Sequence[float]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Joint limits (rad, m) with an infinite bound (a continuous joint's) replaced by -pi / pi,
    and a finite one beyond :data:`WIDEST` brought to it."""
    return (
        tuple(max(float(x), -WIDEST) if math.isfinite(x) else -math.pi for x in lower),
        tuple(min(float(x), WIDEST) if math.isfinite(x) else math.pi for x in upper),
    )


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
    _sobol: Any = field(init=False, default=None, repr=False)
    _block: list[tuple[float, ...]] = field(init=False, default_factory=list, repr=False)

    def __post_init__(self) -> None:
        if len(self.lower) != len(self.upper) or not self.lower:
            raise ValueError("SpaceFill needs lower and upper limits of the same non-zero length")
        lo, hi = finite_box(self.lower, self.upper)
        self._lo, self._hi = np.array(lo), np.array(hi)
        self._fixed = self._hi <= self._lo  # a joint with lower == upper: always that value
        self._rows = np.empty((0, len(lo)))

    @property
    def _engine(self) -> Any:
        """The Sobol engine, made at the first point drawn: importing ``scipy.stats`` costs
        0.55-0.8 s on one CPU, which a campaign that writes no space-filling seeds (a
        scenario's) then pays at its first fresh input instead of before libFuzzer starts."""
        if self._sobol is None:
            from scipy.stats import qmc

            self._sobol = qmc.Sobol(d=len(self._lo), scramble=True, seed=np.random.default_rng(self.seed))
        return self._sobol

    def ready(self) -> None:
        """Make the Sobol engine now, not at the first point drawn (``Sweep.prime``)."""
        _ = self._engine

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


@dataclass
class Uniform:
    """Pseudo-random joint configurations, uniform in the box ``[lower, upper]``, with
    ``SpaceFill``'s ``box`` and ``block``.

    For the dry run (``fuzzer.dry_run``): its sweeps and uniform configurations run before
    ``scipy.stats``, which ``SpaceFill`` needs, is imported (0.55 s on one CPU). The numbers are
    Python's Mersenne Twister (``random.Random(seed).randbytes``), each 64-bit word made a double
    in [0, 1) from its top 53 bits as numpy's generators do: ``numpy.random`` costs 7-10 ms to
    import, which the dry run's first input would wait for. Uniform points cover the box without
    Sobol's stratification: a band of width ``w`` (a share of one joint's range) is missed by
    ``n`` points with probability ``(1 - w)^n`` instead of not at all once ``n >= 1/w``.

    Parameters
    ----------
    lower, upper : sequence of float, length dof
        Joint limits (rad, m); an infinite bound (continuous joint) becomes -pi / pi.
    seed : int
        Equal seeds give equal streams.
    """

    lower: Sequence[float]
    upper: Sequence[float]
    seed: int = 0
    drawn: int = 0
    """Points handed out so far."""

    def __post_init__(self) -> None:
        if len(self.lower) != len(self.upper) or not self.lower:
            raise ValueError("Uniform needs lower and upper limits of the same non-zero length")
        lo, hi = finite_box(self.lower, self.upper)
        self._lo, self._hi = np.array(lo), np.array(hi)
        self._span = np.where(self._hi > self._lo, self._hi - self._lo, 0.0)
        self._rng = random.Random(self.seed)

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) as arrays, infinite bounds replaced by -pi / pi."""
        return self._lo.copy(), self._hi.copy()

    def block(self, n: int) -> np.ndarray:
        """The next ``n`` points, shape (n, dof), inside the box."""
        self.drawn += n
        words = np.frombuffer(self._rng.randbytes(8 * n * len(self._lo)), dtype="<u8")
        unit = (words >> np.uint64(11)).astype(np.float64) * 2.0**-53  # [0, 1): 53 bits, 2**-53 apart
        points: np.ndarray = self._lo + unit.reshape(n, len(self._lo)) * self._span
        return points


ALIGNED_TURNS = 16
"""The aligned stream's multiples of pi/2 lie within this many turns of 0 (and each joint's two
limits are always among its values): enough for any joint of the shipped robots."""


@dataclass
class Aligned:
    """An endless stream of aligned joint configurations: each joint independently at a
    multiple of pi/2 inside its limits or at one of its limits.

    Space-filling points almost never land where joint axes line up, yet that is where
    kinematics code branches: gimbal lock of a roll-pitch-yaw conversion, wrist and elbow
    singularities, ``atan2(0, 0)``, a zero in a denominator. For a 6-joint arm such
    configurations are a finite set (a few hundred thousand), of which a sizeable share is
    singular; one joint at pi/2 with the others anywhere is not (that is what mutating an
    interesting value into a space-filling input gives).

    Parameters
    ----------
    lower, upper : sequence of float, length dof
        Joint limits (rad, m); an infinite bound (continuous joint) becomes -pi / pi, as in
        ``SpaceFill``. A prismatic joint's multiples of pi/2 are in metres: usually only 0.
    seed : int
        Seeds the choices: equal seeds give equal streams.
    """

    lower: Sequence[float]
    upper: Sequence[float]
    seed: int = 0
    drawn: int = 0
    """Configurations handed out so far."""
    choices: list[tuple[float, ...]] = field(init=False, repr=False)
    """Per joint, the values it takes (sorted)."""

    def __post_init__(self) -> None:
        if len(self.lower) != len(self.upper) or not self.lower:
            raise ValueError("Aligned needs lower and upper limits of the same non-zero length")
        self.choices = []
        quarter = math.pi / 2
        for lo, hi in zip(*finite_box(self.lower, self.upper), strict=True):
            # the multiples within ALIGNED_TURNS turns of 0: limits of +-1e7 listed 13 million
            first = max(math.ceil(lo / quarter), -4 * ALIGNED_TURNS)
            last = min(math.floor(hi / quarter), 4 * ALIGNED_TURNS)
            multiples = [k * quarter for k in range(first, last + 1)]
            self.choices.append(tuple(sorted({lo, hi, *multiples})))
        self._rng = random.Random(self.seed)

    def next(self) -> tuple[float, ...]:
        """The next configuration (a tuple of dof floats inside the limits)."""
        self.drawn += 1
        return tuple(self._rng.choice(values) for values in self.choices)


def configuration_message(
    msg_type: str,
    base: dict[str, Any],
    values: tuple[float, ...],
    joint_names: Sequence[str],
    reachable: Callable[[tuple[float, ...]], tuple[tuple[float, ...], tuple[float, ...]]] | None = None,
    frame: str | None = "",
) -> dict[str, Any] | None:
    """A copy of ``base`` (a message of ``msg_type``) carrying configuration ``values``.

    Returns None for a message type without a joint-space or pose field (the source then does
    not apply). A JointState keeps its other fields, with ``name`` set to the robot's joints in
    order when it held names. A PoseStamped gets ``frame`` as its ``header.frame_id``, the
    link whose goal it is (default "": the group's tip, whose pose ``reachable`` gives; a
    parent's other link asked to reach the tip's pose was mostly out of reach); None keeps the
    parent's.
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
        if frame is not None and isinstance(out.get("header"), dict):
            out["header"]["frame_id"] = frame
        return out
    out.update(pose)
    return out


GOAL_STEP = 0.1
"""How far toward another space-filling point a fresh scenario's pose goal lies (a share)."""
_STAMPED: dict[str, Any] = {"header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}}

Reachable = Callable[[tuple[float, ...]], tuple[tuple[float, ...], tuple[float, ...]]]


SEEDED_BY_STATE = ("/pose_target", "/position_target", "/cartesian_path")
"""Steps whose IK starts from the current state (MoveIt seeds a pose goal's and a Cartesian
path's IK with it): a fault that depends on the IK seed shows only from some states."""


def toward(a: Sequence[float], b: Sequence[float], share: float = GOAL_STEP) -> tuple[float, ...]:
    """The configuration ``share`` of the way from ``a`` to ``b`` (rad, m), joint by joint."""
    return tuple(v + share * (t - v) for v, t in zip(a, b, strict=True))


def joint_target_step(values: Sequence[float], joint_names: Sequence[str]) -> dict[str, Any]:
    """A ``/joint_target`` step setting every joint, by name, to ``values``."""
    state = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": list(joint_names),
        "position": list(values),
        "velocity": [],
        "effort": [],
    }
    return {"topic": "/joint_target", "msg": state}


def _state_steps(values: tuple[float, ...], joint_names: Sequence[str]) -> list[dict[str, Any]]:
    """``/joint_target`` (all joints, by name) then ``/go``: the robot moves to ``values``."""
    return [joint_target_step(values, joint_names), {"topic": "/go", "msg": {}}]


def scenario_with_configuration(
    message: dict[str, Any],
    values: tuple[float, ...],
    joint_names: Sequence[str],
    rng: random.Random,
    max_steps: int,
    goal: Callable[[tuple[float, ...]], dict[str, Any]] | None = None,
) -> dict[str, Any] | None:
    """A copy of a scenario (``--op scenario``) that visits configuration ``values``.

    Either one of its ``/joint_target`` steps (picked by ``rng``) gets the configuration (all
    joints, by name), or a ``/joint_target`` + ``/go`` pair moves the robot there right before
    one of its steps seeded by the current state (``SEEDED_BY_STATE``), so the space-filling
    points cover the IK seeds too; each with even odds when both apply. With neither and
    room, the pair goes in at a random place, followed by ``/pose_target`` ``goal(values)`` (a
    PoseStamped message: a pose goal from that state) and ``/go`` when ``goal`` is given and
    there is room for four steps.
    None when nothing applies.
    """
    steps = message.get("steps")
    if not isinstance(steps, list):
        return None
    out = copy.deepcopy(message)
    topics = [step.get("topic") if isinstance(step, dict) else None for step in steps]
    targets = [i for i, topic in enumerate(topics) if topic == "/joint_target"]
    seeded = [i for i, topic in enumerate(topics) if topic in SEEDED_BY_STATE]
    room = max_steps - len(steps)
    if seeded and room >= 2 and (not targets or rng.random() < 0.5):
        at = rng.choice(seeded)
        out["steps"][at:at] = _state_steps(values, joint_names)
        return out
    if targets:
        msg = out["steps"][rng.choice(targets)]["msg"]
        msg["name"], msg["position"] = list(joint_names), list(values)
        return out
    if room < 2:
        return None
    inserted = _state_steps(values, joint_names)
    if goal is not None and room >= 4:
        inserted += [{"topic": "/pose_target", "msg": goal(values)}, {"topic": "/go", "msg": {}}]
    at = rng.randint(0, len(steps))
    out["steps"][at:at] = inserted
    return out


def fresh_inputs(
    op: str,
    msg_type: str,
    stream: SpaceFill | Aligned,
    joint_names: Sequence[str],
    reachable: Reachable | None = None,
    max_steps: int = 16,
    boundary: Boundary | None = None,
    name: str = SPACEFILL,
) -> Maker:
    """The harness's ``Sources.fresh`` (and, with an ``Aligned`` stream and ``name`` ``aligned``,
    ``Sources.aligned``): the parent message carrying the stream's next point, and its lineage
    name ``name``. While ``boundary`` has probes left, every other call instead
    carries the last point with one joint on an edge, named ``spacefill:boundary``
    (``fuzzer.generation.boundary``), and the stream does not advance."""
    last: list[tuple[float, ...]] = []

    def goal(values: tuple[float, ...]) -> dict[str, Any]:
        # the tip at a configuration a tenth of the way from ``values`` toward the stream's next
        # point: reachable, and near enough for an iterative IK from ``values`` to converge
        near = toward(values, stream.next())
        pose = configuration_message("geometry_msgs/PoseStamped", _STAMPED, near, (), reachable)
        assert pose is not None
        return pose

    def fresh(message: dict[str, Any], rng: random.Random) -> Made:
        probed = boundary is not None and boundary.left > 0 and len(last) == 1
        if probed:
            assert boundary is not None
            values, _ = boundary.apply(last.pop())
        else:
            values = stream.next()
            last[:] = [values]
        if op == "scenario":
            out = scenario_with_configuration(
                message, values, joint_names, rng, max_steps, goal if reachable is not None else None
            )
        else:
            out = configuration_message(msg_type, message, values, joint_names, reachable)
        if out is None:
            return None
        return out, (BOUNDARY if probed else name)

    return fresh
