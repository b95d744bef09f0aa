"""The ceiling of the single-input rate: one evaluation (both targets and the oracle) alone.

    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move
    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move --plain

A campaign spends each input on libFuzzer, the mutator, the encoding, the features and the
evaluation. This measures the last part alone, in one process without libFuzzer: the 64
Hypothesis seeds of the default robot (``corpus.make_seeds(session, 64, seed)``) evaluated
round after round (``Evaluator.evaluate``: the mapping, both targets, the oracle; the twin's
IK memory emptied before each pass over them, so that ``ik`` measures solving), with the
twin and the oracle instrumented by Atheris as in a campaign and the float-comparison tracer's
per-input budget, or without instrumentation (``--plain``). No campaign can run more single
inputs a second than this. Prints the median over ``--rounds`` rounds of ``--seconds`` each.
"""

from __future__ import annotations

import argparse
import statistics
import time

from benchmarks import cli
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.generation import corpus
from python_impl.kinematics import IK_MEMO


def rate(op: str, instrumented: bool, rounds: int, seconds: float, seed: int) -> list[float]:
    """Evaluations a second, one figure per round."""
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
    cases = corpus.make_seeds(session, 64, seed)

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
    parser.add_argument("--ops", nargs="+", default=["fk", "move"], choices=("fk", "move", "ik"))
    parser.add_argument("--plain", action="store_true", help="without Atheris' instrumentation")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    cli.check_sizes(parser, rounds=args.rounds, seconds=args.seconds)
    for op in args.ops:
        rates = rate(op, not args.plain, args.rounds, args.seconds, args.seed)
        shown = ", ".join(f"{r:,.0f}" for r in rates)
        kind = "plain" if args.plain else "instrumented"
        print(f"{op} {kind}: median {statistics.median(rates):,.0f} evaluations/s (rounds: {shown})")


if __name__ == "__main__":
    main()
