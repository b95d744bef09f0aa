"""Where a campaign's time goes: a py-spy profile of ``fuzz_diff.py``, tabulated by part.

    taskset -c 1 .venv/bin/python -m benchmarks.profile --op fk --seconds 30 --seed 1
    .venv/bin/python -m benchmarks.profile --from /tmp/profile-fk.txt   # tabulate a saved one

Runs one campaign (default targets native vs python, default robot, a fresh corpus, as
``benchmarks.bench_engine`` does) under ``py-spy record --format raw`` at ``--rate`` samples a
second, keeps the raw stacks (``--out``, default ``build/profiles/``), and prints the share of
samples per part of the engine as a Markdown table: the table of BENCHMARKS.md's "Where the
time goes today".

A sample counts in the first part found walking its stack from the leaf up (:data:`PARTS`, by
file): numpy and standard library frames count for the repository code that called them,
except the ``json`` module's, which count as encoding. Every sample with the harness's batched
sweep (``Harness.run_sweep``) on its stack counts as "batched sweeps", whatever its leaf.
Samples with no repository frame at all (libFuzzer's loop, Atheris, start-up imports) count as
"libFuzzer, Atheris and the rest". py-spy sees Python frames only: time inside the native
module counts for the Python frame that called it (the ``native`` package's facade).

py-spy comes with ``make setup`` (the ``test`` extra); it needs the right to trace a child
process (ptrace), which a container may have to be granted (``--cap-add SYS_PTRACE``).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from collections.abc import Iterable
from pathlib import Path

from benchmarks import cli
from benchmarks.bench_engine import ROOT, campaign_command

SWEEPS = "batched sweeps"
REST = "libFuzzer, Atheris and the rest"
PARTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("twin target (python_impl)", ("python_impl/",)),
    ("native target", ("native/",)),
    ("JSON encode/decode", ("json/", "fuzzer/input/testcase.py")),
    (
        "float-comparison tracing",
        ("fuzzer/selection/floatcmp.py", "fuzzer/selection/compared.py", "fuzzer/selection/cmp_gap.py"),
    ),
    ("feature bookkeeping", ("fuzzer/selection/guidance.py",)),
    (
        "evaluation and oracle",
        (
            "fuzzer/execution/",
            "fuzzer/scenario/oracle",
            "fuzzer/scenario/nudge.py",
            "fuzzer/scenario/ik_rerun.py",
        ),
    ),
    (
        "mutator, crossover, bandits",
        (
            "fuzzer/mutation/",
            "fuzzer/scenario/mutate.py",
            "fuzzer/scenario/dispatch.py",
            "fuzzer/scenario/fresh.py",
            "fuzzer/selection/",
            "fuzzer/generation/",
        ),
    ),
)
"""Parts in the order a frame is tested against them, each with the path fragments of its files
(matched after a ``/``, or at the start of a relative path): the first part a frame matches is
its part. "Evaluation and oracle" is ``fuzzer/execution/`` (the evaluator, the targets' glue,
the oracle and its records) and the scenario oracle."""
ORDER = (SWEEPS, *(name for name, _ in PARTS), REST)
FRAME = re.compile(r"^(?P<function>.*) \((?P<path>[^()]*?)(?::\d+)?\)$")


class ProfileError(ValueError):
    """A raw profile that cannot be read (names the line)."""


def part_of_frame(frame: str) -> str | None:
    """The part of one py-spy frame (``function (path:line)``), or None for a frame of no part."""
    match = FRAME.match(frame)
    if match is None:
        return None
    path = "/" + match["path"].replace("\\", "/").lstrip("/")
    for name, fragments in PARTS:
        if any("/" + fragment in path for fragment in fragments):
            return name
    return None


def part_of_stack(frames: list[str]) -> str:
    """The part a sample counts in (its frames root first, as py-spy writes them)."""
    if any(f.startswith("run_sweep (") and "fuzzer/harness.py" in f for f in frames):
        return SWEEPS
    for frame in reversed(frames):
        part = part_of_frame(frame)
        if part is not None:
            return part
    return REST


def tabulate(lines: Iterable[str]) -> Counter[str]:
    """Samples per part of a py-spy raw profile (lines ``frame;frame;... count``)."""
    counts: Counter[str] = Counter()
    for number, line in enumerate(lines, 1):
        line = line.rstrip("\n")
        if not line.strip():
            continue
        stack, space, count = line.rpartition(" ")
        if not space or not count.isdigit():
            raise ProfileError(f"line {number}: not 'frame;frame;... count': {line[:80]!r}")
        # an empty stack (' 1'): py-spy caught the process with no Python frame on it
        counts[part_of_stack(stack.split(";") if stack else [])] += int(count)
    return counts


def markdown(counts: Counter[str], title: str) -> str:
    """A two-column table: each part's share of the samples (%), in :data:`ORDER`."""
    total = sum(counts.values())
    if total == 0:
        raise ProfileError("the profile holds no samples")
    rows = [f"| part (% of {total:,} samples) | {title} |", "|---|---:|"]
    rows += [f"| {name} | {100 * counts[name] / total:.1f} |" for name in ORDER if name in counts]
    return "\n".join(rows)


def find_py_spy() -> str | None:
    """The py-spy executable beside this Python, else on PATH; None when there is none."""
    beside = Path(sys.executable).parent / "py-spy"
    return str(beside) if beside.is_file() else shutil.which("py-spy")


def py_spy() -> str:
    """:func:`find_py_spy`, or exit naming how to install it."""
    found = find_py_spy()
    if found is None:
        raise SystemExit("profile: py-spy is not installed: `make setup` installs it (the test extra)")
    return found


def record(op: str, seconds: float, seed: int, rate: int, out: Path) -> None:
    """Profile one ``--op op`` campaign of ``seconds`` with ``-seed=seed`` into ``out`` (raw; an
    older file there is removed first, so a failed run never leaves it to be read as this one)."""
    out.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        campaign = campaign_command(tmp, [f"--op={op}", f"-max_total_time={seconds:g}", f"-seed={seed}"])
        cmd = [
            py_spy(),
            "record",
            "--rate",
            str(rate),
            "--format",
            "raw",
            "--output",
            str(out),
            "--",
            *campaign,
        ]
        done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
    if not out.is_file() or out.stat().st_size == 0:
        raise SystemExit(f"profile: py-spy wrote no profile (exit {done.returncode}):\n{done.stderr[-2000:]}")
    if done.returncode not in (0, 1):  # the campaign's own statuses; anything else is no campaign
        out.unlink(missing_ok=True)
        raise SystemExit(f"profile: the campaign failed (exit {done.returncode}):\n{done.stderr[-2000:]}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--op", default="fk", choices=("fk", "move", "ik", "scenario"))
    parser.add_argument("--seconds", type=float, default=30.0, help="campaign length (s)")
    parser.add_argument("--seed", type=int, default=1, help="the campaign's -seed")
    parser.add_argument("--rate", type=int, default=200, help="samples a second")
    parser.add_argument(
        "--out",
        type=Path,
        help="where the raw profile goes: a file, or a folder for the default name (default build/profiles/)",
    )
    parser.add_argument("--from", dest="source", type=Path, help="tabulate this raw profile instead")
    args = parser.parse_args(argv)
    cli.check_sizes(parser, rate=args.rate)
    cli.check_campaign_seconds(parser, seconds=args.seconds)
    if not 1 <= args.seed <= 2**32 - 1:  # libFuzzer's -seed=0 is the clock's: no profile repeats
        parser.error(f"--seed must be from 1 to {2**32 - 1}, not {args.seed}")
    if args.source is not None:
        path, title = args.source, args.source.name
    else:
        name = f"profile-{args.op}-seed{args.seed}.txt"
        path = args.out or ROOT / "build" / "profiles" / name
        if path.is_dir():
            path = path / name
        cli.check_out_file(parser, path)
        title = f"{args.op}, {args.seconds:g} s, seed {args.seed}"
        record(args.op, args.seconds, args.seed, args.rate, path)
        print(f"raw profile: {path}", file=sys.stderr)
    try:
        with path.open(encoding="utf-8", errors="replace") as lines:
            print(markdown(tabulate(lines), title))
    except OSError as err:
        raise SystemExit(f"profile: cannot read {path}: {err.strerror}") from None
    except ProfileError as err:
        raise SystemExit(f"profile: {path}: {err}") from None


if __name__ == "__main__":
    main()
