"""Scenario sequence mutators, their lineage, step-bigram features and step minimization."""

from __future__ import annotations

import copy
import json
import math
import random
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

import python_impl
from fuzzer import campaign
from fuzzer.artifacts.store import ArtifactStore
from fuzzer.execution.session import RunConfig, Session
from fuzzer.harness import Harness
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.input.testcase import TestCase, decode
from fuzzer.mutation import mutators
from fuzzer.mutation.mutators import MutationContext
from fuzzer.scenario.dispatch import for_registry
from fuzzer.scenario.fresh import FRESH_FLOATS, field_types
from fuzzer.scenario.mutate import SEQ_MUTATORS, SPLICE
from fuzzer.scenario.steps import MSG_TYPE, TOPICS, validate
from fuzzer.selection.compared import ComparedValues
from fuzzer.selection.guidance import START, Features, step_bigrams
from fuzzer.triage.ddmin import ddmin
from fuzzer.triage.minimize import Minimizer, joints_that_matter

REGISTRY = MessageRegistry()
MAX = 12
NAMES = tuple(f"joint_{i}" for i in range(1, 7))
"""The joints of the test scenarios' six-value joint targets."""


def toy_fk(q: tuple[float, ...]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A stand-in for the campaign's FK: the tip at the first three joint values, turned by the
    fourth about z (m; unit quaternion x, y, z, w)."""
    return (q[0], q[1], q[2]), (0.0, 0.0, math.sin(q[3] / 2), math.cos(q[3] / 2))


MUTATE, CROSSOVER = for_registry(REGISTRY, MAX, None, toy_fk, NAMES)
SEEDS = range(40)
INTERESTING = (3.1416, -2.0071)
ZOO_CARTESIAN = "benchmarks.zoo.stateful:cartesian_ignores_scaling"


def step(topic: str, **fields: Any) -> dict[str, Any]:
    """A valid step: the registry default of the topic's type with ``fields`` set."""
    msg = REGISTRY.default(TOPICS[topic].msg_type)
    msg.update(fields)
    return {"topic": topic, "msg": msg}


def joint_target(*position: float) -> dict[str, Any]:
    return step("/joint_target", position=list(position))


GO, PLAN, EXECUTE = step("/go"), step("/plan"), step("/execute")


def base_scenario() -> dict[str, Any]:
    return {
        "steps": [
            joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6),
            step("/velocity_scaling", data=0.5),
            PLAN,
            EXECUTE,
            joint_target(-0.3, 0.1, 0.7, 0.0, 0.2, -0.1),
            GO,
            step("/remember", data="here"),
        ]
    }


def other_scenario() -> dict[str, Any]:
    pose = {
        "position": {"x": 0.2, "y": 0.0, "z": 0.4},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    }
    return {"steps": [step("/pose_target", pose=pose), GO, step("/named_target", data="home"), PLAN]}


THRESHOLD = 0.3
"""The one comparison threshold the test contexts know (``seq_compared``)."""


NEAR_THRESHOLD = {
    THRESHOLD,
    math.nextafter(THRESHOLD, math.inf),
    math.nextafter(THRESHOLD, -math.inf),
    *(THRESHOLD + sign * step for sign in (1, -1) for step in (1e-6, 1e-3)),
}
"""What ``compared`` may write for it: the threshold or a value just either side."""


def thresholds() -> ComparedValues:
    """A table that has seen ``0.3 <= x`` with x = 0 and 0.5: threshold 0.3."""
    table = ComparedValues()
    for x in (0.0, 0.5):
        table.watch(7, THRESHOLD, x, x >= THRESHOLD)
    return table


def context(seed: int, other: dict[str, Any] | None = None, known: bool = False) -> MutationContext:
    """A mutation context; ``known``: with a comparison threshold (``thresholds``)."""
    return MutationContext(
        rng=random.Random(seed),
        field_types={},
        interesting_floats=INTERESTING,
        dictionary=("joint_1", "link_6"),
        other=other,
        compared=thresholds() if known else None,
    )


def floats(node: Any) -> list[float]:
    """The floats of a message in field order."""
    if isinstance(node, dict):
        return [x for value in node.values() for x in floats(value)]
    if isinstance(node, list):
        return [x for value in node for x in floats(value)]
    return [node] if isinstance(node, float) else []


def key(s: dict[str, Any]) -> str:
    return json.dumps(s, sort_keys=True)


def removed_one(longer: list[Any], shorter: list[Any]) -> list[int]:
    """Indices i with longer[:i] + longer[i+1:] == shorter."""
    return [i for i in range(len(longer)) if longer[:i] + longer[i + 1 :] == shorter]


# -- sequence mutators ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(SEQ_MUTATORS))
def test_each_mutator_is_seeded_bounded_valid_and_leaves_its_inputs(name: str) -> None:
    parent, other = base_scenario(), other_scenario()
    before, other_before = copy.deepcopy(parent), copy.deepcopy(other)
    used = set()
    for seed in SEEDS:
        known = name == "seq_compared"
        child, reported = MUTATE(parent, context(seed, other, known), name)
        again, _ = MUTATE(parent, context(seed, other, known), name)
        assert child == again  # a seed gives a mutation
        validate(child, REGISTRY, MAX)
        assert parent == before and other == other_before  # inputs untouched
        assert child["steps"] is not parent["steps"]
        used.add(reported)
        old, new = parent["steps"], child["steps"]
        if name == "seq_insert":
            assert len(new) == len(old) + 1 and removed_one(new, old)
        elif name == "seq_delete":
            assert len(new) == len(old) - 1 and removed_one(old, new)
        elif name == "seq_duplicate":
            assert any(new[i] == new[i + 1] for i in removed_one(new, old))
        elif name == "seq_swap":
            moved = [i for i in range(len(old)) if old[i] != new[i]]
            assert len(moved) == 2 and sorted(map(key, old)) == sorted(map(key, new))
        elif name == "seq_move":
            assert new != old and sorted(map(key, old)) == sorted(map(key, new))
            assert any(removed_one(new, old[:i] + old[i + 1 :]) for i in range(len(old)))
        elif name == "seq_step":
            changed = [i for i in range(len(old)) if old[i] != new[i]]
            assert len(changed) == 1 and new[changed[0]]["topic"] == old[changed[0]]["topic"]
        elif name == "seq_motion":
            assert motion_at(old, new) is not None
        elif name == "seq_pose_goal":
            if reported == "seq_pose_goal:observe":  # the /go to the new goal observed
                at = [i for i in range(len(new) - 1) if new[i : i + 2] == [PLAN, EXECUTE] and old[i] == GO]
                assert at and new[at[0] + 2 :] == old[at[0] + 1 :]
                new = [*new[: at[0]], GO, *new[at[0] + 2 :]]
            changed = [i for i in range(len(old)) if old[i] != new[i]]
            assert len(new) == len(old) and len(changed) == 1 and old[changed[0]]["topic"] == "/joint_target"
            assert goal_of(new[changed[0]]) == goal_at(
                old[changed[0]]["msg"]["position"], new[changed[0]]["topic"]
            )
        elif name == "seq_observe":
            at = [i for i in range(len(old)) if old[i] == GO and new[i : i + 2] == [PLAN, EXECUTE]]
            assert any([*new[:i], GO, *new[i + 2 :]] == old for i in at)
        elif name == "seq_compared":
            if reported == "seq_compared:observe":  # the /go after the changed step observed
                at = [i for i in range(len(new) - 1) if new[i : i + 2] == [PLAN, EXECUTE] and old[i] == GO]
                assert at and new[at[0] + 2 :] == old[at[0] + 1 :]
                new = [*new[: at[0]], GO, *new[at[0] + 2 :]]
                assert any(old[i] != new[i] for i in range(at[0]))
            changed = [i for i in range(len(old)) if old[i] != new[i]]
            assert len(changed) == 1 and new[changed[0]]["topic"] == old[changed[0]]["topic"]
            before_values, after_values = floats(old[changed[0]]["msg"]), floats(new[changed[0]]["msg"])
            moved = [b for a, b in zip(before_values, after_values, strict=True) if a != b]
            assert len(moved) == 1 and moved[0] in NEAR_THRESHOLD
        elif name == SPLICE:
            assert any(new == old[:i] + other["steps"][j:] for i in range(8) for j in range(5))
    if name == "seq_step":
        assert len(used) > 3 and all(u.split(":")[1] in mutators.MUTATORS for u in used)
    elif name == "seq_compared":
        assert used == {f"{name}:observe"}  # each float step lies before the /go, observed every time
    elif name == "seq_pose_goal":
        assert used == {name, f"{name}:observe"}  # the second joint target's move is a /go
    else:
        assert used == {name}


def test_seq_compared_observes_every_go_after_the_changed_step_while_there_is_room() -> None:
    """The comparison a threshold flips can be made by any later move (a start state in a
    band is compared by the move after the one that put the arm there): each later ``/go``
    becomes ``/plan`` + ``/execute``, the earlier ones first when the room runs out."""
    remember = step("/remember", data="here")
    parent = {"steps": [GO, step("/velocity_scaling", data=0.5), GO, GO, remember]}
    shapes = set()
    for seed in SEEDS:
        for max_steps, gos in ((MAX, 2), (6, 1)):
            mutate, _ = for_registry(REGISTRY, max_steps)
            child, name = mutate(parent, context(seed, known=True), "seq_compared")
            assert name == "seq_compared:observe"  # every time since 2026-11-28 (OBSERVE_PROBABILITY)
            topics = [s["topic"] for s in child["steps"]]
            observed = ["/plan", "/execute"] * gos + ["/go"] * (2 - gos)
            assert topics == ["/go", "/velocity_scaling", *observed, "/remember"]
            shapes.add(gos)
    assert shapes == {1, 2}


def test_seq_step_names_its_value_mutator_and_keeps_the_topic() -> None:
    parent = {"steps": [GO, joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), PLAN]}
    child, name = MUTATE(parent, context(3), "seq_step:arithmetic")
    assert name == "seq_step:arithmetic"
    assert child["steps"][0] == GO and child["steps"][2] == PLAN
    old, new = parent["steps"][1]["msg"]["position"], child["steps"][1]["msg"]["position"]
    assert sum(a != b for a, b in zip(old, new, strict=True)) == 1
    # only steps with values are mutated by value mutators: a /go-only scenario falls back
    child, name = MUTATE({"steps": [GO, GO]}, context(0), "seq_step")
    assert not name.startswith("seq_step") and 1 <= len(child["steps"]) <= MAX


def test_bounds_make_mutators_fall_back() -> None:
    full = {"steps": [GO, PLAN] * (MAX // 2)}
    one = {"steps": [GO]}
    same = {"steps": [GO, GO, GO]}
    for seed in SEEDS:
        for name in ("seq_insert", "seq_duplicate"):
            child, used = MUTATE(full, context(seed), name)
            assert used != name and len(child["steps"]) <= MAX
            validate(child, REGISTRY, MAX)
        child, used = MUTATE(one, context(seed), "seq_delete")
        assert used != "seq_delete" and len(child["steps"]) >= 1
        assert MUTATE(full, context(seed), "seq_observe")[1] != "seq_observe"  # no room
        assert MUTATE({"steps": [PLAN, EXECUTE]}, context(seed), "seq_observe")[1] != "seq_observe"
        for name in ("seq_swap", "seq_move"):
            assert MUTATE(same, context(seed), name)[1] != name
    # nothing applies to a one-step /go with max_steps 1: noop, an equal copy
    mutate_one, _ = for_registry(REGISTRY, 1)
    child, used = mutate_one(one, context(0))
    assert used == mutators.NOOP and child == one and child is not one


def test_random_mutations_stay_valid_and_reach_every_mutator() -> None:
    message = base_scenario()
    used = set()
    for seed in range(400):
        if seed % 50 == 0:  # walks restarted: a long one stays near max_steps, where a move has no room
            message = base_scenario()
        message, name = MUTATE(message, context(seed, other_scenario(), known=True))
        validate(message, REGISTRY, MAX)
        used.add(name.split(":")[0])
    assert used == set(SEQ_MUTATORS)


def test_fresh_steps_are_made_from_the_scenario() -> None:
    parent = {
        "steps": [joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), joint_target(-1.0, -2.0, 0.0, 0.0, 0.5, 1.5)]
    }
    columns = [{0.1, -1.0, *INTERESTING}, {0.2, -2.0, *INTERESTING}, {0.3, 0.0, *INTERESTING}]
    topics = set()
    for seed in range(200):
        child, _ = MUTATE(parent, context(seed), "seq_insert")
        [i] = removed_one(child["steps"], parent["steps"])[:1]
        new = child["steps"][i]
        topics.add(new["topic"])
        if new["topic"] == "/joint_target" and new not in parent["steps"]:
            position = new["msg"]["position"]
            assert len(position) == 6 and all(v in columns[j] for j, v in enumerate(position[:3]))
            topics.add("recombined")
    assert {"/go", "/plan", "/execute", "recombined"} <= topics


def test_fresh_named_targets_mostly_name_a_target_that_exists_there() -> None:
    """A fresh ``/named_target`` names "home" or a name remembered before it three times in four
    (syzkaller's resources), and sometimes anything else (the unknown-target error path)."""
    parent = {"steps": [joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), GO, step("/remember", data="spot"), GO]}
    known = unknown = 0
    for seed in range(3000):
        child, _ = MUTATE(parent, context(seed), "seq_insert")
        [i] = removed_one(child["steps"], parent["steps"])[:1]
        new = child["steps"][i]
        if new["topic"] != "/named_target" or new in parent["steps"]:
            continue
        remembered = {s["msg"]["data"] for s in child["steps"][:i] if s["topic"] == "/remember"}
        if new["msg"]["data"] in {"home", *remembered}:
            known += 1
        else:
            unknown += 1
    assert known + unknown >= 50
    assert known / (known + unknown) >= 0.7 and unknown > 0


MOVES = (["/go"], ["/plan", "/execute"])
SETTINGS = ([], ["/velocity_scaling"], ["/acceleration_scaling"])


def motion_at(old: list[Any], new: list[Any]) -> tuple[int, list[Any]] | None:
    """Where ``new`` is ``old`` with a move (optionally a scaling factor, then a joint target
    and a move: ``/go``, or ``/plan`` and ``/execute``; optionally followed by
    ``/named_target`` and a move) inserted, and the inserted steps; else None."""
    templates = [[*setting, "/joint_target", *m] for setting in SETTINGS for m in MOVES]
    templates += [[*t, "/named_target", *m] for t in templates for m in MOVES]
    for template in templates:
        size = len(template)
        for i in range(len(old) + 1):
            inserted = new[i : i + size]
            same = len(new) == len(old) + size and new[:i] + new[i + size :] == old
            if same and [s["topic"] for s in inserted] == template:
                return i, inserted
    return None


def test_a_move_often_follows_a_remember_and_then_often_comes_back() -> None:
    parent = {"steps": [joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), GO, step("/remember", data="spot"), PLAN]}
    after, back, moved, planned, moves, scaled = 0, 0, 0, 0, 0, 0
    for seed in range(400):
        child, name = MUTATE(parent, context(seed), "seq_motion")
        assert name == "seq_motion"
        found = motion_at(parent["steps"], child["steps"])
        assert found is not None
        at, inserted = found
        topics = [s["topic"] for s in inserted]
        if topics[0] != "/joint_target":  # a fresh scaling factor first
            factor = inserted.pop(0)["msg"]["data"]
            assert factor in {0.5, *FRESH_FLOATS}  # the scenario's Float64 values, or fresh ones
            scaled += 1
        target = inserted[0]["msg"]["position"]
        assert len(target) == 6 and all(v in {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, *INTERESTING} for v in target)
        moved += target != [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
        topics = [s["topic"] for s in inserted]
        returns = "/named_target" in topics
        planned += topics.count("/plan")
        moves += 1 + returns
        if at == 3:  # right after the /remember
            after += 1
            back += returns
        if returns:
            named = inserted[topics.index("/named_target")]
            assert at == 3 and named["msg"]["data"] == "spot"  # back to the remembered state
    assert 0.5 <= after / 400 <= 0.7  # 1/2 by choice, plus 1/4 x 1/2 of the random places
    assert 0.35 <= back / after <= 0.65 and moved > 100
    assert 0.4 <= planned / moves <= 0.6  # /plan + /execute half the time, else /go
    assert 0.4 <= scaled / 400 <= 0.6  # a scaling factor first half the time


def test_a_move_needs_a_joint_target_to_start_from_and_room() -> None:
    _, name = MUTATE({"steps": [GO, step("/remember", data="x")]}, context(0), "seq_motion")
    assert name != "seq_motion"
    full = {"steps": [joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6)] * (MAX - 1)}
    assert MUTATE(full, context(0), "seq_motion")[1] != "seq_motion"


def test_with_the_limits_a_move_starts_anywhere_inside_them() -> None:
    box = ((-1.0, -2.0, 0.0), (1.0, 2.0, 0.5))
    mutate, _ = for_registry(REGISTRY, MAX, box)
    parent = {"steps": [GO, step("/remember", data="x")]}
    targets = []
    for seed in range(200):
        child, name = mutate(parent, context(seed), "seq_motion")
        assert name == "seq_motion" and validate(child, REGISTRY, MAX) is None
        [target] = [s["msg"] for s in child["steps"] if s["topic"] == "/joint_target"]
        assert target["name"] == [] and len(target["position"]) == 3  # every joint, in order
        targets.append(target["position"])
    inside = [p for p in targets if all(lo <= v <= hi for v, lo, hi in zip(p, *box, strict=True))]
    for p in targets:  # the others: one joint on an engine interesting value (half the time)
        outside = [v for v, lo, hi in zip(p, *box, strict=True) if not lo <= v <= hi]
        assert outside == [] or (len(outside) == 1 and outside[0] in INTERESTING)
    assert 60 <= len(inside) <= 140
    assert len({tuple(p) for p in inside}) == len(inside)  # drawn, not a fixed point
    assert min(p[1] for p in inside) < -1.5 and max(p[1] for p in inside) > 1.5


def goal_of(step: dict[str, Any]) -> tuple[float, ...]:
    """A pose target's position and quaternion, or a position target's point, as one tuple."""
    if step["topic"] == "/position_target":
        return tuple(step["msg"]["point"][k] for k in "xyz")
    pose = step["msg"]["pose"]
    return (*(pose["position"][k] for k in "xyz"), *(pose["orientation"][k] for k in "xyzw"))


def goal_at(position: list[float], topic: str) -> tuple[float, ...]:
    """What ``goal_of`` gives for the goal ``seq_pose_goal`` makes of a joint target (``toy_fk``)."""
    point, quaternion = toy_fk(tuple(position))
    return point if topic == "/position_target" else (*point, *quaternion)


def test_a_joint_target_becomes_the_tips_pose_or_position_there() -> None:
    """``seq_pose_goal`` replaces one joint target of every joint, in order and finite, by the
    tip's pose at it (the campaign's FK), a quarter of the time by its position only; it leaves
    the other steps, and the joint targets it cannot read as a configuration, as they were,
    except the ``/go`` to the new goal, which becomes ``/plan`` + ``/execute``."""
    partial = step("/joint_target", name=["joint_2"], position=[0.4])  # one joint, by name
    reordered = step("/joint_target", name=list(reversed(NAMES)), position=[0.1] * 6)
    unfinite = joint_target(0.1, math.nan, 0.3, 0.4, 0.5, 0.6)
    short = joint_target(0.1, 0.2, 0.3)
    named = step("/joint_target", name=list(NAMES), position=[0.5, -0.5, 0.25, 1.0, 0.0, 0.0])
    parent = {
        "steps": [
            partial,
            joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6),
            reordered,
            GO,
            unfinite,
            short,
            named,
            PLAN,
        ]
    }
    topics: dict[str, int] = {}
    chosen = set()
    for seed in range(400):
        child, name = MUTATE(parent, context(seed), "seq_pose_goal")
        assert name == "seq_pose_goal"
        validate(child, REGISTRY, MAX)
        [at] = [i for i, (a, b) in enumerate(zip(parent["steps"], child["steps"], strict=True)) if a != b]
        new = child["steps"][at]
        chosen.add(at)
        topics[new["topic"]] = topics.get(new["topic"], 0) + 1
        assert goal_of(new) == goal_at(parent["steps"][at]["msg"]["position"], new["topic"])
        assert new["msg"]["header"]["frame_id"] == ""  # the goal of the tip
    assert chosen == {1, 6}  # every joint in order (unnamed, or named in order) and finite
    assert set(topics) == {"/pose_target", "/position_target"}
    assert 0.18 <= topics["/position_target"] / 400 <= 0.32
    # the move to the new goal, when a /go, becomes /plan + /execute (room permitting)
    stop, home = step("/stop"), step("/named_target", data="home")
    for rest, after, observed in (
        ([stop, GO, GO], [stop, PLAN, EXECUTE, GO], True),
        ([PLAN, GO], [PLAN, GO], False),  # a /plan shows its trajectory already
        ([home, GO], [home, GO], False),  # that /go moves to another goal
        ([GO] * (MAX - 1), [GO] * (MAX - 1), False),  # no room
    ):
        child, name = MUTATE(
            {"steps": [joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), *rest]}, context(0), "seq_pose_goal"
        )
        assert child["steps"][0]["topic"] in ("/pose_target", "/position_target")
        assert child["steps"][1:] == after
        assert name == ("seq_pose_goal:observe" if observed else "seq_pose_goal")
    # nothing to give as a pose, or no FK: another mutator
    assert (
        MUTATE({"steps": [partial, unfinite, short, GO]}, context(0), "seq_pose_goal")[1] != "seq_pose_goal"
    )
    without_fk, _ = for_registry(REGISTRY, MAX)
    assert without_fk(base_scenario(), context(0), "seq_pose_goal")[1] != "seq_pose_goal"


def test_a_campaign_gives_the_sequence_mutators_its_robots_forward_kinematics(twin: Session) -> None:
    """The campaign's scenario mutator gives a joint target as the pose the reference's FK puts
    the tip at, for the robot the campaign runs on."""
    mutate = campaign._scenario_mutators(twin)["mutate_message"]
    q = [0.1 * (i + 1) for i in range(len(twin.reference.joint_names))]
    parent = {"steps": [step("/joint_target", position=q), PLAN]}
    topics = set()
    for seed in range(20):
        child, name = mutate(parent, context(seed), "seq_pose_goal")
        assert name == "seq_pose_goal" and child["steps"][1] == PLAN
        tip = twin.reference.forward_kinematics(q)
        goal = child["steps"][0]
        topics.add(goal["topic"])
        expected = (
            (*tip.position, *tip.orientation) if goal["topic"] == "/pose_target" else tuple(tip.position)
        )
        assert goal_of(goal) == pytest.approx(expected, abs=1e-12)
    assert topics == {"/pose_target", "/position_target"}


def test_field_types_cover_arrays_of_messages() -> None:
    types = field_types(REGISTRY, "geometry_msgs/PoseArray")
    assert types["poses"] == "geometry_msgs/Pose[]" and types["poses.orientation.w"] == "float64"
    assert field_types(REGISTRY, "std_msgs/Empty") == {}


def test_bad_inputs_give_clear_errors() -> None:
    with pytest.raises(KeyError, match="unknown sequence mutator"):
        MUTATE(base_scenario(), context(0), "arithmetic")
    with pytest.raises(KeyError, match="unknown value mutator"):
        MUTATE(base_scenario(), context(0), "seq_step:nope")
    with pytest.raises(ValueError, match="not a scenario"):
        MUTATE({"position": [1.0]}, context(0))
    for bad in (0, MAX * 100, True):
        with pytest.raises(ValueError, match="max_steps"):
            for_registry(REGISTRY, bad)


# -- crossover --------------------------------------------------------------------------------------


def test_splice_is_a_prefix_and_a_suffix_within_bounds() -> None:
    a, b = base_scenario(), other_scenario()
    before = copy.deepcopy((a, b))
    _, cross_small = for_registry(REGISTRY, 3)
    children = set()
    for seed in SEEDS:
        child = CROSSOVER(a, b, context(seed))
        assert child == CROSSOVER(a, b, context(seed))
        assert any(child["steps"] == a["steps"][:i] + b["steps"][j:] for i in range(8) for j in range(5))
        assert child != a and child != b
        validate(child, REGISTRY, MAX)
        small = cross_small(a, b, context(seed))
        assert 1 <= len(small["steps"]) <= 3
        children.add(key(child))
    assert (a, b) == before and len(children) > 5
    assert CROSSOVER.lineage_name == SPLICE
    for seed in SEEDS:  # with itself: a range of steps removed or repeated
        self_child = CROSSOVER(a, a, context(seed))["steps"]
        assert any(self_child == a["steps"][:i] + a["steps"][j:] for i in range(8) for j in range(8))


# -- the harness: lineage and step-bigram features ---------------------------------------------------


class Drift(python_impl.MoveGroup):
    """The planted two-call fault: the second successful go() of a group whose joint target
    puts joint_1 above 1 rad ends 1 mrad off on joint_1."""

    def __init__(self, model: Any) -> None:
        super().__init__(model)
        self._gos = 0

    def go(self, joints: Any = None, wait: bool = True) -> bool:
        moved: bool = super().go(joints, wait)
        self._gos += moved
        if moved and self._gos >= 2 and self.get_joint_value_target()[0] > 1.0:
            self._current[0] -= 1e-3
        return moved


drift = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=Drift)
TWIN = ("python", "tests.test_scenario_mutate:drift")


@pytest.fixture(scope="module")
def twin() -> Session:
    return Session.open(RunConfig(op="scenario", targets=TWIN, max_steps=MAX))


def make_harness(tmp_path: Path, session: Session) -> Harness:
    return Harness(
        evaluator=session.evaluator(),
        store=ArtifactStore(tmp_path / "artifacts"),
        features=Features(enabled=False),
        context=context(0),
        sidecar=lambda case, data, ev: {},
        seeds=[TestCase(MSG_TYPE, base_scenario())],
        mutate_message=MUTATE,
        crossover_message=CROSSOVER,
    )


def test_harness_lineage_names_the_sequence_mutators(tmp_path: Path, twin: Session) -> None:
    h = make_harness(tmp_path, twin)
    parent = TestCase(MSG_TYPE, base_scenario(), lineage=("seed",), lineage_length=1)
    names = set()
    for seed in range(30):
        child = decode(h.mutate(parent.encode(), 1 << 16, seed))
        assert child.lineage[:-1] == parent.lineage and child.lineage_length == 2
        validate(child.message, REGISTRY, MAX)
        names.add(child.lineage[-1].split(":")[0])
    assert len(names) > 3 and names <= set(SEQ_MUTATORS)
    # the harness hands a second parent (here: the seed) to the sequence mutator: its steps get copied
    h.seeds = [TestCase(MSG_TYPE, other_scenario())]
    pose_target = other_scenario()["steps"][0]
    # about 2% of children carry that copy (a seq_insert copy or a splice): 300 seeds, 5 of them
    copied = [decode(h.mutate(parent.encode(), 1 << 16, seed)).message for seed in range(300)]
    assert any(pose_target in child["steps"] for child in copied)
    spliced = decode(h.crossover(parent.encode(), TestCase(MSG_TYPE, other_scenario()).encode(), 1 << 16, 1))
    assert spliced.lineage[-1] == SPLICE


def test_step_bigrams() -> None:
    assert step_bigrams(["joint_target", "go", "plan"], ["ok", "failed"]) == [
        f"{START}>joint_target:ok",
        "joint_target:ok>go:failed",
    ]


def test_a_new_order_of_steps_is_a_new_feature(tmp_path: Path, twin: Session) -> None:
    h = make_harness(tmp_path, twin)

    def features_of(steps: list[dict[str, Any]]) -> set[str]:
        before = set(h.features.seen)
        h.test_one_input(TestCase(MSG_TYPE, {"steps": steps}).encode())
        return h.features.seen - before

    target = joint_target(0.5, 0.2, 0.3, 0.4, 0.5, 0.6)
    first = features_of([target, PLAN, GO])
    assert {"q:a:^>joint_target:ok", "q:a:joint_target:ok>plan:ok", "q:b:plan:ok>go:ok"} <= first
    assert features_of([target, PLAN, GO]) == set()  # the same behaviour again: nothing new
    reordered = features_of([target, GO, PLAN])
    assert "q:a:joint_target:ok>go:ok" in reordered and "q:a:go:ok>plan:ok" in reordered
    rejected = features_of([joint_target(9.0, 0.0, 0.0, 0.0, 0.0, 0.0), GO])  # out of the limits
    assert any(name.startswith("q:a:^>joint_target:rejected:") for name in rejected)


# -- minimization -------------------------------------------------------------------------------


def test_ddmin_finds_a_one_minimal_subset() -> None:
    calls: list[tuple[int, ...]] = []

    def holds(subset: list[int]) -> bool:
        calls.append(tuple(subset))
        return {3, 7} <= set(subset)

    kept, reductions = ddmin(list(range(10)), holds, lambda: True)
    assert kept == [3, 7] and reductions > 0
    assert len(calls) == len(set(calls)) and () not in calls
    kept, _ = ddmin(list(range(10)), holds, lambda: len(calls) < 25)  # budget: stops early, still holds
    assert {3, 7} <= set(kept)


def test_minimize_removes_steps_then_shrinks_values(twin: Session) -> None:
    target = joint_target(1.37251, 0.25, -0.3, 0.4, 0.5, 0.6)
    target["msg"]["header"] = {"seq": 7, "stamp": {"secs": 3, "nsecs": 12}, "frame_id": "x"}
    steps = [
        step("/velocity_scaling", data=0.5),
        joint_target(0.1, 0.2, 0.3, 0.4, 0.5, 0.6),
        GO,
        PLAN,
        target,
        step("/remember", data="here"),
        GO,
        EXECUTE,
        step("/goal_tolerance", data=0.001),
        GO,
    ]
    case = TestCase(MSG_TYPE, {"steps": steps}, lineage=("seq_insert",), lineage_length=1)
    evaluator = twin.evaluator()
    ev = evaluator.evaluate(case)
    assert ev.signature is not None and ev.comparison.field == "go.joint_values" and ev.comparison.step == 6
    shrunk = Minimizer(twin).minimize(case)
    kept = shrunk.case.message["steps"]
    # 1-minimal: the joint target and two /go steps (in an order that still diverges)
    assert sorted(s["topic"] for s in kept) == ["/go", "/go", "/joint_target"] and kept[-1] == GO
    [shrunk_target] = [s["msg"] for s in kept if s["topic"] == "/joint_target"]
    position = shrunk_target["position"]
    assert position[1:] == [0.0] * 5 and position[0] > 1.0  # the value that matters, simpler
    assert len(repr(position[0])) < len(repr(1.37251))
    assert shrunk_target["header"] == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
    replay = evaluator.evaluate(shrunk.case)
    assert replay.signature is not None and replay.signature.key == ev.signature.key
    assert shrunk.complete and shrunk.case.lineage[-1] == "minimize"
    assert joints_that_matter(shrunk.case, twin.reference.joint_names) == ["joint_1"]
    assert case.message["steps"] == steps and len(steps) == 10  # the input is untouched


def test_minimize_of_a_scenario_respects_its_budget(twin: Session) -> None:
    evaluator = twin.evaluator()
    case = TestCase(MSG_TYPE, {"steps": [joint_target(1.5, 0.0, 0.0, 0.0, 0.0, 0.0), GO, PLAN, GO, PLAN, GO]})
    shrunk = Minimizer(twin, budget=3).minimize(case)
    assert shrunk.evaluations <= 3 and not shrunk.complete
    assert evaluator.evaluate(shrunk.case).signature is not None


def test_minimize_judges_each_candidate_as_a_replay_does(tmp_path: Path) -> None:
    """One evaluator for every candidate skipped the ill-conditioning re-runs of a signature it
    had seen, and ran each candidate on the targets the one before had moved: this script (an
    acceleration scaling of 5e-324, then a Cartesian path to a pose whose quaternion is 1.5e-9
    long) shrank to w = 1e-9, which a replay files under another signature (a property, the
    split explained), and its sidecar claimed the first (the triage probe)."""
    session = Session.open(RunConfig(op="scenario", targets=("native", ZOO_CARTESIAN)))

    def script(w: float) -> TestCase:
        zero = {"x": 0.0, "y": 0.0, "z": 0.0}
        pose = {"position": zero, "orientation": {**zero, "w": w}}
        steps = [step("/acceleration_scaling", data=5e-324), step("/cartesian_path", poses=[pose])]
        return TestCase(MSG_TYPE, {"steps": steps})

    first = session.evaluator().evaluate(script(1.5e-9))
    other = session.evaluator().evaluate(script(1e-9))
    assert first.signature is not None and other.signature is not None
    assert first.signature.key != other.signature.key  # the two sides of the test
    shrunk = Minimizer(session).minimize(script(1.5e-9))
    replayed = session.evaluator().evaluate(shrunk.case, history=[])
    assert replayed.signature is not None and replayed.signature.key == first.signature.key
    # and a minimized input that replays otherwise is never written under the file's signature
    from fuzzer.artifacts.sidecar_record import build_sidecar
    from fuzzer.triage import crashfiles
    from fuzzer.triage.minimize import Shrunk

    data = script(1.5e-9).encode()
    path = ArtifactStore(tmp_path).write(data, build_sidecar(session, script(1.5e-9), data, first, {}, ""))
    loaded = crashfiles.load(path, {"targets": session.config.targets}, False, {session.config: session})
    with pytest.raises(ValueError, match=f"diverges as {other.signature.key[:12]} when replayed, not as"):
        crashfiles.minimized_sidecar(loaded, Shrunk(script(1e-9), 2, 1, True))
    assert crashfiles.minimized_sidecar(loaded, Shrunk(script(1.5e-9), 2, 0, True))[0] == data
