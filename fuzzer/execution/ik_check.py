"""An IK status divergence judged for what it is: a finding, ill-conditioning or KDL's dead zone.

``judge_status`` takes a single IK call whose two targets split on the status (one
converged, one did not) and decides, in this order:

1. each target is re-run with its documented default seed (its ``home_values``) passed
   explicitly: a target whose answer changes has another default seed, and the divergence
   stands;
2. the requested orientation within ``DEAD_ZONE`` of a half turn from where the seed puts
   the link (``in_dead_zone``): ``known_limitation``;
3. every target's last iterate (a success's answer, a failure's last Newton-Raphson
   iterate) within ``oracle.IK_RESIDUAL`` of the requested pose by its own forward
   kinematics (``at_knife_edge``): ``ill_conditioned``. Both stopped where the convergence
   criterion (every error-twist component within ``IK_EPS``) is decided by rounding: on a pose
   just out of reach, both stall at one configuration about ``IK_EPS`` short, one just inside
   the criterion and one just outside, and a goal move of 5e-7 m gives both the same status;
4. the seeds moved by ``IK_PERTURBATIONS``, then the goal's position moved and, separately,
   its orientation turned by ``GOAL_NUDGES``: a target that changes its own status makes it
   ``ill_conditioned``;
5. a Newton-Raphson iterate that meets a rotation error within ``DEAD_ZONE`` of a half turn
   (``meets_half_turn``): ``known_limitation``. KDL's ``diff`` and the twin's logarithm pick
   opposite axes for an exact half turn, so from there the two iterate differently; step 2
   is this rule at the seed. The iterates are replayed by the twin's own Newton-Raphson
   (``python_impl.model.ik_rotation_errors``) on a fresh model of the robot, not on a
   campaign target; they are KDL's iterates up to the first tie, as both implement one
   documented algorithm (docs/api.md, "Inverse kinematics"). A scenario's ``go``/``plan``
   toward a pose goal has this rule too, after its nudges (``step_meets_half_turn``, called by
   ``Evaluator._scenario_ik``), on the one IK call the twin makes at that step;
6. the call re-run with KDL's small-rotation dead zone in the twin
   (``dead_zone.twin_with_kdl_dead_zone``: KDL's ``diff`` reports no rotation below about
   5e-7 rad, the twin's logarithm does): if the two targets then agree (the same status, and
   ``judge`` finds no counted divergence), that dead zone is the whole difference,
   ``known_limitation``. Near a singularity the pseudo-inverse turns the 1e-7 rad KDL leaves
   alone into a joint step that overshoots a limit, and the clamped iterates stall
   (control@ik/ur5, seed 9, on 02efcff). The scenario path has had this re-run since
   f106be8 (``Evaluator._scenario_ik``).

Otherwise the divergence stands. The caller still checks each target's own claim
(``oracle.ik_property``) when the verdict is no finding.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import replace
from typing import Any

from fuzzer.execution import oracle
from fuzzer.execution.dead_zone import twin_with_kdl_dead_zone
from fuzzer.execution.records import UNCOUNTED, Comparison, Kind, Outcome
from fuzzer.execution.targets import Runner
from fuzzer.input.mapping import IkCall
from fuzzer.scenario.nudge import Axis, turned
from robot_api.records import Pose

IK_PERTURBATIONS = (1e-9, -1e-9, 1e-7)
"""Seed shifts tried when checking an IK status divergence for ill-conditioning (every joint
moves by the shift, alternating in sign for the last one)."""

GOAL_NUDGES: tuple[tuple[float, Axis], ...] = (
    (1e-9, (0.189, -0.198, 0.962)),
    (-1e-9, (0.16, -0.818, 0.552)),
    (1e-7, (0.742, 0.539, -0.4)),
    (-1e-7, (-0.897, -0.442, 0.029)),
    (1e-9, (-0.878, -0.083, -0.471)),
    (-1e-9, (-0.758, -0.564, -0.328)),
)
"""Goal nudges (shift in m or rad, direction): the goal's position moves by ``shift * axis``, or
its orientation turns by ``shift`` about ``axis``. Each try goes another way: where iterates are
chaotic, one try flips a target's answer with some probability (0.3-0.5 on UR5's cases), so
the check needs several independent ones. The axes are random unit vectors
(``numpy.random.default_rng(0).normal(size=(6, 3))`` normalized, to 3 decimals): axes along
the coordinate planes turned out to keep the tie of a half-turn rotation error unbroken."""

DEAD_ZONE = 1e-6
"""KDL's rotation dead zone (rad): ``diff(R_seed, R_target)`` goes through the rotation axis,
undefined at a half turn, so a target within this of pi from the seed's orientation is
reached by one solver and not by the other (docs/api.md, "Known limitations")."""

Seeds = tuple[tuple[float, ...] | None, ...]
Homes = tuple[tuple[float, ...], ...]
RunBoth = Callable[[IkCall, Seeds, Sequence[Runner]], tuple[Outcome, ...]]
"""Runs one IK call on both targets with the given seeds (``Evaluator.run_both``)."""
Judge = Callable[[tuple[Outcome, ...]], Comparison]
"""The oracle's verdict on the call's two outcomes (``Evaluator.judge``)."""


def judge_status(
    call: IkCall,
    outcomes: tuple[Outcome, ...],
    comparison: Comparison,
    runners: Sequence[Runner],
    run_both: RunBoth,
    replay: Any | None,
    judge: Judge | None = None,
) -> Comparison:
    """The status divergence ``comparison`` of ``call``, judged (see the module docstring).

    ``runners`` are fresh targets; ``replay`` is a ``python_impl.RobotModel`` of the robot (or
    None, which skips step 5); ``judge`` the oracle for step 6 (None skips it).
    """
    homes = tuple(r.home for r in runners)
    explicit = run_both(call, homes, runners)
    if any(x.status is not y.status for x, y in zip(outcomes, explicit, strict=True)):
        return comparison  # a target's default seed is not its home_values: a real divergence
    if in_dead_zone(runners[0].model, call, homes[0]):
        return replace(comparison, kind=Kind.KNOWN_LIMITATION)
    if at_knife_edge(call, outcomes):
        return replace(comparison, kind=Kind.ILL_CONDITIONED)
    for goal, seeds in _tries(call, homes):
        for first, second in zip(outcomes, run_both(goal, seeds, runners), strict=True):
            if first.status is not second.status:
                return replace(comparison, kind=Kind.ILL_CONDITIONED)
    if replay is not None and meets_half_turn(replay, call, homes[0]):
        return replace(comparison, kind=Kind.KNOWN_LIMITATION)
    if judge is not None and agree_in_kdl_dead_zone(call, homes, runners, run_both, judge):
        return replace(comparison, kind=Kind.KNOWN_LIMITATION)
    return comparison


def agree_in_kdl_dead_zone(
    call: IkCall, homes: Homes, runners: Sequence[Runner], run_both: RunBoth, judge: Judge
) -> bool:
    """Whether the two targets agree on ``call`` (from ``homes``) once the twin in this process
    uses KDL's small-rotation dead zone: the same status, and no counted divergence by
    ``judge``. False when the twin cannot be swapped (a plugin, a ROS node: the divergence
    stands)."""
    with twin_with_kdl_dead_zone() as swapped:
        again = run_both(call, homes, runners) if swapped else ()
    if len(again) != 2 or again[0].status is not again[1].status:
        return False
    verdict = judge(again)
    return not (verdict.divergent and verdict.kind not in UNCOUNTED)


def _tries(call: IkCall, homes: Homes) -> list[tuple[IkCall, Seeds]]:
    """The seed moves, then (for a full pose) the goal's position moves and orientation turns."""
    out: list[tuple[IkCall, Seeds]] = []
    for i, shift in enumerate(IK_PERTURBATIONS):
        moved = (
            tuple(v + (shift if i < 2 or j % 2 == 0 else -shift) for j, v in enumerate(h)) for h in homes
        )
        out.append((call, tuple(moved)))
    if len(call.position) != 3 or len(call.orientation) != 4:
        return out
    x, y, z = call.position
    moves = [replace(call, position=(x + s * u, y + s * v, z + s * w)) for s, (u, v, w) in GOAL_NUDGES]
    turns = [replace(call, orientation=turned(call.orientation, s, axis)) for s, axis in GOAL_NUDGES]
    out += [(goal, homes) for goal in moves + turns]
    return out


def at_knife_edge(call: IkCall, outcomes: tuple[Outcome, ...]) -> bool:
    """Whether every outcome's last iterate reaches the requested pose within
    ``oracle.IK_RESIDUAL`` (m and rad, ``oracle.pose_gaps``), as its target reports it.

    A success beyond that is a property violation (``oracle.ik_property``), so this says the
    failure ended where a success may: a split decided by the criterion's rounding, not by
    where the two solvers went. An outcome without its pose is no evidence (False).
    """
    requested = (call.position, call.orientation)
    gaps = (g for outcome in outcomes for g in oracle.pose_gaps(outcome, requested))
    return all(g is not None and g <= oracle.IK_RESIDUAL for g in gaps)


def in_dead_zone(model: Any, call: IkCall, seed: tuple[float, ...]) -> bool:
    """Whether the requested orientation is within ``DEAD_ZONE`` of a half turn from the
    orientation the seed gives the link (where KDL's rotation error is undefined)."""
    norm = math.sqrt(sum(x * x for x in call.orientation))
    if not (norm > 0.0 and math.isfinite(norm)):
        return False
    try:
        start = tuple(float(x) for x in model.forward_kinematics(list(seed), call.link).orientation)
    except Exception:  # noqa: BLE001 - a target that cannot answer is not in the dead zone
        return False
    target = tuple(x / norm for x in call.orientation)
    return oracle.rotation_distance(start, target) >= math.pi - DEAD_ZONE


def meets_half_turn(replay: Any, call: IkCall, seed: tuple[float, ...]) -> bool:
    """Whether a Newton-Raphson iterate of ``call`` from ``seed`` meets a rotation error within
    ``DEAD_ZONE`` of pi (``replay``: a ``python_impl.RobotModel``; False when it cannot replay)."""
    if len(call.position) != 3 or len(call.orientation) != 4:
        return False
    return pose_meets_half_turn(replay, Pose(call.position, call.orientation), seed, call.link)


def pose_meets_half_turn(replay: Any, pose: Any, seed: Any, link: Any) -> bool:
    """``meets_half_turn`` for a pose as ``inverse_kinematics`` takes it."""
    try:
        from python_impl.model import ik_rotation_errors

        errors = ik_rotation_errors(replay, pose, seed, link)
    except Exception:  # noqa: BLE001 - a pose or seed the replay rejects is no evidence either way
        return False
    return any(e >= math.pi - DEAD_ZONE for e in errors)


IkRequest = tuple[Any, Any, Any]
"""One call ``inverse_kinematics(pose, seed, link)`` as the twin received it."""


@contextlib.contextmanager
def recorded_ik(model: Any) -> Iterator[list[IkRequest] | None]:
    """While active, every ``inverse_kinematics`` call on models of ``model``'s class (the twin,
    ``python_impl.RobotModel``, or a class built on it) is appended to the yielded list, then
    answered as before. Yields None (and records nothing) for any other model: a native target,
    a plugin or a ROS node is not looked into."""
    if not isinstance(model, _twin_class()):
        yield None
        return
    cls: Any = type(model)
    own = cls.__dict__.get("inverse_kinematics")
    solve = cls.inverse_kinematics
    requests: list[IkRequest] = []

    def recording(self: Any, pose: Any, seed: Any = None, link: Any = None) -> Any:
        requests.append((pose, None if seed is None else tuple(seed), link))
        return solve(self, pose, seed, link)

    cls.inverse_kinematics = recording
    try:
        yield requests
    finally:
        if own is None:
            del cls.inverse_kinematics
        else:
            cls.inverse_kinematics = own


def step_meets_half_turn(
    runners: Sequence[Runner],
    replay: Any | None,
    call: Any,
    step: int,
    run: Callable[[Runner, Any], Any],
) -> bool:
    """Step 5 for a scenario: whether the one IK call the twin makes at step ``step`` of the
    scenario ``call`` (a ``go`` or ``plan`` toward a pose goal: from the current state) has a
    Newton-Raphson iterate at a rotation error within ``DEAD_ZONE`` of pi. ``run(runner, call)``
    runs a scenario on one target (``fuzzer.scenario.execute.run_scenario``); the twin runs the
    steps before ``step``, then those and ``step``, and the step's requests are those the second
    run made past the first's (each run is a new group, the same up to there). False when no
    runner is the twin, ``replay`` is None, or the step made other than one IK call (a
    Cartesian path's many: where its half turn falls says nothing of where the paths parted)."""
    twin = next((r for r in runners if isinstance(r.model, _twin_class())), None)
    if twin is None or replay is None:
        return False
    made = []
    for last in (step, step + 1):
        with recorded_ik(twin.model) as requests:
            if requests is None:
                return False
            try:
                run(twin, replace(call, steps=call.steps[:last]))
            except Exception:  # noqa: BLE001 - a run that fails is no evidence either way
                return False
        made.append(requests)
    ours = made[1][len(made[0]) :]
    if len(ours) != 1 or ours[0][1] is None:
        return False
    pose, seed, link = ours[0]
    return pose_meets_half_turn(replay, pose, seed, link)


def _twin_class() -> type:
    """``python_impl.RobotModel``, or ``NoneType`` (which no model is) without the twin."""
    try:
        from python_impl import RobotModel
    except ImportError:
        return type(None)
    return RobotModel
