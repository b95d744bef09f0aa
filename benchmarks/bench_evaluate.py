"""The ceiling of the single-input rate: one evaluation (both targets and the oracle) alone.

    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move
    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move --plain
    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops fk move --decompose
    taskset -c 1 .venv/bin/python -m benchmarks.bench_evaluate --ops scenario --corpus corpus-scenario/

A campaign spends each input on libFuzzer, the mutator, the encoding, the features and the
evaluation. This measures the last part alone, in one process without libFuzzer: the 64
Hypothesis seeds of the default robot (``corpus.make_seeds(session, 64, seed)``) evaluated
round after round (``Evaluator.evaluate``: the mapping, both targets, the oracle; the twin's
IK memory emptied before each pass over them, so that ``ik`` measures solving), with the
twin and the oracle instrumented by Atheris as in a campaign and the float-comparison tracer's
per-input budget, or without instrumentation (``--plain``). No campaign can run more single
inputs a second than this. Prints the median over ``--rounds`` rounds of ``--seconds`` each.

``--decompose`` splits instrumentation's cost (one op at a time, instrumented): in each round
the same seeds run under five settings in turn, so that the machine's drift falls on all five:
with Atheris' own edge callback (``atheris._trace_branch`` of its core module, a pybind11
function the instrumented code looks up on the module at each edge; a campaign's until the
fifty-second session); the float tracer's budget 0 (its guard alone, the baselines' setting);
the edge callback swapped for a C builtin that does nothing (``abs``), the least any edge
callback can cost, so the bound of what a cheaper one could gain (nothing is counted: not a
setting to fuzz with); both; and as a campaign runs now, with ``fuzzer.selection.fastcov``'s
edge callback. Atheris' core module is imported, as ``atheris.Fuzz()`` does, for its callback
(outside a campaign its counters are not allocated, so the increments do nothing; the calls
cost what they cost). It prints the edges and float comparisons an evaluation makes, then each
setting's median rate.

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


class Seeds:
    """One op's session, evaluator and test cases (the seeds, or ``corpus_dir``'s), the twin and
    the oracle instrumented by Atheris with the float tracer as in a campaign if ``instrumented``."""

    def __init__(self, op: str, instrumented: bool, seed: int, corpus_dir: Path | None = None) -> None:
        config = RunConfig(op=op, tolerance=default_tolerance(op))
        self.tracer = None
        if instrumented:
            from fuzzer.selection.floatcmp import FloatCompareTracer
            from fuzzer.selection.guidance import Features
            from fuzzer.selection.instrument import instrument

            instrument(config)
            self.tracer = FloatCompareTracer(Features())
        session = Session.open(config)
        self.evaluator = session.evaluator()
        self.cases = (
            corpus.make_seeds(session, 64, seed) if corpus_dir is None else corpus_cases(session, corpus_dir)
        )

    def one_pass(self, budget: int | None = None) -> None:
        """Evaluate every case once; the tracer gets ``budget`` (its own by default) per input."""
        IK_MEMO.clear()  # each pass solves its IK problems, as the first did
        for case in self.cases:
            if self.tracer is not None:
                self.tracer.install(budget)  # a fresh budget per input, as the harness does
            self.evaluator.evaluate(case)

    def timed(self, seconds: float, budget: int | None = None) -> float:
        """Evaluations a second over whole passes for at least ``seconds``."""
        start, n = time.perf_counter(), 0
        while time.perf_counter() - start < seconds:
            self.one_pass(budget)
            n += len(self.cases)
        return n / (time.perf_counter() - start)


def rate(
    op: str, instrumented: bool, rounds: int, seconds: float, seed: int, corpus_dir: Path | None = None
) -> list[float]:
    """Evaluations a second, one figure per round (of the seeds, or of ``corpus_dir``'s test cases)."""
    seeds = Seeds(op, instrumented, seed, corpus_dir)
    seeds.one_pass()  # warm-up
    return [seeds.timed(seconds) for _ in range(rounds)]


SETTINGS = (
    "with Atheris' own edge callback",
    "float tracer's guard alone",
    "edge callback at a C no-op's cost",
    "both",
    "as a campaign (the fast edge callback)",
)
"""``--decompose``'s settings, in the order each round runs them."""


def decompose(op: str, rounds: int, seconds: float, seed: int) -> dict[str, list[float]]:
    """Evaluations a second under each of :data:`SETTINGS` (instrumented), one figure per round."""
    import atheris

    from fuzzer.selection import fastcov
    from fuzzer.selection.floatcmp import PER_INPUT

    seeds = Seeds(op, True, seed)
    assert seeds.tracer is not None
    # as atheris.Fuzz() does: its core module's pybind11 _trace_branch (counters not allocated
    # outside a campaign, so Atheris' increment does nothing; the calls cost what they cost)
    import atheris.core_with_libfuzzer as core

    atheris._trace_branch = branch = core._trace_branch
    why = fastcov.install(atheris)
    if why is not None:
        raise SystemExit(f"bench_evaluate --decompose: the fast edge callback: {why}")
    fast = atheris._trace_branch
    settings = dict(
        zip(
            SETTINGS,
            ((branch, PER_INPUT), (branch, 0), (abs, PER_INPUT), (abs, 0), (fast, PER_INPUT)),
            strict=True,
        )
    )  # each setting's edge callback and float tracer budget
    edges = [0]

    def counting(index: int) -> None:
        edges[0] += 1
        branch(index)

    atheris._trace_branch = branch
    seeds.one_pass(PER_INPUT)  # warm-up (first calls fill caches)
    atheris._trace_branch = counting
    before = seeds.tracer.traced
    try:
        seeds.one_pass(10**9)  # every edge and every float comparison counted
    finally:
        atheris._trace_branch = branch
    cases = len(seeds.cases)
    print(
        f"{op}: per evaluation, {edges[0] / cases:,.0f} edge callbacks and "
        f"{(seeds.tracer.traced - before) / cases:,.0f} float comparisons (the first {PER_INPUT} traced)"
    )
    rates: dict[str, list[float]] = {name: [] for name in SETTINGS}
    for _ in range(rounds):
        for name, (callback, budget) in settings.items():
            atheris._trace_branch = callback
            try:
                rates[name].append(seeds.timed(seconds, budget))
            finally:
                atheris._trace_branch = branch
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
    parser.add_argument(
        "--decompose",
        action="store_true",
        help="split instrumentation's cost: edges and float comparisons per evaluation, and the rate "
        "with Atheris' own edge callback, with the float tracer's guard alone, with the edge callback "
        "at a C no-op's cost, with both, and as a campaign (the fast edge callback)",
    )
    args = parser.parse_args()
    cli.check_sizes(parser, rounds=args.rounds, seconds=args.seconds)
    if args.decompose and (args.plain or args.corpus is not None):
        parser.error("--decompose measures the instrumented seeds: not with --plain or --corpus")
    if args.decompose:
        print(machine.reference_line("before"))
        for op in args.ops:
            for name, rates in decompose(op, args.rounds, args.seconds, args.seed).items():
                shown = ", ".join(f"{r:,.0f}" for r in rates)
                print(f"{op} {name}: median {statistics.median(rates):,.0f} evaluations/s (rounds: {shown})")
        print(machine.reference_line("after"))
        return
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
