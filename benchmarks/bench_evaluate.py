"""The ceiling of the single-input rate: one evaluation (both targets and the oracle) alone.

    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move
    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move --plain
    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops scenario --corpus corpus-scenario/

A campaign spends each input on libFuzzer, the mutator, the encoding, the features and the
evaluation. This measures the last part alone, in one process without libFuzzer: the 64
Hypothesis seeds of the default robot (``corpus.make_seeds(session, 64, seed)``) evaluated
round after round (``Evaluator.evaluate``: the mapping, both targets, the oracle; the twin's
IK memory emptied before each pass over them, so that ``ik`` measures solving), with the
twin and the oracle instrumented by Atheris as in a campaign and the float-comparison tracer's
per-input budget, or without instrumentation (``--plain``). No campaign can run more single
inputs a second than this. Prints the median over ``--rounds`` rounds of ``--seconds`` each.

``--corpus DIR`` evaluates the test cases in a folder instead (a campaign's corpus, one op):
the seeds of a scenario campaign mostly agree, while the inputs a campaign keeps diverge more
often and take the oracle's slower rules (the thirty-seventh session's A/B, BENCHMARKS.md).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

from benchmarks import cli, machine
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.generation import corpus
from fuzzer.input.testcase import TestCase, TestCaseError, decode
from python_impl.kinematics import IK_MEMO


def corpus_cases(session: Session, directory: Path) -> list[TestCase]:
    """The test cases of this session's message type among ``directory``'s files (sorted by
    name, hidden ones left out); a file that is not one is named on stderr and skipped."""
    cases, skipped = [], 0
    for path in sorted(p for p in directory.iterdir() if p.is_file() and not p.name.startswith(".")):
        try:
            case = decode(path.read_bytes())
            if case.msg_type != session.config.message_type:
                raise TestCaseError(f"message type {case.msg_type}, not {session.config.message_type}")
        except (OSError, ValueError) as exc:
            skipped += 1
            if skipped <= 3:
                print(f"skipping {path}: {exc}", file=sys.stderr)
            continue
        cases.append(case)
    if skipped:
        print(f"{skipped} file(s) of {directory} skipped, {len(cases)} test case(s) kept", file=sys.stderr)
    if not cases:
        raise SystemExit(f"bench_evaluate: no {session.config.message_type} test case in {directory}")
    return cases


def rate(
    op: str, instrumented: bool, rounds: int, seconds: float, seed: int, corpus_dir: Path | None = None
) -> list[float]:
    """Evaluations a second, one figure per round (of the seeds, or of ``corpus_dir``'s test cases)."""
    config = RunConfig(op=op, tolerance=default_tolerance(op))
    tracer = None
    if instrumented:
        from fuzzer.selection.floatcmp import FloatCompareTracer
        from fuzzer.selection.guidance import Features
        from fuzzer.selection.instrument import instrument

        instrument(config)
        tracer = FloatCompareTracer(Features())
    session = Session.open(config)
    evaluator = session.evaluator()
    cases = corpus.make_seeds(session, 64, seed) if corpus_dir is None else corpus_cases(session, corpus_dir)

    def one_pass() -> None:
        IK_MEMO.clear()  # each pass solves its IK problems, as the first did
        for case in cases:
            if tracer is not None:
                tracer.install()  # a fresh budget per input, as the harness does
            evaluator.evaluate(case)

    one_pass()  # warm-up
    rates = []
    for _ in range(rounds):
        start, n = time.perf_counter(), 0
        while time.perf_counter() - start < seconds:
            one_pass()
            n += len(cases)
        rates.append(n / (time.perf_counter() - start))
    return rates


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--ops", nargs="+", default=["fk", "move"], choices=("fk", "move", "ik", "scenario"))
    parser.add_argument("--plain", action="store_true", help="without Atheris' instrumentation")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--corpus",
        type=Path,
        metavar="DIR",
        help="evaluate the test cases in DIR (a campaign's corpus) instead of the seeds; one --ops",
    )
    args = parser.parse_args()
    cli.check_sizes(parser, rounds=args.rounds, seconds=args.seconds)
    if args.corpus is not None and (len(args.ops) != 1 or not args.corpus.is_dir()):
        parser.error(
            "--corpus needs one --ops and a folder" + ("" if args.corpus.is_dir() else f": {args.corpus}")
        )
    print(machine.reference_line("before"))
    for op in args.ops:
        rates = rate(op, not args.plain, args.rounds, args.seconds, args.seed, args.corpus)
        shown = ", ".join(f"{r:,.0f}" for r in rates)
        kind = "plain" if args.plain else "instrumented"
        print(f"{op} {kind}: median {statistics.median(rates):,.0f} evaluations/s (rounds: {shown})")
    print(machine.reference_line("after"))


if __name__ == "__main__":
    main()
