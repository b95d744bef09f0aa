"""How often one mutator's children of one parent show a deep scenario bug (no campaign).

A campaign's detection rate mixes the mutator with everything around it (which parent is
picked, which mutator the bandit draws, the clock). This probe isolates the mutator: it runs
the tutorial scripts of ``--warm-seeds`` seeds through the instrumented targets so the
comparison table learns thresholds as a campaign's start-up would, picks one of those scripts
as the parent, freezes the table, and evaluates ``--children`` children of that parent made by
``--mutator`` with seeds 0.. (each child on its own ``random.Random(seed)``), counting those
the oracle reports as a counted divergence::

    .venv/bin/python -m benchmarks.probe_mutator --bug profile_switch_band --parent 0 --children 400

The parent is the ``--parent``-th script in the order the tutorial seeds give them. Output:
the parent's steps, the operands the comparison table holds for it, and the counts per
lineage name. Deterministic for a given commit and arguments.
"""

from __future__ import annotations

import argparse
import collections
import hashlib
import json
import operator
import random
import sys
from typing import Any

OPS = (operator.lt, operator.le, operator.eq, operator.ne, operator.gt, operator.ge)


def _key(message: dict[str, Any]) -> bytes:
    return hashlib.blake2b(json.dumps(message, sort_keys=True).encode(), digest_size=16).digest()


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.probe_mutator", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--bug", required=True, help="a deep scenario bug (benchmarks.zoo.DEEP, op scenario)")
    parser.add_argument(
        "--parent", type=int, default=0, help="index of the parent among the tutorial scripts"
    )
    parser.add_argument("--children", type=int, default=400)
    parser.add_argument("--mutator", default="seq_compared", help="a sequence mutator's name")
    parser.add_argument("--warm-seeds", type=int, default=3, help="tutorial seeds run first (default 3)")
    args = parser.parse_args(argv)
    from benchmarks.zoo import DEEP

    bug = next((b for b in DEEP if b.name == args.bug and b.op == "scenario"), None)
    if bug is None:
        parser.error(
            f"--bug: {args.bug!r} is not a deep scenario bug; known: "
            f"{', '.join(b.name for b in DEEP if b.op == 'scenario')}"
        )
    if args.children < 1 or args.warm_seeds < 1:
        parser.error("--children and --warm-seeds must be at least 1")

    import atheris

    from fuzzer.campaign import _scenario_mutators
    from fuzzer.execution.records import UNCOUNTED
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.execution.tolerance import default_tolerance
    from fuzzer.generation.corpus import tutorial_seeds
    from fuzzer.input.testcase import TestCase
    from fuzzer.mutation.mutators import MutationContext
    from fuzzer.selection.compared import ComparedValues
    from fuzzer.selection.floatcmp import FloatCompareTracer
    from fuzzer.selection.guidance import Features
    from fuzzer.selection.instrument import instrument

    config = RunConfig(
        op="scenario",
        robot=bug.robot,
        targets=("native", bug.target),
        tolerance=default_tolerance("scenario"),
    )
    instrument(config)
    session = Session.open(config)
    evaluator = session.evaluator()
    table = ComparedValues()
    tracer = FloatCompareTracer(Features(), compared=table)
    original = atheris._trace_cmp
    try:
        cases = [case for seed in range(args.warm_seeds) for case in tutorial_seeds(session, seed)]
        if not 0 <= args.parent < len(cases):
            parser.error(f"--parent must be in 0..{len(cases) - 1}")
        for case in cases:
            tracer.install()
            table.begin()
            evaluator.evaluate(case)
            table.end(_key(case.message))
        parent = cases[args.parent]
        table.select(_key(parent.message))
        atheris._trace_cmp = lambda a, b, opid, site, is_const: OPS[opid](a, b)  # the table stays as it is
        mutate = _scenario_mutators(session)["mutate_message"]
        try:
            mutate(
                parent.message,
                MutationContext(rng=random.Random(0), field_types={}, compared=table),
                args.mutator,
            )
        except KeyError as exc:
            parser.error(f"--mutator: {exc.args[0]}")
        made: collections.Counter[str] = collections.Counter()
        shown: collections.Counter[str] = collections.Counter()
        for seed in range(args.children):
            ctx = MutationContext(rng=random.Random(seed), field_types={}, compared=table)
            child, name = mutate(parent.message, ctx, args.mutator)
            made[name] += 1
            comparison = evaluator.evaluate(
                TestCase(parent.msg_type, child, 0, "probe", ("probe",), 1)
            ).comparison
            if comparison is not None and comparison.divergent and comparison.kind not in UNCOUNTED:
                shown[name] += 1
    finally:
        atheris._trace_cmp = original  # the process goes on as it was (tests run this in theirs)
    result = {
        "parent": [step["topic"] for step in parent.message["steps"]],
        "operands": table.operands(),
        "children": dict(made),
        "detected": dict(shown),
    }
    json.dump(result, sys.stdout, indent=1)
    print()
    return result


if __name__ == "__main__":
    main()
