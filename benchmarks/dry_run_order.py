"""Which of the dry run's first-stage inputs show a bug, counted in inputs, not seconds.

    .venv/bin/python -m benchmarks.dry_run_order --bugs wrap_past_pi off_by_tolerance --seeds 30
    .venv/bin/python -m benchmarks.dry_run_order --bugs execute_skips_start_check --seeds 60 --first-seed 10

For each bug (a ``move`` or ``scenario`` bug of ``benchmarks.bench_deep.BUGS``: their first stage
is inputs one at a time; an ``fk`` one's is batched sweeps) and each ``-seed`` in turn, the
first stage's inputs of a full-engine campaign (``fuzzer.dry_run.Stages``, in the order its child
evaluates them, literals included) are evaluated in one process with the campaign's evaluator,
as are the inputs of uniform sampling with the same seed (``benchmarks.baselines``, at most
``--uniform-inputs``). Printed: per source of the first stage's inputs (its lineage: uniform,
aligned, boundary probes, literals; tutorials and uniform scripts for a scenario), how many
inputs it has and in how many seeds it holds the first detection; then the index of the first
detection, the first stage's against uniform sampling's (median, mean, the seeds without one,
and the two-sided Mann-Whitney U test over the seeds).

Why: the benchmark tables time trials from launch, on a shared VM, and their 10 trials per
(bug, engine) are seeds 0-9 every time, so the same random streams meet the same bugs in every
sweep. An input count per seed depends neither on the machine's load nor on its speed, and
runs over any seeds; it answers whether the first stage's order or a seed's luck makes a
difference (``docs/benchmarks-log.md``, thirty-second session). It says nothing of the
start-up, of the time an input costs, or of what the campaign finds after its first stage.

A detection is an evaluation the oracle calls divergent, of a kind that is not
``ill_conditioned``, ``known_limitation`` or ``flaky`` (``benchmarks.trials.NOT_DETECTIONS``).
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from benchmarks import baselines, cli
from benchmarks.bench_deep import BUGS
from benchmarks.trials import NOT_DETECTIONS
from benchmarks.zoo import Bug
from fuzzer import dry_run
from fuzzer.execution.evaluate import Evaluator
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.input.testcase import TestCase

OPS = ("move", "scenario")
"""Ops whose first stage is inputs one at a time (``fk``'s is batched sweeps, ``ik`` has none)."""
WANTED = 32
"""Seeds a campaign makes by default: the first stage's inputs are numbered after them."""


@dataclass(frozen=True)
class SeedResult:
    """One seed of one bug: where the first detection came, in inputs from the first."""

    bug: str
    seed: int
    first_stage: int
    """Inputs in the first stage."""
    detected_at: int | None
    """Index of the first stage's first detecting input (None: none detects)."""
    source: str | None
    """That input's source (its lineage's last step)."""
    sources: dict[str, int]
    """Inputs per source in the first stage."""
    uniform_at: int | None
    """Index of uniform sampling's first detecting input (None: none of ``--uniform-inputs``)."""


def open_session(bug: Bug) -> Session:
    if bug.op not in OPS:
        raise ValueError(
            f"{bug.name}: op {bug.op!r}; only {', '.join(OPS)} bugs have a first stage of single inputs"
        )
    targets = ("native", bug.target)
    return Session.open(
        RunConfig(
            op=bug.op,
            robot=bug.robot,
            tip_link=bug.tip_link,
            targets=targets,
            tolerance=default_tolerance(bug.op),
        )
    )


def detects(evaluator: Evaluator, case: TestCase) -> bool:
    comparison = evaluator.evaluate(case).comparison
    return bool(
        comparison is not None and comparison.divergent and comparison.kind.value not in NOT_DETECTIONS
    )


def source_of(case: TestCase) -> str:
    return case.lineage[-1] if case.lineage else case.origin


def first_stage(session: Session, seed: int) -> list[TestCase]:
    """The first stage's inputs of a full-engine campaign with ``-seed=seed``, in order."""
    stages = dry_run.Stages(session, "rrosfuzz", seed, WANTED, 0, lambda base, sweep: None)  # type: ignore[arg-type,return-value]
    return [case for _, part in stages._first_parts(literals=True) for case in part]


def one_seed(bug: Bug, session: Session, seed: int, uniform_inputs: int) -> SeedResult:
    cases = first_stage(session, seed)
    evaluator = session.evaluator()  # as the dry run's child: one evaluator, the inputs in order
    at = next((i for i, case in enumerate(cases) if detects(evaluator, case)), None)
    evaluator, rng = session.evaluator(), random.Random(seed)
    uniform_at = next(
        (i for i in range(uniform_inputs) if detects(evaluator, baselines._uniform(session, rng, i))), None
    )
    return SeedResult(
        bug.name,
        seed,
        len(cases),
        at,
        None if at is None else source_of(cases[at]),
        dict(Counter(map(source_of, cases))),
        uniform_at,
    )


def summary(results: Sequence[SeedResult], uniform_inputs: int) -> str:
    """A bug's Markdown summary over its seeds."""
    from scipy.stats import mannwhitneyu

    first = results[0]
    lines = [
        f"**{first.bug}** ({len(results)} seeds from {first.seed}; "
        f"a first stage of {first.first_stage} inputs)",
        "",
        "| source | inputs | seeds whose first detection it holds |",
        "|---|---:|---:|",
    ]
    held = Counter(r.source for r in results if r.source is not None)
    for source, count in first.sources.items():
        lines.append(f"| {source} | {count} | {held.get(source, 0)} |")
    missed = sum(r.detected_at is None for r in results)
    lines.append(f"| (none: after the first stage) | - | {missed} |")
    # a miss is later than any detection of either arm: one censoring index for both (the first
    # stage's miss counted as its own length, 200, against uniform's 400, made an arm that never
    # detected look significantly sooner than one that did at 250-259)
    never = max(first.first_stage, uniform_inputs)
    stage = [r.detected_at if r.detected_at is not None else never for r in results]
    uniform = [r.uniform_at if r.uniform_at is not None else never for r in results]
    p = mannwhitneyu(stage, uniform).pvalue if stage != uniform else 1.0
    lines += [
        "",
        "| | median index | mean index | seeds without a detection |",
        "|---|---:|---:|---:|",
        f"| first stage | {statistics.median(stage):g} | {statistics.mean(stage):.1f} | {missed} |",
        f"| uniform sampling | {statistics.median(uniform):g} | {statistics.mean(uniform):.1f} | "
        f"{sum(r.uniform_at is None for r in results)} (of {uniform_inputs} inputs) |",
        "",
        f"Mann-Whitney U, two-sided, first stage against uniform sampling: p = {p:.3g} (a seed "
        f"without a detection counts as index {never}, past every detection of either arm; so do "
        "the medians and means above).",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> list[SeedResult]:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--bugs", nargs="+", required=True, metavar="BUG", help="move or scenario bugs of the zoo"
    )
    parser.add_argument("--seeds", type=int, default=30, help="seeds per bug (default 30)")
    parser.add_argument("--first-seed", type=int, default=0, help="the first -seed (default 0)")
    parser.add_argument(
        "--uniform-inputs",
        type=int,
        default=400,
        help="uniform sampling's inputs per seed at most (default 400)",
    )
    parser.add_argument(
        "--out", type=Path, default=None, help="also write each seed's result to this new file (JSON Lines)"
    )
    args = parser.parse_args(argv)
    unknown = [name for name in args.bugs if name not in BUGS]
    if unknown:
        parser.error(f"unknown bug(s): {', '.join(unknown)} (known: {', '.join(BUGS)})")
    wrong = [f"{name} ({BUGS[name].op})" for name in args.bugs if BUGS[name].op not in OPS]
    if wrong:
        parser.error(
            f"only {' and '.join(OPS)} bugs have a first stage of single inputs, not {', '.join(wrong)}"
        )
    if args.seeds < 1 or args.uniform_inputs < 1:
        parser.error("--seeds and --uniform-inputs must be at least 1")
    if args.first_seed < 0:  # random.Random(-1) is random.Random(1): the seeds would repeat
        parser.error(f"--first-seed must be 0 or more, not {args.first_seed}")
    if len(set(args.bugs)) < len(args.bugs):
        parser.error("--bugs names a bug twice")
    if args.out is not None:
        cli.check_out_file(parser, args.out)  # before the first bug's seeds, not after
        if args.out.exists():  # appended to, as each bug ends: a re-run doubled its records
            parser.error(f"{args.out} exists: name another --out, or remove it")
    everything: list[SeedResult] = []
    for name in args.bugs:
        bug = BUGS[name]
        session = open_session(bug)
        seeds = range(args.first_seed, args.first_seed + args.seeds)
        results = [one_seed(bug, session, seed, args.uniform_inputs) for seed in seeds]
        if args.out is not None:
            with args.out.open("a", encoding="utf-8") as handle:
                handle.writelines(json.dumps(asdict(r)) + "\n" for r in results)
        print(summary(results, args.uniform_inputs), end="\n\n", flush=True)
        everything += results
    return everything


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
