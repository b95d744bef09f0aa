"""The joint-space walk of IK goals (``fuzzer.generation.walk``): goals moved through joint
space stay the poses of configurations inside the limits, and only an ``ik`` campaign has it."""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from fuzzer.execution.records import Outcome, Status
from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.spacefill import SpaceFill, configuration_message
from fuzzer.generation.walk import CAPACITY, FRONTIER, Walk
from fuzzer.input.mapping import FkCall, IkCall
from fuzzer.input.testcase import TestCase, decode
from fuzzer.mutation import mutators
from fuzzer.selection.bandit import Bandit
from fuzzer.selection.guidance import Features
from fuzzer.selection.search import _walk, search_parts
from fuzzer.selection.state import ALIGNED, MUTATE, SPACEFILL, WALK, Sources
from tests.test_harness import make_harness

STAMPED = "geometry_msgs/PoseStamped"
HEADER = {"header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}}


def _ik_session() -> Session:
    return Session.open(RunConfig(op="ik"))


def _goal(walk: Walk, session: Session, values: tuple[float, ...]) -> dict:  # type: ignore[type-arg]
    """A PoseStamped goal made as the space-filling source makes it (through ``recording``)."""
    message = configuration_message(STAMPED, HEADER, values, (), walk.recording(session.facts().reachable))
    assert message is not None
    return message


def _pose(message: dict) -> tuple[tuple[float, ...], tuple[float, ...]]:  # type: ignore[type-arg]
    p, o = message["pose"]["position"], message["pose"]["orientation"]
    return (p["x"], p["y"], p["z"]), (o["x"], o["y"], o["z"], o["w"])


def test_a_walked_goal_is_the_pose_of_a_nearby_configuration_inside_the_limits() -> None:
    session = _ik_session()
    facts = session.facts()
    walk = _walk(session, facts)
    start = SpaceFill(facts.lower, facts.upper, seed=3).next()
    message = _goal(walk, session, start)
    rng = random.Random(7)
    reached = 0
    for _ in range(60):  # a chain: each child is the next parent
        made = walk.make(message, rng)
        assert made is not None and made[1] == WALK
        child = made[0]
        assert child["header"] == message["header"]  # the parent's other fields are kept
        known = walk.configuration(child)
        assert known is not None and known[1] is None
        values = known[0]
        assert all(lo <= v <= hi for v, lo, hi in zip(values, facts.lower, facts.upper, strict=True))
        assert _pose(child) == facts.reachable(values)  # exactly the pose of that configuration
        # reachable: IK seeded at the configuration converges to the goal
        result = session.reference.inverse_kinematics(_pose(child), list(values))
        reached += str(result.status) == "success"
        message = child
    assert reached == 60
    other = walk.make(message, random.Random(7))
    again = _walk(session, facts)
    _goal(again, session, start)
    assert other is not None
    chain = [walk.make(_goal(walk, session, start), random.Random(s)) for s in range(5)]
    assert chain == [again.make(_goal(again, session, start), random.Random(s)) for s in range(5)]


def test_a_step_moves_one_two_or_every_joint_inside_the_limits() -> None:
    lower, upper = (-1.0, -2.0, 0.0, -math.inf, -0.5, -3.0), (1.0, 2.0, 0.1, math.inf, 0.5, 3.0)
    walk = Walk(STAMPED, lower, upper, lambda v, link: ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
    rng = random.Random(0)
    moved = {1: 0, 2: 0, 6: 0}
    middle = (0.0, 0.0, 0.05, 0.0, 0.0, 0.0)  # a move from the middle, clamped or not, changes a joint
    sizes = []
    for _ in range(2000):
        q = walk.step(middle, rng)
        assert all(lo <= v <= hi for v, lo, hi in zip(q, walk.lower, walk.upper, strict=True))
        moved[sum(a != b for a, b in zip(q, middle, strict=True))] += 1
        sizes.append(max(abs(a - b) for a, b in zip(q, middle, strict=True)))
    assert 900 < moved[1] < 1100 and 400 < moved[2] < 600 and 400 < moved[6] < 600
    assert min(sizes) < 1e-4 and max(sizes) > 0.3  # from about 1e-4 of a range to a third of it


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-1e6, 1e6), st.floats(0.0, 1e6)).map(lambda t: (t[0], t[0] + t[1])),
        min_size=1,
        max_size=8,
    ),
    st.integers(0, 2**32 - 1),
)
def test_a_step_never_leaves_any_box(box: list[tuple[float, float]], seed: int) -> None:
    lower, upper = [lo for lo, _ in box], [hi for _, hi in box]
    walk = Walk(STAMPED, lower, upper, lambda v, link: ((0.0,) * 3, (0.0, 0.0, 0.0, 1.0)))
    rng = random.Random(seed)
    q = tuple(lower)
    for _ in range(20):
        q = walk.step(q, rng)
        assert all(lo <= v <= hi and math.isfinite(v) for v, lo, hi in zip(q, lower, upper, strict=True))


def _stamped(position: tuple[float, ...], orientation: tuple[float, ...], link: str = "") -> dict[str, Any]:
    pose = configuration_message("geometry_msgs/Pose", {}, (), (), lambda _: (position, orientation))
    return {"header": {**HEADER["header"], "frame_id": link}, "pose": pose}


def test_learns_only_a_converged_first_target_s_answer_that_reaches_the_goal() -> None:
    session = _ik_session()
    walk = _walk(session, session.facts())
    q = (0.1, -0.2, 0.3, 0.4, -0.5, 0.6)
    position, orientation = walk.pose_of(q, None)
    message = _stamped(position, orientation)
    call = IkCall(position, orientation)
    ok, failed = (
        Outcome(Status.OK, values={"joint_values": q}),
        Outcome(Status.FAILED, values={"joint_values": q}),
    )
    walk.learn(call, (failed, ok))
    walk.learn(FkCall(q), (ok, ok))
    walk.learn(call, (Outcome(Status.OK, values={"joint_values": (math.nan,) * 6}), ok))
    walk.learn(call, (Outcome(Status.OK, values={"joint_values": (0.1,) * 5}), ok))
    walk.learn(call, ())
    # a first target that claims success wrongly: its answer's pose is 2e-4 m or rad away
    for lie in ((0.1, -0.2, 0.3, 0.4, -0.5, 0.6002), (0.1002, -0.2, 0.3, 0.4, -0.5, 0.6)):
        walk.learn(call, (Outcome(Status.OK, values={"joint_values": lie}), ok))
    walk.learn(IkCall((10**400, 0.0, 0.0), orientation), (ok, ok))  # an int too large for a float
    walk.learn(IkCall(position, orientation, "no_such_link"), (ok, ok))
    assert len(walk) == 0 and walk.make(message, random.Random(0)) is None
    near = (0.1, -0.2, 0.3, 0.4, -0.5, 0.60001)  # within LEARN_SLACK, as KDL stops short
    walk.learn(call, (Outcome(Status.OK, values={"joint_values": near}), failed))
    assert walk.configuration(message) == (near, None)
    lp, lo = walk.pose_of(q, "link_3")
    linked = _stamped(lp, lo, "link_3")
    assert walk.configuration(linked) is None
    walk.learn(IkCall(lp, lo, "link_3"), (ok, ok))
    made = walk.make(linked, random.Random(0))
    assert made is not None and made[0]["header"]["frame_id"] == "link_3"
    known = walk.configuration(made[0])
    assert known is not None
    expected = session.reference.forward_kinematics(list(known[0]), "link_3")
    assert _pose(made[0]) == (tuple(expected.position), tuple(expected.orientation))


def test_a_walk_moves_only_the_joints_before_the_goal_s_link_and_never_gives_the_goal_again() -> None:
    """Probe B (sixty-fourth session): every walk of a ``base_link`` goal, and about half of
    those of ``link_1`` and ``link_2`` goals, gave the parent's goal again (a joint after the
    link moved); a boundary probe's configuration, just past a limit, stayed past it."""
    session = _ik_session()
    walk = _walk(session, session.facts())
    assert walk.movers(None) == tuple(range(6)) and walk.movers("link_2") == (0, 1)
    assert walk.movers("base_link") == () and walk.movers("no_such_link") == ()
    q = (0.1, -0.2, 0.3, 0.4, -0.5, 0.6)
    for link, moving in (("link_1", 1), ("link_2", 2), ("link_4", 4), (None, 6)):
        here = walk.pose_of(q, link)
        goal = _stamped(here[0], here[1], link or "")
        walk.note(here[0], here[1], link, q)
        for s in range(100):
            made = walk.make(goal, random.Random(s))
            assert made is not None and _pose(made[0]) != _pose(goal)
            values = walk.configuration(made[0])
            assert values is not None and values[0][moving:] == q[moving:]
    at_base = walk.pose_of(q, "base_link")
    base = _stamped(at_base[0], at_base[1], "base_link")
    walk.note(at_base[0], at_base[1], "base_link", q)
    assert walk.make(base, random.Random(0)) is None
    past = (walk.lower[0] - 1e-4, *q[1:])  # a boundary probe's configuration
    assert all(walk.step(past, random.Random(s), (5,))[0] == walk.lower[0] for s in range(20))


def test_space_filling_goals_are_the_tip_s_and_walked_goals_keep_their_link() -> None:
    """Probe B: a space-filling or aligned goal kept its parent's ``frame_id`` but carried the
    tip's pose, asking another link to reach it (mostly out of reach)."""
    tip = ((0.1, 0.2, 0.3), (0.0, 0.0, 0.0, 1.0))
    parent = _stamped((9.0, 9.0, 9.0), (0.0, 0.0, 0.0, 1.0), "joint_6")
    made = configuration_message(STAMPED, parent, (0.0,), (), lambda _: tip)
    assert made is not None and made["header"]["frame_id"] == "" and _pose(made) == tip
    kept = configuration_message(STAMPED, parent, (0.0,), (), lambda _: tip, frame=None)
    assert kept is not None and kept["header"]["frame_id"] == "joint_6"
    assert parent["header"]["frame_id"] == "joint_6"  # a copy


def test_malformed_parents_are_not_walked_and_old_goals_are_forgotten() -> None:
    walk = Walk(
        STAMPED, (-1.0,), (1.0,), lambda v, link: ((v[0], 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)), capacity=3
    )
    rng = random.Random(0)
    parents: list[Any] = [{}, {"pose": {}}, {"pose": {"position": 1}}, {**HEADER, "pose": None}, []]
    for parent in parents:
        assert walk.make(parent, rng) is None
    goals = []
    for i in range(4):
        values = (i / 10.0,)
        message = configuration_message(
            STAMPED, HEADER, values, (), walk.recording(lambda v: walk.pose_of(v, None))
        )
        goals.append(message)
    assert len(walk) == 3 and walk.configuration(goals[0]) is None  # type: ignore[arg-type]
    assert walk.configuration(goals[1]) == ((0.1,), None)  # type: ignore[arg-type]
    assert Walk(STAMPED, (-1.0,), (1.0,), walk.pose_of).capacity == CAPACITY
    pose = Walk("geometry_msgs/Pose", (-1.0,), (1.0,), walk.pose_of)
    bare = configuration_message(
        "geometry_msgs/Pose", {}, (0.5,), (), pose.recording(lambda v: walk.pose_of(v, None))
    )
    made = pose.make(bare, rng)  # type: ignore[arg-type]
    assert made is not None and set(made[0]) == {"position", "orientation"}
    nan = Walk(STAMPED, (-1.0,), (1.0,), lambda v, link: ((math.nan, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
    nan.note((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), None, (0.0,))
    zero = configuration_message(
        STAMPED, HEADER, (0.0,), (), lambda _: ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    )
    assert nan.make(zero, rng) is None  # type: ignore[arg-type]


def test_only_an_ik_campaign_has_the_walk_arm() -> None:
    for op, walks in (("ik", True), ("move", False), ("fk", False), ("scenario", False)):
        sources = search_parts(Session.open(RunConfig(op=op)), "rrosfuzz", 0, Features(enabled=False))[
            "sources"
        ]
        assert (sources.walk is not None) == walks
        assert (WALK in sources.source.arms) == walks
    made = Sources(Bandit((MUTATE, WALK)), Bandit(("zero",)), lambda m, r: None)
    assert made.make(WALK, {}, random.Random(0)) is None  # no walk: that arm mutates
    made.learn(IkCall((0.0,) * 3, (0.0, 0.0, 0.0, 1.0)), ())  # nothing to learn into
    made.reward(WALK, True)
    assert made.source.arms[WALK].rewards == 1 and made.mutators.arms["zero"].pulls == 0


def test_the_harness_walks_a_goal_once_a_run_showed_its_configuration(tmp_path: Path) -> None:
    """A seed's goal is walked only after its run: the first target's converged IK solution is
    its configuration; before that the walk arm mutates it instead."""
    h = make_harness(tmp_path, op="ik")
    session = _ik_session()
    walk = _walk(session, session.facts())
    source = Bandit((MUTATE, SPACEFILL, ALIGNED, WALK), {WALK: 1e9}, floor=0.0)
    h.sources = Sources(
        source, Bandit(tuple(mutators.WEIGHTS), mutators.WEIGHTS), lambda m, r: None, None, walk
    )
    converged = []
    for seed in h.seeds:
        data = seed.encode()
        assert decode(h.mutate(data, 4096, 0)).strategy != WALK
        ev = h._execute(seed, data, True)
        if ev.outcomes and ev.outcomes[0].status is Status.OK:
            converged.append(data)
    assert converged
    for data in converged:
        child = decode(h.mutate(data, 4096, 1))
        assert child.strategy == WALK and child.lineage[-1] == WALK
        h.test_one_input(child.encode())
    assert source.arms[WALK].pulls == len(converged)


def _goal_of(record: Any, values: tuple[float, ...]) -> dict[str, Any]:
    message = configuration_message(STAMPED, HEADER, values, (), record)
    assert message is not None
    return message


def _cases(walk: Walk, count: int) -> list[TestCase]:
    record = walk.recording(lambda v: walk.pose_of(v, None))
    return [TestCase(STAMPED, _goal_of(record, (i / 100.0,)), 0, "t", (f"c{i}",)) for i in range(count)]


def test_the_walk_starts_half_the_time_from_the_input_nearest_a_site_s_flip() -> None:
    walk = Walk(STAMPED, (-1.0,), (1.0,), lambda v, link: ((v[0], 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
    far = configuration_message(
        STAMPED, HEADER, (0.5,), (), lambda v: ((9.0, 9.0, 9.0), (0.0, 0.0, 0.0, 1.0))
    )
    unknown = TestCase(STAMPED, far, 0, "t", ("far",))  # type: ignore[arg-type]
    rng = random.Random(0)
    walk.offer(3, unknown)
    assert not walk.frontier and walk.parent(unknown, rng) is unknown
    cases = _cases(walk, 12)
    for i, case in enumerate(cases):
        walk.offer(i % 3, case)  # each site's nearest so far is the last offered for it
    assert {site: id(c) for site, c in walk.frontier.items()} == {
        0: id(cases[9]),
        1: id(cases[10]),
        2: id(cases[11]),
    }
    picks = [walk.parent(unknown, rng) for _ in range(3000)]
    own = sum(p is unknown for p in picks)
    assert 1350 < own < 1650
    by_site = [sum(p is cases[9 + k] for p in picks) for k in range(3)]
    assert all(400 < n < 600 for n in by_site)  # the sites drawn uniformly
    for site in range(FRONTIER + 5):
        walk.offer(100 + site, cases[0])
    assert len(walk.frontier) == FRONTIER and 0 not in walk.frontier and 100 + FRONTIER + 4 in walk.frontier


class _Nearer:
    """A float tracer whose every input came nearer the flip of site 7 (``grows``), or none did."""

    compared = None

    def __init__(self, grows: bool) -> None:
        self.nearer: list[int] = []
        self.grows = grows

    def install(self) -> None:
        self.nearer[:] = [7] if self.grows else []


def test_the_harness_offers_the_walk_what_came_nearer_and_walks_on_from_it(tmp_path: Path) -> None:
    for grows in (False, True):
        h = make_harness(tmp_path / str(grows), op="ik")
        session = _ik_session()
        walk = _walk(session, session.facts())
        source = Bandit((MUTATE, SPACEFILL, ALIGNED, WALK), {WALK: 1e9}, floor=0.0)
        h.sources = Sources(
            source, Bandit(tuple(mutators.WEIGHTS), mutators.WEIGHTS), lambda m, r: None, None, walk
        )
        h.float_tracer = _Nearer(grows)  # type: ignore[assignment]
        walkable = []
        for seed in h.seeds:
            h.test_one_input(seed.encode())
            if walk.configuration(seed.message) is not None:
                walkable.append(seed)
        assert walkable
        assert list(walk.frontier) == ([7] if grows else [])
        if not grows:
            continue
        assert walk.frontier[7] == walkable[-1]  # the last one to come nearer (decoded again)
        stranger = TestCase(STAMPED, h.seeds[0].message, 0, "t", ("stranger",))
        made = [decode(h.mutate(stranger.encode(), 4096, s)) for s in range(40)]
        # walked from the frontier's input, whose lineage the child carries, or from the parent
        walked = [c for c in made if c.strategy == WALK]
        assert any(tuple(c.lineage[:-1]) == walkable[-1].lineage for c in walked)
        assert all(c.lineage[-1] == WALK for c in walked)
