"""Checks that the benchmarks' command lines share: a bad option is the parser's error, named,
before anything runs (never a traceback, never a sweep of hours that ends on an unwritable
folder)."""

from __future__ import annotations

import argparse
import math
from collections import Counter
from pathlib import Path


def check_sizes(parser: argparse.ArgumentParser, **given: float | None) -> None:
    """The parser's error for a count or a budget (``given``: option name with ``_`` for ``-``,
    value or ``None`` when not given) that is not a finite number above 0."""
    for name, value in given.items():
        if value is not None and not (value > 0 and math.isfinite(value)):
            parser.error(f"--{name.replace('_', '-')} must be a finite number above 0, not {value}")


def check_folder(parser: argparse.ArgumentParser, folder: Path) -> None:
    """The parser's error when ``folder`` (where results go) cannot be made, before any trial runs."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parser.error(f"{folder}: cannot hold the results ({exc.strerror or exc})")


MAX_SECONDS = 2**31 - 1
"""The longest campaign libFuzzer's ``-max_total_time`` (a C int) can hold."""

MAX_TRIALS = 10_000
"""The most trials per (bug, engine) a journal takes (``benchmarks.journal``)."""

MAX_SEED = 2**31
"""The largest seed a journal takes (``benchmarks.journal``; libFuzzer's ``-seed`` goes to 2**32 - 1)."""


def check_trials(parser: argparse.ArgumentParser, trials: int, first_seed: int, name: str = "trials") -> None:
    """The parser's error for more trials than a journal takes, or seeds past its largest: the
    sweep would otherwise plan them all (99,999,999 trials: a MemoryError) or write a journal its
    own ``--render`` then refuses."""
    if trials > MAX_TRIALS:
        parser.error(f"--{name} must be at most {MAX_TRIALS}, not {trials}")
    last = first_seed + trials - 1
    if last > MAX_SEED:
        parser.error(f"--first-seed and --{name} reach seed {last}, past {MAX_SEED}")


def check_campaign_seconds(parser: argparse.ArgumentParser, **given: float | None) -> None:
    """The parser's error for a campaign's length (given as in :func:`check_sizes`) that libFuzzer
    cannot keep: ``-max_total_time`` counts whole seconds, and 0 means no limit at all, so 0.5 s
    would run a campaign until its trial's timeout and 2.5 s would give the full engine 2 s and the
    baselines 2.5."""
    check_sizes(parser, **given)
    for name, value in given.items():
        if value is not None and value > MAX_SECONDS:  # 1e308 passed, and a baseline ran for good
            parser.error(
                f"--{name.replace('_', '-')} must be at most {MAX_SECONDS} s (libFuzzer's "
                f"-max_total_time is an int), not {value}"
            )
        if value is not None and value != int(value):
            parser.error(
                f"--{name.replace('_', '-')} must be a whole number of seconds (libFuzzer's "
                f"-max_total_time), not {value}"
            )


def check_unique(parser: argparse.ArgumentParser, **given: list[str] | tuple[str, ...] | None) -> None:
    """The parser's error for a name given twice in a list option (``--bugs a a``): a sweep keys its
    trials by name, so a duplicate would be planned twice and run once."""
    for name, values in given.items():
        repeated = sorted(v for v, n in Counter(values or ()).items() if n > 1)
        if repeated:
            parser.error(f"--{name.replace('_', '-')} names {', '.join(repeated)} more than once")


def check_out_file(parser: argparse.ArgumentParser, path: Path) -> None:
    """The parser's error when the results file ``path`` cannot be written (a folder, or a folder
    that cannot be made), before the measurement instead of after it."""
    if path.is_dir():
        parser.error(f"{path} is a folder: name the results file")
    check_folder(parser, path.parent)
