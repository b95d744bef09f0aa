"""The options of the command line (``fuzzer.cli``): the campaign's parser, the replay parser,
the configuration options the subcommands share (``fuzzer.cli_tools``), and the run
configuration made of them."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fuzzer.execution.session import RunConfig
from fuzzer.execution.tolerance import DECIMAL, Tolerance, default_tolerance
from fuzzer.input.mapping import OPS
from fuzzer.input.paths import given_path
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
  2   usage error, or libFuzzer's own error (the summary says so)
  70  a timeout (libFuzzer's -timeout_exitcode; also when a -fork/-jobs worker timed out)
  71  out of memory (libFuzzer's -rss_limit_mb)
  74  a folder could not be written (a full disk, a read-only mount, a corpus folder
      removed during the campaign), with a message naming it and any divergent input it
      could not save
  77  a crash: a target died (deadly signal) or --stop-on-divergence stopped at one
      (libFuzzer's -error_exitcode)
  130 interrupted (Ctrl-C)       143 terminated (SIGTERM); both print the summary once fuzzing began
  -jobs/-fork: the workers' crash, oom and timeout files make it 77, 71 or 70 (libFuzzer's
      supervisor says 1 or 0); a 1 no file explains reads "a job failed" in the summary
  any other status is libFuzzer's own
"""

MUTATORS = ("rrosfuzz", "weights", "libfuzzer")
FORWARDED_SEED = "--generation-seed"  # --seed, in the argv of libFuzzer's child processes
"""``--mutator``'s choices (the benchmark drivers pass one on)."""


def seconds(text: str) -> float:
    """A positive, finite number of seconds (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be a positive, finite number of seconds")
    if not DECIMAL.fullmatch(text):  # float() takes 1_0 for 10, and other scripts' digits
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds")
    return value


class UsageError(Exception):
    """Reported as ``error: ...`` with exit status 2."""


def split_flags(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """(libFuzzer flags, everything else)."""
    flags, rest = [], []
    for arg in argv:
        if arg.startswith("-") and not arg.startswith("--") and arg not in ("-h",) and len(arg) > 1:
            flags.append(arg)
        else:
            rest.append(arg)
    return flags, rest


def config_options(parser: argparse.ArgumentParser) -> None:
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
        help="two targets: native, python, ros_tf or module:attribute, e.g. "
        "adapters.pinocchio_adapter:api (default native,python)",
    )
    parser.add_argument(
        "--tolerance",
        default=None,
        help="reasonable difference: 1e-6 (m and rad) or m=1e-5,rad=1e-6 (default 1e-6; 1e-5 for --op ik)",
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
    trust_option(parser)


def trust_option(parser: argparse.ArgumentParser, overrides: bool = True) -> None:
    """``--trust-sidecar``; ``overrides``: the parser has ``--targets``, ``--robot``, ``--msg-path``."""
    parser.add_argument(
        "--trust-sidecar",
        action="store_true",
        help="import the targets a crash file's sidecar (or a corpus manifest) names, even if they are "
        "not the builtins, and read the robot file and message folders it names even outside the "
        "working directory and the file's folder; without it such a file is refused"
        + (" unless --targets (--robot, --msg-path) is given" if overrides else ""),
    )


def campaign_robot_option(parser: argparse.ArgumentParser, kept: str = "") -> None:
    """``--robot`` of the commands that read one crash file's robot (``promote``, ``export-bag``,
    ``view``): the campaign's file, for a sidecar path relative to another working folder."""
    parser.add_argument(
        "--robot",
        default=None,
        help="the campaign's URDF file (or robot name), when the sidecar's path was relative to "
        f"another working folder; it must be the campaign's file (SHA-256){kept}",
    )


def campaign_parser() -> argparse.ArgumentParser:
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
    parser.add_argument(
        "corpus", nargs="+", type=given_path, help="corpus folder(s); the first receives new seeds"
    )
    config_options(parser)
    parser.add_argument(
        "--seeds",
        type=int,
        default=None,
        help="Hypothesis seeds to generate into the corpus (default 32 when it is empty; at most 100000)",
    )
    parser.add_argument(
        "--seed", type=int, default=None, help="seed of the seed generation (default: -seed or 0)"
    )
    # --seed as it is handed to libFuzzer's child processes: libFuzzer warns "did you mean
    # '-seed=N'" on a --seed=N in its argv, as if ours were its own flag mistyped
    parser.add_argument(FORWARDED_SEED, dest="seed", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument(
        "--seeds-from-bag",
        type=given_path,
        default=None,
        metavar="FILE.bag",
        help="write the bag's messages of the campaign's type (any topic) into the corpus as seeds "
        "(ROS 1 from apt: scripts/ros-ensure.sh)",
    )
    parser.add_argument(
        "--artifacts", type=given_path, default=Path("artifacts"), help="crash files (default artifacts/)"
    )
    parser.add_argument(
        "--stop-on-divergence",
        action="store_true",
        help="the first divergence is a libFuzzer crash (exit 77)",
    )
    parser.add_argument(
        "--mutator",
        choices=MUTATORS,
        default="rrosfuzz",
        help="rrosfuzz: the structured mutators, chosen by a bandit beside fresh space-filling "
        "inputs, with float comparisons of the Python targets as features (default); weights: "
        "the structured mutators by fixed weights only (a baseline: the engine before the "
        "bandit); libfuzzer: libFuzzer's own byte mutator only (a baseline)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no live progress line")
    parser.add_argument(
        "--progress-interval",
        type=seconds,
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


def replay_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py replay", description="Replay crash files or folders; exit 1 if any still diverges."
    )
    parser.add_argument("paths", nargs="+", type=given_path)
    config_options(parser)
    parser.add_argument("--no-progress", action="store_true", help="accepted for symmetry; replay shows none")
    return parser


def config_from(
    args: argparse.Namespace, *, overrides_only: bool = False
) -> tuple[RunConfig, dict[str, Any]]:
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
        if len(args.targets.split(",")) != 2:  # native,python, : a third name left out?
            raise UsageError(f"--targets {args.targets!r}: an empty name between its commas")
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
        given["max_steps"] = max_steps_of(args.max_steps)
    config = RunConfig(**given)
    if "tolerance" not in given:
        config = replace(config, tolerance=default_tolerance(config.op))
    return config, given


def max_steps_of(text: Any) -> int:
    """``--max-steps``: an integer in 1..MAX_STEPS_LIMIT."""
    if not re.fullmatch(r"\s*[+-]?\d+\s*", str(text), re.ASCII):  # int() takes 1_0 and other digits
        raise UsageError(f"--max-steps {text!r}: not an integer")
    value = int(str(text), 10)
    if not 1 <= value <= MAX_STEPS_LIMIT:
        raise UsageError(f"--max-steps {value}: must be from 1 to {MAX_STEPS_LIMIT}")
    return value


def forwarded_options(args: argparse.Namespace) -> tuple[str, ...]:
    """Our options as --name=value tokens, for libFuzzer's child processes."""
    out = []
    for name in (
        "robot",
        "tip_link",
        "op",
        "targets",
        "tolerance",
        "msg_type",
        "progress_interval",
        "mutator",
        "transport",
        "max_steps",
    ):
        value = getattr(args, name)
        if value is not None:
            out.append(f"--{name.replace('_', '-')}={value}")
    if args.seed is not None:
        out.append(f"{FORWARDED_SEED}={args.seed}")
    out += [f"--msg-path={p}" for p in args.msg_path]
    out += [f"--artifacts={args.artifacts.resolve()}"]
    for flag in ("no_filter", "stop_on_divergence", "no_progress"):
        if getattr(args, flag):
            out.append(f"--{flag.replace('_', '-')}")
    if args.seeds is not None:
        out.append(f"--seeds={args.seeds}")
    return tuple(out)
