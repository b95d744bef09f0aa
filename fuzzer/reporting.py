"""Everything the engine shows a person: progress, warnings, summaries, verdicts.

The only module that writes to the terminal. Progress goes to stderr: one tqdm
line redrawn in place on a terminal, a plain line every few seconds otherwise
(libFuzzer's own per-input lines are hidden unless ``--verbose``).
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from fuzzer.selection.state import Stats

PREFIX = "[rrosfuzz]"
LINES = "\n"
"""``shown``'s ``keep`` for a message whose line breaks are its own (a ROS log's last lines)."""


_terminal: TextIO | None = None


def terminal() -> TextIO:
    """Where the engine's own lines go: stderr, or the copy of it that ``keep_terminal`` made."""
    return _terminal or sys.stderr


def keep_terminal() -> None:
    """Keep the engine's lines on the terminal when libFuzzer's ``-close_fd_mask=2`` sends file
    descriptor 2 to /dev/null to silence the target: a copy of stderr, as libFuzzer keeps one for
    its own lines (its ``DupAndCloseStderr``). The summary was lost with the target's output."""
    global _terminal
    if _terminal is not None:
        return
    sys.stderr.flush()
    try:
        fd = os.dup(sys.stderr.fileno())
    except (AttributeError, OSError, ValueError):  # no stderr, or not a file's (a test's capture)
        return
    _terminal = os.fdopen(
        fd, "w", encoding=sys.stderr.encoding or "utf-8", errors="backslashreplace", buffering=1
    )


@contextlib.contextmanager
def target_output_closed(mask: int) -> Iterator[None]:
    """libFuzzer's ``-close_fd_mask`` where the target runs outside libFuzzer (the dry run):
    stdout (``mask & 1``) and stderr (``mask & 2``) to /dev/null meanwhile, the engine's own
    lines kept on the terminal (``keep_terminal``)."""
    fds = [fd for fd in (1, 2) if mask & fd]
    if not fds:
        yield
        return
    if mask & 2:
        keep_terminal()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    saved = [os.dup(fd) for fd in fds]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in fds:
            os.dup2(null, fd)
        yield
    finally:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        for fd, copy in zip(fds, saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)
        os.close(null)


def info(text: str, stream: TextIO | None = None) -> None:
    (stream or terminal()).write(f"{PREFIX} {text}\n")
    (stream or terminal()).flush()


MESSAGE_LINE_CHARS = 2000
"""At most this many characters of one line of a warning or error: a sidecar's 2 MB robot path
made a 2,000,254-byte error line (the middle is left out, and counted)."""

MESSAGE_LINES = 40
"""At most this many lines of a warning or error (a log's last lines are fewer)."""


def bounded(line: str) -> str:
    """``line`` with its middle left out (and counted) past ``MESSAGE_LINE_CHARS``."""
    if len(line) <= MESSAGE_LINE_CHARS:
        return line
    half = MESSAGE_LINE_CHARS // 2
    return f"{line[:half]} ... ({len(line) - 2 * half} characters left out) ... {line[-half:]}"


def message(text: str) -> str:
    """A warning's or error's text for the terminal: unprintable characters escaped
    (:func:`shown`) but its own line breaks, each continuation line indented (so that a line
    break in a file name or a sidecar's string cannot print a line that reads as the program's
    own, such as ``fuzz_diff.py: error: ...``), and bounded (``MESSAGE_LINE_CHARS``,
    ``MESSAGE_LINES``)."""
    lines = shown(text, LINES).split("\n")
    if len(lines) > MESSAGE_LINES:
        lines = [*lines[: MESSAGE_LINES - 1], f"... ({len(lines) - MESSAGE_LINES + 1} more lines)"]
    return "\n    ".join(map(bounded, lines))


def warn(text: str) -> None:
    terminal().write(f"{PREFIX} warning: {message(text)}\n")
    terminal().flush()


def error(text: str) -> None:
    """An error that ends the run (the caller sets the status)."""
    terminal().write(f"{PREFIX} error: {message(text)}\n")
    terminal().flush()


def out(text: str = "") -> None:
    """Primary output (verdicts, tables): stdout. A character UTF-8 cannot hold (a lone surrogate:
    a file name's undecodable byte) is written as its escape, as stderr does, not raised.

    Written whole to the file descriptor (``os.write`` until every byte is out): through the text
    layer, a write the reader cut short (``show DIR | head``: 65,536 of 697,916 bytes taken before
    ``head`` left) ended the program with status 0 and the rest lost without a word, where the
    next write raises ``BrokenPipeError`` (status 141)."""
    try:
        fd = _descriptor()
        if fd is None:  # a stream of Python's (a test's capture): its own writes
            try:
                sys.stdout.write(text + "\n")
            except UnicodeEncodeError:
                encoding = sys.stdout.encoding or "utf-8"
                sys.stdout.write(text.encode(encoding, "backslashreplace").decode(encoding) + "\n")
            sys.stdout.flush()
            return
        sys.stdout.flush()  # what print() left in the buffer goes first
        encoding = sys.stdout.encoding or "utf-8"
        try:
            data = (text + "\n").encode(encoding, sys.stdout.errors or "strict")
        except UnicodeEncodeError:
            data = (text + "\n").encode(encoding, "backslashreplace")
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
    except OSError as exc:  # /dev/full, a full disk: the CLI names it (BrokenPipeError included)
        if exc.filename is None:
            exc.filename = "<stdout>"
        raise


def _descriptor() -> int | None:
    """stdout's file descriptor, or None when it is not a file's (a test's capture)."""
    try:
        return sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # io.UnsupportedOperation is both
        return None


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
        if enabled and terminal().isatty():
            from tqdm import tqdm

            self._bar = tqdm(
                file=terminal(),
                total=total_seconds,
                unit="s",
                desc="starting",
                leave=False,
                dynamic_ncols=True,  # one line, cut to the terminal's width
                bar_format=f"{PREFIX} {{elapsed}} |{{bar:12}}| {{desc}}"
                if total_seconds
                else f"{PREFIX} {{elapsed}} {{desc}}",
            )

    def tick(self) -> None:
        if not self.enabled or time.monotonic() < self._next:
            return
        self._next = time.monotonic() + self.interval
        line = status_line(self.stats, len(self.features.seen))
        if self._bar is not None:
            self._bar.n = min(self.stats.elapsed, self._bar.total or self.stats.elapsed)
            self._bar.set_description_str(line, refresh=True)
        else:
            info(line)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


EXIT_MEANINGS = {
    0: "no new divergence",
    1: "new divergences found",
    70: "timeouts",
    71: "out of memory",
    74: "the artifacts folder could not be written",
    77: "a target died, or --stop-on-divergence stopped at a divergence",
    130: "interrupted (Ctrl-C)",
    143: "terminated (SIGTERM)",
}
"""What a campaign's exit status means (docs/engine.md, "Exit status of a campaign")."""


def meaning_of(exit_code: int) -> str:
    """What ``exit_code`` means at the end of a campaign (:data:`EXIT_MEANINGS`)."""
    return EXIT_MEANINGS.get(exit_code, "libFuzzer's status")


def summary(
    stats: Stats,
    features: int,
    artifacts: str,
    corpus: Iterable[str],
    new_files: list[str],
    *,
    totals: dict[str, Any] | None = None,
    timeouts: Sequence[str] = (),
    crashes: Sequence[str] = (),
    explained: Mapping[str, int] | None = None,
    exit_code: int | None = None,
    exit_meaning: str | None = None,
    dry_run: dict[str, Any] | None = None,
) -> None:
    """The end-of-campaign report (stderr). ``new_files``: crash files written since the
    start, by this process or by its -fork/-jobs workers; ``totals``: the workers' counters
    summed (``divlog.worker_totals``) when this process supervised them; ``timeouts`` and
    ``crashes``: libFuzzer's timeout-/crash- files written since the start; ``explained``: the
    crash files written since the start whose divergence the oracle explains (kinds in
    ``processes.NOT_FINDINGS``), counted by kind: not findings, but on disk for triage;
    ``exit_meaning``: what ``exit_code`` means here, when not what it means alone; ``dry_run``:
    the dry run's children's counters summed (``divlog.worker_totals``), which the lines above
    do not count."""
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
        "  largest value difference: "
        + (
            f"{stats.max_difference:.3g} {stats.max_difference_unit}"
            if stats.max_difference_unit
            else "not finite (every value divergence had an infinite or NaN difference)"
            if stats.divergent.get("value")
            else "none (no value divergence)"
        ),
    ]
    if stats.by_strategy:
        lines.append(
            "  divergences by mutation strategy: "
            + ", ".join(f"{k} {n}" for k, n in stats.by_strategy.most_common())
        )
    if totals is not None:
        lines = _totals_lines(totals, stats.elapsed)
    if dry_run and dry_run.get("execs"):
        kinds = dry_run.get("divergent", {})
        lines.append(
            f"  the dry run, besides ({dry_run.get('processes', 0)} child process(es) before libFuzzer): "
            f"{dry_run['execs']} executions, {dry_run.get('divergences', 0)} divergences"
            + (f" ({', '.join(f'{k} {n}' for k, n in sorted(kinds.items()))})" if kinds else "")
        )
    if timeouts:
        lines.append(f"  timeouts: {len(timeouts)} input(s) ran past -timeout: {', '.join(timeouts[:5])}")
    if crashes:
        lines.append(f"  libFuzzer crashes: {len(crashes)}: {', '.join(crashes[:5])}")
    lines.append(f"  crash files ({len(new_files)} new this run) in: {artifacts}")
    for path in new_files[:20]:
        lines.append(f"    {path}")
    if len(new_files) > 20:
        lines.append(f"    ... and {len(new_files) - 20} more")
    if explained:
        kinds = ", ".join(f"{kind} {n}" for kind, n in sorted(explained.items()))
        lines.append(
            f"  explained, not findings: {sum(explained.values())} more crash file(s) new this run "
            f"({kinds}), written for triage: python fuzz_diff.py triage {artifacts}"
        )
    lines.append(f"  corpus: {', '.join(corpus)}")
    lines.append("  replay one with: python fuzz_diff.py <crash file>")
    if exit_code is not None:
        lines.append(f"  exit status {exit_code} ({exit_meaning or meaning_of(exit_code)})")
    for line in lines:
        info(line)


def _totals_lines(totals: dict[str, Any], elapsed: float) -> list[str]:
    """Summary lines of a -fork/-jobs campaign: the workers' counters summed."""
    kinds = totals.get("divergent", {})
    execs = totals.get("execs", 0)
    return [
        f"campaign summary (totals over {totals.get('processes', 0)} child process(es): jobs and merges)",
        f"  executions: {execs} in {elapsed:.1f} s ({execs / max(elapsed, 1e-9):,.0f}/s); "
        f"filtered {totals.get('filtered', 0)}, malformed {totals.get('malformed', 0)}",
        f"  divergences: {totals.get('divergences', 0)} "
        + (f"({', '.join(f'{k} {n}' for k, n in sorted(kinds.items()))})" if kinds else ""),
        f"  unique signatures: {totals.get('signatures', 0)}",
    ]


def shown(text: str, keep: str = "") -> str:
    """``text`` with its unprintable characters (line breaks, ESC, bidi overrides) as Python
    escapes, but those in ``keep``: a file named ``crash-x<newline>y: now agrees`` prints no
    verdict of its own, and a name holding terminal escapes reaches the terminal as text.
    ``keep=LINES``: an error message that ends with a log's last lines; the report's strings
    keep tabs too (:func:`fuzzer.report.markup.visible`)."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() or c in keep else repr(c)[1:-1] for c in text)


def verdict(path: str, text: str, detail: str = "") -> None:
    out(bounded(shown(f"{path}: {text}" + (f" ({detail})" if detail else ""))))
