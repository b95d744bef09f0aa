"""Baseline engines without libFuzzer, for the bug-finding comparison.

    python -m benchmarks.baselines {paper,hypothesis,uniform} --seconds S --seed N
        [--robot R] [--tip-link L] [--op OP] [--targets A,B] --artifacts DIR

* ``paper``: the paper's loop without coverage: Hypothesis seeds, the paper's
  three mutation strategies and four combinations (Table II), parents chosen by
  difference priority (Algorithm 3: the highest-difference inputs, rank
  weighted) half of the time, else a seed. For ``--op scenario`` the strategy
  mutates the values of one step of the script (the full engine's
  ``seq_step:<strategy>``), never the order or number of its steps.
* ``hypothesis``: Hypothesis generation only (Table I strategies with the
  engine's robot-aware hints; for ``--op scenario`` the scripts of
  ``fuzzer.input.mapping.scenario_strategy``), batch after batch, never mutating.
* ``uniform``: uniform random joint values inside the limits (continuous joints
  in (-pi, pi]); for IK, the pose of a uniform random configuration. For
  ``--op scenario``, scripts drawn the same way (``fuzzer.generation.scripts``): a
  uniform number of steps, each kind drawn with the generator's weights
  (``fuzzer.input.mapping.SCENARIO_WEIGHTS``), joint targets uniform inside the
  limits, pose and position targets and Cartesian waypoints the poses of uniform
  configurations, settings uniform in the generator's ranges.

``uniform`` and ``hypothesis`` start with their own first input (no Hypothesis seeds to wait
for; ``uniform`` never imports Hypothesis); ``paper`` starts with its 32 Hypothesis seeds.

Each evaluates inputs exactly like the engine (the same ``Harness.test_one_input``:
filtering, oracle, confirmation with the same time budget, crash files,
``divergences.jsonl``/``stats.jsonl``),
only without libFuzzer and without coverage features, and prints the same
summary line, so ``benchmarks/bench_zoo.py`` reads every engine the same way.
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from benchmarks import cli
from fuzzer import campaign, reporting
from fuzzer.artifacts.divlog import CampaignLog
from fuzzer.artifacts.sidecar_record import build_sidecar
from fuzzer.artifacts.store import WRITE_FAILED_EXIT, ArtifactStore, ArtifactsUnwritable
from fuzzer.execution.session import ConfigError, RunConfig, Session, versions
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.generation import corpus, scripts
from fuzzer.harness import Harness
from fuzzer.input.libfuzzer_flags import DEFAULT_FLAGS
from fuzzer.input.testcase import TestCase
from fuzzer.mutation import mutators, session_values
from fuzzer.mutation.mutators import MutationContext
from fuzzer.scenario.mutate import SEQ_STEP
from fuzzer.selection.guidance import Features

ENGINES = ("paper", "hypothesis", "uniform")
HYPOTHESIS_BATCH = 128
"""Inputs Hypothesis alone generates at a time (``corpus.make_seeds``), batch after batch."""


def _harness(session: Session, artifacts: Path, seeds: list[TestCase], seed: int) -> Harness:
    ctx = mutators.MutationContext(
        rng=random.Random(seed),
        field_types={}
        if session.config.op == "scenario"
        else session_values.field_types(session, session.config.message_type),
        interesting_floats=tuple(session_values.interesting_values(session)),
    )
    digest = session.robot_digest()
    evaluator = session.evaluator()
    # the oracle's re-runs get the full engine's budget (half its default -timeout): without one,
    # checking a scenario divergence of a slow target took 90 s of a 10-s trial
    evaluator.check_seconds = campaign.check_seconds(int(DEFAULT_FLAGS["-timeout"]))
    return Harness(
        evaluator=evaluator,
        store=ArtifactStore(artifacts),
        features=Features(enabled=False),
        context=ctx,
        sidecar=lambda c, d, e: build_sidecar(session, c, d, e, versions(), digest),
        seeds=seeds,
        log=CampaignLog(artifacts),
        joint_names=tuple(session.reference.joint_names),
    )


def _uniform(session: Session, rng: random.Random, sequence: int) -> TestCase:
    if session.config.op == "scenario":
        return TestCase(
            session.config.message_type, scripts.uniform_script(session, rng), sequence, "uniform"
        )
    q = scripts.configuration(session, rng)
    header = scripts.header()
    message: dict[str, Any]
    if session.config.op == "ik":
        pose = session.reference.forward_kinematics(q)
        message = {
            "header": header,
            "pose": {
                "position": dict(zip("xyz", pose.position, strict=True)),
                "orientation": dict(zip("xyzw", pose.orientation, strict=True)),
            },
        }
    else:
        message = {"header": header, "name": [], "position": q, "velocity": [], "effort": []}
    return TestCase(session.config.message_type, message, sequence, "uniform")


def _paper_mutate(
    session: Session,
) -> Callable[[dict[str, Any], MutationContext, str], tuple[dict[str, Any], str]]:
    """``mutate(message, ctx, strategy) -> (message, name)``: the paper's strategy on the
    message, or for a scenario on the values of one of its steps (``seq_step:<strategy>``)."""
    if session.config.op != "scenario":
        return mutators.mutate
    from fuzzer.scenario import dispatch

    scenario_mutate, _ = dispatch.for_registry(session.registry, session.config.max_steps)
    return lambda message, ctx, strategy: scenario_mutate(message, ctx, f"{SEQ_STEP}:{strategy}")


def run(engine: str, session: Session, artifacts: Path, seconds: float, seed: int) -> Harness:
    """Run the baseline ``engine`` for ``seconds`` on ``session``, its crash files and log in
    ``artifacts``, every random choice drawn from ``seed``."""
    rng = random.Random(seed)
    # what each engine evaluates first is also its Harness's seed: uniform sampling and
    # Hypothesis alone never wait for seeds they would not use (32 Hypothesis seeds, and for
    # uniform sampling Hypothesis' import, cost 0.1-0.6 s of one CPU before the first input,
    # the most on scenarios; docs/benchmarks-log.md, "A dry run for scenarios")
    if engine == "uniform":
        seeds = [_uniform(session, rng, 0)]
    elif engine == "hypothesis":
        seeds = corpus.make_seeds(session, HYPOTHESIS_BATCH, seed * 100_003)
    else:
        seeds = corpus.make_seeds(session, 32, seed)
    harness = _harness(session, artifacts, seeds, seed)
    deadline = time.monotonic() + seconds
    if engine == "paper":
        mutate = _paper_mutate(session)
        prefix = f"{SEQ_STEP}:" if session.config.op == "scenario" else ""
        accepted = {f"{prefix}{strategy}" for strategy in mutators.PAPER_STRATEGIES}
        for case in seeds:
            harness.test_one_input(case.encode())
        while time.monotonic() < deadline:
            preferred = harness.pool.pick(rng) if rng.random() < 0.5 else None
            parent = harness._decode(preferred)[0] if preferred else None
            parent = parent or rng.choice(seeds)
            harness.context.rng = rng
            strategy = rng.choice(mutators.PAPER_STRATEGIES)
            message, name = mutate(parent.message, harness.context, strategy)
            if name in accepted:  # a child of the paper's strategies, not of a fallback mutator
                harness.test_one_input(parent.child(message, name).encode())
    elif engine == "hypothesis":
        batch = 0
        while time.monotonic() < deadline:
            later = batch > 0
            cases = corpus.make_seeds(session, HYPOTHESIS_BATCH, seed * 100_003 + batch) if later else seeds
            for case in cases:
                harness.test_one_input(case.encode())
                if time.monotonic() >= deadline:
                    break
            batch += 1
    elif engine == "uniform":
        n = 0
        while time.monotonic() < deadline:
            harness.test_one_input((seeds[0] if n == 0 else _uniform(session, rng, n)).encode())
            n += 1
    else:
        raise ValueError(f"unknown engine {engine!r}")
    harness.maybe_snapshot(force=True)
    return harness


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("engine", choices=ENGINES)
    parser.add_argument("--seconds", type=float, required=True)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--artifacts", type=Path, required=True)
    parser.add_argument("--robot", default="probot_anno")
    parser.add_argument("--tip-link", default=None)
    parser.add_argument("--op", default="move", choices=("move", "fk", "ik", "scenario"))
    parser.add_argument("--targets", default="native,python")
    args = parser.parse_args()
    cli.check_sizes(parser, seconds=args.seconds)
    pair = args.targets.split(",")
    if len(pair) != 2 or not all(pair):
        parser.error(f"--targets takes two targets, as in native,python, not {args.targets!r}")
    a, b = pair
    config = RunConfig(
        op=args.op,
        robot=args.robot,
        tip_link=args.tip_link,
        targets=(a, b),
        tolerance=default_tolerance(args.op),
    )
    try:  # the robot, tip link and targets load before the artifacts folder is made
        session = Session.open(config)
    except ConfigError as exc:  # a robot, tip link or target the session cannot load
        parser.error(str(exc))
    cli.check_folder(parser, args.artifacts)
    try:
        harness = run(args.engine, session, args.artifacts, args.seconds, args.seed)
    except ArtifactsUnwritable:  # said by the harness, with any input it could not save
        sys.exit(WRITE_FAILED_EXIT)
    reporting.summary(harness.stats, 0, str(args.artifacts), [], [])


if __name__ == "__main__":
    main()
