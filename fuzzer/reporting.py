"""Everything the engine shows a person: progress, warnings, summaries, verdicts.

The only module that writes to the terminal. Progress goes to stderr (next to
libFuzzer's own status lines): a tqdm bar on a terminal, a plain line every few
seconds otherwise.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from fuzzer.harness import Stats

PREFIX = "[rrosfuzz]"


def info(text: str, stream: TextIO | None = None) -> None:
    (stream or sys.stderr).write(f"{PREFIX} {text}\n")
    (stream or sys.stderr).flush()


def warn(text: str) -> None:
    sys.stderr.write(f"{PREFIX} warning: {text}\n")
    sys.stderr.flush()


def out(text: str = "") -> None:
    """Primary output (verdicts, tables): stdout."""
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def status_line(stats: Stats, features: int) -> str:
    rate = stats.execs / stats.elapsed if stats.elapsed > 0 else 0.0
    kinds = ", ".join(f"{k} {n}" for k, n in sorted(stats.divergent.items())) or "none"
    return (
        f"execs {stats.execs} ({rate:,.0f}/s) | divergences {stats.divergences} ({kinds}) | "
        f"signatures {len(stats.signatures)} | features {features} | filtered {stats.filtered} "
        f"| malformed {stats.malformed}"
    )


class Progress:
    """Live progress of a campaign; call ``tick`` after every execution."""

    def __init__(
        self,
        stats: Stats,
        features: Any,
        interval: float = 5.0,
        total_seconds: float | None = None,
        enabled: bool = True,
    ) -> None:
        self.stats = stats
        self.features = features
        self.interval = interval
        self.enabled = enabled
        self._next = time.monotonic() + interval
        self._bar: Any = None
        if enabled and sys.stderr.isatty():
            from tqdm import tqdm

            self._bar = tqdm(
                total=total_seconds,
                unit="s",
                desc=PREFIX,
                leave=False,
                dynamic_ncols=True,
                bar_format="{desc} {elapsed} {bar} {postfix}" if total_seconds else None,
            )

    def tick(self) -> None:
        if not self.enabled or time.monotonic() < self._next:
            return
        self._next = time.monotonic() + self.interval
        line = status_line(self.stats, len(self.features.seen))
        if self._bar is not None:
            self._bar.n = min(self.stats.elapsed, self._bar.total or self.stats.elapsed)
            self._bar.set_postfix_str(line, refresh=True)
        else:
            info(line)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def summary(stats: Stats, features: int, artifacts: str, corpus: Iterable[str], new_files: list[str]) -> None:
    """The end-of-campaign report (stderr). ``new_files``: crash files written since the
    start, by this process or by its -fork/-jobs workers."""
    lines = [
        "campaign summary",
        f"  executions: {stats.execs} in {stats.elapsed:.1f} s "
        f"({stats.execs / max(stats.elapsed, 1e-9):,.0f}/s); filtered {stats.filtered}, "
        f"malformed {stats.malformed}",
        f"  divergences: {stats.divergences} "
        + (
            f"({', '.join(f'{k} {n}' for k, n in sorted(stats.divergent.items()))})"
            if stats.divergences
            else ""
        ),
        f"  unique signatures: {len(stats.signatures)}; behaviour features seen: {features}",
        f"  largest difference: {stats.max_difference:.3g}",
    ]
    if stats.by_strategy:
        lines.append(
            "  divergences by mutation strategy: "
            + ", ".join(f"{k} {n}" for k, n in stats.by_strategy.most_common())
        )
    if not stats.execs:
        lines = ["campaign summary (this process supervised workers; their logs hold their counts)"]
    lines.append(f"  crash files ({len(new_files)} new this run) in: {artifacts}")
    for path in new_files[:20]:
        lines.append(f"    {path}")
    if len(new_files) > 20:
        lines.append(f"    ... and {len(new_files) - 20} more")
    lines.append(f"  corpus: {', '.join(corpus)}")
    lines.append("  replay one with: python fuzz_diff.py <crash file>")
    for line in lines:
        info(line)


def verdict(path: str, text: str, detail: str = "") -> None:
    out(f"{path}: {text}" + (f" ({detail})" if detail else ""))
