"""Command line of RROSFuzz (``python fuzz_diff.py`` and the ``rrosfuzz`` script).

    fuzz_diff.py CORPUS_DIR [CORPUS_DIR...] [-libfuzzer_flag=value ...] [--options]
    fuzz_diff.py CRASH_FILE... [--options]       replay files (like replay, below)
    fuzz_diff.py show FILE...                    a crash file's test case as JSON
    fuzz_diff.py replay PATH... [--options]      replay files or folders (exit 1 if any diverges)
    fuzz_diff.py triage DIR|CRASH... [--json]    buckets of an artifacts folder, most severe first
    fuzz_diff.py minimize CRASH... [--budget N]  shrink to the simplest input with the same signature
    fuzz_diff.py report DIR [-o OUT]             HTML report with the paper's tables and figures
    fuzz_diff.py promote CRASH... [--fixed]      add to the regression suite (tests/regressions/)
    fuzz_diff.py coverage CORPUS... [--html DIR] line and branch coverage of python_impl

Arguments starting with a single dash go to libFuzzer unchanged
(``-max_total_time=60``, ``-runs=N``, ``-seed=N``, ``-jobs=N``, ``-fork=N``,
``-dict=FILE``, ``-merge=1``, ...). Bad arguments exit with status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.artifacts.store import MARKERS, WRITE_FAILED_EXIT, ArtifactsUnwritable
from fuzzer.cli_options import (
    SUBCOMMANDS,
    UsageError,
    campaign_parser,
    config_from,
    forwarded_options,
    split_flags,
)
from fuzzer.execution.session import ConfigError, unread_msg_path
from fuzzer.input.mapping import DEFAULT_MSG_TYPE
from fuzzer.input.paths import FolderUnwritable
from fuzzer.processes import CHILD_ENV, int_flag
from fuzzer.signals import INT_EXIT, INTERRUPTED_EXIT, TERM_EXIT, terminated

MAX_SEEDS = 100_000
"""The most Hypothesis seeds one campaign writes (about 800 MB of corpus; 3,000 took 62 s at
the idle class beside a benchmark). Before the cap, ``--seeds=100000000`` set out to write
about 800 GB, more than the disk holds, with no word until it was stopped."""


def campaign_main(flags: Sequence[str], args: argparse.Namespace) -> int:
    """A campaign (``fuzz_diff.py CORPUS_DIR ...``): ``flags`` are libFuzzer's, ``args`` the
    options ``main`` parsed (``campaign_parser``; one parser, one parse)."""

    # Files next to libFuzzer flags are libFuzzer's business (-minimize_crash, running single inputs).
    if args.seeds is not None and not 0 <= args.seeds <= MAX_SEEDS:
        raise UsageError(
            f"--seeds must be from 0 to {MAX_SEEDS} (each is a file in the corpus, with the full "
            f"engine's space-filling seed beside it: about 8 kB in all), not {args.seeds}"
        )
    from fuzzer.artifacts import travel

    # settings travel: from a crash file's sidecar (-minimize_crash), else the corpus manifest
    if not travel.is_child() and not travel.adopt_sidecar(args, [p for p in args.corpus if p.is_file()]):
        travel.adopt_manifest(args, [p for p in args.corpus if p.is_dir()])
    if not travel.is_child() and args.max_steps is None:
        from fuzzer.artifacts.manifest import recorded_max_steps

        args.max_steps = recorded_max_steps(args.corpus, args.op)
    files = [p for p in args.corpus if p.is_file()]
    minimizing = (
        int_flag(tuple(flags), "-minimize_crash", 0) > 0 or int_flag(tuple(flags), "-cleanse_crash", 0) > 0
    )
    if minimizing and (len(files) != 1 or len(args.corpus) != 1) and not travel.is_child():
        # given a folder, libFuzzer ran it as an input: a traceback ending in std::bad_alloc, an
        # empty crash file and exit 77 ("a target died")
        raise UsageError(
            "-minimize_crash=1 and -cleanse_crash=1 take one crash file, not "
            + (f"the folder {args.corpus[0]}" if len(args.corpus) == 1 else f"{len(args.corpus)} paths")
            + " (`fuzz_diff.py minimize CRASH` minimizes with the oracle's signature)"
        )
    if files and len(files) < len(args.corpus) and not travel.is_child():  # libFuzzer: "Not a directory"
        raise UsageError(
            f"{files[0]}: a file among corpus folders; a campaign takes folders "
            "(`fuzz_diff.py replay FILE` replays a file, `fuzz_diff.py show FILE` prints it)"
        )
    config, _ = config_from(args)
    from fuzzer.artifacts.divlog import STATS
    from fuzzer.artifacts.travel import CONFIGURATION

    created = [p for p in (*args.corpus, args.artifacts) if not p.exists()]
    records = [name for name in (CONFIGURATION, STATS) if not os.path.lexists(args.artifacts / name)]
    markers = not os.path.lexists(args.artifacts / MARKERS)
    try:
        return _campaign(flags, args, config)
    except (OSError, ArtifactsUnwritable):  # a full disk: its line made later campaigns warn of
        if CONFIGURATION in records and not any(args.artifacts.glob("crash-*")):  # "crash files of
            with contextlib.suppress(OSError):  # a campaign on another configuration" it never ran
                (args.artifacts / CONFIGURATION).unlink(missing_ok=True)
        raise
    except (UsageError, ConfigError):
        for path in created:  # a refused campaign leaves no empty folder behind (nor its own records)
            with contextlib.suppress(OSError):
                (path / CONFIGURATION).unlink(missing_ok=True)
                (path / MARKERS).rmdir()
            with contextlib.suppress(OSError):
                path.rmdir()
        if args.artifacts not in created:  # nor its records in a folder that was there (its line
            for name in records:  # made later campaigns warn of "crash files of a campaign" it never ran)
                with contextlib.suppress(OSError):
                    (args.artifacts / name).unlink(missing_ok=True)
            if markers:
                with contextlib.suppress(OSError):
                    (args.artifacts / MARKERS).rmdir()  # only when empty
        raise


def _campaign(flags: Sequence[str], args: argparse.Namespace, config: Any) -> int:
    """The rest of ``campaign_main``, once the run's configuration is known."""
    from fuzzer.artifacts import travel
    from fuzzer.campaign import CampaignOptions, run

    unread = unread_msg_path(config.op, config.msg_type, config.msg_path)
    if unread is not None:  # recorded as typed, a relative folder broke the crash files' replay elsewhere
        if not travel.is_child():
            reporting.warn(unread)
        config = replace(config, msg_path=())
        args.msg_path = []  # nor handed to libFuzzer's jobs
    if not travel.is_child():  # bad paths: exit 2 with a message; a corpus of another robot/op: refused
        merge = any(int_flag(tuple(flags), name, 0) > 0 for name in ("-merge", "-set_cover_merge"))
        folders = travel.prepare_campaign(args.corpus, args.artifacts, merge=merge)
        travel.check_manifests(folders, config)
        travel.note_configuration(args.artifacts, config)
    from fuzzer.input.libfuzzer_flags import (
        check_dictionary,
        check_int_flags,
        check_path_flags,
        default_max_len,
        libfuzzer_argv,
    )
    from fuzzer.input.paths import file_problem
    from fuzzer.processes import drawn_seed, flag_value

    try:
        check_int_flags(tuple(flags))
    except ValueError as exc:
        raise UsageError(str(exc)) from None

    seed = args.seed
    if seed is None:
        value = flag_value(tuple(flags), "-seed") or "0"  # the last -seed, as libFuzzer takes it
        seed = int(value) if value.lstrip("-").isdigit() else 0
    from fuzzer.execution.tolerance import below_ik_precision

    noise = below_ik_precision(config.op, config.tolerance)
    if noise is not None and not travel.is_child():
        reporting.warn(noise)
    if args.max_steps is not None and config.op != "scenario" and not travel.is_child():
        reporting.warn(
            f"--max-steps {args.max_steps}: only a scenario has steps; --op {config.op} ignores it"
        )
    if args.stop_on_divergence and int_flag(tuple(flags), "-fork", 0) > 0:
        # fork mode merges the corpus first: each divergent input crashed its merge (one retry
        # each: 31 in 20 s, no input fuzzed), and each job's stop on a signature already on file
        # was a crash file without a sidecar, counted as a target that died
        raise UsageError(
            "--stop-on-divergence with -fork: libFuzzer's fork mode would stop its merge at every "
            "divergent input; use it in one process, or with -jobs"
        )
    given_seed = flag_value(tuple(flags), "-seed")
    if int_flag(tuple(flags), "-jobs", 0) > 0 and given_seed not in (None, "0") and not travel.is_child():
        reporting.warn(
            f"-jobs with -seed={given_seed}: libFuzzer gives every job that seed, so each repeats "
            "the others' choices (a probe's two jobs evaluated 259 of 995 divergent inputs twice); "
            "leave -seed out, and each job draws its own"
        )
    malloc_limit = flag_value(tuple(flags), "-malloc_limit_mb")
    if malloc_limit not in (None, "0") and not travel.is_child():
        reporting.warn(
            f"-malloc_limit_mb={malloc_limit} does nothing here: libFuzzer's malloc hooks need a "
            "sanitizer's allocator, which Atheris' build has not; -rss_limit_mb limits memory (exit 71)"
        )
    flags, drawn = drawn_seed(tuple(flags), tuple(args.corpus))  # after ours: it stays as it was
    drawn_note = (
        f"libFuzzer's -seed={drawn}: drawn for this campaign (given no -seed, or -seed=0); "
        f"the same command with -seed={drawn} --seed={seed} repeats its choices"
        if drawn is not None
        else ""
    )
    bag_problem = None if args.seeds_from_bag is None else file_problem(args.seeds_from_bag)
    if bag_problem is not None:
        raise UsageError(f"--seeds-from-bag {args.seeds_from_bag}: {bag_problem}")
    try:  # libFuzzer refuses these after start-up with its status 1, the status of "divergences"
        check_path_flags(tuple(flags))
    except FolderUnwritable:
        raise
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    dictionary = flag_value(flags, "-dict")  # the last, as libFuzzer takes it
    if dictionary is not None:
        dict_problem = "an empty path" if not dictionary else file_problem(Path(dictionary))  # not "."
        if dict_problem is not None:
            raise UsageError(f"-dict={dictionary}: {dict_problem}")
        try:  # libFuzzer refuses a bad one only after start-up, with an exit status of its own
            check_dictionary(Path(dictionary))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    options = CampaignOptions(
        corpus=tuple(args.corpus),
        artifacts=args.artifacts,
        libfuzzer_flags=tuple(flags),
        forwarded=forwarded_options(args),
        seeds=args.seeds,
        seed=seed,
        stop_on_divergence=args.stop_on_divergence,
        progress=not args.no_progress,
        progress_interval=args.progress_interval,
        dictionary_file=dictionary,
        mutator=args.mutator,
        verbose=args.verbose,
        seeds_from_bag=args.seeds_from_bag,
        max_len=default_max_len(config.op, config.max_steps),
        drawn_note=drawn_note,
    )
    try:
        libfuzzer_argv(options)  # a word a -fork parent's shell would split: refused before start-up
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return run(config, options)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    job = os.environ.get(CHILD_ENV) == "1"  # a -jobs/-fork job (the campaign sets it for them later)
    try:
        if argv and argv[0] in SUBCOMMANDS:
            from fuzzer.cli_tools import (
                coverage_main,
                minimize_main,
                promote_main,
                replay_main,
                report_main,
                triage_main,
            )

            handler = {
                "show": _show_main,
                "replay": replay_main,
                "triage": triage_main,
                "minimize": minimize_main,
                "report": report_main,
                "promote": promote_main,
                "coverage": coverage_main,
                "export-bag": _export_bag_main,
                "view": _view_main,
            }[argv[0]]
            return handler(argv[1:])
        flags, rest = split_flags(argv)
        from fuzzer.processes import flag_value

        help_flag = flag_value(tuple(flags), "-help")
        if help_flag is not None and help_flag.strip() not in ("", "0"):
            return _libfuzzer_help()
        parser = campaign_parser()
        known, extra = parser.parse_known_args(rest)
        if not flags and known.corpus and all(p.is_file() for p in known.corpus):  # fuzz_diff.py CRASH...
            from fuzzer.cli_tools import replay_main

            return replay_main(rest)
        for path in known.corpus:
            if _missing_artifact(path):
                raise UsageError(f"{path}: no such file (not fuzzed into as a new corpus folder)")
        if extra:  # as parse_args says it
            parser.error(f"unrecognized arguments: {' '.join(extra)}")
        return campaign_main(flags, known)
    except FolderUnwritable as exc:
        reporting.terminal().write(f"fuzz_diff.py: error: {reporting.message(str(exc))}\n")
        return WRITE_FAILED_EXIT
    except (UsageError, ConfigError) as exc:
        reporting.terminal().write(f"fuzz_diff.py: error: {reporting.message(str(exc))}\n")
        return 2
    except BrokenPipeError:  # `... | head`: the reader is gone; end quietly, like other tools
        _silence_stdout()
        return 141
    except ArtifactsUnwritable:  # said (the dry run's first input, in this process before libFuzzer)
        return WRITE_FAILED_EXIT
    except OSError as exc:  # a full disk or a read-only folder (a campaign's seeds, a tool's output)
        where = f"{exc.filename}: " if exc.filename else ""
        reporting.terminal().write(
            f"fuzz_diff.py: error: {reporting.shown(f'{where}{exc.strerror or exc}')}\n"
        )
        _silence_stdout()
        return WRITE_FAILED_EXIT
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM before libFuzzer runs (then Atheris ends it)
        term = terminated()
        reporting.terminal().write(f"fuzz_diff.py: {'terminated' if term else 'interrupted'}\n")
        if job:  # in its start-up: the status of libFuzzer's interrupted job (a -fork parent stops)
            return INTERRUPTED_EXIT
        return TERM_EXIT if term else INT_EXIT


def _show_main(argv: Sequence[str]) -> int:
    from fuzzer.triage.show import show_main

    return show_main(argv)


def _libfuzzer_help() -> int:
    """``-help=1``: libFuzzer's own flag list, and nothing else, as libFuzzer does (it ran the
    dry run, wrote seeds and crash files, and needed a corpus first)."""
    import atheris

    sys.stdout.write("fuzz_diff.py passes these libFuzzer flags on (its own options: --help):\n")
    sys.stdout.flush()
    atheris.Setup([sys.argv[0] or "fuzz_diff.py", "-help=1"], lambda data: None)
    atheris.Fuzz()
    return 0


def _export_bag_main(argv: Sequence[str]) -> int:
    from fuzzer.ros.bags import export_bag_main

    return export_bag_main(argv)


def _view_main(argv: Sequence[str]) -> int:
    from fuzzer.ros.view import view_main

    return view_main(argv)


def _missing_artifact(path: Path) -> bool:
    """A path named like a crash file that does not exist (a typo, not a new corpus folder)."""
    from fuzzer.input.paths import looks_like_artifact

    return looks_like_artifact(path) and not path.exists() and not path.is_symlink()


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush cannot fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


__all__ = ["DEFAULT_MSG_TYPE", "main"]
