"""Search strength on the deep zoo bugs (issue 11), with FuzzBench/Magma-style statistics.

    .venv/bin/python -m benchmarks.bench_deep --mode full --write-md   # 10 trials x 60 s per (bug, engine)
    .venv/bin/python -m benchmarks.bench_deep --mode short --write-md  # 10 trials x 10 s, 5 engines
    .venv/bin/python -m benchmarks.bench_deep --mode zoo --write-md    # the 23 shallow zoo bugs, 10 x 10 s
    .venv/bin/python -m benchmarks.bench_deep --mode quick             # 2 trials x 10 s, two bugs (CI-sized)
    .venv/bin/python -m benchmarks.bench_deep --mode full --stop-after 120   # two hours of it, then
    .venv/bin/python -m benchmarks.bench_deep --mode full --resume           # the rest, later

Every deep bug (``benchmarks.zoo.DEEP``: faults confined to narrow regions of the input
space), or with ``--mode zoo`` every bug of the shallow zoo (``benchmarks.zoo.ZOO``), runs
under every engine of ``benchmarks.bench_zoo`` (``full``, ``libfuzzer``, ``paper``,
``hypothesis``, ``uniform``; the baselines run the scenario bugs too since 2026-11-29),
N trials each (``-seed`` = the trial number, counted from ``--first-seed``, default 0), on the
same budget, each trial a subprocess started the same way (``bench_zoo.run_one``). A trial
stops at its first detection (``stop_at_detection``): its time to first detection is the
engine's own timestamp in its log, which stopping does not change, and what it would find
later is not measured. Per (bug, engine): detection rate and median time to first
detection; per bug, the full engine against each baseline: the two-sided Mann-Whitney U
test on the times to detection (a trial that never detects counts as the budget: censored)
and the Vargha-Delaney A12 (the probability that a full-engine trial detects sooner than a
baseline trial, ties half; 0.5 = no difference). A survival plot (the share of trials that
have found the bug over time) goes to
``benchmarks/results/deep-<mode>.png``; with ``--write-md`` the table replaces the marked
section of BENCHMARKS.md (``--mode zoo`` and ``--mode full``: sections of their own, so that
``make bench-deep``'s 10-s table and ``make bench``'s 60-s one stand side by side).

Each finished trial is also appended to ``deep-<mode>.jsonl`` in the results folder as it ends
(``benchmarks.journal``), so a sweep stopped part way (``--stop-after MINUTES``, or killed)
keeps what it ran: ``--resume`` runs only the missing trials, on the same code (the journal's
commit, or one that changed only results and Markdown), and ``--from-json deep-<mode>.jsonl``
tabulates them so far. The journal goes once ``deep-<mode>.json`` holds every trial. With
``--first-seed N`` (seeds other than the tables' 0-9) the files are ``deep-<mode>-seedsN-M.*``
and no table of BENCHMARKS.md is replaced.
"""

from __future__ import annotations

import argparse
import json
import random
import sys
from dataclasses import asdict
from pathlib import Path

from benchmarks import cli, journal, sweeps
from benchmarks.bench_zoo import ALL_ENGINES, RESULTS, Run, run_one
from benchmarks.deep_stats import Mode, markdown, plot
from benchmarks.zoo import DEEP, UNTUNED, ZOO, Bug
from benchmarks.zoo_tables import ROOT, replace_section

MARKS = ("<!-- bench_deep:begin -->", "<!-- bench_deep:end -->")
TITLE = "## Search strength on deep bugs (issue 11)"
SECTIONS = {
    "zoo": (
        ("<!-- bench_deep_zoo:begin -->", "<!-- bench_deep_zoo:end -->"),
        "### The zoo with FuzzBench statistics (issue 11)",
    ),
    "full": (
        ("<!-- bench_deep_full:begin -->", "<!-- bench_deep_full:end -->"),
        "### The deep bugs in 60-s trials (`make bench`)",
    ),
}
"""Modes with a BENCHMARKS.md section of their own: (marks, title); the others use MARKS, TITLE."""
BUGS: dict[str, Bug] = {b.name: b for b in (*DEEP, *ZOO, *UNTUNED)}
"""The bugs this benchmark runs, by name: the deep ones, the shallow zoo, then the bugs the
engine was not tuned on (``--bugs`` only; no mode runs them)."""


MODES = {
    "quick": Mode(
        bugs=("narrower_band", "computed_branch"), trials=2, budget=10.0, engines=("full", "uniform")
    ),
    "short": Mode(
        bugs=tuple(b.name for b in DEEP),
        trials=10,
        budget=10.0,
        engines=("full", "libfuzzer", "paper", "hypothesis", "uniform"),
    ),
    "full": Mode(bugs=tuple(b.name for b in DEEP), trials=10, budget=60.0),
    "zoo": Mode(
        bugs=tuple(b.name for b in ZOO),
        trials=10,
        budget=10.0,
        engines=("full", "libfuzzer", "paper", "hypothesis", "uniform"),
    ),
}
"""quick: CI-sized (about a minute on 2 cores). short: every deep bug against the baselines the
goal names, 10 trials x 10 s (32 minutes on 2 cores for the first 12 deep bugs, 55 before
trials stopped at their first detection; the three deep scenario bugs of 2026-11-27 add 60
trials of at most 10 s, about 5 minutes; with the baselines' 120 trials of the four scenario
bugs, since 2026-11-29, all 750 trials took 41 minutes on 5821603). full: 10 trials x 60 s,
the old engine (``weights``) too: 900 trials (690 for the first 12 bugs, about 2.7 hours on 2
cores at 4.2 trials a minute; the three deep scenario bugs add 90 trials that mostly run their
whole minute, about 45 minutes; the baselines' 120 trials of the four scenario bugs about 40
more, estimated), run in pieces with the journal.
zoo: the 23 shallow zoo bugs (``benchmarks.zoo.ZOO``) against the same baselines, 10 trials x
10 s: 1,150 trials (the 22 before the sixty-ninth session: 1,100 trials, 28 minutes on 2 cores
on 2e15dd3; before the baselines ran the 8 scenario bugs, 860 trials took 25 on 0586935 and 34
on an earlier, slower machine)."""


def main(argv: list[str] | None = None) -> list[Run]:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--mode", choices=MODES, default="quick")
    parser.add_argument("--bugs", nargs="+", default=None, choices=list(BUGS))
    parser.add_argument("--engines", nargs="+", default=None, choices=ALL_ENGINES)
    parser.add_argument("--trials", type=int, default=None)
    parser.add_argument(
        "--first-seed",
        type=int,
        default=0,
        help="the first trial's -seed (default 0): the trials are seeds FIRST_SEED to "
        "FIRST_SEED + trials - 1, e.g. to see whether a verdict holds beyond the tables' seeds 0-9",
    )
    parser.add_argument("--budget", type=float, default=None)
    parser.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2: one per core)")
    parser.add_argument("--write-md", action="store_true", help="update BENCHMARKS.md")
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        help=f"folder for deep-<mode>.json and .png ({RESULTS}; with --from-json, no plot is written "
        "unless --results or --write-md is given)",
    )
    sweeps.add_arguments(parser, "--results' deep-<mode>.jsonl")
    parser.add_argument(
        "--from-json",
        type=Path,
        default=None,
        help="tabulate the runs of an earlier deep-<mode>.json, or of a journal "
        "(deep-<mode>.jsonl) so far, instead of running (its bugs, engines, trials and budget; "
        "--mode names the output files)",
    )
    args = parser.parse_args(argv)
    sweeps.check_arguments(parser, args)
    base = MODES[args.mode]
    mode = Mode(
        tuple(args.bugs or base.bugs),
        args.trials or base.trials,
        args.budget or base.budget,
        tuple(args.engines or base.engines),
    )
    if mode.engines[0] != "full":
        parser.error("the first engine must be 'full' (the one compared against the others)")
    cli.check_sizes(parser, trials=args.trials)
    cli.check_trials(parser, mode.trials, args.first_seed)
    cli.check_campaign_seconds(parser, budget=args.budget)
    cli.check_unique(parser, bugs=args.bugs, engines=args.engines)
    # tabulating a file writes a plot only where asked: not over the tables' own deep-<mode>.png
    args.plot = args.from_json is None or args.write_md or args.results is not None
    elsewhere = args.results is not None and args.results.resolve() != RESULTS.resolve()
    args.results = args.results or RESULTS
    if args.first_seed < 0:
        parser.error(f"--first-seed must be 0 or more, not {args.first_seed}")
    args.stem = f"deep-{args.mode}"
    if args.first_seed:  # other seeds than the tables': files of their own, and no table replaced
        if args.write_md:
            parser.error(
                "--write-md takes the tables' seeds (from 0); --first-seed's trials get files of their own"
            )
        args.stem += f"-seeds{args.first_seed}-{args.first_seed + mode.trials - 1}"
    # --write-md replaces the mode's table and links its plot in RESULTS: nothing else may (a
    # journal's own refusal comes first)
    if args.write_md and (args.from_json is None or args.from_json.suffix != ".jsonl"):
        if elsewhere:
            parser.error(f"--write-md links the plot in {RESULTS}: --results must be it or not given")
        if mode != base and args.from_json is None:
            parser.error(
                f"--write-md replaces the {args.mode} table: it takes the mode's bugs, engines, trials "
                "and budget"
            )
    cli.check_folder(parser, args.results)
    if args.from_json is not None:
        partial = args.from_json.suffix == ".jsonl"
        if partial and args.write_md:
            parser.error(
                f"{args.from_json}: a journal so far is no finished table: "
                f"--write-md takes a deep-<mode>.json"
            )
        try:
            runs = load_runs(args.from_json)
            mode = Mode(
                tuple(sorted(dict.fromkeys(r.bug for r in runs), key=_bug_order)),
                max(sum(r.bug == b.bug and r.engine == b.engine for r in runs) for b in runs),
                max(float(r.budget) for r in runs),
                tuple(sorted({r.engine for r in runs}, key=lambda e: (e != "full", ALL_ENGINES.index(e)))),
            )
        except (OSError, ValueError, TypeError, AttributeError, RecursionError) as exc:
            parser.error(f"{args.from_json}: not a bench_deep results file ({exc})")
        if mode.engines[0] != "full":
            parser.error(f"{args.from_json}: no runs of the full engine")
        if args.write_md:
            same = (set(mode.bugs), set(mode.engines), mode.trials, mode.budget) == (
                set(base.bugs),
                set(base.engines),
                base.trials,
                base.budget,
            )
            if not same or {r.seed for r in runs} != set(range(base.trials)):
                parser.error(
                    f"{args.from_json}: not the {args.mode} table's bugs, engines, trials, budget and "
                    f"seeds (0-{base.trials - 1}), which --write-md replaces: tabulate it without --write-md"
                )
            mode = base  # its columns in the table's order
        so_far = (
            f"A sweep in progress: the {len(runs)} trials its journal holds so far (a cell counts its own). "
        )
        return _report(runs, mode, args, argv, copy=False, note=so_far if partial else "")
    seeds = range(args.first_seed, args.first_seed + mode.trials)
    jobs = [(BUGS[b], e, t) for b in mode.bugs for e in mode.engines for t in seeds]
    # a seeded random order, as FuzzBench does: a change of machine load during the sweep then
    # falls on every engine alike instead of on the engines that happen to run last
    random.Random(0).shuffle(jobs)
    commit = journal.commit_of(ROOT)
    sweep = journal.Sweep(
        args.mode,
        mode.bugs,
        mode.engines,
        mode.trials,
        mode.budget,
        commit,
        first_seed=args.first_seed,
        machine=journal.machine_of(),
    )
    path = args.results / f"{args.stem}.jsonl"

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        return run_one(job[0], job[1], job[2], mode.budget, stop_at_detection=True, cpu=cpu)

    progress = sweeps.sweep_in_journal(parser, args, path, sweep, ROOT, jobs, trial, "--from-json")
    runs = progress.runs
    if not progress.complete:
        return runs
    _report(runs, mode, args, argv, copy=True)
    path.unlink()  # deep-<mode>.json holds every trial now
    return runs


def _bug_order(name: str) -> tuple[int, str]:
    """The zoo's order (``DEEP``, then ``ZOO``), then other names alphabetically."""
    order = list(BUGS)
    return (order.index(name), "") if name in order else (len(order), name)


def load_runs(path: Path) -> list[Run]:
    """The runs of a deep-<mode>.json, or those of a journal (``.jsonl``) so far (fields this
    version does not know are dropped)."""
    if path.suffix == ".jsonl":
        header, held = journal.read(path)
        runs = journal.planned(header, held)
        if not runs:
            raise ValueError("the journal holds no finished trial yet")
        return runs
    rows = json.loads(path.read_text(encoding="utf-8"))
    if not isinstance(rows, list) or not rows or not all(isinstance(row, dict) for row in rows):
        raise ValueError("expected a non-empty list of runs")
    return [journal.run_of(row) for row in rows]


def _report(
    runs: list[Run], mode: Mode, args: argparse.Namespace, argv: list[str] | None, copy: bool, note: str = ""
) -> list[Run]:
    """Write deep-<mode>.json (unless tabulating one) and .png, print the tables (after
    ``note``), and with --write-md put them into BENCHMARKS.md."""
    if copy:  # the results folder: made by main's check_folder
        (args.results / f"{args.stem}.json").write_text(json.dumps([asdict(r) for r in runs], indent=1))
    if args.plot:
        plot(runs, mode, args.results / f"{args.stem}.png")
    cmd = "python -m benchmarks.bench_deep " + " ".join(sys.argv[1:] if argv is None else argv)
    text = note + markdown(runs, mode, cmd.strip(), args.jobs if copy else None)
    print(text)
    if args.write_md:
        picture = f"\n\n![survival](benchmarks/results/deep-{args.mode}.png)"
        replace_section(text + picture, *SECTIONS.get(args.mode, (MARKS, TITLE)))
    return runs


if __name__ == "__main__":
    main()
