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

A zoo bug runs with its own op (``--op scenario`` for the stateful ones, which only
the full and libFuzzer engines run: the baselines have no scenario op). ``--mode ops``
runs each stateful bug under both ``--op move`` and ``--op scenario`` (full engine) and
writes the section "Which ops detect the stateful bugs".
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from benchmarks.trials import NOT_DETECTIONS, run_until_detection
from benchmarks.zoo import BY_NAME, CONTROL, CONTROLS, STATEFUL, ZOO, Bug
from fuzzer.artifacts.divlog import DIVERGENCES, STATS, read_lines

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
ENGINES = ("full", "libfuzzer", "paper", "hypothesis", "uniform")
ALL_ENGINES = (*ENGINES, "weights")
"""``weights``: the full engine without its bandit, space-filling inputs and float features
(``--mutator weights``, the engine before issue 11), for ``benchmarks.bench_deep``."""
CONTROL_ENGINES = ("full",)
"""Engines run on the control configurations (the plain ``control`` entry runs them all)."""
SCENARIO_ENGINES = ("full", "libfuzzer")
"""Engines that have ``--op scenario`` (the baselines do not)."""


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
MARK_BEGIN, MARK_END = "<!-- bench_zoo:begin -->", "<!-- bench_zoo:end -->"


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

    @property
    def search_time(self) -> float | None:
        """Seconds from the first evaluated test case to the first detection (start-up excluded)."""
        if self.detected_at is None or self.first_input is None:
            return None
        return max(0.0, self.detected_at - self.first_input)


def command(bug: Bug, engine: str, seed: int, budget: float, workdir: Path) -> list[str]:
    artifacts, corpus = workdir / "artifacts", workdir / "corpus"
    common = [f"--robot={bug.robot}", f"--op={bug.op}", f"--targets=native,{bug.target}"]
    if bug.tip_link:
        common.append(f"--tip-link={bug.tip_link}")
    if engine in ("full", "libfuzzer", "weights"):
        cmd = [
            sys.executable,
            str(ROOT / "fuzz_diff.py"),
            str(corpus),
            f"-max_total_time={int(budget)}",
            f"-seed={seed}",
            f"--artifacts={artifacts}",
            "--no-progress",
            *common,
        ]
        return cmd if engine == "full" else [*cmd, f"--mutator={engine}"]
    return [
        sys.executable,
        "-m",
        "benchmarks.baselines",
        engine,
        f"--seconds={budget}",
        f"--seed={seed}",
        f"--artifacts={artifacts}",
        *common,
    ]


def replay_fidelity(bug: Bug, artifacts: Path) -> tuple[int, int, tuple[str, ...]]:
    """Replay every crash file of a run in one new process: (files, same signature, misses)."""
    crashes = sorted(
        p for p in artifacts.glob("crash-*") if p.suffix != ".json" and Path(f"{p}.json").is_file()
    )
    if not crashes:
        return 0, 0, ()
    done = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), *map(str, crashes), f"--targets=native,{bug.target}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
    )
    same, misses = 0, []
    for path in crashes:
        line = next(
            (ln for ln in done.stdout.splitlines() if ln.startswith(f"{path}:")),
            f"no verdict (exit {done.returncode}: {done.stderr.strip()[-300:]})",
        )
        if "still diverges (same signature)" in line:
            same += 1
        else:
            kind = json.loads(path.with_name(path.name + ".json").read_text())["signature"]["kind"]
            misses.append(f"{kind}: {line.removeprefix(f'{path}: ')}")
    return len(crashes), same, tuple(misses)


def run_one(
    bug: Bug,
    engine: str,
    seed: int,
    budget: float,
    replay: bool = False,
    *,
    stop_at_detection: bool = False,
    keep_failures: Path | None = None,
) -> Run:
    """Run one trial of ``engine`` against ``bug`` in a fresh folder and read its logs.

    Parameters
    ----------
    bug, engine, seed, budget
        What ``command`` runs (``budget``: seconds; the trial is killed, and
        ``subprocess.TimeoutExpired`` raised, 180 s past it).
    replay
        Replay the full engine's crash files in a new process (``replay_fidelity``).
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

    Returns
    -------
    Run
        The trial's record.
    """
    with tempfile.TemporaryDirectory(prefix="rrosfuzz-bench-") as tmp:
        workdir = Path(tmp)
        artifacts = workdir / "artifacts"
        cmd = command(bug, engine, seed, budget, workdir)
        started = time.time()
        if stop_at_detection:
            returncode = run_until_detection(cmd, artifacts, budget + 180, ROOT)
        else:
            returncode = subprocess.run(
                cmd,
                cwd=ROOT,
                capture_output=True,
                text=True,
                timeout=budget + 180,
                check=False,
                env=dict(os.environ, PYTHONPATH=str(ROOT)),
            ).returncode
        hits = [r for r in read_lines(artifacts / DIVERGENCES) if r.get("kind") not in NOT_DETECTIONS]
        first = min((float(r["t"]) - started for r in hits), default=None)
        last: dict[Any, dict[str, Any]] = {}
        for record in read_lines(artifacts / STATS):
            last[record.get("pid")] = record
        starts = [float(r["first_input"]) for r in last.values() if r.get("first_input") is not None]
        started_search = min(starts) - started if starts else None
        executions = sum(int(r.get("execs", 0)) for r in last.values())
        elapsed = max((float(r.get("elapsed", 0.0)) for r in last.values()), default=0.0)
        fidelity = replay_fidelity(bug, artifacts) if replay and engine == "full" else (0, 0, ())
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
        found_fields(hits),
        started_search,
    )


def found_fields(hits: list[dict[str, Any]]) -> tuple[str, ...]:
    """``kind field: largest difference unit`` per (kind, field) of the logged divergences."""
    largest: dict[tuple[str, str], tuple[float, str]] = {}
    for r in hits:
        key = (str(r.get("kind")), str(r.get("field")))
        diff = float(r.get("difference") or 0.0)
        if key not in largest or diff > largest[key][0]:
            largest[key] = (diff, str(r.get("unit") or ""))
    return tuple(f"{k} {f}: {d:.2g} {u}".rstrip() for (k, f), (d, u) in sorted(largest.items()))


def summarize(runs: list[Run], engines: tuple[str, ...], bugs: tuple[str, ...]) -> dict[str, Any]:
    cells: dict[str, dict[str, Any]] = {}
    for bug in bugs:
        for engine in engines:
            mine = [r for r in runs if r.bug == bug and r.engine == engine]
            if not mine:
                continue
            times = sorted(r.detected_at if r.detected_at is not None else float("inf") for r in mine)
            median = statistics.median(times)
            cells[f"{bug}/{engine}"] = {
                "detected": sum(r.detected_at is not None for r in mine),
                "runs": len(mine),
                "median_ttd": None if median == float("inf") else median,
                "median_signatures": statistics.median(r.signatures for r in mine),
                "median_exec_per_s": statistics.median(r.executions / r.elapsed for r in mine),
                "divergences": sum(r.divergences for r in mine),
                "minutes": sum(r.elapsed for r in mine) / 60.0,
            }
    return cells


def _fmt_ttd(cell: dict[str, Any], budget: float) -> str:
    ttd = "-" if cell["median_ttd"] is None else f"{cell['median_ttd']:.1f}"
    if cell["median_ttd"] is None and cell["detected"]:
        ttd = f">{budget:.0f}"
    return f"{ttd} ({cell['detected']}/{cell['runs']})"


MARGIN, MARGIN_S = 0.10, 0.25


def compare_times(mine: float, other: float) -> str:
    """'faster', 'slower' or 'tie' (not found by either, or within the margins)."""
    if mine == other:
        return "tie"
    if other == float("inf"):
        return "faster"
    if mine == float("inf"):
        return "slower"
    if abs(mine - other) <= max(MARGIN * min(mine, other), MARGIN_S):
        return "tie"
    return "faster" if mine < other else "slower"


def _is_config_control(name: str) -> bool:
    return name.startswith("control@")


def buckets_per_bug(result: dict[str, Any], engine: str = "full") -> dict[str, float]:
    """Median unique signatures (buckets) per zoo bug that the engine detected."""
    out = {}
    for bug in result["bugs"]:
        cell = result["cells"].get(f"{bug}/{engine}")
        if cell and not BY_NAME[bug].is_control and cell["detected"]:
            out[bug] = cell["median_signatures"]
    return out


def controls_markdown(result: dict[str, Any]) -> list[str]:
    """The false-positive table: every control run of the full engine."""
    runs = [r for r in result["runs"] if BY_NAME[r["bug"]].is_control and r["engine"] == "full"]
    if not runs:
        return []
    lines = [
        "False positives: the unmodified twin against native (full engine). A control run that reports "
        "any divergence counting as a detection is a false positive.",
        "",
        "| control configuration | op | runs reporting a divergence | divergences per minute |",
        "|---|---|---|---|",
    ]
    for bug in result["bugs"]:
        mine = [r for r in runs if r["bug"] == bug]
        if not mine:
            continue
        minutes = sum(r["elapsed"] for r in mine) / 60.0
        found = sum(r.get("divergences", 0) for r in mine)
        reporting = sum(1 for r in mine if r.get("divergences", 0) or r["detected_at"] is not None)
        rate = found / minutes if minutes else 0.0
        lines.append(f"| {bug} | {BY_NAME[bug].op} | {reporting}/{len(mine)} | {rate:.1f} |")
    minutes = sum(r["elapsed"] for r in runs) / 60.0
    reporting = sum(1 for r in runs if r.get("divergences", 0) or r["detected_at"] is not None)
    total = sum(r.get("divergences", 0) for r in runs)
    lines += [
        "",
        f"False-positive rate: {reporting} of {len(runs)} control runs reported a divergence; "
        f"{total} divergences in {minutes:.1f} min ({total / minutes if minutes else 0.0:.1f} per minute).",
    ]
    return lines


def summarize_ops(runs: list[Run], bugs: tuple[str, ...], ops: tuple[str, ...]) -> dict[str, Any]:
    """Per ``bug/op``: the cells of :func:`summarize` (one engine), keyed by the op run."""
    cells = {}
    for op in ops:
        mine = [replace(r, engine=op) for r in runs if r.op == op]
        for key, cell in summarize(mine, (op,), bugs).items():
            cells[key] = cell
    return cells


def _largest_by_field(runs: Iterable[dict[str, Any]]) -> list[str]:
    """``--op OP kind field: largest difference unit`` over the runs' ``fields``, one per field."""
    largest: dict[tuple[str, str], tuple[float, str]] = {}
    for run in runs:
        for entry in run.get("fields", ()):
            name, _, rest = entry.partition(": ")
            number, _, unit = rest.partition(" ")
            key = (str(run["op"]), name)
            if key not in largest or float(number) > largest[key][0]:
                largest[key] = (float(number), unit)
    return [f"`--op {op}` {name}: {d:.2g} {u}".rstrip() for (op, name), (d, u) in sorted(largest.items())]


def ops_markdown(result: dict[str, Any]) -> str:
    """The table of ``--mode ops``: which op detects each stateful bug."""
    ops, budget, cells = result["ops"], result["budget"], result["cells"]
    lines = [
        "Each stateful zoo bug (`benchmarks/zoo/stateful.py`: it needs a second call on a live group, or "
        "shows only in a trajectory) against native, full engine, under each op: "
        f"{result['seeds']} seed(s) x {budget:.0f} s per (bug, op), "
        f"{result['jobs']} runs at a time on {result['cpus']} CPUs. "
        f"Command: `{result['command']}`.",
        "",
        "Median time to first detection in seconds from launch (runs that detected it); `-`: not detected. "
        "Expected: `--op move` (one call on a fresh group) misses every one, `--op scenario` finds them; "
        "the `control@` rows (the unmodified twin) give the false positives of the same campaigns.",
        "",
        "| bug | robot | " + " | ".join(f"`--op {op}`" for op in ops) + " | median buckets (scenario) "
        "| what was found (all runs; kind field: largest difference) |",
        "|---|---|" + "---|" * len(ops) + "---|---|",
    ]
    for bug in result["bugs"]:
        row = [cells.get(f"{bug}/{op}") for op in ops]
        scenario = cells.get(f"{bug}/scenario")
        buckets = f"{scenario['median_signatures']:g}" if scenario and scenario["detected"] else "-"
        cols = " | ".join(_fmt_ttd(c, budget) if c else "" for c in row)
        what = _largest_by_field(r for r in result["runs"] if r["bug"] == bug)
        lines.append(
            f"| {bug} | {Path(BY_NAME[bug].robot).stem} | {cols} | {buckets} | {'; '.join(what) or '-'} |"
        )
    lines.append("")
    bugs = [b for b in result["bugs"] if not BY_NAME[b].is_control]
    for op in ops:
        hit = sum(1 for b in bugs if (cells.get(f"{b}/{op}") or {}).get("detected"))
        lines.append(f"- `--op {op}`: {hit} of {len(bugs)} stateful bugs detected in at least one run.")
    if result.get("load"):
        lines.append(
            f"\nLoad average (1, 5, 15 min) before / after the sweep: {result['load']} "
            f"on {result['cpus']} CPUs "
            "(above the CPU count, other work shared the machine: times to detection are longer than idle)."
        )
    return "\n".join(lines)


def markdown(result: dict[str, Any]) -> str:
    if result.get("ops"):
        return ops_markdown(result)
    engines, budget = result["engines"], result["budget"]
    bugs = [b for b in result["bugs"] if not _is_config_control(b)]
    cells = result["cells"]
    lines = [
        f"Mode `{result['mode']}`: {len(bugs)} bugs x {len(engines)} engines x {result['seeds']} seed(s), "
        f"{budget:.0f} s each, {result['jobs']} runs at a time on {result['cpus']} CPUs "
        f"({result['machine']}). Command: `{result['command']}`.",
    ]
    configs = len(result["bugs"]) - len(bugs)
    if not bugs:
        return "\n".join(
            [lines[0].replace("0 bugs", f"{configs} control configurations"), "", *controls_markdown(result)]
        )
    lines += [
        "",
        "Median time to first detection in seconds from launch (startup included), and runs that detected it "
        "(`-`: not detected within the budget by at least half the runs).",
        "",
        "| bug | op | " + " | ".join(engines) + " |",
        "|---|---|" + "---|" * len(engines),
    ]
    verdicts = {e: {"faster": 0, "tie": 0, "slower": 0} for e in engines if e != "full"}
    comparable = 0
    for bug in bugs:
        row = [cells.get(f"{bug}/{e}") for e in engines]
        op = BY_NAME[bug].op
        lines.append(f"| {bug} | {op} | " + " | ".join(_fmt_ttd(c, budget) if c else "" for c in row) + " |")
        full = cells.get(f"{bug}/full")
        if BY_NAME[bug].is_control or not full:
            continue
        comparable += 1
        full_t = full["median_ttd"] if full["median_ttd"] is not None else float("inf")
        for e, tally in verdicts.items():
            other = cells.get(f"{bug}/{e}")
            other_t = other["median_ttd"] if other and other["median_ttd"] is not None else float("inf")
            tally[compare_times(full_t, other_t)] += 1
    lines += [
        "",
        f"The full engine against each baseline over the {comparable} bugs (faster / tie / slower; "
        f"a difference counts when it is over {MARGIN:.0%} and over {MARGIN_S} s):",
        "",
    ]
    lines += [
        f"- vs {e}: {t['faster']} faster, {t['tie']} tie, {t['slower']} slower" for e, t in verdicts.items()
    ]
    lines.append("")
    lines += [
        "Median unique signatures found within the budget:",
        "",
        "| bug | " + " | ".join(engines) + " |",
        "|---|" + "---|" * len(engines),
    ]
    for bug in bugs:
        row = [cells.get(f"{bug}/{e}") for e in engines]
        lines.append(
            f"| {bug} | " + " | ".join(f"{c['median_signatures']:g}" if c else "" for c in row) + " |"
        )
    lines += [
        "",
        "Throughput (median exec/s over every run of that op):",
        "",
        "| op | " + " | ".join(engines) + " |",
        "|---|" + "---|" * len(engines),
    ]
    for op in ("fk", "move", "ik", "scenario"):
        values = []
        for e in engines:
            rates = [
                c["median_exec_per_s"]
                for k, c in cells.items()
                if k.endswith(f"/{e}") and BY_NAME[k.rsplit("/", 1)[0]].op == op
            ]
            values.append(f"{statistics.median(rates):,.0f}" if rates else "")
        lines.append(f"| {op} | " + " | ".join(values) + " |")
    per_bug = buckets_per_bug(result)
    if per_bug:
        counts = list(per_bug.values())
        worst = max(per_bug, key=lambda b: per_bug[b])
        lines += [
            "",
            f"One bug, one bucket: buckets (unique signatures) per detected zoo bug, full engine: "
            f"median {statistics.median(counts):g}, max {max(counts):g} ({worst}) over {len(counts)} bugs "
            "(goal: median 1, at most 3).",
        ]
    replayed = [r for r in result["runs"] if r.get("replayed")]
    if replayed:
        files = sum(r["replayed"] for r in replayed)
        same = sum(r["replay_same"] for r in replayed)
        lines += [
            "",
            f"Replay fidelity: {same} of {files} crash files ({same / files:.0%}) replayed in a new process "
            "with the same signature.",
        ]
        lines += [f"- not replayed, {r['bug']}: {m}" for r in replayed for m in r["replay_misses"]]
    control_lines = controls_markdown(result)
    if control_lines:
        lines += ["", *control_lines]
    return "\n".join(lines)


def plot(result: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    engines, bugs, budget, cells = result["engines"], result["bugs"], result["budget"], result["cells"]
    bugs = [b for b in bugs if not BY_NAME[b].is_control]
    if not bugs or result.get("ops"):
        return
    fig = Figure(figsize=(10, 0.45 * len(bugs) + 1.8))
    ax = fig.add_subplot()
    height = 0.8 / len(engines)
    for i, engine in enumerate(engines):
        ys, xs = [], []
        for j, bug in enumerate(bugs):
            c = cells.get(f"{bug}/{engine}")
            ttd = c["median_ttd"] if c and c["median_ttd"] is not None else budget * 1.5
            ys.append(j + i * height)
            xs.append(ttd)
        ax.barh(ys, xs, height=height, label=engine)
    ax.axvline(budget, color="black", linestyle="--", linewidth=1)
    ax.set_yticks([j + 0.4 - height / 2 for j in range(len(bugs))], bugs)
    ax.set_xscale("log")
    ax.set_xlabel(
        f"median time to first detection (s, log); bars past the dashed line: not found in {budget:.0f} s"
    )
    ax.invert_yaxis()
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


SECTIONS = {
    "controls": "## False positives (controls, short sweep)",
    "buckets": "## One bug, one bucket, and replay fidelity (short sweep)",
    "ops": "## Which ops detect the stateful bugs",
}


def write_markdown(text: str, path: Path = ROOT / "BENCHMARKS.md", mode: str = "full") -> None:
    """Replace this mode's marked section of BENCHMARKS.md (``full``: the main one; the
    short ``controls`` and ``buckets`` sweeps have sections of their own)."""
    begin, end = MARK_BEGIN, MARK_END
    if mode in SECTIONS:
        begin, end = f"<!-- bench_zoo_{mode}:begin -->", f"<!-- bench_zoo_{mode}:end -->"
    replace_section(text, (begin, end), SECTIONS.get(mode, "## Bug-finding power (the bug zoo)"), path)


def replace_section(
    text: str, marks: tuple[str, str], title: str, path: Path = ROOT / "BENCHMARKS.md"
) -> None:
    """Put ``text`` between the ``marks`` comments of ``path``; append it under ``title`` if absent."""
    begin, end = marks
    content = path.read_text(encoding="utf-8")
    block = f"{begin}\n{text}\n{end}"
    if begin in content:
        head, rest = content.split(begin, 1)
        content = head + block + rest.split(end, 1)[1]
    else:
        content = content.rstrip() + f"\n\n{title}\n\n" + block + "\n"
    path.write_text(content, encoding="utf-8")


def plan_jobs(
    bugs: tuple[str, ...], engines: tuple[str, ...], seeds: int, ops: tuple[str, ...] = ()
) -> list[tuple[Bug, str, int]]:
    """The runs of a sweep, as (bug, engine, seed): each bug under its own op, or under each
    of ``ops``; controls only with CONTROL_ENGINES; scenario runs only with SCENARIO_ENGINES."""
    return [
        (bug, e, s)
        for b in bugs
        for bug in ([replace(BY_NAME[b], op=op) for op in ops] if ops else [BY_NAME[b]])
        for e in engines
        if (not _is_config_control(b) or e in CONTROL_ENGINES)
        and (bug.op != "scenario" or e in SCENARIO_ENGINES)
        for s in range(1, seeds + 1)
    ]


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
    parser.add_argument("--budget", type=float, default=None)
    parser.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2: one per core)")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--write-md", action="store_true", help="update BENCHMARKS.md")
    parser.add_argument(
        "--render", type=Path, default=None, help="only render a saved result (JSON) as markdown, run nothing"
    )
    parser.add_argument(
        "--replay", action="store_true", help="replay each full-engine run's crash files in a new process"
    )
    parser.add_argument(
        "--keep-failures",
        type=Path,
        default=None,
        help="where a control run that reports a divergence leaves its artifacts "
        "(default: control-failures/ next to --out)",
    )
    args = parser.parse_args(argv)
    if args.render is not None:
        saved: dict[str, Any] = json.loads(args.render.read_text(encoding="utf-8"))
        text = markdown(saved)
        print(text)
        if args.write_md:
            write_markdown(text, mode=str(saved.get("mode", "full")))
        return saved
    mode = MODES[args.mode]
    bugs = tuple(args.bugs or mode.bugs)
    unknown = [b for b in bugs if b not in BY_NAME]
    if unknown:
        parser.error(f"unknown bugs: {unknown}")
    seeds = args.seeds or mode.seeds
    budget = args.budget or mode.budget
    engines = tuple(args.engines or mode.engines)
    replay = args.replay or mode.replay
    jobs = plan_jobs(bugs, engines, seeds, mode.ops)
    out = args.out or RESULTS / f"zoo-{args.mode}.json"
    keep = args.keep_failures or out.parent / "control-failures"
    load_before = _load()
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        runs = list(
            pool.map(lambda job: run_one(job[0], job[1], job[2], budget, replay, keep_failures=keep), jobs)
        )
    result = {
        "mode": args.mode,
        "bugs": list(bugs),
        "engines": list(engines),
        "seeds": seeds,
        "budget": budget,
        "jobs": args.jobs,
        "cpus": os.cpu_count(),
        "machine": platform.machine(),
        "command": "python -m benchmarks.bench_zoo " + " ".join(argv if argv is not None else sys.argv[1:]),
        "runs": [asdict(r) for r in runs],
        "cells": summarize_ops(runs, bugs, mode.ops) if mode.ops else summarize(runs, engines, bugs),
        "ops": list(mode.ops),
        "load": f"{load_before} / {_load()}",
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1), encoding="utf-8")
    plot(result, out.with_suffix(".png"))
    text = markdown(result)
    print(text)
    if args.write_md:
        write_markdown(text, mode=args.mode)
    return result


if __name__ == "__main__":
    main()
