"""What the full engine's dry run evaluates besides the seeds and probes (fuzzer/dry_run.py):
uniform sweeps for ``fk``, uniform configurations for ``move``, aligned configurations for both,
made without ``scipy.stats``, most of them before the seeds exist (``Stages``)."""

from __future__ import annotations

import json
import random
from pathlib import Path

import numpy as np
import pytest

from fuzzer import dry_harness, dry_run
from fuzzer.artifacts.divlog import CampaignLog
from fuzzer.artifacts.store import ArtifactStore
from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.boundary import REACH_FACTOR, beyond_reach
from fuzzer.generation.corpus import make_seeds, orientation_cases, reach_cases, tutorial_seeds, uniform_cases
from fuzzer.generation.scripts import uniform_script
from fuzzer.generation.spacefill import Uniform
from fuzzer.generation.sweep import ROWS, Sweep
from fuzzer.harness import Harness
from fuzzer.input.mapping import MoveCall
from fuzzer.input.testcase import TestCase, decode
from fuzzer.scenario import steps as scenario_steps
from fuzzer.selection.state import ALIGNED, BOUNDARY, SPACEFILL, UNIFORM
from tests.support import python
from tests.test_harness import make_harness


def test_a_uniform_stream_stays_in_the_box_and_repeats_with_its_seed() -> None:
    lower, upper = [-1.0, 0.0, float("-inf"), 2.0], [1.0, 0.5, float("inf"), 2.0]
    a = Uniform(lower, upper, seed=3).block(4096)
    assert a.shape == (4096, 4)
    assert np.array_equal(a, Uniform(lower, upper, seed=3).block(4096))
    assert not np.array_equal(a, Uniform(lower, upper, seed=4).block(4096))
    lo, hi = np.array([-1.0, 0.0, -np.pi, 2.0]), np.array([1.0, 0.5, np.pi, 2.0])
    assert (a >= lo).all() and (a <= hi).all()
    assert (a[:, 3] == 2.0).all(), "a joint with lower == upper keeps its value"
    # every tenth of each free joint's range is visited (4096 points: a miss has odds 1e-187)
    for j in range(3):
        tenths = np.floor((a[:, j] - lo[j]) / (hi[j] - lo[j]) * 10)
        assert set(tenths.astype(int)) == set(range(10))
    with pytest.raises(ValueError, match="same non-zero length"):
        Uniform([0.0], [1.0, 2.0])


def test_a_sweep_names_its_source_in_the_lineage_and_rejects_an_unknown_one() -> None:
    session = Session.open(RunConfig(op="fk"))
    sweep = dry_harness.sweep(session, "rrosfuzz", seed=1)
    assert sweep is not None and sweep.source == "uniform" and not sweep.due() and not sweep.due()
    q, labels, owner = sweep.batch([])
    assert q.shape == (ROWS, len(session.reference.joint_limits))
    assert set(labels) == {"sweep:uniform"} and set(owner) == {-1}
    with pytest.raises(ValueError, match="unknown sweep source 'halton'"):
        Sweep([0.0], [1.0], session.config.tolerance, source="halton")


@pytest.mark.parametrize(
    ("op", "mutator", "transport"),
    [
        ("scenario", "rrosfuzz", "inprocess"),
        ("ik", "rrosfuzz", "inprocess"),
        ("fk", "libfuzzer", "inprocess"),
        ("move", "weights", "inprocess"),
    ],
)
def test_only_the_full_engine_sweeps_in_an_fk_or_move_dry_run(op: str, mutator: str, transport: str) -> None:
    assert dry_harness.sweep(Session.open(RunConfig(op=op, transport=transport)), mutator, seed=1) is None


def test_a_move_dry_run_sweep_files_a_goal_fk_fault_as_a_move_at_default_scaling(tmp_path: Path) -> None:
    """``narrow_band`` (FK wrong in a band 0.1% of joint 2's range) through ``move``: a sweep's
    flagged row becomes a move to that configuration, its scaling MoveIt's default even where
    the Harness's seed (the message the rows go into) asks for a 0.001 velocity scaling."""
    h = make_harness(tmp_path, targets=("native", "benchmarks.zoo.deep:narrow_band"), op="move")
    session = Session.open(RunConfig(op="move"))
    h.sweep = dry_harness.sweep(session, "rrosfuzz", seed=1)
    h.joint_names = tuple(session.reference.joint_names)
    base = h.seeds[0]
    h.seeds = [base.child({**base.message, "velocity": [0.001], "effort": [0.5]}, "seed")]
    dry_harness.evaluate(h, [], before=dry_run.TOTAL_SWEEPS["move"])
    assert h.sweep is not None and h.sweep.compared == dry_run.TOTAL_SWEEPS["move"] * ROWS
    assert h.stats.signatures and h.sweep.unconfirmed == 0
    crash = next(p for p in (tmp_path / "artifacts").glob("crash-*") if p.suffix != ".json")
    case = decode(crash.read_bytes())
    assert case.strategy == "sweep:uniform"
    assert case.message["velocity"] == [] and case.message["effort"] == []
    call = h.evaluator.mapping(case.message)
    assert isinstance(call, MoveCall) and call.velocity_scaling is None
    assert h.evaluator.evaluate(case).divergent


def test_an_fk_dry_run_sweep_finds_a_narrow_band_and_files_it_as_an_ordinary_crash(tmp_path: Path) -> None:
    """A band 0.1% of joint 2's range wide (``narrow_band``): 32 sweeps of 1,024 uniform rows
    miss it with odds of about 1e-14. The flagged row is confirmed on the single-call path."""
    h = make_harness(tmp_path, targets=("native", "benchmarks.zoo.deep:narrow_band"), op="fk")
    session = Session.open(RunConfig(op="fk"))
    h.sweep = dry_harness.sweep(session, "rrosfuzz", seed=1)
    h.joint_names = tuple(session.reference.joint_names)
    dry_harness.evaluate(h, [], before=dry_run.TOTAL_SWEEPS["fk"])
    assert h.sweep is not None and h.sweep.compared == dry_run.TOTAL_SWEEPS["fk"] * ROWS
    assert h.stats.signatures and h.sweep.unconfirmed == 0
    assert h.stats.first_input is not None
    crash = next(p for p in (tmp_path / "artifacts").glob("crash-*") if p.suffix != ".json")
    case = decode(crash.read_bytes())
    assert case.strategy == "sweep:uniform"
    assert h.evaluator.evaluate(case).divergent
    sidecar = json.loads(Path(f"{crash}.json").read_text())
    assert sidecar["lineage"][-1] == "sweep:uniform"


def test_no_dry_run_sweep_reports_between_correct_targets(tmp_path: Path) -> None:
    h = make_harness(tmp_path, op="fk")
    h.sweep = dry_harness.sweep(Session.open(RunConfig(op="fk")), "rrosfuzz", seed=2)
    dry_harness.evaluate(h, [], before=dry_run.TOTAL_SWEEPS["fk"])
    assert h.sweep is not None and h.sweep.compared == dry_run.TOTAL_SWEEPS["fk"] * ROWS
    assert h.sweep.flagged == 0 and not h.stats.signatures


def _stages(op: str, seed: int = 1, wanted: int = 8) -> dry_run.Stages:
    def no_harness(*_: object) -> Harness:
        raise AssertionError("making the inputs needs no harness")

    return dry_run.Stages(Session.open(RunConfig(op=op)), "rrosfuzz", seed, wanted, 0, no_harness)


def test_the_dry_run_sweeps_do_not_import_scipy_stats_or_numpy_random() -> None:
    """They run before the campaign imports scipy.stats (0.55 s on one CPU): a sweep of the dry
    run and its uniform and aligned configurations must not pull it in. The first stage's
    inputs (a first sweep without centres, a move's first stage, a scenario's tutorial and
    uniform scripts) must not import numpy.random either (7-11 ms, which the first input would
    wait for)."""
    program = """
import sys
from fuzzer import dry_harness, dry_run
from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.corpus import make_seeds
session = Session.open(RunConfig(op="fk"))
sweep = dry_harness.sweep(session, "rrosfuzz", seed=1)
sweep.run([r.model for r in session.evaluator().runners], [])
for op in ("fk", "move", "scenario"):
    dry_run.Stages(Session.open(RunConfig(op=op)), "rrosfuzz", 1, 4, 0, None).first_cases()
first_stage = "numpy.random" in sys.modules
move = Session.open(RunConfig(op="move"))
stages = dry_run.Stages(move, "rrosfuzz", 1, 4, 0, None)
made = stages.first_cases() + stages.second_cases(make_seeds(move, 4, 1))
print(len(made), sweep.compared, "scipy.stats" in sys.modules, first_stage)
"""
    done = python(program)
    assert done.returncode == 0, done.stderr[-3000:]
    expected = 2 * 2 * 6 + dry_run.ALIGNED["move"] + dry_run.UNIFORM["move"] + 4
    assert done.stdout.split() == [str(expected), str(ROWS), "False", "False"]


def test_the_first_sweep_of_a_dry_run_is_small_and_the_next_ones_full() -> None:
    session = Session.open(RunConfig(op="fk"))
    models = [r.model for r in session.evaluator().runners]
    sweep = dry_harness.sweep(session, "rrosfuzz", seed=1, first_rows=dry_run.FIRST_ROWS)
    assert sweep is not None
    assert [sweep.run(models, []).rows for _ in range(3)] == [dry_run.FIRST_ROWS, ROWS, ROWS]
    assert sweep.compared == dry_run.FIRST_ROWS + 2 * ROWS
    plain = dry_harness.sweep(session, "rrosfuzz", seed=1)
    assert plain is not None and plain.run(models, []).rows == ROWS


def test_a_move_dry_run_makes_uniform_and_aligned_configurations_and_probes_before_the_seeds() -> None:
    stages = _stages("move")
    session = stages.session
    early, aligned, total = dry_run.EARLY["move"], dry_run.ALIGNED["move"], dry_run.UNIFORM["move"]
    lead = dry_run.LEAD
    first = stages.first_cases()
    lineages = [c.lineage for c in first]
    probes = len(first) - early - aligned
    assert 0 < lead < early <= total
    expected = [(UNIFORM,)] * lead + [(ALIGNED,)] * aligned + [(BOUNDARY,)] * probes
    assert lineages == expected + [(UNIFORM,)] * (early - lead)
    assert probes == 2 * 2 * len(session.reference.joint_limits)
    seeds = make_seeds(session, 8, 1)
    second = stages.second_cases(seeds)
    assert second[:8] == seeds
    rest = second[8:]
    assert len(rest) == total - early and all(c.lineage == (UNIFORM,) for c in rest)
    uniform = first[:lead] + first[lead + aligned + probes :]
    numbers = [c.sequence for c in uniform]
    assert numbers == list(range(8 + probes, 8 + probes + early))
    limits = session.reference.joint_limits
    for case in uniform + rest:
        assert case.origin == SPACEFILL
        position = case.message["position"]
        assert all(lim.lower <= v <= lim.upper for v, lim in zip(position, limits, strict=True))
    for case in first[lead : lead + aligned]:
        position = case.message["position"]
        on_grid = [abs(v / (np.pi / 2) - round(v / (np.pi / 2))) < 1e-12 for v in position]
        at_limit = [v in (lim.lower, lim.upper) for v, lim in zip(position, limits, strict=True)]
        assert all(g or a for g, a in zip(on_grid, at_limit, strict=True)), position
    again = _stages("move").first_cases()
    assert [c.message for c in again] == [c.message for c in first], "the same -seed, the same inputs"
    other = _stages("move", seed=2).first_cases()
    assert [c.message for c in other[:early]] != [c.message for c in first[:early]]
    assert [c.message for c in rest] != [c.message for c in first[:early]], "the stages' streams differ"


def test_fk_and_ik_dry_runs_have_no_uniform_configurations() -> None:
    fk = _stages("fk")
    first = fk.first_cases()
    assert {c.lineage for c in first} == {(ALIGNED,), (BOUNDARY,)}, "fk sweeps its uniform rows"
    seeds = make_seeds(fk.session, 4, 1)
    assert fk.second_cases(seeds) == seeds
    ik = _stages("ik", wanted=4)
    reach = reach_cases(ik.session, 1 + dry_run.SWEEP_SEED, 4)
    assert len(reach) == 1
    assert ik.first_cases() == orientation_cases(ik.session, 4 + 1) + reach, "the pose probes only"
    assert ik.second_cases(seeds) == seeds
    assert uniform_cases(ik.session, 8, 1) == [], "a pose would cost an FK each"
    assert uniform_cases(Session.open(RunConfig(op="scenario")), 8, 1) == []


def test_a_scenario_dry_run_is_the_tutorials_then_uniform_scripts_in_its_first_stage() -> None:
    stages = _stages("scenario", wanted=8)
    session = stages.session
    first = stages.first_cases()
    tutorials = tutorial_seeds(session, 1, 8)
    assert tutorials and first[: len(tutorials)] == tutorials, (
        "the campaign's own tutorial seeds, as numbered there"
    )
    scripts = first[len(tutorials) :]
    assert len(scripts) == dry_run.SCRIPTS
    assert [c.sequence for c in scripts] == list(
        range(8 + len(tutorials), 8 + len(tutorials) + dry_run.SCRIPTS)
    )
    rng = random.Random(1 + dry_run.SWEEP_SEED)
    assert [c.message for c in scripts] == [uniform_script(session, rng) for _ in scripts], (
        "the uniform baseline's"
    )
    for case in scripts:
        assert case.origin == SPACEFILL and case.lineage == (UNIFORM,)
        scenario_steps.validate(case.message, session.registry, session.config.max_steps)
    assert stages.literal_cases() == []
    assert [c.message for c in _stages("scenario", seed=2).first_cases()] != [c.message for c in first]


def test_a_scenario_dry_run_evaluates_its_first_stage_and_has_no_second(tmp_path: Path) -> None:
    session = Session.open(RunConfig(op="scenario"))
    store, log = ArtifactStore(tmp_path), CampaignLog(tmp_path)
    names = tuple(session.reference.joint_names)
    made: list[Harness] = []

    def harness(base: list[TestCase], sweep: Sweep | None) -> Harness:
        made.append(dry_harness.harness(session.evaluator(), store, log, lambda *_: {}, base, names, sweep))
        return made[-1]

    stages = dry_run.Stages(session, "rrosfuzz", 1, 8, 0, harness)
    stages._launch = lambda work: work()  # type: ignore[method-assign]  # in this process, no fork
    stages.first()
    assert len(made) == 1 and made[0].sweep is None
    tutorials = len(tutorial_seeds(session, 1, 8))
    assert made[0].stats.executed_by_strategy == {"tutorial": tutorials, UNIFORM: dry_run.SCRIPTS}
    stages.second(make_seeds(session, 2, 1))
    assert len(made) == 1, "libFuzzer runs the seeds; a scenario seed is too dear to run twice"


def test_beyond_reach_moves_a_pose_along_its_direction_and_leaves_other_types_alone() -> None:
    stamped = {"header": {}, "pose": {"position": {"x": 3.0, "y": 0.0, "z": 4.0}, "orientation": {"w": 1.0}}}
    out = beyond_reach("geometry_msgs/PoseStamped", stamped, 10.0)
    assert out is not None and out["pose"]["position"] == pytest.approx({"x": 6.0, "y": 0.0, "z": 8.0})
    assert out["pose"]["orientation"] == {"w": 1.0} and stamped["pose"]["position"]["x"] == 3.0
    origin = beyond_reach("geometry_msgs/Pose", {"position": {"x": 0.0, "y": 0.0, "z": 0.0}}, 2.0)
    assert origin is not None and origin["position"] == {"x": 2.0, "y": 0.0, "z": 0.0}
    assert beyond_reach("sensor_msgs/JointState", {"position": [0.0]}, 2.0) is None


@pytest.mark.parametrize("robot", ["probot_anno", "ur5", "panda"])
def test_the_reach_probe_is_out_of_reach_and_correct_targets_agree_on_it(robot: str) -> None:
    """Both correct targets fail on it alike (no report); a target that reports a failed IK as
    a success (``ik_status_misread``) diverges there."""
    from fuzzer.execution.records import Status

    session = Session.open(RunConfig(op="ik", robot=robot))
    (probe,) = reach_cases(session, seed=7)
    position = probe.message["pose"]["position"]
    distance = float(np.linalg.norm([position[k] for k in "xyz"]))
    facts = session.facts()
    assert facts.reachable is not None
    samples = Uniform(facts.lower, facts.upper, seed=8).block(256)
    farthest = max(float(np.linalg.norm(facts.reachable(tuple(map(float, q)))[0])) for q in samples)
    assert distance >= REACH_FACTOR * farthest * 0.9 > farthest
    evaluation = session.evaluator().evaluate(probe)
    assert not evaluation.divergent
    assert [o.status for o in evaluation.outcomes] == [Status.FAILED] * 2, evaluation.outcomes
    if robot == "probot_anno":
        targets = ("native", "benchmarks.zoo.bugs:ik_status_misread")
        misread = Session.open(RunConfig(op="ik", targets=targets))
        assert misread.evaluator().evaluate(reach_cases(misread, seed=7)[0]).divergent


class _Recorder:
    """A harness that records what the first stage's child hands it (no target runs)."""

    sweep = None  # run_sweep stands for the sweeps

    def __init__(self, events: list[object]) -> None:
        self.events = events

    def test_one_input(self, data: bytes) -> None:
        self.events.append(decode(data))

    def run_sweep(self) -> None:
        self.events.append("sweep")

    def maybe_snapshot(self, force: bool = False) -> None:
        self.events.append("snapshot")


@pytest.mark.parametrize(
    ("op", "target"),
    [
        ("move", "benchmarks.zoo.deep:per_joint_band"),
        ("fk", "python"),
        ("ik", "python"),
        ("scenario", "python"),
    ],
)
def test_the_first_stage_evaluates_its_first_input_before_it_makes_the_rest(
    monkeypatch: pytest.MonkeyPatch, op: str, target: str
) -> None:
    """The child evaluates the first stage's inputs in ``first_cases``' order with the literal
    configurations at ``_literal_at``, each part made when its turn comes: a ``move``'s first
    uniform configuration before the other 183 inputs are made (2-3 ms), with one snapshot at
    the end."""
    events: list[object] = []
    session = Session.open(RunConfig(op=op, targets=("native", target)))
    stages = dry_run.Stages(session, "rrosfuzz", 3, 8, 0, lambda seeds, sweep: _Recorder(events))
    monkeypatch.setattr(dry_run, "launch", lambda work, timeout: work())  # the child's work, here
    made = dry_run.aligned_cases

    def aligned(*args: object, **kwargs: object) -> list[TestCase]:
        events.append("aligned made")
        return made(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(dry_run, "aligned_cases", aligned)
    stages.first()
    monkeypatch.setattr(dry_run, "aligned_cases", made)
    expected = _stages(op, seed=3).first_cases()
    early = min(dry_run.EARLY.get(op, 0), dry_run.UNIFORM.get(op, 0))
    # the literals go after the first HEAD uniform configurations (move), else after the probes
    at = min(dry_run.HEAD, early) if early else len(expected)
    literals = dry_run.Stages(session, "rrosfuzz", 3, 8, 0, None)
    literals.first_cases()
    evaluated = [e for e in events if isinstance(e, TestCase)]
    if op == "fk":  # its sweeps first: FIRST_ROWS rows, then the early ones; the late ones last
        early, late = dry_run.EARLY["fk"], dry_run.LATE["fk"]
        assert events[: early + 1] == ["sweep"] * (early + 1)
        end = events.index("snapshot")  # the child's last event
        assert events[end - late : end] == ["sweep"] * late
        assert "sweep" not in events[early + 1 : end - late], "the probes between them"
    if op == "move":  # its sweeps last only: its first inputs are configurations
        late = dry_run.LATE["move"]
        end = events.index("snapshot")
        assert late > 0 and events[end - late : end] == ["sweep"] * late
        assert "sweep" not in events[: end - late]
        assert literals.literal_cases(), "per_joint_band's module compares against numbers"
        assert isinstance(events[0], TestCase) and events[0].lineage == (UNIFORM,), events[:2]
        assert events.index("aligned made") > 1, "made after the first input"
    expected = expected[:at] + literals.literal_cases() + expected[at:]
    assert [c.encode() for c in evaluated] == [c.encode() for c in expected]
    handed = [e for e in events if e != "aligned made"]  # (the campaign's own count makes them again)
    assert handed[-1] == "snapshot" and handed.count("snapshot") == 1
