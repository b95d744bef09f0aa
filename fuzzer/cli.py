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
import math
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fuzzer.execution.session import ConfigError, RunConfig
from fuzzer.execution.tolerance import Tolerance, default_tolerance
from fuzzer.input.mapping import DEFAULT_MSG_TYPE, OPS
from fuzzer.scenario.steps import MAX_STEPS, MAX_STEPS_LIMIT
from robot_api import robots

SUBCOMMANDS = ("show", "replay", "triage", "minimize", "report", "promote", "coverage", "export-bag", "view")
COMMANDS_HELP = """\
commands (fuzz_diff.py COMMAND --help for each):
  show FILE...          print crash or corpus files' test cases as JSON (read as data, nothing run)
  replay PATH...        replay crash files or folders; exit 1 if any still diverges
  triage DIR|CRASH...   buckets of an artifacts folder, most severe first (--json)
  minimize CRASH...     shrink crash files to the simplest input with the same signature
  report DIR            HTML report of an artifacts folder (-o OUT)
  promote CRASH...      add crash files to the regression suite (--fixed)
  coverage CORPUS...    line and branch coverage of python_impl over a corpus
  export-bag CRASH      a divergence as a ROS bag for `rosbag play` (-o OUT.bag; ROS 1 from apt)
  view CRASH            a divergence in RViz, both targets' arms overlaid (ROS 1 + RViz from apt)

exit status of a campaign:
  0   no new divergence          1   new divergences (crash files written by this run)
  2   usage error                70  a timeout (libFuzzer's -timeout_exitcode; also when
                                     a -fork/-jobs worker timed out)
  77  a crash: a target died (deadly signal) or --stop-on-divergence stopped at one
      (libFuzzer's -error_exitcode); any other status is libFuzzer's own
"""


def _seconds(text: str) -> float:
    """A positive, finite number of seconds (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be a positive, finite number of seconds")
    return value


class UsageError(Exception):
    """Reported as ``error: ...`` with exit status 2."""


def _split(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """(libFuzzer flags, everything else)."""
    flags, rest = [], []
    for arg in argv:
        if arg.startswith("-") and not arg.startswith("--") and arg not in ("-h",) and len(arg) > 1:
            flags.append(arg)
        else:
            rest.append(arg)
    return flags, rest


def _config_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--robot",
        default=None,
        help=f"URDF file or robot name ({', '.join(robots.known_robots())}); default {robots.DEFAULT_ROBOT}",
    )
    parser.add_argument(
        "--tip-link", default=None, help="last link of the chain (default: the contract's rule)"
    )
    parser.add_argument(
        "--op",
        choices=OPS,
        default=None,
        help="operation to fuzz (default move: the paper's arm.go(); scenario: scripts of calls on "
        "one live MoveGroup, docs/engine.md)",
    )
    parser.add_argument(
        "--max-steps",
        default=None,
        metavar="N",
        help=f"--op scenario: at most N steps per test case, 1..{MAX_STEPS_LIMIT} (default {MAX_STEPS})",
    )
    parser.add_argument(
        "--targets",
        default=None,
        help="two targets: native, python or module:attribute (default native,python)",
    )
    parser.add_argument(
        "--tolerance",
        default=None,
        help="reasonable difference: 1e-6 (m and rad) or m=1e-5,rad=1e-6 (default 1e-6)",
    )
    parser.add_argument(
        "--msg-type",
        default=None,
        help="ROS message type of the inputs (default sensor_msgs/JointState; "
        "geometry_msgs/PoseStamped for ik)",
    )
    parser.add_argument(
        "--msg-path",
        action="append",
        default=[],
        metavar="DIR",
        help="extra .msg roots laid out as DIR/<pkg>/msg/<Type>.msg (e.g. /usr/share)",
    )
    parser.add_argument(
        "--no-filter", action="store_true", help="keep NaN, inf and absurd values (robustness campaigns)"
    )
    parser.add_argument(
        "--transport",
        choices=("inprocess", "ros"),
        default=None,
        help="how targets run: inprocess (default), or ros: each target a ROS node on a master "
        "(ROS_MASTER_URI's, else a new one on a free loopback port; docs/engine.md)",
    )
    _trust_option(parser)


def _trust_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--trust-sidecar",
        action="store_true",
        help="import the targets a crash file's sidecar (or a corpus manifest) names, even if they are "
        "not the builtins; without it such a file is refused unless --targets is given",
    )


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py",
        description="Differential fuzzing of two implementations of one robot motion API "
        "(libFuzzer via Atheris). Single-dash arguments go to libFuzzer.",
        epilog=COMMANDS_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        usage="fuzz_diff.py CORPUS_DIR [CORPUS_DIR ...] [-libfuzzer_flag=value ...] [options]\n"
        "       fuzz_diff.py CRASH_FILE [options]\n"
        f"       fuzz_diff.py {{{','.join(SUBCOMMANDS)}}} ... (see below)",
    )
    parser.add_argument("corpus", nargs="+", type=Path, help="corpus folder(s); the first receives new seeds")
    _config_options(parser)
    parser.add_argument(
        "--seeds",
        type=int,
        default=None,
        help="Hypothesis seeds to generate into the corpus (default 32 when it is empty)",
    )
    parser.add_argument(
        "--seed", type=int, default=None, help="seed of the seed generation (default: -seed or 0)"
    )
    parser.add_argument(
        "--seeds-from-bag",
        type=Path,
        default=None,
        metavar="FILE.bag",
        help="write the bag's messages of the campaign's type (any topic) into the corpus as seeds "
        "(ROS 1 from apt: scripts/ros-ensure.sh)",
    )
    parser.add_argument(
        "--artifacts", type=Path, default=Path("artifacts"), help="crash files (default artifacts/)"
    )
    parser.add_argument(
        "--stop-on-divergence",
        action="store_true",
        help="the first divergence is a libFuzzer crash (exit 77)",
    )
    parser.add_argument(
        "--mutator",
        choices=("rrosfuzz", "weights", "libfuzzer"),
        default="rrosfuzz",
        help="rrosfuzz: the structured mutators, chosen by a bandit beside fresh space-filling "
        "inputs, with float comparisons of the Python targets as features (default); weights: "
        "the structured mutators by fixed weights only (a baseline: the engine before the "
        "bandit); libfuzzer: libFuzzer's own byte mutator only (a baseline)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no live progress line")
    parser.add_argument(
        "--progress-interval",
        type=_seconds,
        default=5.0,
        help="seconds between progress updates (default 5)",
    )
    parser.add_argument(
        "--verbose",
        action="store_true",
        help="show libFuzzer's own per-input lines (NEW, REDUCE, pulse); hidden by default "
        "(-verbosity=0), crash and timeout reports always show",
    )
    return parser


def _replay_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py replay", description="Replay crash files or folders; exit 1 if any still diverges."
    )
    parser.add_argument("paths", nargs="+", type=Path)
    _config_options(parser)
    parser.add_argument("--no-progress", action="store_true", help="accepted for symmetry; replay shows none")
    return parser


def _config(args: argparse.Namespace, *, overrides_only: bool = False) -> tuple[RunConfig, dict[str, Any]]:
    """A RunConfig from the options, and the options given explicitly (for replay overrides)."""
    given: dict[str, Any] = {}
    if args.robot is not None:
        given["robot"] = args.robot
    if args.tip_link is not None:
        given["tip_link"] = args.tip_link
    if args.op is not None:
        given["op"] = args.op
    if args.targets is not None:
        specs = tuple(s.strip() for s in args.targets.split(",") if s.strip())
        if len(specs) == 2 and specs[0] == specs[1]:
            raise UsageError(
                f"--targets names {specs[0]!r} twice: a differential campaign needs two different targets"
            )
        if len(specs) != 2:
            raise UsageError(f"--targets needs exactly two targets, got {len(specs)}: {args.targets!r}")
        given["targets"] = specs
    if args.tolerance is not None:
        try:
            given["tolerance"] = Tolerance.parse(args.tolerance)
        except ValueError as exc:
            raise UsageError(f"--tolerance: {exc}") from None
    if args.msg_type is not None:
        given["msg_type"] = args.msg_type
    if args.msg_path:
        for root in args.msg_path:
            if not Path(root).is_dir():
                raise UsageError(f"--msg-path {root}: not a folder")
        given["msg_path"] = tuple(args.msg_path)
    if args.no_filter:
        given["filtering"] = False
    if args.transport is not None:
        given["transport"] = args.transport
    if args.max_steps is not None:
        given["max_steps"] = _max_steps(args.max_steps)
    config = RunConfig(**given)
    if "tolerance" not in given:
        config = replace(config, tolerance=default_tolerance(config.op))
    return config, given


def _max_steps(text: Any) -> int:
    """``--max-steps``: an integer in 1..MAX_STEPS_LIMIT."""
    try:
        value = int(str(text), 10)
    except ValueError:
        raise UsageError(f"--max-steps {text!r}: not an integer") from None
    if not 1 <= value <= MAX_STEPS_LIMIT:
        raise UsageError(f"--max-steps {value}: must be from 1 to {MAX_STEPS_LIMIT}")
    return value


def _forwarded(args: argparse.Namespace) -> tuple[str, ...]:
    """Our options as --name=value tokens, for libFuzzer's child processes."""
    out = []
    for name in (
        "robot",
        "tip_link",
        "op",
        "targets",
        "tolerance",
        "msg_type",
        "seed",
        "progress_interval",
        "mutator",
        "transport",
        "max_steps",
    ):
        value = getattr(args, name)
        if value is not None:
            out.append(f"--{name.replace('_', '-')}={value}")
    out += [f"--msg-path={p}" for p in args.msg_path]
    out += [f"--artifacts={args.artifacts.resolve()}"]
    for flag in ("no_filter", "stop_on_divergence", "no_progress"):
        if getattr(args, flag):
            out.append(f"--{flag.replace('_', '-')}")
    if args.seeds is not None:
        out.append(f"--seeds={args.seeds}")
    return tuple(out)


def campaign_main(argv: Sequence[str]) -> int:
    from fuzzer.campaign import CampaignOptions, run

    flags, rest = _split(argv)
    args = _parser().parse_args(rest)
    # Files next to libFuzzer flags are libFuzzer's business (-minimize_crash, running single inputs).
    if args.seeds is not None and args.seeds < 0:
        raise UsageError("--seeds must be >= 0")
    from fuzzer.artifacts import travel

    # settings travel: from a crash file's sidecar (-minimize_crash), else the corpus manifest
    if not travel.is_child() and not travel.adopt_sidecar(args, [p for p in args.corpus if p.is_file()]):
        travel.adopt_manifest(args, [p for p in args.corpus if p.is_dir()])
    if not travel.is_child() and args.max_steps is None:
        from fuzzer.artifacts.manifest import recorded_max_steps

        args.max_steps = recorded_max_steps(args.corpus, args.op)
    files = [p for p in args.corpus if p.is_file()]
    if files and len(files) < len(args.corpus) and not travel.is_child():  # libFuzzer: "Not a directory"
        raise UsageError(
            f"{files[0]}: a file among corpus folders; a campaign takes folders "
            "(`fuzz_diff.py replay FILE` replays a file, `fuzz_diff.py show FILE` prints it)"
        )
    config, _ = _config(args)
    if not travel.is_child():  # bad paths: exit 2 with a message; a corpus of another robot/op: refused
        folders = travel.prepare_campaign(args.corpus, args.artifacts)
        travel.check_manifests(folders, config)
    seed = args.seed
    if seed is None:
        value = next((f.split("=", 1)[1] for f in flags if f.startswith("-seed=")), "0")
        seed = int(value) if value.lstrip("-").isdigit() else 0
    if args.seeds_from_bag is not None and not args.seeds_from_bag.is_file():
        raise UsageError(f"--seeds-from-bag {args.seeds_from_bag}: no such file")
    dictionary = next((f.split("=", 1)[1] for f in flags if f.startswith("-dict=")), None)
    if dictionary is not None and not Path(dictionary).is_file():
        raise UsageError(f"-dict={dictionary}: no such file")
    options = CampaignOptions(
        corpus=tuple(args.corpus),
        artifacts=args.artifacts,
        libfuzzer_flags=tuple(flags),
        forwarded=_forwarded(args),
        seeds=args.seeds,
        seed=seed,
        stop_on_divergence=args.stop_on_divergence,
        progress=not args.no_progress,
        progress_interval=args.progress_interval,
        dictionary_file=dictionary,
        mutator=args.mutator,
        verbose=args.verbose,
        seeds_from_bag=args.seeds_from_bag,
    )
    return run(config, options)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
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
        flags, rest = _split(argv)
        if not flags:
            known, _ = _parser().parse_known_args(rest)
            if known.corpus and all(p.is_file() for p in known.corpus):  # fuzz_diff.py CRASH...
                from fuzzer.cli_tools import replay_main

                return replay_main(rest)
        known, _ = _parser().parse_known_args(rest)
        for path in known.corpus:
            if _missing_artifact(path):
                raise UsageError(f"{path}: no such file (not fuzzed into as a new corpus folder)")
        return campaign_main(argv)
    except (UsageError, ConfigError) as exc:
        sys.stderr.write(f"fuzz_diff.py: error: {exc}\n")
        return 2
    except BrokenPipeError:  # `... | head`: the reader is gone; end quietly, like other tools
        _silence_stdout()
        return 141


def _show_main(argv: Sequence[str]) -> int:
    from fuzzer.triage.show import show_main

    return show_main(argv)


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
