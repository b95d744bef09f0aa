"""A paired A/B test of two arms of the engine on zoo bugs: both arms of a pair run at once.

    .venv/bin/python -m benchmarks.bench_ab --arm before /tmp/ab-before --arm after . \\
        --bugs wrap_past_pi per_joint_band --trials 20 --first-seed 10 --out /tmp/ab.jsonl
    .venv/bin/python -m benchmarks.bench_ab --arm off . RROSFUZZ_X=0 --arm on . RROSFUZZ_X=1 ...
    .venv/bin/python -m benchmarks.bench_ab --arm full . --arm uniform . --engines full uniform ...
    .venv/bin/python -m benchmarks.bench_ab --from-json /tmp/ab.jsonl     # tabulate a file
    .venv/bin/python -m benchmarks.bench_ab --from-json run1.jsonl run2.jsonl   # pool runs

Why paired: two arms run as two sweeps minutes apart differ in start-up by 10-15 ms on these
shared VMs (docs/benchmarks-log.md, forty-first session), more than most changes to the start-up
or the dry run save, so a difference measured from launch said more about the minute than about
the change. Here every pair (bug, seed) runs both arms at the same moment, each on a CPU of its
own (which arm gets which CPU: a seeded coin per pair), so whatever the machine does in that
second it does to both; the pairs run one after another in a seeded random order. With
``--serial`` (or fewer than two CPUs to pin to) a pair's arms run one after the other on one
CPU, in the coin's order: the two do not slow each other down (two interpreters starting side
by side on two vCPUs of a shared host do, unevenly), at twice the wall time.

An arm is ``--arm NAME DIR [VAR=VALUE ...]``: the tree at ``DIR`` run by its own
``DIR/.venv/bin/python`` (``make setup`` there first: a code arm needs its own native build and
editable install; a checkout of one commit into another's folder measured the wrong code,
docs/benchmarks-log.md, thirty-ninth session), with the environment settings given (``env``;
both arms go through ``env``, settings or not). Both arms may be one tree with different
settings, or one tree and setting under two engines (``--engines full uniform``: the engine
against a baseline of ``benchmarks.bench_zoo``, pair by pair). Each trial is
``benchmarks.bench_zoo.run_one`` with ``stop_at_detection``, as in ``benchmarks.bench_deep``:
time to first detection from launch (the engine's own timestamp), start-up (launch to first
evaluated input) and search (first input to detection).

Per bug, the second arm against the first: each arm's medians; the Wilcoxon signed-rank test
(two-sided, ``zero_method="zsplit"``) on the pairs' differences, a trial without detection
counted as the budget, for launch, search and start-up; the median paired difference; the
share of pairs in which the second arm was sooner (ties half: the paired A12) and the verdict
at p < 0.05; beside them the unpaired Mann-Whitney U and A12 the tables use. Each finished pair
is appended to ``--out`` (JSON lines: a header naming the arms, their commits and settings, the
engines, the budget and the machine; then one trial per line), so ``--resume`` goes on with the
pairs missing on the same arms, commits and machine. ``--from-json`` with several files pools
their pairs (the same arm names, engines and budget in each): a pair is a (file, bug, seed), so
runs of the same seeds (``make bench-paired`` twice) count twice, which makes p a little
optimistic, as the table's header says.
"""

from __future__ import annotations

import argparse
import json
import random
import re
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from benchmarks import cli, journal, sweeps, trials
from benchmarks.ab_table import FORMAT, pool, read, report
from benchmarks.bench_deep import BUGS
from benchmarks.bench_zoo import ALL_ENGINES, Run, run_one

SETTING = re.compile(r"[A-Za-z_][A-Za-z0-9_]*=[^\0]*")
"""An environment setting as ``env`` takes it."""


@dataclass(frozen=True)
class Arm:
    """One side of the test: the tree at ``root`` (its commit) with ``env`` settings."""

    name: str
    root: str
    commit: str
    env: tuple[str, ...] = ()

    @property
    def python(self) -> str:
        return str(Path(self.root) / ".venv" / "bin" / "python")


def main(argv: list[str] | None = None) -> dict[str, list[tuple[Run, Run]]]:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--arm",
        nargs="+",
        action="append",
        metavar="NAME DIR [VAR=VALUE]",
        help="an arm: its name, its tree, environment settings; twice (the second against the first)",
    )
    parser.add_argument(
        "--bugs",
        nargs="+",
        choices=list(BUGS),
        metavar="BUG",
        help="zoo bugs (benchmarks.zoo: deep or shallow)",
    )
    parser.add_argument(
        "--engines",
        nargs=2,
        choices=ALL_ENGINES,
        default=["full", "full"],
        metavar="ENGINE",
        help="the first arm's engine and the second's (default: full full; e.g. full uniform, "
        "to race the engine against a baseline in pairs)",
    )
    parser.add_argument("--trials", type=int, default=20, help="pairs per bug (%(default)s)")
    parser.add_argument(
        "--first-seed",
        type=int,
        default=1,
        help="the first pair's -seed (%(default)s; at least 1: libFuzzer takes -seed=0 as 'draw one', "
        "and each arm would draw its own)",
    )
    parser.add_argument("--budget", type=float, default=10.0, help="seconds per trial (%(default)s)")
    parser.add_argument("--out", type=Path, help="the pairs' file (JSON lines), appended as each pair ends")
    parser.add_argument(
        "--serial",
        action="store_true",
        help="run a pair's arms one after the other on one CPU (the coin's order) instead of at once",
    )
    parser.add_argument("--resume", action="store_true", help="go on with the pairs --out does not hold yet")
    parser.add_argument(
        "--from-json",
        type=Path,
        nargs="+",
        metavar="FILE",
        help="tabulate files of pairs instead of running (several: their pairs pooled)",
    )
    args = parser.parse_args(argv)
    if args.from_json is not None:
        try:
            headers, runs, batches = pool(args.from_json)
        except ValueError as exc:
            parser.error(str(exc))
        return report(headers[0], runs, batches, headers[1:])
    arms = _arms(parser, args)
    if not args.bugs or args.out is None:
        parser.error("--bugs and --out are needed to run (or --from-json FILE to tabulate)")
    cli.check_sizes(parser, trials=args.trials)
    cli.check_trials(parser, args.trials, args.first_seed)
    cli.check_campaign_seconds(parser, budget=args.budget)
    cli.check_unique(parser, bugs=args.bugs)
    if args.first_seed < 1:
        parser.error(
            f"--first-seed must be 1 or more, not {args.first_seed} (libFuzzer takes -seed=0 as "
            "'draw a seed', so the two arms of a pair would not share one)"
        )
    header = {
        "format": FORMAT,
        "arms": [asdict(arm) for arm in arms],
        "engines": list(args.engines),
        "budget": args.budget,
        "machine": journal.machine_of(),
        "serial": args.serial,
    }
    cli.check_folder(parser, args.out.parent)
    done = _open(parser, args.out, header, args.resume)
    pairs = [
        (bug, seed) for bug in args.bugs for seed in range(args.first_seed, args.first_seed + args.trials)
    ]
    random.Random(0).shuffle(pairs)
    todo = [p for p in pairs if p not in done]
    print(f"{len(todo)} of {len(pairs)} pairs to run, {args.out}", flush=True)
    for arm in arms:
        sweeps.compile_tree(Path(arm.root))
    runs = _run(arms, todo, args.engines, args.budget, args.out, args.serial)
    return report(header, [*_flat(done), *runs])


def _arms(parser: argparse.ArgumentParser, args: argparse.Namespace) -> list[Arm]:
    """The two arms of the command line, checked: a name each, a tree with its own ``.venv``,
    settings as ``VAR=VALUE``."""
    given = args.arm or []
    if len(given) != 2:
        parser.error(f"two --arm NAME DIR [VAR=VALUE ...] are needed, not {len(given)}")
    arms = []
    for spec in given:
        if len(spec) < 2:
            parser.error(f"--arm {' '.join(spec)}: NAME DIR [VAR=VALUE ...] expected")
        name, folder, *env = spec
        root = Path(folder).resolve()
        if not (root / "fuzz_diff.py").is_file():
            parser.error(f"--arm {name}: {folder} is not an RROSFuzz tree (no fuzz_diff.py)")
        if not (root / ".venv" / "bin" / "python").is_file():
            parser.error(f"--arm {name}: {folder} has no .venv/bin/python (run `make setup` there)")
        bad = [s for s in env if not SETTING.fullmatch(s)]
        if bad:
            parser.error(f"--arm {name}: {bad[0]!r} is not an environment setting VAR=VALUE")
        arms.append(Arm(name, str(root), journal.commit_of(root), tuple(env)))
    if arms[0].name == arms[1].name:
        parser.error(f"the two arms need different names, not both {arms[0].name!r}")
    if (arms[0].root, arms[0].env) == (arms[1].root, arms[1].env) and args.engines[0] == args.engines[1]:
        parser.error("the two arms are the same tree with the same settings and engine")
    return arms


def _open(
    parser: argparse.ArgumentParser, out: Path, header: dict[str, Any], resume: bool
) -> dict[Any, list[Run]]:
    """The pairs ``out`` already holds, by (bug, seed) (none for a new file); the parser's error
    for a file that exists without ``--resume``, or whose header differs from ``header``."""
    if out.is_dir():
        parser.error(f"--out {out} is a folder: name the pairs' file (JSON lines)")
    if not out.exists():
        try:
            out.write_text(json.dumps(header) + "\n", encoding="utf-8")
        except OSError as exc:
            parser.error(f"{out}: cannot hold the pairs ({exc.strerror or exc})")
        return {}
    if not resume:
        parser.error(f"{out} exists: --resume goes on with it, or name another --out")
    try:
        held, runs = read(out)
    except ValueError as exc:
        parser.error(str(exc))
    for key in ("arms", "engines", "budget", "machine", "serial"):
        if held.get(key, False) != json.loads(json.dumps(header[key])):  # as the file holds it
            parser.error(f"{out}: another test ({key}: {held.get(key)!r}, here {header[key]!r})")
    _cut_partial_line(out)
    by_pair: dict[tuple[str, int], dict[str, Run]] = {}
    for side, run in runs:
        by_pair.setdefault((run.bug, run.seed), {})[side] = run
    return {pair: [both["a"], both["b"]] for pair, both in by_pair.items() if len(both) == 2}


def _cut_partial_line(out: Path) -> None:
    """Drop a last line cut short (a process killed while writing it; ``read`` leaves it out and
    its pair runs again), so the next pair appended starts a line of its own."""
    with out.open("r+b") as handle:
        data = handle.read()
        if data and not data.endswith(b"\n"):
            handle.truncate(data.rfind(b"\n") + 1)


def _flat(done: dict[Any, list[Run]]) -> list[tuple[str, Run]]:
    return [(side, run) for both in done.values() for side, run in zip(("a", "b"), both, strict=True)]


def _run(
    arms: list[Arm],
    todo: list[tuple[str, int]],
    engines: list[str],
    budget: float,
    out: Path,
    serial: bool = False,
) -> list[tuple[str, Run]]:
    """Run the pairs, both arms at once (``serial``: one after the other on one CPU); append each
    finished pair to ``out``."""
    coin = random.Random(1)
    cpus = sweeps.cores(2)
    if serial:  # both on one CPU: the last, where a 2-CPU machine's interrupts are fewer
        one_cpu = sweeps.cores(1) if cpus is None else cpus[1:]
        cpus = None if one_cpu is None else [one_cpu[0], one_cpu[0]]
    done: list[tuple[str, Run]] = []
    with ThreadPoolExecutor(max_workers=2) as pool:
        for index, (name, seed) in enumerate(todo, 1):
            bug = BUGS[name]
            order = [0, 1] if coin.random() < 0.5 else [1, 0]  # order[i]: the arm on cpus[i]

            def one(slot: int, bug: Any = bug, seed: int = seed, order: list[int] = order) -> Run:
                arm, engine = arms[order[slot]], engines[order[slot]]
                cpu = None if cpus is None else cpus[slot]
                root = Path(arm.root)
                env = list(arm.env)
                return run_one(
                    bug,
                    engine,
                    seed,
                    budget,
                    stop_at_detection=True,
                    cpu=cpu,
                    root=root,
                    python=arm.python,
                    env=env,
                )

            try:
                if cpus is None or serial:  # one after the other, in the coin's order
                    got = [one(0), one(1)]
                else:
                    futures = [pool.submit(one, slot) for slot in (0, 1)]
                    got = [f.result() for f in futures]
            except KeyboardInterrupt:
                trials.stop_all()
                print(f"interrupted: {len(done) // 2} pairs kept in {out}; --resume goes on", file=sys.stderr)
                raise SystemExit(130) from None
            runs = [got[order.index(0)], got[order.index(1)]]
            for arm, run in zip(arms, runs, strict=True):
                if run.first_input is None and run.returncode not in (0, -9):
                    raise SystemExit(
                        f"{arm.name} ({arm.root}) did not start {run.engine} on {name} "
                        f"(exit {run.returncode}): run its command by hand to see why"
                    )
            with out.open("a", encoding="utf-8") as file:
                for arm, run in zip(arms, runs, strict=True):
                    file.write(json.dumps({"arm": arm.name, **asdict(run)}) + "\n")
            done += [("a", runs[0]), ("b", runs[1])]
            a, b = (r.detected_at for r in runs)
            print(
                f"[{index}/{len(todo)}] {name} seed {seed}: {arms[0].name} {a} {arms[1].name} {b}", flush=True
            )
    return done


if __name__ == "__main__":
    main()
