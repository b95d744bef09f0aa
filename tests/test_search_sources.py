"""The harness's input sources (issue 11): space-filling inputs and bandits, end to end."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.spacefill import SpaceFill, fresh_inputs, scenario_with_configuration
from fuzzer.harness import Harness
from fuzzer.input.testcase import decode
from fuzzer.mutation import mutators
from fuzzer.selection.bandit import Bandit
from fuzzer.selection.state import MUTATE, SPACEFILL, Sources
from tests.support import fuzz
from tests.test_harness import make_harness


def _with_sources(tmp_path: Path, seed: int = 0) -> tuple[Harness, SpaceFill]:
    h = make_harness(tmp_path)
    session = Session.open(RunConfig())
    limits = session.reference.joint_limits
    stream = SpaceFill([lim.lower for lim in limits], [lim.upper for lim in limits], seed=seed)
    facts = session.facts()
    fresh = fresh_inputs("move", "sensor_msgs/JointState", stream, facts.joint_names, facts.reachable)
    h.sources = Sources(Bandit((MUTATE, SPACEFILL)), Bandit(tuple(mutators.WEIGHTS), mutators.WEIGHTS), fresh)
    return h, stream


def test_space_filling_inputs_come_from_mutate_and_crossover(tmp_path: Path) -> None:
    h, stream = _with_sources(tmp_path)
    parent = h.seeds[0].encode()
    children = [decode(h.mutate(parent, 4096, s)) for s in range(200)]
    children += [decode(h.crossover(parent, h.seeds[1].encode(), 4096, s)) for s in range(200)]
    fresh = [c for c in children if c.strategy == SPACEFILL]
    assert 50 < len(fresh) < 350 and stream.drawn == len(fresh)
    limits = Session.open(RunConfig()).reference.joint_limits
    for child in fresh:
        values = zip(child.message["position"], limits, strict=True)
        assert all(lim.lower <= v <= lim.upper for v, lim in values)
    others = {c.strategy for c in children} - {SPACEFILL}
    # "seed": the parent itself, when a child is larger than max_size (_emit's fallback)
    assert others and others <= {*mutators.MUTATORS, "noop", "splice", "seed"}


def test_sources_are_deterministic_and_rewarded(tmp_path: Path) -> None:
    a, _ = _with_sources(tmp_path / "a")
    b, _ = _with_sources(tmp_path / "b")
    data = a.seeds[2].encode()
    assert [a.mutate(data, 4096, s) for s in range(60)] == [b.mutate(data, 4096, s) for s in range(60)]
    for s in range(30):
        a.test_one_input(a.mutate(data, 4096, 100 + s))
    assert a.sources is not None
    source = a.sources.source.arms
    rewarded = source[MUTATE].rewards + source[SPACEFILL].rewards
    assert rewarded > 0  # new behaviour features early on
    assert sum(arm.pulls for arm in a.sources.mutators.arms.values()) > 0
    a.sources.reward("seq_step:arithmetic", True)  # a scenario's inner mutator credits its outer one
    assert set(a.sources.to_json()) == {"source", "mutators"}


def test_only_what_the_last_step_made_credits_the_arms(tmp_path: Path) -> None:
    """A corpus file made by a mutator in another run (a campaign resumed on its corpus) was
    credited again when libFuzzer read it: a run with no mutation at all had 404 pulls, 334 of
    them "paid" (the determinism probe). A parent emitted in place of a child too large for
    ``max_size`` credited the parent's strategy."""
    h, _ = _with_sources(tmp_path)
    assert h.sources is not None

    def pulls() -> int:
        assert h.sources is not None
        return sum(arm.pulls for arm in h.sources.source.arms.values())

    data = h.seeds[2].encode()
    made = [h.mutate(data, 4096, s) for s in range(5)]  # the last step's child is the last one
    for old in made[:4]:  # as from the corpus: made by a mutator, but not by the last step
        assert decode(old).origin == "mutation"
        h.test_one_input(old)
    assert pulls() == 0
    h.test_one_input(made[4])
    assert pulls() == 1
    h.test_one_input(made[4])  # run again: credited once
    assert pulls() == 1
    parent = h.seeds[2]
    child = parent.child(parent.message, "comb1")  # a longer lineage: larger than the parent
    emitted = h._emit(child, parent, len(parent.encode()), data)
    assert emitted == parent.encode() and h._credit is None  # the parent in the child's place
    h.test_one_input(emitted)
    assert pulls() == 1


def test_a_scenario_gets_its_configuration_in_a_joint_target() -> None:
    rng = random.Random(4)
    js = {"header": {}, "name": [], "position": [0.0], "velocity": [], "effort": []}
    with_target = {"steps": [{"topic": "/go", "msg": {}}, {"topic": "/joint_target", "msg": js}]}
    out = scenario_with_configuration(with_target, (0.1, 0.2), ("a", "b"), rng, 16)
    assert out is not None and out["steps"][1]["msg"]["position"] == [0.1, 0.2]
    assert out["steps"][1]["msg"]["name"] == ["a", "b"] and js["position"] == [0.0]
    without = {"steps": [{"topic": "/go", "msg": {}}]}
    out = scenario_with_configuration(without, (0.1, 0.2), ("a", "b"), rng, 16)
    assert out is not None and [s["topic"] for s in out["steps"]].count("/joint_target") == 1
    assert len(out["steps"]) == 3
    assert scenario_with_configuration(without, (0.1,), ("a",), rng, 2) is None  # no room
    assert scenario_with_configuration({"steps": "x"}, (0.1,), ("a",), rng, 16) is None


def test_a_scenario_visits_the_configuration_before_a_step_seeded_by_the_state() -> None:
    """A pose goal's IK starts from the current state (MoveIt seeds it so): the space-filling
    configuration also becomes that state, a /joint_target + /go right before the step."""
    pose = {"header": {}, "pose": {}}
    js = {"header": {}, "name": [], "position": [0.0], "velocity": [], "effort": []}
    scenario = {
        "steps": [
            {"topic": "/joint_target", "msg": js},
            {"topic": "/go", "msg": {}},
            {"topic": "/pose_target", "msg": pose},
            {"topic": "/go", "msg": {}},
        ]
    }
    placed = set()
    for seed in range(20):
        out = scenario_with_configuration(scenario, (0.3, 0.2), ("a", "b"), random.Random(seed), 16)
        assert out is not None
        topics = [s["topic"] for s in out["steps"]]
        if len(topics) == 6:  # inserted before the pose goal
            assert topics[2:5] == ["/joint_target", "/go", "/pose_target"]
            assert out["steps"][2]["msg"]["position"] == [0.3, 0.2]
            placed.add("before pose")
        else:  # or the existing joint target overwritten
            assert out["steps"][0]["msg"]["position"] == [0.3, 0.2]
            placed.add("overwritten")
    assert placed == {"before pose", "overwritten"}
    assert scenario_with_configuration(scenario, (0.3, 0.2), ("a", "b"), random.Random(0), 5) is not None
    only_pose = {"steps": scenario["steps"][2:]}
    assert scenario_with_configuration(only_pose, (0.3,), ("a",), random.Random(0), 3) is None  # no room


def test_a_scenario_without_targets_gets_a_state_and_a_pose_goal_from_it() -> None:
    session = Session.open(RunConfig(op="scenario"))
    facts = session.facts()
    stream = SpaceFill(facts.lower, facts.upper, seed=3)
    fresh = fresh_inputs("scenario", "", stream, facts.joint_names, facts.reachable, 16)
    made = fresh({"steps": [{"topic": "/stop", "msg": {}}]}, random.Random(1))
    assert made is not None and made[1] == SPACEFILL
    out = made[0]
    topics = [s["topic"] for s in out["steps"]]
    assert [t for t in topics if t != "/stop"] == ["/joint_target", "/go", "/pose_target", "/go"]
    goal = next(s["msg"] for s in out["steps"] if s["topic"] == "/pose_target")
    session.registry.validate("geometry_msgs/PoseStamped", goal)
    assert set(goal["pose"]) == {"position", "orientation"}


def test_the_corpus_starts_with_space_filling_seeds_beside_the_hypothesis_ones() -> None:
    from fuzzer.generation.boundary import probes
    from fuzzer.generation.corpus import SPACEFILL_SEED, space_filling_seeds

    session = Session.open(RunConfig(op="move"))
    seeds = space_filling_seeds(session, 16, 1, first=32)
    limits = session.reference.joint_limits
    assert [s.sequence for s in seeds] == list(range(32, 48)) and {s.origin for s in seeds} == {"spacefill"}
    positions = [tuple(s.message["position"]) for s in seeds]
    assert len(set(positions)) == 16
    # each seed is a Sobol point; the first ones carry the first round of boundary probes, in
    # order: one joint 5e-5 past a limit (two sides of six joints: twelve)
    facts = session.facts()
    stream = SpaceFill(facts.lower, facts.upper, seed=1 + SPACEFILL_SEED)
    points = [stream.next() for _ in range(16)]
    edges = probes(facts.lower, facts.upper)[:12]
    for j, e in edges:
        assert min(abs(e - limits[j].lower), abs(e - limits[j].upper)) == pytest.approx(5e-5, abs=1e-12)
    for case, values, point, (j, edge) in zip(seeds, positions, points, edges, strict=False):
        session.validate(case.message)
        assert values[j] == edge and not limits[j].lower <= edge <= limits[j].upper
        assert values[:j] + values[j + 1 :] == point[:j] + point[j + 1 :]
    assert positions[12:] == points[12:]
    # stratified: each of the 16 points in its own sixteenth of every joint's range
    for j, lim in enumerate(limits):
        bins = {int(16 * (v[j] - lim.lower) / (lim.upper - lim.lower)) for v in points}
        assert len(bins) == 16
    assert [s.message for s in space_filling_seeds(session, 16, 1, first=32)] == [s.message for s in seeds]
    assert space_filling_seeds(session, 16, 2)[0].message != seeds[0].message
    assert space_filling_seeds(Session.open(RunConfig(op="scenario")), 8, 1) == []
    ik = space_filling_seeds(Session.open(RunConfig(op="ik")), 4, 1)
    assert len(ik) == 4 and all(set(s.message["pose"]) == {"position", "orientation"} for s in ik)


def test_slow_ops_write_fewer_space_filling_seed_files() -> None:
    """IK inputs each run a solver: one space-filling seed file (the first boundary probe), the
    others come from the space-filling source during the campaign; fast ops as many as Hypothesis'."""
    from fuzzer.generation.corpus import space_filling_count

    assert space_filling_count("ik", 32) == 1
    assert [space_filling_count(op, 32) for op in ("fk", "move")] == [32, 32]
    assert space_filling_count("ik", 0) == 0 and space_filling_count("fk", 5) == 5


def test_an_ik_campaign_writes_one_space_filling_seed_and_the_orientation_probes(tmp_path: Path) -> None:
    corpus = tmp_path / "corpus"
    art = f"--artifacts={tmp_path / 'art'}"
    done = fuzz(str(corpus), "-runs=0", "--op=ik", "--seeds=4", art, "--no-progress")
    assert done.returncode == 0, done.stderr[-2000:]
    cases = [decode(p.read_bytes()) for p in corpus.iterdir() if p.name.startswith("seed-")]
    origins = sorted((c.origin, c.lineage) for c in cases)
    assert (
        origins
        == [("hypothesis", ())] * 4 + [("spacefill", ())] + [("spacefill", ("spacefill:boundary",))] * 4
    )
    assert sorted(c.sequence for c in cases) == list(range(9))
    # the baselines' mutators get no generated probes
    corpus = tmp_path / "plain"
    done = fuzz(str(corpus), "-runs=0", "--op=ik", "--seeds=4", art, "--no-progress", "--mutator=libfuzzer")
    assert done.returncode == 0, done.stderr[-2000:]
    plain = [decode(p.read_bytes()).origin for p in corpus.iterdir() if p.name.startswith("seed-")]
    assert plain == ["hypothesis"] * 4


def test_orientation_probes_scale_the_home_poses_quaternion() -> None:
    """A pose target's precondition is a unit quaternion: the probes give the home pose's
    quaternion the lengths of ``ORIENTATION_SCALES``, and nothing else changes."""
    import math

    from fuzzer.generation.boundary import ORIENTATION_SCALES, scale_orientation
    from fuzzer.generation.corpus import orientation_cases

    session = Session.open(RunConfig(op="ik"))
    cases = orientation_cases(session, first=33)
    home = session.reference.forward_kinematics(list(session.reference.home_values))
    assert [c.sequence for c in cases] == [33, 34, 35, 36]
    assert {(c.origin, c.lineage) for c in cases} == {("spacefill", ("spacefill:boundary",))}
    for case, scale in zip(cases, ORIENTATION_SCALES, strict=True):
        session.validate(case.message)
        pose = case.message["pose"]
        assert [pose["position"][k] for k in "xyz"] == pytest.approx(list(home.position), abs=1e-12)
        q = [pose["orientation"][k] for k in "xyzw"]
        assert q == pytest.approx([scale * v for v in home.orientation], abs=1e-15)
        assert math.hypot(*q) == pytest.approx(scale, rel=1e-12)
    for op in ("fk", "move", "scenario"):
        assert orientation_cases(Session.open(RunConfig(op=op))) == []
    plain = {
        "position": {"x": 1.0, "y": 0.0, "z": 0.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    }
    assert scale_orientation("geometry_msgs/Pose", plain, 2.0) == {
        **plain,
        "orientation": {**plain["orientation"], "w": 2.0},
    }
    assert plain["orientation"]["w"] == 1.0  # a copy
    assert scale_orientation("sensor_msgs/JointState", {"position": [0.0]}, 2.0) is None


def test_orientation_probes_show_an_unnormalized_quaternion_and_agree_on_correct_targets() -> None:
    """The zoo's ``quaternion_not_normalized`` diverges from native on the probes of non-zero
    length other than one; the correct twin agrees with native on all four, zero included."""
    from fuzzer.generation.corpus import orientation_cases

    for robot in ("probot_anno", "ur5", "panda"):
        session = Session.open(RunConfig(op="ik", robot=robot))
        evaluator = session.evaluator()
        assert not any(evaluator.evaluate(c).divergent for c in orientation_cases(session))
    buggy = Session.open(
        RunConfig(op="ik", targets=("native", "benchmarks.zoo.bugs:quaternion_not_normalized"))
    )
    evaluator = buggy.evaluator()
    assert [evaluator.evaluate(c).divergent for c in orientation_cases(buggy)] == [True, True, True, False]


def _forced(tmp_path: Path, arm: str) -> Harness:
    """A harness whose bandits always mutate (never a space-filling input) with ``arm``."""
    h, _ = _with_sources(tmp_path)
    assert h.sources is not None
    h.sources.source = Bandit((MUTATE, SPACEFILL), {MUTATE: 1e9}, floor=0.0)
    h.sources.mutators = Bandit(tuple(mutators.WEIGHTS), {arm: 1e9}, floor=0.0)
    return h


def test_libfuzzers_crossover_is_a_bandit_step(tmp_path: Path) -> None:
    """libFuzzer's crossover crosses only when the bandit picks the crossover's arm; else it is
    the bandit's mutator on the first parent."""
    h = _forced(tmp_path / "a", "arithmetic")
    a, b = h.seeds[0], h.seeds[1]
    children = [decode(h.crossover(a.encode(), b.encode(), 4096, s)) for s in range(40)]
    assert {c.strategy for c in children} == {"arithmetic"}
    h = _forced(tmp_path / "b", "splice")
    crossed = [decode(h.crossover(a.encode(), b.encode(), 4096, s)) for s in range(40)]
    assert {c.strategy for c in crossed} == {"splice"}
    mixed = [c for c in crossed if any(x not in a.message["position"] for x in c.message["position"])]
    assert mixed and all(
        set(c.message["position"]) <= {*a.message["position"], *b.message["position"]} for c in mixed
    )
    # a mutation that picks the crossover's arm crosses too (with a high-difference input or a seed)
    spliced = [decode(h.mutate(a.encode(), 4096, s)) for s in range(40)]
    assert {c.strategy for c in spliced} == {"splice"}
    assert any(c.message["position"] != a.message["position"] for c in spliced)


def test_every_arm_is_credited_no_more_rewards_than_inputs(tmp_path: Path) -> None:
    h, _ = _with_sources(tmp_path)
    seeds = [s.encode() for s in h.seeds]
    made = 0
    for s in range(120):
        data = seeds[s % len(seeds)]
        child = h.crossover(data, seeds[(s + 1) % len(seeds)], 4096, s) if s % 2 else h.mutate(data, 4096, s)
        made += decode(child).origin == "mutation"  # not: a parent again, its child too large (_emit)
        h.test_one_input(child)
    assert h.sources is not None
    for bandit in (h.sources.source, h.sources.mutators):
        assert all(arm.rewards <= arm.pulls for arm in bandit.arms.values())
    assert made > 100 and sum(arm.pulls for arm in h.sources.source.arms.values()) == made


def test_scipy_stats_is_imported_only_where_a_space_filling_point_is_drawn() -> None:
    """``scipy.stats`` costs 0.55-0.8 s of imports: the baselines, replay and the full engine's
    dry-run child must not wait for it (docs/benchmarks-log.md, "Orientation probes, ... start-up"), nor a
    scenario campaign, which writes no space-filling seeds, before libFuzzer starts: its search
    parts (the fresh-input makers over a Sobol stream) import it at the first point drawn."""
    from tests.support import python

    program = (
        "import random, sys\n"
        "import fuzzer.campaign, fuzzer.harness, fuzzer.cli, benchmarks.baselines\n"
        "assert 'scipy.stats' not in sys.modules, 'imported with the engine'\n"
        "from fuzzer.execution.session import RunConfig, Session\n"
        "from fuzzer.generation.corpus import make_seeds\n"
        "from fuzzer.selection.guidance import Features\n"
        "from fuzzer.selection.search import search_parts\n"
        "session = Session.open(RunConfig(op='scenario'))\n"
        "parts = search_parts(session, 'rrosfuzz', 1, Features(enabled=False))\n"
        "assert 'scipy.stats' not in sys.modules, 'imported before a point is drawn'\n"
        "from fuzzer.generation.corpus import tutorial_seeds\n"
        "assert tutorial_seeds(session, 1) and 'scipy.stats' not in sys.modules, 'by the tutorials'\n"
        "seed = make_seeds(session, 1, 1)[0]\n"
        "made = parts['sources'].make('spacefill', seed.message, random.Random(1))\n"
        "assert made is not None and 'scipy.stats' in sys.modules\n"
        "from fuzzer.generation.spacefill import SpaceFill\n"
        "stream = SpaceFill((-1.0, -2.0), (1.0, 2.0), seed=1)\n"
        "assert stream.next() == SpaceFill((-1.0, -2.0), (1.0, 2.0), seed=1).next()\n"
    )
    done = python(program)
    assert done.returncode == 0, done.stderr[-2000:]
