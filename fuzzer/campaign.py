"""Running a campaign under libFuzzer (Atheris).

Order matters: the Python targets and the oracle are imported inside
``atheris.instrument_imports`` before anything else loads them, the feature
counters are reserved before ``atheris.Fuzz()``, and the argv handed to Atheris
carries our options as ``--name=value`` tokens, which libFuzzer ignores but
copies to the child processes of ``-fork``/``-jobs``/``-merge``.
"""

from __future__ import annotations

import contextlib
import datetime
import hashlib
import math
import os
import random
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.artifacts import ArtifactStore, atomic_write, clean_temporaries
from fuzzer.divlog import CampaignLog
from fuzzer.session import RunConfig, Session, outcome_json, versions
from fuzzer.targets import module_of
from fuzzer.testcase import TestCase, TestCaseError, decode

CHILD_ENV = "RROSFUZZ_CHILD"
DEFAULT_FLAGS = {"-max_len": "16384", "-timeout": "20"}


@dataclass(frozen=True)
class CampaignOptions:
    """What the CLI hands over (beyond the run configuration)."""

    corpus: tuple[Path, ...]
    artifacts: Path
    libfuzzer_flags: tuple[str, ...]
    forwarded: tuple[str, ...]
    seeds: int | None
    seed: int
    stop_on_divergence: bool
    progress: bool
    progress_interval: float
    dictionary_file: str | None
    mutator: str = "rrosfuzz"


def instrument(config: RunConfig) -> None:
    """Import the Python targets and the oracle with Atheris coverage instrumentation."""
    import atheris

    names = sorted({module_of(spec) for spec in config.targets} - {"native"} | {"fuzzer.oracle"})
    fresh = [n for n in names if n not in sys.modules]
    if fresh:
        with atheris.instrument_imports(include=fresh):
            for name in fresh:
                with contextlib.suppress(Exception):  # a bad target is reported when it is loaded
                    __import__(name)


def parse_dictionary(path: str) -> list[str | float]:
    """Tokens of a libFuzzer -dict file (``name="value"`` or ``"value"`` lines)."""
    tokens: list[str | float] = []
    for raw in Path(path).read_text(encoding="utf-8", errors="replace").splitlines():
        line = raw.strip()
        if not line or line.startswith("#") or '"' not in line:
            continue
        body = line[line.index('"') + 1 : line.rindex('"')]
        text = body.encode("latin-1", "backslashreplace").decode("unicode_escape", "replace")
        try:
            tokens.append(float(text))
        except ValueError:
            tokens.append(text)
    return tokens


def field_types(session: Session, msg_type: str, prefix: str = "") -> dict[str, str]:
    """Dotted path -> ROS builtin type of every mutable leaf (arrays of messages are left out)."""
    out: dict[str, str] = {}
    for f in session.registry.get(msg_type).fields:
        path = f"{prefix}{f.name}"
        suffix = "" if not f.is_array else ("[]" if f.length is None else f"[{f.length}]")
        if f.is_builtin:
            out[path] = f.type + suffix
        elif not f.is_array:
            out.update(field_types(session, f.type, path + "."))
    return out


def interesting_values(session: Session) -> list[float]:
    """Joint limits and the tolerance band around them: where divergences live."""
    eps = (0.0, 1e-9, 1e-6, 5e-5, 1e-4, 1.5e-4)
    values: list[float] = []
    for lim in session.reference.joint_limits:
        for bound in (lim.lower, lim.upper):
            if math.isfinite(bound):
                values.extend(bound + s * e for e in eps for s in (-1.0, 1.0))
    return values


def make_seeds(session: Session, n: int, seed: int) -> list[TestCase]:
    """n seeds from Hypothesis strategies of the message definition, with robot-aware hints."""
    from fuzzer.mapping import seed_hints
    from fuzzer.seeds import generate_seeds
    from fuzzer.strategies import strategy_for

    msg_type = session.config.message_type
    strategy = strategy_for(
        session.registry,
        msg_type,
        hints=seed_hints(msg_type, session.facts()),
        allow_special_floats=not session.config.filtering,
    )
    messages = generate_seeds(strategy, n, seed)
    return [TestCase(msg_type, m, sequence=i, origin="hypothesis") for i, m in enumerate(messages)]


def write_seeds(corpus: Path, seeds: list[TestCase]) -> None:
    for case in seeds:
        data = case.encode()
        atomic_write(corpus / f"seed-{case.sequence:05d}-{hashlib.sha1(data).hexdigest()[:10]}", data)


def prescan(session: Session, corpus: tuple[Path, ...]) -> tuple[int, list[TestCase]]:
    """Warn about every corpus file that is not a valid test case of this campaign.

    libFuzzer still feeds them in; they are skipped as malformed. Returns
    (number of usable files, the generated seeds found among them).
    """
    usable, seeds = 0, []
    msg_type = session.config.message_type
    for directory in corpus:
        clean_temporaries(directory)
        for path in sorted(p for p in directory.iterdir() if p.is_file() and not p.name.startswith(".")):
            try:
                case = decode(path.read_bytes())
                if case.msg_type != msg_type:
                    raise TestCaseError(f"message type {case.msg_type}, this campaign fuzzes {msg_type}")
                session.registry.validate(msg_type, case.message)
            except (OSError, ValueError) as exc:
                reporting.warn(f"skipping corpus file {path}: {exc}")
                continue
            usable += 1
            if case.origin == "hypothesis":
                seeds.append(case)
    return usable, seeds


def libfuzzer_mutate(data: bytes, max_size: int) -> bytes:
    """libFuzzer's own mutator. Looked up at each call: Atheris replaces ``Mutate`` when
    ``Fuzz()`` starts, and the version bound before that exits the process."""
    import atheris

    return atheris.Mutate(data, max_size)  # type: ignore[no-any-return]


def run(config: RunConfig, options: CampaignOptions) -> int:
    """Run a campaign; returns only if libFuzzer does (it usually exits the process)."""
    import atheris

    instrument(config)
    from fuzzer import mutators
    from fuzzer.guidance import Features
    from fuzzer.harness import Harness

    session = Session.open(config)
    child = os.environ.get(CHILD_ENV) == "1"
    options.artifacts.mkdir(parents=True, exist_ok=True)
    folders = tuple(p for p in options.corpus if not p.is_file())
    for directory in folders:
        directory.mkdir(parents=True, exist_ok=True)
    store = ArtifactStore(options.artifacts)

    usable, seeds = prescan(session, folders) if not child else (1, [])
    wanted = (
        options.seeds
        if options.seeds is not None
        else (0 if usable or len(folders) < len(options.corpus) else 32)
    )
    if wanted and not child and folders:
        generated = make_seeds(session, wanted, options.seed)
        write_seeds(folders[0], generated)
        seeds = generated + seeds
        reporting.info(
            f"wrote {len(generated)} seeds from Hypothesis ({config.message_type}) to {folders[0]}"
        )
    if not seeds:
        seeds = make_seeds(session, 8, options.seed)  # in memory, to restart from damaged inputs

    limits = session.reference.joint_limits
    lower = tuple(lim.lower for lim in limits)
    upper = tuple(lim.upper for lim in limits)
    types = field_types(session, config.message_type)
    interesting = interesting_values(session)
    dictionary: list[str | float] = [*session.reference.joint_names, *session.reference.link_names]
    if options.dictionary_file:
        dictionary += parse_dictionary(options.dictionary_file)
    from fuzzer.mapping import FOCUS

    focus = FOCUS.get(config.message_type, ())

    context = mutators.MutationContext(
        rng=random.Random(options.seed),
        field_types=types,
        interesting_floats=tuple(interesting),
        dictionary=tuple(dictionary),
        allow_special=not config.filtering,
        libfuzzer_mutate=libfuzzer_mutate,
        focus=focus,
    )

    recorded_versions = versions()
    digest = session.robot_digest()

    def sidecar(case: TestCase, data: bytes, ev: Any) -> dict[str, Any]:
        return build_sidecar(session, case, data, ev, recorded_versions, digest)

    features = Features()
    harness = Harness(
        evaluator=session.evaluator(),
        store=store,
        features=features,
        context=context,
        sidecar=sidecar,
        seeds=seeds,
        lower=lower,
        upper=upper,
        stop_on_divergence=options.stop_on_divergence,
        log=CampaignLog(options.artifacts),
        joint_names=tuple(session.reference.joint_names),
    )
    total = _flag_value(options.libfuzzer_flags, "-max_total_time")
    progress = reporting.Progress(
        harness.stats,
        features,
        options.progress_interval,
        float(total) if total else None,
        enabled=options.progress,
    )
    harness.on_exec = progress.tick

    from fuzzer.exit_hook import on_exit

    started = time.time()

    def finish() -> None:
        progress.close()
        if harness.stats.execs:
            harness.maybe_snapshot(force=True)
        new_files = [str(p) for p in store.crash_files() if p.stat().st_mtime >= started]
        reporting.summary(
            harness.stats,
            len(features.seen),
            str(options.artifacts),
            [str(c) for c in options.corpus],
            new_files,
        )

    on_exit(finish)
    reporting.info(
        f"fuzzing {config.op} on {session.urdf.name} ({session.reference.dof} joints): "
        f"{config.targets[0]} vs {config.targets[1]}, {config.message_type}, tolerance "
        f"{config.tolerance.metres:g} m / {config.tolerance.radians:g} rad, artifacts in {options.artifacts}"
    )
    argv = libfuzzer_argv(options)
    os.environ[CHILD_ENV] = "1"
    os.environ["PATH"] = os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", "")
    if options.mutator == "libfuzzer":  # baseline: libFuzzer's own byte-level mutations of the JSON
        atheris.Setup(argv, harness.test_one_input)
    else:
        atheris.Setup(
            argv, harness.test_one_input, custom_mutator=harness.mutate, custom_crossover=harness.crossover
        )
    atheris.Fuzz()
    return 0


def _flag_value(flags: tuple[str, ...], name: str) -> str | None:
    for flag in flags:
        key, _, value = flag.partition("=")
        if key == name:
            return value
    return None


def libfuzzer_argv(options: CampaignOptions) -> list[str]:
    """argv for Atheris: our script (absolute, for re-execution), libFuzzer flags with our
    defaults, our options as --name=value tokens, the corpus folders."""
    script = os.path.abspath(sys.argv[0])
    flags = list(options.libfuzzer_flags)
    for name, value in DEFAULT_FLAGS.items():
        if _flag_value(options.libfuzzer_flags, name) is None:
            flags.append(f"{name}={value}")
    if _flag_value(options.libfuzzer_flags, "-artifact_prefix") is None:
        flags.append(f"-artifact_prefix={options.artifacts.resolve()}/")
    return [script, *flags, *options.forwarded, *(str(c) for c in options.corpus)]


def build_sidecar(
    session: Session, case: TestCase, data: bytes, ev: Any, recorded: dict[str, str], digest: str
) -> dict[str, Any]:
    """Everything needed to understand and replay one divergence."""
    comparison = {
        **asdict(ev.comparison),
        "kind": str(ev.comparison.kind),
        "joints": list(ev.comparison.joints),
    }
    return {
        "rrosfuzz_sidecar": 1,
        "sha1": hashlib.sha1(data).hexdigest(),
        "signature": ev.signature.to_json(),
        "comparison": comparison,
        "difference": ev.difference,
        "config": session.config.to_json(),
        "robot_path": str(session.urdf),
        "robot_sha256": digest,
        "joint_names": list(session.reference.joint_names),
        "testcase": case.to_json(),
        "strategy": case.strategy,
        "lineage": list(case.lineage),
        "call": {"kind": type(ev.call).__name__, **asdict(ev.call)},
        "outcomes": [outcome_json(r, o) for r, o in zip(session.runners, ev.outcomes, strict=True)],
        "versions": recorded,
        "written": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }
