"""The baselines' scenario op (``benchmarks.baselines``): uniform scripts, the paper's strategies
on one step's values, Hypothesis' scripts; each a valid script the engine evaluates."""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest

from benchmarks import baselines
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.generation import corpus
from fuzzer.generation import scripts as uniform
from fuzzer.input.libfuzzer_flags import DEFAULT_FLAGS
from fuzzer.input.mapping import REMEMBERED
from fuzzer.mutation import mutators
from fuzzer.scenario import steps as scenario_steps
from tests.support import python


def _config() -> RunConfig:
    return RunConfig(op="scenario", targets=("native", "python"), tolerance=default_tolerance("scenario"))


@pytest.fixture(scope="module")
def session() -> Session:
    return Session.open(_config())


def test_uniform_scripts_are_valid_and_uniform_inside_the_limits(session: Session) -> None:
    rng = random.Random(3)
    scripts = [baselines._uniform(session, rng, i).message for i in range(200)]
    again = [baselines._uniform(session, random.Random(3), 0).message]
    assert again[0] == scripts[0]  # one seed, one script
    kinds: set[str] = set()
    lengths = set()
    for script in scripts:
        scenario_steps.validate(script, session.registry, session.config.max_steps)
        lengths.add(len(script["steps"]))
        remembered = ["home"]
        for step in script["steps"]:
            kind = scenario_steps.TOPICS[step["topic"]].kind
            kinds.add(kind)
            msg = step["msg"]
            if kind == "joint_target":
                assert msg["name"] == list(session.reference.joint_names)
                for q, lim in zip(msg["position"], session.reference.joint_limits, strict=True):
                    low = -math.pi if math.isinf(lim.lower) else lim.lower
                    high = math.pi if math.isinf(lim.upper) else lim.upper
                    assert low <= q <= high
            elif kind == "remember":
                assert msg["data"] in REMEMBERED
                remembered.append(msg["data"])
            elif kind == "named_target":
                assert msg["data"] in remembered  # home, or a name stored earlier in the script
            elif kind in uniform.SETTINGS:
                low, high = uniform.SETTINGS[kind]
                assert low <= msg["data"] <= high
            elif kind == "cartesian_path":
                assert uniform.WAYPOINTS[0] <= len(msg["poses"]) <= uniform.WAYPOINTS[1]
    assert kinds == {scenario_steps.TOPICS[t].kind for t in scenario_steps.TOPICS}  # every kind comes up
    assert min(lengths) == 1 and max(lengths) == session.config.max_steps


def test_a_uniform_pose_target_is_the_pose_of_a_configuration(session: Session) -> None:
    rng = random.Random(5)
    step = uniform.uniform_step(session, rng, "pose_target", [])
    q = uniform.configuration(session, random.Random(5))
    pose = session.reference.forward_kinematics(q)
    assert [step["pose"]["position"][k] for k in "xyz"] == pytest.approx(list(pose.position))


def test_the_papers_loop_changes_the_values_of_one_step_only(session: Session) -> None:
    mutate = baselines._paper_mutate(session)
    parents = corpus.make_seeds(session, 16, 7)
    ctx = mutators.MutationContext(rng=random.Random(1), field_types={})
    changed = 0
    for i in range(200):
        parent = parents[i % len(parents)].message
        strategy = mutators.PAPER_STRATEGIES[i % len(mutators.PAPER_STRATEGIES)]
        child, name = mutate(parent, ctx, strategy)
        if name != f"seq_step:{strategy}":
            continue  # the run loop drops a child of another mutator
        topics = [s["topic"] for s in child["steps"]]
        assert topics == [s["topic"] for s in parent["steps"]]  # the script's calls stay
        differ = [a for a, b in zip(child["steps"], parent["steps"], strict=True) if a != b]
        assert len(differ) == 1
        changed += 1
    assert changed > 100


@pytest.mark.parametrize("engine", baselines.ENGINES)
def test_each_baseline_runs_scenarios(engine: str, tmp_path: Path) -> None:
    harness = baselines.run(engine, Session.open(_config()), tmp_path, 1.0, 1)
    assert harness.stats.execs > 0
    assert harness.stats.malformed == 0


def test_the_baselines_oracle_has_the_full_engines_re_run_budget(session: Session, tmp_path: Path) -> None:
    """Without it a slow target's scenario divergence took 90 s of re-runs in a 10-s trial."""
    from fuzzer import campaign

    harness = baselines._harness(session, tmp_path, corpus.make_seeds(session, 2, 1), 1)
    budget = campaign.check_seconds(int(DEFAULT_FLAGS["-timeout"]))
    assert budget is not None and harness.evaluator.check_seconds == budget


@pytest.mark.parametrize("op", ["scenario", "move"])
def test_uniform_sampling_and_hypothesis_alone_start_with_their_own_first_input(
    op: str, tmp_path: Path
) -> None:
    """Neither waits for 32 Hypothesis seeds it would never evaluate (about 0.2 s of one CPU;
    for uniform sampling, Hypothesis' import too): the start-up the tables compare is each
    engine's own. Uniform sampling's inputs are the same stream as before, from its first."""
    program = f"""
import random, sys
from pathlib import Path
from benchmarks import baselines
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.harness import Harness
seen = []
def first(self, data):
    seen.append((data, "hypothesis" in sys.modules))
    if len(seen) == 2:
        raise SystemExit(0)
Harness.test_one_input = first
config = RunConfig(op={op!r}, targets=("native", "python"), tolerance=default_tolerance({op!r}))
try:
    baselines.run("uniform", Session.open(config), Path({str(tmp_path / "uniform")!r}), 5.0, 7)
except SystemExit:
    pass
session, rng = Session.open(config), random.Random(7)
expected = [baselines._uniform(session, rng, n).encode() for n in range(2)]
print([data for data, _ in seen] == expected, seen[0][1])
"""
    done = python(program)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["True", "False"], "the same inputs, and no Hypothesis before the first"
    config = RunConfig(op=op, targets=("native", "python"), tolerance=default_tolerance(op))
    harness = baselines.run("hypothesis", Session.open(config), tmp_path, 0.3, 2)
    batch = corpus.make_seeds(Session.open(config), baselines.HYPOTHESIS_BATCH, 2 * 100_003)
    assert harness.seeds == batch, "its first batch is its Harness's seed, not 32 more"
