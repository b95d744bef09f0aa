"""Command line of RROSFuzz (``python fuzz_diff.py`` and the ``rrosfuzz`` script).

    fuzz_diff.py CORPUS_DIR [CORPUS_DIR...] [-libfuzzer_flag=value ...] [--options]
    fuzz_diff.py CRASH_FILE [--options]          replay one file
    fuzz_diff.py replay PATH... [--options]      replay files or folders (exit 1 if any diverges)
    fuzz_diff.py triage DIR [--json]             buckets of an artifacts folder, most severe first
    fuzz_diff.py minimize CRASH... [--budget N]  shrink to the simplest input with the same signature
    fuzz_diff.py report DIR [-o OUT]             HTML report with the paper's tables and figures
    fuzz_diff.py promote CRASH [--fixed]         add to the regression suite (tests/regressions/)
    fuzz_diff.py coverage CORPUS... [--html DIR] line and branch coverage of python_impl

Arguments starting with a single dash go to libFuzzer unchanged
(``-max_total_time=60``, ``-runs=N``, ``-seed=N``, ``-jobs=N``, ``-fork=N``,
``-dict=FILE``, ``-merge=1``, ...). Bad arguments exit with status 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.mapping import DEFAULT_MSG_TYPE, OPS
from fuzzer.session import ConfigError, RunConfig
from fuzzer.tolerance import Tolerance, default_tolerance
from robot_api import robots

SUBCOMMANDS = ("replay", "triage", "minimize", "report", "promote", "coverage")


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
        "--op", choices=OPS, default=None, help="operation to fuzz (default move: the paper's arm.go())"
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


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py",
        description="Differential fuzzing of two implementations of one robot motion API "
        "(libFuzzer via Atheris). Single-dash arguments go to libFuzzer.",
        epilog="Replay: fuzz_diff.py CRASH_FILE, or fuzz_diff.py replay PATH...",
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
        "--artifacts", type=Path, default=Path("artifacts"), help="crash files (default artifacts/)"
    )
    parser.add_argument(
        "--stop-on-divergence",
        action="store_true",
        help="the first divergence is a libFuzzer crash (exit 77)",
    )
    parser.add_argument(
        "--mutator",
        choices=("rrosfuzz", "libfuzzer"),
        default="rrosfuzz",
        help="rrosfuzz: the structured mutators (default); libfuzzer: libFuzzer's own byte "
        "mutator only (a baseline)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no live progress lines")
    parser.add_argument("--progress-interval", type=float, default=5.0, help="seconds between progress lines")
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
    config = RunConfig(**given)
    if "tolerance" not in given:
        config = replace(config, tolerance=default_tolerance(config.op))
    return config, given


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


def replay_main(argv: Sequence[str]) -> int:
    from fuzzer.replay import expand, replay_file

    args = _replay_parser().parse_args(argv)
    base, given = _config(args)
    sessions: dict[Any, Any] = {}
    diverging = 0
    files = expand(args.paths)
    if not files:
        raise UsageError("nothing to replay")
    for path in files:
        if not path.exists():
            raise UsageError(f"{path}: no such file")
        result = replay_file(path, base, given, sessions)
        diverging += result.diverges
        reporting.verdict(str(path), str(result.result), result.detail)
    return 1 if diverging else 0


def triage_main(argv: Sequence[str]) -> int:
    from fuzzer import triage

    parser = argparse.ArgumentParser(prog="fuzz_diff.py triage", description="List divergence buckets.")
    parser.add_argument("directory", type=Path)
    parser.add_argument("--json", action="store_true", help="machine-readable output")
    args = parser.parse_args(argv)
    if not args.directory.is_dir():
        raise UsageError(f"{args.directory}: not a folder")
    buckets = triage.collect(args.directory)
    if args.json:
        reporting.out(triage.dumps(buckets))
    else:
        for line in triage.table(buckets):
            reporting.out(line)
    return 0


def minimize_main(argv: Sequence[str]) -> int:
    from fuzzer.artifacts import ArtifactStore, load_sidecar
    from fuzzer.minimize import Minimizer, joints_that_matter
    from fuzzer.session import Session
    from fuzzer.testcase import TestCaseError, decode

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py minimize",
        description="Shrink crash files to the simplest input with the same signature.",
    )
    parser.add_argument("paths", nargs="+", type=Path, help="crash files (with sidecars)")
    parser.add_argument("--budget", type=int, default=2000, help="evaluations per file (default 2000)")
    parser.add_argument(
        "-o",
        "--output",
        type=Path,
        default=None,
        help="folder for minimized files (default: next to each crash file)",
    )
    args = parser.parse_args(argv)
    if args.budget < 1:
        raise UsageError("--budget must be >= 1")
    sessions: dict[Any, Any] = {}
    for path in args.paths:
        sidecar = load_sidecar(path) if path.is_file() else None
        if sidecar is None or "signature" not in sidecar:
            raise UsageError(f"{path}: not a crash file with a sidecar")
        config = RunConfig.from_json(sidecar["config"])
        if config not in sessions:
            sessions[config] = Session.open(config)
        session = sessions[config]
        try:
            case = decode(path.read_bytes())
        except TestCaseError as exc:
            raise UsageError(f"{path}: {exc}") from None
        try:
            shrunk = Minimizer(session, args.budget).minimize(case, sidecar["signature"]["key"])
        except ValueError as exc:
            reporting.verdict(str(path), f"not minimized: {exc}")
            continue
        data = shrunk.case.encode()
        store = ArtifactStore(args.output or path.parent)
        out = dict(
            sidecar,
            testcase=shrunk.case.to_json(),
            minimized_from=path.name,
            joints_that_matter=joints_that_matter(shrunk.case, session.reference.joint_names),
            shrink={
                "evaluations": shrunk.evaluations,
                "accepted": shrunk.accepted,
                "complete": shrunk.complete,
            },
        )
        written = store.write(data, out)
        minimized = written.with_name("minimized-" + written.name.split("-", 1)[1])
        written.replace(minimized)
        written.with_name(written.name + ".json").replace(minimized.with_name(minimized.name + ".json"))
        reporting.verdict(
            str(path),
            f"minimized to {minimized}",
            f"{len(path.read_bytes())} -> {len(data)} bytes, {shrunk.evaluations} evaluations, "
            f"joints that matter: {', '.join(out['joints_that_matter']) or 'none'}"
            + ("" if shrunk.complete else ", budget exhausted"),
        )
    return 0


def report_main(argv: Sequence[str]) -> int:
    from fuzzer.report import write_report

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py report", description="Write a self-contained HTML report of an artifacts folder."
    )
    parser.add_argument("directory", type=Path)
    parser.add_argument("-o", "--output", type=Path, default=None, help="output folder (default DIR/report)")
    args = parser.parse_args(argv)
    if not args.directory.is_dir():
        raise UsageError(f"{args.directory}: not a folder")
    page = write_report(args.directory, args.output)
    reporting.out(f"report: {page}")
    return 0


def promote_main(argv: Sequence[str]) -> int:
    from fuzzer.regressions import SUITE, PromoteError, promote

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py promote", description="Add a crash file to the regression suite."
    )
    parser.add_argument("crash", type=Path)
    parser.add_argument("--fixed", action="store_true", help="it is fixed: the targets must agree on it")
    parser.add_argument("--note", default="", help="why it is kept")
    parser.add_argument("--suite", type=Path, default=SUITE, help=f"suite folder (default {SUITE})")
    args = parser.parse_args(argv)
    if not args.crash.is_file():
        raise UsageError(f"{args.crash}: no such file")
    try:
        done = promote(args.crash, args.fixed, args.note, args.suite)
    except PromoteError as exc:
        reporting.out(f"not promoted: {exc}")
        return 1
    reporting.out(f"promoted {done.path} (expect: {done.expect})")
    return 0


def coverage_main(argv: Sequence[str]) -> int:
    from fuzzer.coverage_report import measure

    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py coverage", description="Line and branch coverage of python_impl over a corpus."
    )
    parser.add_argument("corpus", nargs="+", type=Path)
    _config_options(parser)
    parser.add_argument("--html", type=Path, default=Path("coverage_html"), help="HTML output folder")
    args = parser.parse_args(argv)
    for path in args.corpus:
        if not path.exists():
            raise UsageError(f"{path}: no such file or folder")
    config, _ = _config(args)
    reporting.out(measure(list(args.corpus), config, args.html).line())
    return 0


def campaign_main(argv: Sequence[str]) -> int:
    from fuzzer.campaign import CampaignOptions, run

    flags, rest = _split(argv)
    args = _parser().parse_args(rest)
    # Files next to libFuzzer flags are libFuzzer's business (-minimize_crash, running single inputs).
    if args.seeds is not None and args.seeds < 0:
        raise UsageError("--seeds must be >= 0")
    config, _ = _config(args)
    seed = args.seed
    if seed is None:
        value = next((f.split("=", 1)[1] for f in flags if f.startswith("-seed=")), "0")
        seed = int(value) if value.lstrip("-").isdigit() else 0
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
    )
    return run(config, options)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv and argv[0] in SUBCOMMANDS:
            handler = {
                "replay": replay_main,
                "triage": triage_main,
                "minimize": minimize_main,
                "report": report_main,
                "promote": promote_main,
                "coverage": coverage_main,
            }[argv[0]]
            return handler(argv[1:])
        flags, rest = _split(argv)
        if not flags:
            known, _ = _parser().parse_known_args(rest)
            if len(known.corpus) == 1 and known.corpus[0].is_file():
                return replay_main(rest)
        return campaign_main(argv)
    except (UsageError, ConfigError) as exc:
        sys.stderr.write(f"fuzz_diff.py: error: {exc}\n")
        return 2


__all__ = ["DEFAULT_MSG_TYPE", "main"]
