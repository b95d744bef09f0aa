"""Bug-finding power: every engine against every zoo bug, on the same budget.

    .venv/bin/python -m benchmarks.bench_zoo --mode quick     # a few bugs, 1 seed, short budget
    .venv/bin/python -m benchmarks.bench_zoo --mode full      # all bugs + controls, 5 seeds
    .venv/bin/python -m benchmarks.bench_zoo --mode controls  # false positives only
    .venv/bin/python -m benchmarks.bench_zoo --mode buckets   # buckets per injected bug only
    .venv/bin/python -m benchmarks.bench_zoo --mode ops       # stateful bugs: --op move vs scenario

Engines, each a subprocess started the same way (the clock starts at launch):

* ``full``: ``fuzz_diff.py``, the whole engine;
* ``libfuzzer``: ``fuzz_diff.py --mutator=libfuzzer`` (Atheris, libFuzzer's own mutator only);
* ``paper``, ``hypothesis``, ``uniform``: ``benchmarks/baselines.py``.

Per run: time to first detection (the first logged divergence that is not
``ill_conditioned``, ``known_limitation`` or ``flaky``), unique signatures (for a
zoo bug: its buckets, goal one), and exec/s. The controls (the unmodified twin on
every configuration a bug uses, ``fk`` on every known robot, ``ik`` on the default
arm; full engine only) give the false-positive rate: control runs that reported
any divergence, and divergences per minute. Results go to
``benchmarks/results/zoo-<mode>.json`` and a plot ``zoo-<mode>.png``; with
``--write-md`` the tables replace the marked section of BENCHMARKS.md.

A zoo bug runs with its own op (``--op scenario`` for the stateful ones; every engine has
it, the baselines since 2026-11-29: ``benchmarks.baselines``). ``--mode ops``
runs each stateful bug under both ``--op move`` and ``--op scenario`` (full engine) and
writes the section "Which ops detect the stateful bugs".

Each finished run is also appended to a journal beside the results file (``zoo-<mode>.jsonl``,
``benchmarks.journal``), and the runs go in a seeded random order: a sweep stopped part way
(``--stop-after MINUTES``, or killed) keeps what it ran, and ``--resume`` runs only the missing
ones, on the same code. The journal goes once ``zoo-<mode>.json`` holds every run.

``--first-seed N`` runs seeds from N instead of 1 (controls beyond the tables' seeds 1 to
``--seeds``, say): its files are ``zoo-<mode>-seedsN-M.*``, and it replaces no table.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from benchmarks import cli, journal, sweeps, trials
from benchmarks.trials import NOT_DETECTIONS, run_until_detection
from benchmarks.zoo import BY_NAME, CONTROL, CONTROLS, STATEFUL, ZOO, Bug
from benchmarks.zoo_tables import (
    ROOT,
    is_config_control,
    markdown,
    plot,
    summarize,
    summarize_ops,
    write_markdown,
)
from fuzzer.artifacts.divlog import DIVERGENCES, STATS, read_lines

RESULTS = ROOT / "benchmarks" / "results"
ENGINES = ("full", "libfuzzer", "paper", "hypothesis", "uniform")
ALL_ENGINES = (*ENGINES, "weights")
"""``weights``: the full engine without its bandit, space-filling inputs and float features
(``--mutator weights``, the engine before issue 11), for ``benchmarks.bench_deep``."""
FIRST_SEED = 1
"""The tables' first ``-seed``, and the least ``--first-seed`` (libFuzzer takes ``-seed=0`` for
a seed from the clock). A journal written before ``--first-seed`` holds seeds from here
(``journal.sweep_of``)."""
CONTROL_ENGINES = ("full",)
"""Engines run on the control configurations (the plain ``control`` entry runs them all)."""
SCENARIO_ENGINES = ENGINES
"""Engines that have ``--op scenario``: all (the baselines of ``benchmarks.baselines`` since
2026-11-29; results files from before hold no baseline run of a scenario bug)."""


@dataclass(frozen=True)
class Mode:
    bugs: tuple[str, ...]
    seeds: int
    budget: float  # seconds per run
    engines: tuple[str, ...] = ENGINES
    replay: bool = False
    ops: tuple[str, ...] = ()
    """When given, every bug runs under each of these ops instead of its own."""


MODES = {
    "quick": Mode(bugs=("silent_clamp", "off_by_tolerance", "wrap_positive"), seeds=1, budget=8.0),
    "full": Mode(bugs=tuple(b.name for b in (*ZOO, CONTROL, *CONTROLS)), seeds=5, budget=20.0, replay=True),
    "controls": Mode(bugs=tuple(b.name for b in CONTROLS), seeds=1, budget=15.0, engines=("full",)),
    "buckets": Mode(bugs=tuple(b.name for b in ZOO), seeds=1, budget=10.0, engines=("full",), replay=True),
    "ops": Mode(
        bugs=tuple(b.name for b in (*STATEFUL, *CONTROLS) if b.op == "scenario"),
        seeds=3,
        budget=30.0,
        engines=("full",),
        ops=("move", "scenario"),
    ),
}


@dataclass(frozen=True)
class Run:
    bug: str
    engine: str
    seed: int
    budget: float
    detected_at: float | None
    signatures: int
    executions: int
    elapsed: float
    op: str
    returncode: int
    divergences: int = 0
    """Logged divergences that count as detections."""
    replayed: int = 0
    """Crash files (with a sidecar) replayed in a fresh process (``--replay``)."""
    replay_same: int = 0
    """Of those, the ones that replayed with the same signature."""
    replay_misses: tuple[str, ...] = ()
    """Kind and verdict of each file that did not."""
    fields: tuple[str, ...] = ()
    """Per field that diverged: ``kind field: largest difference unit`` (what was found)."""
    first_input: float | None = None
    """Seconds from the process start to the first evaluated test case (the start-up: imports,
    seeds, instrumentation); None when the run logged none."""
    libfuzzer_seed: int | None = None
    """libFuzzer's ``-seed`` of the trial's campaign, as its ``stats.jsonl`` records it: the one
    ``fuzz_diff.py`` drew for ``-seed=0`` (``bench_deep``'s first trial), which ``-seed=N
    --seed=0`` repeats; None for the baselines (no libFuzzer) and runs from before it was kept."""

    @property
    def search_time(self) -> float | None:
        """Seconds from the first evaluated test case to the first detection (start-up excluded)."""
        if self.detected_at is None or self.first_input is None:
            return None
        return max(0.0, self.detected_at - self.first_input)


def command(
    bug: Bug,
    engine: str,
    seed: int,
    budget: float,
    workdir: Path,
    root: Path = ROOT,
    python: str = sys.executable,
) -> list[str]:
    """The trial's command line: ``engine`` against ``bug`` in the tree at ``root`` (its
    ``fuzz_diff.py`` or its ``benchmarks.baselines``, run by ``python``), logs in ``workdir``."""
    artifacts, corpus = workdir / "artifacts", workdir / "corpus"
    common = [f"--robot={bug.robot}", f"--op={bug.op}", f"--targets=native,{bug.target}"]
    if bug.tip_link:
        common.append(f"--tip-link={bug.tip_link}")
    if engine in ("full", "libfuzzer", "weights"):
        cmd = [
            python,
            str(root / "fuzz_diff.py"),
            str(corpus),
            f"-max_total_time={int(budget)}",
            f"-seed={seed}",
            f"--artifacts={artifacts}",
            "--no-progress",
            *common,
        ]
        return cmd if engine == "full" else [*cmd, f"--mutator={engine}"]
    return [
        python,
        "-m",
        "benchmarks.baselines",
        engine,
        f"--seconds={budget}",
        f"--seed={seed}",
        f"--artifacts={artifacts}",
        *common,
    ]


def run_one(
    bug: Bug,
    engine: str,
    seed: int,
    budget: float,
    replay: bool = False,
    *,
    stop_at_detection: bool = False,
    keep_failures: Path | None = None,
    cpu: int | None = None,
    root: Path = ROOT,
    python: str = sys.executable,
    env: Sequence[str] | None = None,
) -> Run:
    """Run one trial of ``engine`` against ``bug`` in a fresh folder and read its logs.

    Parameters
    ----------
    bug, engine, seed, budget
        What ``command`` runs (``budget``: seconds; the trial is killed, and
        ``subprocess.TimeoutExpired`` raised, 180 s past it).
    replay
        Replay the full engine's crash files in a new process (``benchmarks.trials.replay_fidelity``).
    keep_failures
        A control run that reports a divergence (a false positive) copies its artifacts
        (crash files, sidecars, logs) to ``keep_failures/<bug>-<engine>-seed<seed>/`` before
        its temporary folder goes: a campaign depends on the clock, so a rerun may not find
        it again.
    stop_at_detection
        Kill the trial (its whole process group) once its logs show a detection and a stats
        snapshot with its first input (``benchmarks.trials.run_until_detection``). The time to first detection
        is the engine's own timestamp in the divergence log (``t``), so stopping, and how long
        the kill takes, do not change it; the start-up (``first_input``) neither. The counts
        that need the whole run (signatures, executions, elapsed) then cover only the part
        before the kill, and ``returncode`` is ``-SIGKILL``: ``benchmarks.bench_deep`` uses it,
        this module's tables (signatures, throughput) do not. The harness logs its first
        snapshot right after its first input, so a trial stops soon after its detection.

    cpu
        Run the trial, and every process it starts, on this CPU only (``taskset``; a sweep
        gives each trial running at a time its own, ``benchmarks.sweeps.cores``); None: any.
    root, python
        The tree whose engine runs (its working folder and ``PYTHONPATH``), and the Python that
        runs it (default: this tree and this Python); ``benchmarks.bench_ab`` runs another tree
        with that tree's own ``.venv``.
    env
        ``VAR=VALUE`` settings the trial runs with (through ``env``; None: none, and no ``env``).

    Returns
    -------
    Run
        The trial's record.
    """
    with tempfile.TemporaryDirectory(prefix="rrosfuzz-bench-") as tmp:
        workdir = Path(tmp)
        artifacts = workdir / "artifacts"
        cmd = command(bug, engine, seed, budget, workdir, root, python)
        cmd = sweeps.pinned(cmd if env is None else ["env", *env, *cmd], cpu)
        started = time.time()
        if stop_at_detection:
            returncode = run_until_detection(cmd, artifacts, budget + 180, root)
        else:
            returncode = trials.run_to_end(cmd, budget + 180, root)
        hits = [r for r in read_lines(artifacts / DIVERGENCES) if r.get("kind") not in NOT_DETECTIONS]
        first = min((float(r["t"]) - started for r in hits), default=None)
        last: dict[Any, dict[str, Any]] = {}
        for record in read_lines(artifacts / STATS):
            last[record.get("pid")] = record
        kept = {r["seed"].get("libfuzzer") for r in last.values() if isinstance(r.get("seed"), dict)}
        libfuzzer_seed = kept.pop() if len(kept) == 1 else None
        if not isinstance(libfuzzer_seed, int) or isinstance(libfuzzer_seed, bool):
            libfuzzer_seed = None
        starts = [float(r["first_input"]) for r in last.values() if r.get("first_input") is not None]
        started_search = min(starts) - started if starts else None
        executions = sum(int(r.get("execs", 0)) for r in last.values())
        elapsed = max((float(r.get("elapsed", 0.0)) for r in last.values()), default=0.0)
        fidelity = trials.replay_fidelity(bug, artifacts, root) if replay and engine == "full" else (0, 0, ())
        if keep_failures is not None and bug.is_control and hits and artifacts.is_dir():
            name = "".join(c if c.isalnum() or c in "-_." else "_" for c in f"{bug.name}-{engine}-seed{seed}")
            shutil.copytree(artifacts, keep_failures / name, dirs_exist_ok=True)
    return Run(
        bug.name,
        engine,
        seed,
        budget,
        first,
        len({r["sig"] for r in hits}),
        executions,
        elapsed or budget,
        bug.op,
        returncode,
        len(hits),
        *fidelity,
        trials.found_fields(hits),
        started_search,
        libfuzzer_seed,
    )


def plan_jobs(
    bugs: tuple[str, ...],
    engines: tuple[str, ...],
    seeds: int,
    ops: tuple[str, ...] = (),
    first_seed: int = FIRST_SEED,
) -> list[tuple[Bug, str, int]]:
    """The runs of a sweep, as (bug, engine, seed): each bug under its own op, or under each
    of ``ops``; controls only with CONTROL_ENGINES; scenario runs only with SCENARIO_ENGINES;
    ``seeds`` seeds from ``first_seed``."""
    return [
        (bug, e, s)
        for b in bugs
        for bug in ([replace(BY_NAME[b], op=op) for op in ops] if ops else [BY_NAME[b]])
        for e in engines
        if (not is_config_control(b) or e in CONTROL_ENGINES)
        and (bug.op != "scenario" or e in SCENARIO_ENGINES)
        for s in range(first_seed, first_seed + seeds)
    ]


def result_of(sweep: journal.Sweep, runs: list[Run]) -> dict[str, Any]:
    """A sweep's runs and their cells, as the results file keeps them (without how and where
    they ran: jobs, cpus, machine, command, load)."""
    bugs, engines = sweep.bugs, sweep.engines
    return {
        "mode": sweep.mode,
        "bugs": list(bugs),
        "engines": list(engines),
        "seeds": sweep.trials,
        "first_seed": sweep.first_seed,
        "budget": sweep.budget,
        "runs": [asdict(r) for r in runs],
        "cells": summarize_ops(runs, bugs, sweep.ops) if sweep.ops else summarize(runs, engines, bugs),
        "ops": list(sweep.ops),
    }


def render(parser: argparse.ArgumentParser, path: Path, write_md: bool) -> dict[str, Any]:
    """Print the tables of a saved result (``zoo-<mode>.json``), or of a journal's runs so far
    (``zoo-<mode>.jsonl``; not for BENCHMARKS.md), and with ``write_md`` put a saved result's
    into BENCHMARKS.md. A file that is neither is the parser's error."""
    note = ""
    if path.suffix == ".jsonl" and write_md:
        parser.error(f"{path}: a journal so far is no finished table: --write-md takes a zoo-<mode>.json")
    try:
        if path.suffix == ".jsonl":
            header, runs = journal.read(path, "bench_zoo")
            sweep = journal.sweep_of(header, "bench_zoo")
            runs = journal.planned(header, runs, "bench_zoo")
            unknown = sorted({b for b in [*sweep.bugs, *(r.bug for r in runs)] if b not in BY_NAME})
            if unknown:
                raise ValueError(f"unknown bugs {unknown}")
            jobs = plan_jobs(sweep.bugs, sweep.engines, sweep.trials, sweep.ops, sweep.first_seed)
            plan = {sweeps.key_of(job): i for i, job in enumerate(jobs)}
            runs.sort(key=lambda r: plan.get(sweeps.run_key(r), len(plan)))  # the plan's order
            saved = {**result_of(sweep, runs), "jobs": "?", "cpus": "?", "machine": "not recorded"}
            saved["command"] = f"python -m benchmarks.bench_zoo --mode {sweep.mode} (commit {sweep.commit})"
            note = f"A sweep in progress: {len(runs)} of its {len(plan)} runs so far.\n\n"
        else:
            saved = json.loads(path.read_text(encoding="utf-8"))
        text = note + markdown(saved)
    except (
        OSError,
        UnicodeDecodeError,
        ValueError,
        KeyError,
        TypeError,
        AttributeError,
        RecursionError,
        ArithmeticError,
    ) as exc:
        parser.error(f"{path}: not a bench_zoo result or journal ({type(exc).__name__}: {exc})")
    if write_md:
        table = MODES.get(str(saved.get("mode")))
        if table is None or (
            saved.get("first_seed", FIRST_SEED) != FIRST_SEED
            or list(saved.get("bugs", ())) != [b for b in table.bugs]
            or list(saved.get("engines", ())) != list(table.engines)
        ):
            parser.error(
                f"{path}: not a table's bugs, engines and seeds (from {FIRST_SEED}), which --write-md "
                "replaces: tabulate it without --write-md"
            )
    print(text)
    if write_md:
        write_markdown(text, mode=str(saved.get("mode", "full")))
    return saved


def _load() -> str:
    """The 1, 5 and 15 minute load averages, as ``uptime`` shows them."""
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--mode", choices=MODES, default="quick")
    parser.add_argument("--bugs", nargs="+", default=None)
    parser.add_argument("--engines", nargs="+", default=None, choices=ENGINES)
    parser.add_argument("--seeds", type=int, default=None)
    parser.add_argument(
        "--first-seed",
        type=int,
        default=FIRST_SEED,
        help=f"the first run's -seed (default {FIRST_SEED}): the runs are seeds FIRST_SEED to "
        "FIRST_SEED + seeds - 1, e.g. controls beyond the tables' seeds; other seeds than the "
        "default get files of their own (zoo-<mode>-seedsN-M.*) and replace no table",
    )
    parser.add_argument("--budget", type=float, default=None)
    parser.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2: one per core)")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--write-md", action="store_true", help="update BENCHMARKS.md")
    parser.add_argument(
        "--render",
        type=Path,
        default=None,
        help="only render a saved result (zoo-<mode>.json), or a journal's runs so far "
        "(zoo-<mode>.jsonl), as markdown; run nothing",
    )
    parser.add_argument(
        "--replay", action="store_true", help="replay each full-engine run's crash files in a new process"
    )
    sweeps.add_arguments(parser, "the journal beside --out (zoo-<mode>.jsonl)")
    parser.add_argument(
        "--keep-failures",
        type=Path,
        default=None,
        help="where a control run that reports a divergence leaves its artifacts "
        "(default: control-failures/ next to --out)",
    )
    args = parser.parse_args(argv)
    sweeps.check_arguments(parser, args)
    cli.check_sizes(parser, seeds=args.seeds)
    cli.check_trials(parser, args.seeds or MODES[args.mode].seeds, args.first_seed, "seeds")
    cli.check_campaign_seconds(parser, budget=args.budget)
    cli.check_unique(parser, bugs=args.bugs, engines=args.engines)
    if args.render is not None:
        return render(parser, args.render, args.write_md)
    mode = MODES[args.mode]
    bugs = tuple(args.bugs or mode.bugs)
    unknown = [b for b in bugs if b not in BY_NAME]
    if unknown:
        parser.error(f"unknown bugs: {unknown}")
    seeds = args.seeds or mode.seeds
    budget = args.budget or mode.budget
    engines = tuple(args.engines or mode.engines)
    replay = args.replay or mode.replay
    if args.first_seed < 1:  # libFuzzer takes -seed=0 for a seed from the clock: no replay
        parser.error(
            f"--first-seed must be 1 or more (libFuzzer's -seed=0 is the clock's), not {args.first_seed}"
        )
    stem = f"zoo-{args.mode}"
    if args.first_seed != FIRST_SEED:  # other seeds than the tables': files of their own
        if args.write_md:
            parser.error(
                f"--write-md takes the tables' seeds (from {FIRST_SEED}); "
                "--first-seed's runs get files of their own"
            )
        stem += f"-seeds{args.first_seed}-{args.first_seed + seeds - 1}"
    jobs = plan_jobs(bugs, engines, seeds, mode.ops, args.first_seed)
    out = args.out or RESULTS / f"{stem}.json"
    keep = args.keep_failures or out.parent / "control-failures"
    cli.check_out_file(parser, out)
    path = out.with_suffix(".jsonl")
    if path == out:
        parser.error(f"--out {out}: a .jsonl name is the sweep's journal; name the results file .json")
    sweep = journal.Sweep(
        args.mode,
        bugs,
        engines,
        seeds,
        budget,
        journal.commit_of(ROOT),
        "bench_zoo",
        mode.ops,
        replay,
        first_seed=args.first_seed,
        machine=journal.machine_of(),
    )
    load_before = _load()

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        return run_one(job[0], job[1], job[2], budget, replay, keep_failures=keep, cpu=cpu)

    progress = sweeps.sweep_in_journal(parser, args, path, sweep, ROOT, jobs, trial, "--render", shuffle=True)
    runs = progress.runs
    if not progress.complete:
        return {"runs": [asdict(r) for r in runs], "complete": False}
    result = {
        **result_of(sweep, runs),
        "jobs": args.jobs,
        "cpus": os.cpu_count(),
        "machine": f"{platform.machine()}, {journal.cpu_model()}",
        "command": "python -m benchmarks.bench_zoo " + " ".join(argv if argv is not None else sys.argv[1:]),
        "load": f"{load_before} / {_load()}",
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1), encoding="utf-8")
    path.unlink()  # the results file holds every run now
    plot(result, out.with_suffix(".png"))
    text = markdown(result)
    print(text)
    if args.write_md:
        write_markdown(text, mode=args.mode)
    return result


if __name__ == "__main__":
    main()
