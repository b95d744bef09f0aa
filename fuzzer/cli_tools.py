"""The subcommands that read what campaigns left (``replay``, ``triage``, ``minimize``,
``report``, ``promote``, ``coverage``; ``fuzz_diff.py CRASH...`` is ``replay``). The campaign
itself, the shared options and the dispatch are in ``fuzzer.cli``, which imports this module
when one of these runs."""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.artifacts.store import WRITE_FAILED_EXIT
from fuzzer.cli_options import (
    UsageError,
    campaign_robot_option,
    config_from,
    config_options,
    replay_parser,
    trust_option,
)
from fuzzer.execution.session import ConfigError
from fuzzer.input.paths import given_path


def replay_main(argv: Sequence[str]) -> int:
    from fuzzer.triage.isolated import replay_isolated
    from fuzzer.triage.replay import source_of

    args = replay_parser().parse_args(argv)
    base, given = config_from(args)
    sessions: dict[Any, Any] = {}
    diverging = errors = 0
    files = _inputs(args.paths)
    for path in files:
        try:
            result = replay_isolated(path, base, given, sessions, args.trust_sidecar)
        except ConfigError as exc:
            _skip_file(exc, files)
            errors += 1
            continue
        if not result.has_sidecar and source_of(path) == "command line":
            reporting.warn(
                f"{path}: no sidecar, so no recorded configuration or signature to compare with; "
                "replayed under the command line's configuration (give --op, --robot, --targets... "
                "to choose another)"
            )
        diverging += result.diverges
        reporting.verdict(str(path), str(result.result), result.detail)
        for line in result.steps[1:]:
            reporting.out(reporting.shown("    " + line))
    return 2 if errors else (1 if diverging else 0)


def _ends_its_process(
    path: Path, base: Any, given: dict[str, Any], sessions: dict[Any, Any], trust: bool
) -> str | None:
    """What ``path``'s replay does to its process, when it kills it, ends it or hangs (None
    otherwise): such a file is libFuzzer's to minimize (``fuzzer.triage.isolated``)."""
    from fuzzer.triage.isolated import CRASHES, ENDS, HANGS, replay_isolated

    try:
        verdict = replay_isolated(path, base, given, sessions, trust)
    except ConfigError:
        return None  # load() said it already, or shrink() will
    return f"{verdict.result} ({verdict.detail})" if verdict.result in (CRASHES, ENDS, HANGS) else None


def _skip_file(exc: ConfigError, files: list[Path]) -> None:
    """A file of several that cannot be read under this configuration: say so and go on (the
    caller counts it); with a single file, the error is the command's (re-raised)."""
    if len(files) == 1:
        raise exc
    sys.stderr.write(f"fuzz_diff.py: error: {reporting.message(str(exc))}\n")


def _inputs(paths: Sequence[Path], *, folders: bool = True) -> list[Path]:
    """Crash files from paths, folders and shell globs (sidecars skipped); missing ones are errors."""
    from fuzzer.input.paths import PathError, crash_inputs

    try:
        return crash_inputs(paths, folders=folders)
    except PathError as exc:
        raise UsageError(str(exc)) from None


def triage_main(argv: Sequence[str]) -> int:
    from fuzzer.triage import pipeline as triage

    parser = argparse.ArgumentParser(prog="fuzz_diff.py triage", description="List divergence buckets.")
    parser.add_argument(
        "paths",
        nargs="+",
        type=given_path,
        help="an artifacts folder, or crash files of one folder (globs work)",
    )
    parser.add_argument("--json", action="store_true", help="machine-readable output")
    args = parser.parse_args(argv)
    if len(args.paths) == 1 and args.paths[0].is_dir():
        directory, files = args.paths[0], None
    else:
        files = _inputs(args.paths, folders=False)
        folders = {p.parent.resolve() for p in files}
        if len(folders) > 1:
            raise UsageError("crash files from several folders: give one artifacts folder at a time")
        directory = files[0].parent
    try:
        buckets = triage.collect(directory, files)
    except OSError as exc:
        raise UsageError(f"{directory}: cannot read: {exc.strerror or exc}") from None
    if args.json:
        reporting.out(triage.dumps(buckets))
    else:
        for line in triage.table(buckets):
            reporting.out(line)
    return 0


def minimize_main(argv: Sequence[str]) -> int:
    from fuzzer.triage import crashfiles

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py minimize",
        description="Shrink crash files to the simplest input with the same signature, under the "
        "configuration their sidecars record (options given here override it).",
        epilog="exit status: 0 every file minimized or already minimal; 1 a file that no longer "
        "reproduces its signature, or that kills, ends or hangs its process (nothing written for it); "
        "2 a file or sidecar that cannot be read; 74 an output that cannot be written",
    )
    parser.add_argument("paths", nargs="+", type=given_path, help="crash files with sidecars (globs work)")
    config_options(parser)
    parser.add_argument("--budget", type=int, default=2000, help="evaluations per file (default 2000)")
    parser.add_argument(
        "-o",
        "--output",
        type=given_path,
        default=None,
        help="folder for minimized files (default: next to each crash file)",
    )
    args = parser.parse_args(argv)
    if args.budget < 1:
        raise UsageError("--budget must be >= 1")
    base, given = config_from(args)
    files = _inputs(args.paths, folders=False)
    if args.output is not None:
        from fuzzer.input.paths import prepare_folder

        prepare_folder(args.output, "--output", writable=True)
    sessions: dict[Any, Any] = {}
    errors = unwritten = stale = 0
    for path in files:
        try:
            loaded = crashfiles.load(path, given, args.trust_sidecar, sessions)
        except ConfigError as exc:
            _skip_file(exc, files)
            errors += 1
            continue
        ended = _ends_its_process(path, base, given, sessions, args.trust_sidecar)
        if ended is not None:  # it ended minimize with it (exit 134, no word)
            reporting.verdict(
                str(path), f"not minimized: it {ended}; libFuzzer's -minimize_crash=1 minimizes such an input"
            )
            stale += 1
            continue
        try:
            shrunk = crashfiles.shrink(loaded, args.budget)
        except ValueError as exc:  # it does not reproduce its signature: nothing is written
            reporting.verdict(str(path), f"not minimized: {exc}")
            stale += 1
            continue
        if crashfiles.already_minimal(loaded, shrunk):
            detail = f"{shrunk.evaluations} evaluations, no file written"
            reporting.verdict(str(path), "already minimal", detail)
            continue
        try:
            data, out = crashfiles.minimized_sidecar(loaded, shrunk)
        except ValueError as exc:
            reporting.verdict(str(path), f"not minimized: {exc}")
            stale += 1
            continue
        folder = args.output or path.parent
        try:
            minimized = crashfiles.write_minimized(folder, data, out)
        except OSError as exc:  # a full disk or a read-only folder: nothing of this file is left there
            problem = f"cannot write into {folder}: {exc.strerror or exc}"
            sys.stderr.write(f"fuzz_diff.py: error: {reporting.message(problem)}\n")
            unwritten += 1
            continue
        reporting.verdict(
            str(path),
            f"minimized to {minimized}",
            f"{len(loaded.raw)} -> {len(data)} bytes, {shrunk.evaluations} evaluations, "
            f"joints that matter: {', '.join(out['joints_that_matter']) or 'none'}"
            + ("" if shrunk.complete else ", budget exhausted"),
        )
    return WRITE_FAILED_EXIT if unwritten else (2 if errors else (1 if stale else 0))


def report_main(argv: Sequence[str]) -> int:
    from fuzzer.report import write_report

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py report", description="Write a self-contained HTML report of an artifacts folder."
    )
    parser.add_argument("directory", type=given_path)
    parser.add_argument(
        "-o", "--output", type=given_path, default=None, help="output folder (default DIR/report)"
    )
    parser.add_argument(
        "--robot",
        action="append",
        default=[],
        help="a campaign's URDF file (or robot name), for sidecars whose path was relative to "
        "another working folder: used for every crash file whose sidecar records its SHA-256 "
        "(repeat it for several robots)",
    )
    trust_option(parser, overrides=False)
    args = parser.parse_args(argv)
    if not args.directory.is_dir():
        raise UsageError(f"{args.directory}: not a folder")
    robots = _robots_by_digest(args.robot)
    _unused_robots(args.directory, robots)
    output = args.output
    if output is None:
        output = args.directory / "report"
        if output.is_symlink():  # a crafted folder must not make us write elsewhere
            raise UsageError(f"{output} is a symbolic link; choose the output folder with -o")
    from fuzzer.input.paths import prepare_folder

    prepare_folder(output, "report output", writable=True)
    page = write_report(args.directory, output, trust=args.trust_sidecar, robots=robots)
    reporting.out(reporting.shown(f"report: {page}"))
    return 0


def _robots_by_digest(given: Sequence[str]) -> dict[str, str]:
    """``report --robot`` files by their SHA-256 (a usage error for one that does not resolve)."""
    from fuzzer.artifacts.manifest import robot_digest

    out = {}
    for robot in given:
        digest = robot_digest(robot)
        if digest is None:
            raise UsageError(f"--robot {robot}: neither a shipped robot nor a readable file")
        out[digest] = robot
    return out


def _unused_robots(directory: Path, robots: dict[str, str]) -> None:
    """Warn of a ``report --robot`` that no sidecar of ``directory`` records (it did nothing)."""
    if not robots:
        return
    from fuzzer.artifacts.store import load_sidecar
    from fuzzer.input.paths import crash_inputs

    recorded = set()
    try:
        for path in crash_inputs([directory]):
            sidecar = load_sidecar(path)
            digest = sidecar.get("robot_sha256") if isinstance(sidecar, dict) else None
            if isinstance(digest, str):
                recorded.add(digest.lower())
    except (ConfigError, OSError):
        return  # the report says what it cannot read
    for digest, robot in robots.items():
        if digest not in recorded:
            reporting.warn(f"--robot {robot}: no crash file here records its SHA-256; it is not used")


def promote_main(argv: Sequence[str]) -> int:
    from fuzzer.triage.regressions import SUITE, PromoteError, promote

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py promote", description="Add a crash file to the regression suite."
    )
    parser.add_argument("crash", nargs="+", type=given_path, help="crash files with sidecars (globs work)")
    parser.add_argument("--fixed", action="store_true", help="it is fixed: the targets must agree on it")
    parser.add_argument("--note", default="", help="why it is kept")
    parser.add_argument("--suite", type=given_path, default=SUITE, help=f"suite folder (default {SUITE})")
    campaign_robot_option(parser, ", and is kept in the suite")
    trust_option(parser, overrides=False)
    args = parser.parse_args(argv)
    status = 0
    for crash in _inputs(args.crash, folders=False):
        try:
            trust = args.trust_sidecar
            done = promote(crash, args.fixed, args.note, args.suite, trust=trust, robot=args.robot)
        except PromoteError as exc:
            reporting.out(reporting.bounded(reporting.shown(f"not promoted: {exc}")))
            status = max(status, 1)
            continue
        reporting.out(reporting.shown(f"promoted {done.path} (expect: {done.expect})"))
    return status


def coverage_main(argv: Sequence[str]) -> int:
    from fuzzer.report.coverage import measure

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py coverage", description="Line and branch coverage of python_impl over a corpus."
    )
    parser.add_argument("corpus", nargs="+", type=given_path)
    config_options(parser)
    parser.add_argument(
        "--html",
        type=given_path,
        default=Path("coverage_html"),
        help="HTML output folder (default coverage_html, replaced if there)",
    )
    args = parser.parse_args(argv)
    from fuzzer.input.paths import PathError, check_input_file

    for path in args.corpus:
        if not path.exists():
            raise UsageError(f"{path}: no such file or folder")
        check_input_file(path)
    from fuzzer.artifacts.travel import adopt_manifest

    adopt_manifest(args, [p for p in args.corpus if p.is_dir()])
    config, _ = config_from(args)
    from fuzzer.artifacts.travel import check_manifests

    check_manifests([p for p in args.corpus if p.is_dir()], config)
    if args.html.exists() and not args.html.is_dir():
        raise PathError(f"--html {args.html}: is a file, not a folder")
    html = args.html.resolve()
    for folder in (p.resolve() for p in args.corpus if p.is_dir()):
        if html == folder or folder in html.parents:  # its pages became the corpus's inputs
            raise PathError(f"--html {args.html}: inside the corpus folder {folder}; choose one outside it")
    from fuzzer.input.paths import prepare_folder

    # a path through a file said "Not a directory" and exited 74; read-only still exits 74
    made = not args.html.exists()
    prepare_folder(args.html, "--html", writable=True)
    try:
        totals = measure(list(args.corpus), config, args.html)
    except (ConfigError, OSError):
        if made:  # a refused run leaves no empty folder behind
            with contextlib.suppress(OSError):
                args.html.rmdir()
        raise
    reporting.out(totals.line())
    return 0
