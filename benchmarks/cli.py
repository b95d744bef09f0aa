"""Checks that the benchmarks' command lines share: a bad option is the parser's error, named,
before anything runs (never a traceback, never a sweep of hours that ends on an unwritable
folder)."""

from __future__ import annotations

import argparse
import math
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
