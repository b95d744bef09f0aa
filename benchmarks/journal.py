"""A journal of a benchmark's finished trials, so a sweep of hours can stop and go on.

``bench_deep``'s full mode takes about 2.7 hours on two cores, ``bench_zoo``'s about two.
Without a journal their results existed only once every trial had run: a sweep stopped at hour
two (a reboot, a session that ends) left nothing. Now each finished trial is appended to
``<results>.jsonl`` beside the results file (``deep-<mode>.jsonl``, ``zoo-<mode>.jsonl``) as it
ends (one JSON object a line, flushed and fsynced), under a first line that names the sweep:
its tool and mode, bugs, engines, trials and budget (and ``bench_zoo``'s ops and replay), and
the commit that ran it. ``--resume`` reads the journal, checks that it belongs to this sweep and
to the same code, and runs only the trials it does not hold (``benchmarks.sweeps``); once every
trial has run, the results file is written and the journal removed. "The same code": the
journal's commit, or a later one that changed nothing outside ``benchmarks/results/`` and the
Markdown files (a session that commits a partial journal and some notes can go on from its own
next commit).

One sweep writes a journal at a time: it holds an exclusive lock on ``<journal>.lock`` while it
runs, and a second one started on the same results folder stops with an error instead of running
the same trials again into the same file.

The journal is data: it is parsed as JSON, never evaluated. A last line cut short (a process
killed while writing it) is ignored, and its trial runs again; any other bad line is an error
that names the file and the line.
"""

from __future__ import annotations

import fcntl
import json
import math
import os
import platform
import subprocess
import threading
from dataclasses import MISSING, asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from benchmarks import cli

if TYPE_CHECKING:  # bench_zoo imports this module
    from benchmarks.bench_zoo import Run


def format_of(tool: str) -> str:
    """The header's ``journal`` value of ``tool``'s journals."""
    return f"rrosfuzz {tool} journal 1"


FORMAT = format_of("bench_deep")


class JournalError(ValueError):
    """A journal that cannot be continued; the message names the file and the problem."""


@dataclass(frozen=True)
class Sweep:
    """What a journal's trials belong to: a mode's runs at one commit.

    Attributes
    ----------
    mode : str
        The ``--mode`` name (it names the files).
    bugs, engines : tuple of str
        The mode's bugs and engines, in order.
    trials : int
        Trials per (bug, engine).
    budget : float
        Seconds per trial.
    commit : str
        ``git rev-parse HEAD`` of the tree that runs the trials, ``+dirty`` appended when it has
        uncommitted changes to tracked files ("unknown" outside a git checkout).
    tool : str
        The benchmark (``bench_deep``, ``bench_zoo``): it names the header's format.
    ops : tuple of str
        ``bench_zoo``'s ops that every bug runs under (its ``ops`` mode), or none.
    replay : bool
        ``bench_zoo``'s replay of crash files, part of each trial's record.
    first_seed : int
        The first trial's ``-seed`` (``--first-seed``; ``bench_zoo``'s from 1): the trials are seeds
        ``first_seed`` to ``first_seed + trials - 1``.
    machine : str
        The machine that runs the trials (:func:`machine_of`; "" in journals from before it was
        kept): ``--resume`` on another refuses, since one table's times must come from one kind
        of machine (this workplace's sessions land on Intel Xeon or AMD EPYC VMs, whose
        quiet start-ups differed by about 1.5x).
    """

    mode: str
    bugs: tuple[str, ...]
    engines: tuple[str, ...]
    trials: int
    budget: float
    commit: str
    tool: str = "bench_deep"
    ops: tuple[str, ...] = ()
    replay: bool = False
    first_seed: int = 0
    machine: str = ""

    def header(self) -> dict[str, Any]:
        row = asdict(self)
        return {"journal": format_of(row.pop("tool")), **row}


MAX_TRIALS = cli.MAX_TRIALS
"""The most trials (or seeds) per cell a journal's header may name: a sweep plans every one of
them, so a damaged header's 10**7 would fill the memory before anything is read."""


def sweep_of(header: dict[str, Any], tool: str) -> Sweep:
    """The sweep a journal's ``header`` (of ``tool``) names; an older header's missing ``ops``,
    ``replay``, ``first_seed`` and ``machine`` are their defaults. A ``bench_zoo`` header's
    ``first_seed`` 0, or none, is 1: its sweeps ran seeds from 1 before it had ``--first-seed``
    (whose least value is 1, since libFuzzer takes ``-seed=0`` for a seed from the clock).

    Raises
    ------
    JournalError
        A field is missing or has the wrong type (named).
    """
    kinds: dict[str, Any] = {
        "mode": str,
        "trials": int,
        "first_seed": int,
        "budget": (int, float),
        "commit": str,
        "machine": str,
        "replay": bool,
    }
    values = _as_written(header, tool)
    for name in (
        "mode",
        "bugs",
        "engines",
        "trials",
        "first_seed",
        "budget",
        "commit",
        "machine",
        "ops",
        "replay",
    ):
        value = values.get(name)
        if name in ("bugs", "engines", "ops"):
            good = isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value)
        else:
            good = isinstance(value, kinds[name]) and (name == "replay" or not isinstance(value, bool))
        if not good:
            raise JournalError(f"the header's {name} is missing or not what it should be: {value!r}")
    if not 1 <= values["trials"] <= MAX_TRIALS or not 0 <= values["first_seed"] <= cli.MAX_SEED:
        raise JournalError(
            f"the header's trials {values['trials']!r} or first_seed {values['first_seed']!r} is out of "
            f"range (trials 1..{MAX_TRIALS})"
        )
    if not seconds_ok(values["budget"], "> 0"):
        raise JournalError(
            f"the header's budget {values['budget']!r} is not a finite number of seconds above 0"
        )
    tuples = {k: tuple(values[k]) for k in ("bugs", "engines", "ops")}
    return Sweep(**{**values, **tuples, "budget": float(values["budget"]), "tool": tool})


def _as_written(header: dict[str, Any], tool: str) -> dict[str, Any]:
    """``header``'s sweep fields, an older journal's missing ones at their defaults, and a
    ``bench_zoo`` journal's ``first_seed`` 0 at 1 (see :func:`sweep_of`)."""
    values = {**_DEFAULTS, **{k: v for k, v in header.items() if k in _FIELDS}}
    if tool == "bench_zoo" and type(values["first_seed"]) is int and values["first_seed"] == 0:
        values["first_seed"] = 1
    return values


SAME_SWEEP = ("mode", "bugs", "engines", "trials", "first_seed", "budget", "ops", "replay")
"""The header's keys that must equal this run's for ``--resume``."""
_DEFAULTS = {f.name: f.default for f in fields(Sweep) if f.default is not MISSING}
_FIELDS = {f.name for f in fields(Sweep)} - {"tool"}


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``, else ``platform.processor()`` or
    ``platform.machine()``)."""
    model = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as info:
            model = next(
                (line.split(":", 1)[1].strip() for line in info if line.startswith("model name")), ""
            )
    except OSError:
        pass
    return model or platform.processor() or platform.machine() or "unknown"


def machine_of() -> str:
    """This machine, as a journal keeps it: the CPU's model name and the number of CPUs."""
    return f"{cpu_model()}, {os.cpu_count()} CPUs"


def commit_of(root: Path) -> str:
    """``root``'s commit, with ``+dirty`` when a tracked file outside ``IGNORED`` differs from
    it (the results a sweep writes, such as ``make bench``'s earlier steps', do not count)."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, check=True, timeout=30
        ).stdout.strip()
        changed = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", ".", *_EXCLUDED],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
            timeout=30,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head + ("+dirty" if changed else "")


IGNORED = ("benchmarks/results", "*.md")
"""Paths whose changes do not make a tree's trials differ from the journal's (results, prose)."""
_EXCLUDED = tuple(f":(exclude){p}" for p in IGNORED)


def same_code(root: Path, commit: str) -> bool:
    """Whether ``root``'s working tree has the tracked files of ``commit`` outside ``IGNORED``."""
    if commit.endswith("+dirty") or commit == "unknown":
        return False
    try:
        diff = subprocess.run(
            ["git", "diff", "--quiet", commit, "--", ".", *_EXCLUDED],
            cwd=root,
            capture_output=True,
            timeout=60,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return False
    return diff.returncode == 0


_KINDS: dict[str, tuple[type, ...]] = {
    **dict.fromkeys(("bug", "engine", "op"), (str,)),
    **dict.fromkeys(("seed", "signatures", "executions", "returncode", "divergences"), (int,)),
    **dict.fromkeys(("replayed", "replay_same"), (int,)),
    **dict.fromkeys(("budget", "elapsed"), (int, float)),
    **dict.fromkeys(("detected_at", "first_input"), (int, float, type(None))),
    "libfuzzer_seed": (int, type(None)),
}
"""The JSON types each field of a trial may have."""


_SECONDS: dict[str, str] = {"budget": "> 0", "elapsed": "> 0", "detected_at": ">= 0", "first_input": ">= 0"}
"""The times of a trial, and the least each may be (a zero budget or elapsed time would be divided by)."""


def seconds_ok(value: float, least: str) -> bool:
    """Whether ``value`` is a finite number of seconds ``least`` (``'> 0'`` or ``'>= 0'``)."""
    try:
        number = float(value)
    except OverflowError:  # an int beyond any float
        return False
    return math.isfinite(number) and (number > 0 if least == "> 0" else number >= 0)


def run_of(row: Any) -> Run:
    """A trial from its JSON object (fields this version does not know are dropped).

    Raises
    ------
    TypeError
        ``row`` is not an object, lacks a field, or a field has the wrong type (named).
    """
    from benchmarks.bench_zoo import Run

    if not isinstance(row, dict):
        raise TypeError("not an object")
    fields = {k: v for k, v in row.items() if k in Run.__dataclass_fields__}
    for name, kinds in _KINDS.items():
        if name in fields and (isinstance(fields[name], bool) or not isinstance(fields[name], kinds)):
            names = " or ".join("null" if k is type(None) else k.__name__ for k in kinds)
            raise TypeError(f"{name}: {fields[name]!r} is not {names}")
    for name, least in _SECONDS.items():
        value = fields.get(name)
        if value is not None and not seconds_ok(value, least):
            raise TypeError(f"{name}: {value!r} is not a finite number of seconds {least}")
    for name in ("replay_misses", "fields"):
        value = fields.get(name, ())
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise TypeError(f"{name}: not a list of strings")
        fields[name] = tuple(value)
    return Run(**fields)


def read(path: Path, tool: str = "bench_deep") -> tuple[dict[str, Any], list[Run]]:
    """A journal's header and its trials (a last line cut short left out).

    Raises
    ------
    JournalError
        The file cannot be read, its first line is not a journal header, or a line other than
        the last is not a trial.
    """
    try:
        lines = path.read_text(encoding="utf-8").split("\n")
    except (OSError, UnicodeDecodeError) as exc:
        raise JournalError(f"{path}: cannot be read ({exc})") from exc
    complete = lines[:-1]  # every line a writer finished ends with a newline
    try:
        header = json.loads(complete[0]) if complete else None
    except (ValueError, RecursionError):  # RecursionError: JSON nested past the interpreter's limit
        header = None
    if not isinstance(header, dict) or header.get("journal") != format_of(tool):
        raise JournalError(f"{path}: not a {tool} journal (its first line is not the header)")
    runs = []
    for number, line in enumerate(complete[1:], start=2):
        try:
            runs.append(run_of(json.loads(line)))
        except (ValueError, TypeError, RecursionError) as exc:
            raise JournalError(f"{path}, line {number}: not a trial ({exc})") from exc
    return header, runs


def planned(header: dict[str, Any], runs: list[Run], tool: str = "bench_deep") -> list[Run]:
    """The trials of ``runs`` that the journal's sweep (``header``) plans, each once (the first
    line of a trial written twice), as ``--resume`` holds them: a tabulation counted a line
    repeated, and a trial of a seed outside the sweep's, into its cells."""
    sweep = sweep_of(header, tool)
    seeds = range(sweep.first_seed, sweep.first_seed + sweep.trials)
    held: dict[tuple[str, str, str, int], Run] = {}
    for run in runs:
        if run.bug in sweep.bugs and run.engine in sweep.engines and run.seed in seeds:
            held.setdefault((run.bug, run.engine, run.op, run.seed), run)
    return list(held.values())


def check(path: Path, header: dict[str, Any], sweep: Sweep, root: Path) -> None:
    """Raise a :class:`JournalError` naming what differs when ``header`` is not ``sweep``'s,
    or when ``root`` does not hold the code of the journal's commit (:func:`same_code`)."""
    mine = json.loads(json.dumps(sweep.header()))  # tuples as lists, as read back
    written = _as_written(header, sweep.tool)
    for key in SAME_SWEEP:
        theirs = json.loads(json.dumps(written[key]))  # older journals' defaults, as read back
        if theirs != mine[key]:
            raise JournalError(
                f"{path}: written for another sweep ({key} {theirs!r}, this run's "
                f"{mine[key]!r}); run the same options, or --restart"
            )
    machine = header.get("machine", "")
    if machine and sweep.machine and machine != sweep.machine:
        raise JournalError(
            f"{path}: its trials ran on another machine ({machine}; this one: {sweep.machine}), "
            f"and one table's times must come from one kind of machine. Resume it there, or --restart"
        )
    commit = header.get("commit")
    if not isinstance(commit, str) or not same_code(root, commit):
        raise JournalError(
            f"{path}: written by commit {commit}, and this tree ({sweep.commit}) has other code "
            f"(a table must come from one engine; a tree with uncommitted changes cannot be "
            f"checked). Resume from a checkout of that commit (git worktree add DIR COMMIT), or "
            f"--restart"
        )


def _aside(path: Path) -> Path:
    """Where ``--restart`` keeps an unfinished journal: ``<name>.old``, or ``<name>.old.N`` (the
    first free N from 2) so that a second restart does not overwrite the first one's."""
    aside = path.with_name(path.name + ".old")
    number = 2
    while aside.exists():
        aside = path.with_name(f"{path.name}.old.{number}")
        number += 1
    return aside


def _lock_of(path: Path) -> Path:
    """The lock file of the journal at ``path``."""
    return path.with_name(path.name + ".lock")


def _hold(path: Path, tool: str) -> int:
    """An open descriptor of ``path``'s lock file, locked exclusively (``flock``)."""
    lock = _lock_of(path)
    lock.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        raise JournalError(
            f"{path}: another {tool} is running this sweep now (it holds {lock.name})"
        ) from None
    return fd


class Journal:
    """Appends finished trials to a journal file, one at a time (thread-safe), under the
    sweep's lock (:meth:`close` lets it go)."""

    def __init__(self, path: Path, sweep: Sweep, fresh: bool, lock: int) -> None:
        self.path = path
        self._held = lock
        self._lock = threading.Lock()
        if fresh:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._write(sweep.header(), "w")
        else:
            self._cut_short_line()

    def _cut_short_line(self) -> None:
        """Drop a last line a killed writer left without its newline, so appends start clean."""
        data = self.path.read_bytes()
        if data and not data.endswith(b"\n"):
            with self.path.open("r+b") as f:
                f.truncate(data.rfind(b"\n") + 1)

    def _write(self, row: dict[str, Any], how: str) -> None:
        with self.path.open(how, encoding="utf-8") as f:
            f.write(json.dumps(row) + "\n")
            f.flush()
            os.fsync(f.fileno())

    def add(self, run: Run) -> None:
        with self._lock:
            self._write(asdict(run), "a")

    def close(self) -> None:
        """Let the sweep's lock go (and its file)."""
        if self._held >= 0:
            _lock_of(self.path).unlink(missing_ok=True)
            os.close(self._held)
            self._held = -1


def open_sweep(
    path: Path, sweep: Sweep, root: Path, *, resume: bool, restart: bool
) -> tuple[Journal, list[Run]]:
    """The sweep's journal at ``path`` and the trials it already holds (none unless ``resume``).

    Raises
    ------
    JournalError
        ``path`` holds an unfinished sweep and neither ``resume`` nor ``restart`` is given, or
        ``resume`` and there is no journal, or it is not this sweep's (:func:`check`).
    """
    lock = _hold(path, sweep.tool)
    try:
        if path.exists() and not restart:
            if not resume:
                raise JournalError(
                    f"{path} holds an unfinished sweep: --resume goes on with it, --restart starts "
                    f"over (keeping it as {path.name}.old, or .old.N when that is taken)"
                )
            header, done = read(path, sweep.tool)
            check(path, header, sweep, root)
            return Journal(path, sweep, False, lock), done
        if resume:
            raise JournalError(f"nothing to resume: {path} does not exist")
        if path.exists():
            path.replace(_aside(path))
        return Journal(path, sweep, True, lock), []
    except BaseException:
        _lock_of(path).unlink(missing_ok=True)
        os.close(lock)
        raise
