"""A campaign's memory over time: RSS sampled from ``/proc`` while one or two trees fuzz at once.

    .venv/bin/python -m benchmarks.bench_memory --arm before /tmp/base --arm after . \\
        --op scenario --seconds 600 --seed 1 --out benchmarks/results/memory-scenario.jsonl
    .venv/bin/python -m benchmarks.bench_memory --from-json benchmarks/results/memory-scenario.jsonl

Each arm (``--arm NAME DIR``: the tree at ``DIR`` run by its own ``DIR/.venv/bin/python``, as in
``benchmarks.bench_ab``) runs ``fuzz_diff.py --op OP`` from a new corpus for ``--seconds`` with
``-seed``, pinned to a CPU of its own (arm i on CPU i of the ones this process may use), both
at once: whatever the machine does, it does to both. Every ``--every`` seconds the campaign
process's ``VmRSS`` and ``VmHWM`` (its peak) are read from ``/proc/PID/status`` (Linux).

The table gives, per arm, RSS at 60, 120 and 240 s and at the end, the peak, and the growth
after 240 s (the least-squares slope of RSS against time, ``scipy.stats.linregress``; the first
minutes fill the engine's bounded caches), with the campaign's executions. The samples go to
``--out`` as JSON lines (a header naming the arms and their commits, then one line per sample,
then each arm's end), which ``--from-json`` tabulates again. Linux only (``/proc``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import tempfile
import time
from functools import partial
from pathlib import Path
from typing import Any

from benchmarks import cli, journal

FORMAT = "rrosfuzz-bench-memory"
OPS = ("fk", "ik", "move", "scenario")
MARKS = (60, 120, 240)
"""Seconds at which the table gives RSS; growth is fitted after the last."""
_EXECUTIONS = re.compile(r"executions: (\d+) in")


def _status(pid: int) -> tuple[int, int] | None:
    """(VmRSS, VmHWM) of ``pid`` in KiB, or None once it has ended."""
    try:
        text = Path(f"/proc/{pid}/status").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    fields = dict(line.split(":", 1) for line in text.splitlines() if ":" in line)
    try:
        return int(fields["VmRSS"].split()[0]), int(fields["VmHWM"].split()[0])
    except (KeyError, ValueError, IndexError):
        return None  # a zombie has no VmRSS


def run(arms: list[dict[str, str]], args: argparse.Namespace, out: Path) -> list[dict[str, Any]]:
    """Run every arm's campaign at once, each on its own CPU; append samples to ``out``."""
    cpus = sorted(os.sched_getaffinity(0))
    work = Path(tempfile.mkdtemp(prefix="bench-memory-"))
    procs = []
    try:
        for i, arm in enumerate(arms):
            folder = work / arm["name"]
            cmd = [
                str(Path(arm["root"]) / ".venv" / "bin" / "python"),
                str(Path(arm["root"]) / "fuzz_diff.py"),
                f"--op={args.op}",
                str(folder / "corpus"),
                f"-max_total_time={args.seconds}",
                f"-seed={args.seed}",
                f"--artifacts={folder / 'artifacts'}",
                "--no-progress",
            ]
            cpu = {cpus[i % len(cpus)]}
            log = (work / f"{arm['name']}.log").open("wb")
            procs.append(
                subprocess.Popen(
                    cmd,
                    cwd=arm["root"],
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    preexec_fn=partial(os.sched_setaffinity, 0, cpu),
                )
            )
            log.close()
        start = time.monotonic()
        rows: list[dict[str, Any]] = []
        with out.open("a", encoding="utf-8") as sink:
            while any(p.poll() is None for p in procs):
                t = round(time.monotonic() - start)
                for arm, proc in zip(arms, procs, strict=True):
                    got = _status(proc.pid) if proc.poll() is None else None
                    if got is not None:
                        row = {"arm": arm["name"], "t": t, "rss_kb": got[0], "hwm_kb": got[1]}
                        rows.append(row)
                        sink.write(json.dumps(row) + "\n")
                sink.flush()
                time.sleep(args.every)
            for arm, proc in zip(arms, procs, strict=True):
                text = (work / f"{arm['name']}.log").read_text(encoding="utf-8", errors="replace")
                found = _EXECUTIONS.findall(text)
                end = {
                    "arm": arm["name"],
                    "returncode": proc.returncode,
                    "executions": int(found[-1]) if found else None,
                }
                rows.append(end)
                sink.write(json.dumps(end) + "\n")
        return rows
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        shutil.rmtree(work, ignore_errors=True)


def _nearest(samples: list[dict[str, Any]], t: float) -> dict[str, Any]:
    return min(samples, key=lambda r: abs(r["t"] - t))


def table(header: dict[str, Any], rows: list[dict[str, Any]]) -> str:
    """The Markdown table of ``rows`` (samples and ends) under ``header``'s arms."""
    from scipy.stats import linregress

    lines = [
        f"{header['op']}, {header['seconds']} s, -seed={header['seed']}, {header['machine']}",
        "",
        "| arm (commit) | RSS at " + " / ".join(map(str, MARKS)) + " / end (MB) | peak (MB) "
        f"| growth after {MARKS[-1]} s (MB/min) | executions |",
        "|---|---|---|---|---|",
    ]
    for arm in header["arms"]:
        samples = [r for r in rows if r.get("arm") == arm["name"] and "t" in r]
        ends = [r for r in rows if r.get("arm") == arm["name"] and "executions" in r]
        if not samples:
            continue
        at = [_nearest(samples, mark)["rss_kb"] / 1024 for mark in MARKS]
        late = [r for r in samples if r["t"] >= MARKS[-1]]
        slope = "-"
        if len(late) >= 3:
            fit = linregress([r["t"] for r in late], [r["rss_kb"] / 1024 for r in late])
            slope = f"{fit.slope * 60:.2f}"
        marks = " / ".join(f"{v:.0f}" for v in (*at, samples[-1]["rss_kb"] / 1024))
        peak = max(r["hwm_kb"] for r in samples) / 1024
        executions = ends[-1]["executions"] if ends else "-"
        lines.append(
            f"| {arm['name']} ({arm['commit'][:7]}) | {marks} | {peak:.0f} | {slope} | {executions} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> str:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--arm", nargs=2, action="append", metavar=("NAME", "DIR"), help="an arm (once or twice)"
    )
    parser.add_argument("--op", choices=OPS, default="scenario", help="the campaigns' op (%(default)s)")
    parser.add_argument("--seconds", type=int, default=600, help="each campaign's length (%(default)s)")
    parser.add_argument("--seed", type=int, default=1, help="-seed of both campaigns (%(default)s)")
    parser.add_argument("--every", type=float, default=10.0, help="seconds between samples (%(default)s)")
    parser.add_argument("--out", type=Path, help="the samples' file (JSON lines; a new file)")
    parser.add_argument("--from-json", type=Path, metavar="FILE", help="tabulate a file instead of running")
    args = parser.parse_args(argv)
    if args.from_json is not None:
        try:
            lines = [json.loads(line) for line in args.from_json.read_text(encoding="utf-8").splitlines()]
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            parser.error(f"--from-json {args.from_json}: not a file of this benchmark ({exc})")
        if not lines or not isinstance(lines[0], dict) or lines[0].get("format") != FORMAT:
            parser.error(f"--from-json {args.from_json}: no {FORMAT} header")
        text = table(lines[0], [r for r in lines[1:] if isinstance(r, dict)])
        print(text)
        return text
    cli.check_sizes(parser, seconds=args.seconds, every=args.every)
    if args.seconds > cli.MAX_SECONDS:
        parser.error(f"--seconds must be at most {cli.MAX_SECONDS}, not {args.seconds}")
    if not 1 <= args.seed < cli.MAX_SEED:
        parser.error(f"--seed must be from 1 to {cli.MAX_SEED - 1}, not {args.seed}")
    if not args.arm or len(args.arm) > 2 or args.out is None:
        parser.error("one or two --arm NAME DIR and --out FILE are needed (or --from-json FILE)")
    if not Path("/proc/self/status").is_file():
        parser.error("this benchmark reads /proc (Linux)")
    arms = []
    for name, folder in args.arm:
        root = Path(folder).resolve()
        if not (root / "fuzz_diff.py").is_file() or not (root / ".venv" / "bin" / "python").is_file():
            parser.error(
                f"--arm {name}: {folder} is not an RROSFuzz tree with its .venv (run `make setup` there)"
            )
        arms.append({"name": name, "root": str(root), "commit": journal.commit_of(root)})
    if len({a["name"] for a in arms}) != len(arms):
        parser.error("the arms need different names")
    if args.out.exists():
        parser.error(f"--out {args.out} exists: name a new file")
    cli.check_folder(parser, args.out.parent)
    header = {
        "format": FORMAT,
        "arms": arms,
        "op": args.op,
        "seconds": args.seconds,
        "seed": args.seed,
        "machine": journal.machine_of(),
    }
    args.out.write_text(json.dumps(header) + "\n", encoding="utf-8")
    text = table(header, run(arms, args, args.out))
    print(text)
    return text


if __name__ == "__main__":
    main()
