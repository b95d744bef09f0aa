"""The seed corpus of a campaign: Hypothesis seeds of the campaign's message type (or scenario),
seeds from a ROS bag, writing them into the corpus folder, and the check of the files already
there (Algorithm 1's initial seeds)."""

from __future__ import annotations

import hashlib
import math
from collections.abc import Iterable, Sequence
from pathlib import Path

from fuzzer import reporting
from fuzzer.artifacts.store import atomic_write, clean_temporaries
from fuzzer.execution.session import ConfigError, Session
from fuzzer.input.paths import contained
from fuzzer.input.testcase import MAX_BYTES, TestCase, TestCaseError, read_case


def make_seeds(session: Session, n: int, seed: int) -> list[TestCase]:
    """n seeds from Hypothesis strategies of the message definition, with robot-aware hints
    (for ``--op scenario`` a sequence strategy over the topics' step strategies)."""
    from fuzzer.generation.seeds import generate_seeds
    from fuzzer.generation.strategies import strategy_for
    from fuzzer.input.mapping import scenario_strategy, seed_hints

    msg_type = session.config.message_type
    special = not session.config.filtering
    if session.config.op == "scenario":
        strategy = scenario_strategy(session.registry, session.facts(), session.config.max_steps, special)
    else:
        strategy = strategy_for(
            session.registry,
            msg_type,
            hints=seed_hints(msg_type, session.facts()),
            allow_special_floats=special,
        )
    from hypothesis.errors import Unsatisfiable

    try:
        messages = generate_seeds(strategy, n, seed)
    except Unsatisfiable as exc:  # a chain of 1,300 joints: every message past Hypothesis' buffer
        dof = len(session.reference.joint_names)
        raise ConfigError(
            f"--robot: Hypothesis draws no seed message for a chain of {dof} joints ({exc})"
        ) from None
    return [TestCase(msg_type, m, sequence=i, origin="hypothesis") for i, m in enumerate(messages)]


SPACEFILL_SEED = 0xC0DE5
"""Added to ``-seed`` for the space-filling seeds' Sobol stream (not the harness's own)."""

TUTORIAL_SEED = 0x7070
"""Added to ``-seed`` for the configurations of the tutorial scripts' seeds."""

SLOW_OP_SPACEFILL_SEEDS = {"ik": 1}
"""Space-filling seed files of the ops whose evaluation is slow (``ik``: a solver run per input,
about 100 a second; the others as many as the Hypothesis seeds). libFuzzer runs every seed file
before its first mutation, and 32 reachable poses cost an IK campaign about 0.25 s of that
(docs/benchmarks-log.md, "Fewer space-filling seed files for IK"); the space-filling source brings the
rest during the campaign, where the bandit weighs them against mutations."""


def space_filling_count(op: str, wanted: int) -> int:
    """How many space-filling seed files a campaign of ``op`` writes beside ``wanted``
    Hypothesis seeds."""
    return min(wanted, SLOW_OP_SPACEFILL_SEEDS.get(op, wanted))


def space_filling_seeds(session: Session, n: int, seed: int, first: int = 0) -> list[TestCase]:
    """``n`` seeds covering the joint space (issue 11, "beside the Hypothesis seeds"): the first
    points of a scrambled Sobol sequence inside the limits (``fuzzer.generation.spacefill``), each in
    the zero message of the campaign's type (a JointState's positions, a Float64MultiArray's
    data, for IK the pose FK gives the configuration), the first round of boundary probes put
    into the first of them (one joint of each 5e-5 past a limit: ``fuzzer.generation.boundary``;
    as many as the robot has finite limits). Numbered from ``first``,
    origin ``spacefill``. None at all for a scenario (its configurations come during the
    campaign), a chain without joints or a message type without a joint-space or pose field."""
    from fuzzer.generation.boundary import Boundary
    from fuzzer.generation.spacefill import SpaceFill, configuration_message

    config = session.config
    limits = session.reference.joint_limits
    if config.op == "scenario" or not limits or n <= 0:
        return []
    facts = session.facts()
    stream = SpaceFill(facts.lower, facts.upper, seed=seed + SPACEFILL_SEED)
    probes = Boundary(facts.lower, facts.upper, rounds=1)
    base = session.registry.default(config.message_type)
    out = []
    for i in range(n):
        values, _ = probes.apply(stream.next())
        message = configuration_message(config.message_type, base, values, facts.joint_names, facts.reachable)
        if message is None:
            return []
        out.append(TestCase(config.message_type, message, sequence=first + i, origin="spacefill"))
    return out


def boundary_cases(session: Session, rounds: int, first: int = 0) -> list[TestCase]:
    """The first ``rounds`` rounds of boundary probes (``fuzzer.generation.boundary``), each on
    the middle of the joint box (0 on a side without a limit): one input per probe, origin
    ``spacefill`` and lineage ``spacefill:boundary``, numbered from ``first``. For the dry run
    (``fuzzer.dry_run``): the campaign's own fresh inputs bring the same probes later, on
    space-filling points. None for a scenario, a chain without joints or a message type without
    a joint-space field."""
    from fuzzer.generation.boundary import Boundary
    from fuzzer.generation.spacefill import configuration_message
    from fuzzer.selection.state import BOUNDARY, SPACEFILL

    config = session.config
    limits = session.reference.joint_limits
    if config.op == "scenario" or not limits or rounds <= 0:
        return []
    facts = session.facts()
    middle = [
        (lo + hi) / 2 if math.isfinite(lo) and math.isfinite(hi) else 0.0
        for lo, hi in zip(facts.lower, facts.upper, strict=True)
    ]
    base = session.registry.default(config.message_type)
    out: list[TestCase] = []
    probes = Boundary(facts.lower, facts.upper, rounds=rounds)
    while probes.left:
        values, _ = probes.apply(middle)
        message = configuration_message(config.message_type, base, values, facts.joint_names, facts.reachable)
        if message is None:
            return []
        out.append(TestCase(config.message_type, message, first + len(out), SPACEFILL, (BOUNDARY,), 1))
    return out


def configuration_cases(
    session: Session, configurations: Iterable[Sequence[float]], lineage: str, first: int = 0
) -> list[TestCase]:
    """One input per joint configuration (rad, m; the robot's joints in order), each in the
    zero message of the campaign's type, origin ``spacefill`` and lineage ``lineage``, numbered
    from ``first``: the dry run's uniform and aligned configurations (``fuzzer.dry_run``). None
    for a scenario, a chain without joints or a message type without a joint-space field (a
    pose's would cost an FK each)."""
    from fuzzer.generation.spacefill import configuration_message
    from fuzzer.selection.state import SPACEFILL

    config = session.config
    if config.op == "scenario" or not session.reference.joint_limits:
        return []
    facts = session.facts()
    base = session.registry.default(config.message_type)
    out: list[TestCase] = []
    for values in configurations:
        message = configuration_message(
            config.message_type, base, tuple(map(float, values)), facts.joint_names
        )
        if message is None:
            return []
        out.append(TestCase(config.message_type, message, first + len(out), SPACEFILL, (lineage,), 1))
    return out


def uniform_cases(
    session: Session, n: int, seed: int, first: int = 0, start: int = 0, stop: int | None = None
) -> list[TestCase]:
    """``configuration_cases`` of ``n`` configurations uniform at random inside the limits
    (``spacefill.Uniform``: no ``scipy.stats``), lineage ``spacefill:uniform``; only those from
    ``start`` to ``stop`` (numbered from ``first + start``): a stream's parts made apart."""
    from fuzzer.generation.spacefill import Uniform
    from fuzzer.selection.state import UNIFORM

    if n <= 0 or not session.reference.joint_limits:
        return []
    facts = session.facts()
    rows = Uniform(facts.lower, facts.upper, seed=seed).block(n)[start:stop]
    return configuration_cases(session, rows, UNIFORM, first + start)


def uniform_scripts(session: Session, n: int, seed: int, first: int = 0) -> list[TestCase]:
    """``n`` uniform random scripts (``fuzzer.generation.scripts``, the uniform baseline's), origin
    ``spacefill`` and lineage ``spacefill:uniform``, numbered from ``first``, drawn with ``seed``.
    None for the other ops or a chain without joints."""
    import random

    from fuzzer.generation.scripts import uniform_script
    from fuzzer.selection.state import SPACEFILL, UNIFORM

    config = session.config
    if n <= 0 or config.op != "scenario" or not session.reference.joint_limits:
        return []
    rng = random.Random(seed)
    return [
        TestCase(config.message_type, uniform_script(session, rng), first + i, SPACEFILL, (UNIFORM,), 1)
        for i in range(n)
    ]


def aligned_cases(session: Session, n: int, seed: int, first: int = 0) -> list[TestCase]:
    """``configuration_cases`` of ``n`` aligned configurations (``spacefill.Aligned``: each
    joint at a multiple of pi/2 or a limit), lineage ``aligned``."""
    from fuzzer.generation.spacefill import Aligned
    from fuzzer.selection.state import ALIGNED

    if n <= 0 or not session.reference.joint_limits:
        return []
    facts = session.facts()
    stream = Aligned(facts.lower, facts.upper, seed=seed)
    return configuration_cases(session, [stream.next() for _ in range(n)], ALIGNED, first)


def literal_cases(session: Session, n: int, first: int = 0) -> list[TestCase]:
    """``configuration_cases`` of up to ``n`` configurations with joints at the numbers the
    Python targets compare against (``fuzzer.generation.literals``; their modules' source is
    parsed, never run), the middles of the bands they test first (as ``literal_scripts``),
    lineage ``spacefill:literal``. None for a scenario (as ``configuration_cases``), without
    reading a source."""
    from fuzzer.selection.state import LITERAL

    if n <= 0 or session.config.op == "scenario" or not session.reference.joint_limits:
        return []
    return configuration_cases(session, _literal_configurations(session, n, bands=True), LITERAL, first)


def _literal_configurations(session: Session, n: int, bands: bool = False) -> list[tuple[float, ...]]:
    """Up to ``n`` ``literal_configurations`` of the numbers the Python targets' modules compare
    against (``literals.module_numbers``; with ``bands``, their bands' middles first)."""
    from fuzzer.execution.targets import module_of
    from fuzzer.generation.literals import literal_configurations, module_numbers

    modules = [module_of(spec) for spec in session.config.targets if spec != "native"]
    facts = session.facts()
    return literal_configurations(module_numbers(modules, bands), facts.lower, facts.upper, n)


def literal_scripts(session: Session, scripts: Sequence[TestCase], n: int, seed: int) -> list[TestCase]:
    """The first of ``scripts`` (a scenario's uniform ones), each run from its own literal
    configuration (``scripts.with_start``): up to ``n`` configurations at the numbers the Python
    targets compare against, the middles of the bands they test first (``literals.band_middles``:
    a state inside a band, out of reach of the oracle's nudges), their Cartesian paths' poses
    drawn with ``seed``; lineage ``spacefill:uniform`` then ``spacefill:literal``, the scripts'
    numbers kept. None for the other ops, a target without such numbers, or ``max_steps`` below
    ``scripts.START_STEPS``."""
    import random

    from fuzzer.generation.scripts import with_start
    from fuzzer.selection.state import LITERAL

    if n <= 0 or session.config.op != "scenario" or not session.reference.joint_limits:
        return []
    rng = random.Random(seed)
    out = []
    for case, values in zip(scripts, _literal_configurations(session, n, bands=True), strict=False):
        message = with_start(session, case.message, list(values), rng)
        if message is None:
            return []
        out.append(
            TestCase(
                case.msg_type,
                message,
                case.sequence,
                case.origin,
                (*case.lineage, LITERAL),
                case.lineage_length + 1,
            )
        )
    return out


def tutorial_seeds(session: Session, seed: int, first: int = 0) -> list[TestCase]:
    """The scripts of MoveIt's tutorials for a scenario campaign (``fuzzer.generation.tutorial``),
    origin and lineage ``tutorial``, numbered from ``first``; their configurations drawn with
    ``seed``. None for the other ops or a chain without joints."""
    from fuzzer.generation.tutorial import TUTORIAL, tutorial_scenarios

    config = session.config
    if config.op != "scenario" or not session.reference.joint_limits:
        return []
    facts = session.facts()
    scripts = tutorial_scenarios(
        facts.lower, facts.upper, facts.joint_names, facts.reachable, seed + TUTORIAL_SEED, config.max_steps
    )
    return [
        TestCase(config.message_type, message, first + i, TUTORIAL, (TUTORIAL,), 1)
        for i, (_, message) in enumerate(scripts)
    ]


def orientation_cases(session: Session, first: int = 0) -> list[TestCase]:
    """The orientation probes of a pose-target campaign (``ik``): the pose FK gives at the robot's
    home configuration (where an IK seeded there converges at once), its quaternion scaled to each
    length of ``fuzzer.generation.boundary.ORIENTATION_SCALES``. Origin ``spacefill``, lineage
    ``spacefill:boundary``, numbered from ``first``. The full engine's dry run evaluates them
    first, and the campaign writes them as seed files beside the space-filling ones (four IK
    evaluations). None for a message type without a pose, or a chain without joints."""
    from fuzzer.generation.boundary import ORIENTATION_SCALES, scale_orientation
    from fuzzer.generation.spacefill import configuration_message
    from fuzzer.selection.state import BOUNDARY, SPACEFILL

    config = session.config
    if config.op == "scenario" or not session.reference.joint_limits:
        return []
    facts = session.facts()
    home = tuple(session.reference.home_values)
    base = session.registry.default(config.message_type)
    pose = configuration_message(config.message_type, base, home, facts.joint_names, facts.reachable)
    out: list[TestCase] = []
    for scale in ORIENTATION_SCALES:
        message = None if pose is None else scale_orientation(config.message_type, pose, scale)
        if message is None:
            return []
        out.append(TestCase(config.message_type, message, first + len(out), SPACEFILL, (BOUNDARY,), 1))
    return out


def reach_cases(session: Session, seed: int, first: int = 0) -> list[TestCase]:
    """The reach probe of a pose-target campaign (``ik``): the home configuration's pose moved
    out of reach (``fuzzer.generation.boundary.beyond_reach``: ``REACH_FACTOR`` times the
    farthest tip of ``REACH_SAMPLES`` uniform configurations, ``seed``). Origin ``spacefill``,
    lineage ``spacefill:boundary``, numbered ``first``. The dry run's first stage evaluates it
    (both IK solvers then run out of iterations: about 0.16 s on the default robot). None for a
    message type without a pose, or a chain without joints."""
    from fuzzer.generation.boundary import POSE_TYPES, REACH_FACTOR, REACH_SAMPLES, beyond_reach
    from fuzzer.generation.spacefill import Uniform, configuration_message
    from fuzzer.selection.state import BOUNDARY, SPACEFILL

    config = session.config
    if config.message_type not in POSE_TYPES or not session.reference.joint_limits:
        return []  # before the samples: no pose to move (a scenario's message type neither)
    facts = session.facts()
    home = tuple(session.reference.home_values)
    base = session.registry.default(config.message_type)
    pose = configuration_message(config.message_type, base, home, facts.joint_names, facts.reachable)
    if pose is None or facts.reachable is None:
        return []
    sampled = Uniform(facts.lower, facts.upper, seed=seed).block(REACH_SAMPLES)
    farthest = max(math.dist(facts.reachable(tuple(map(float, q)))[0], (0.0, 0.0, 0.0)) for q in sampled)
    message = beyond_reach(config.message_type, pose, REACH_FACTOR * max(farthest, 1.0))
    if message is None:
        return []
    return [TestCase(config.message_type, message, first, SPACEFILL, (BOUNDARY,), 1)]


def bag_seeds(session: Session, bag: Path) -> list[TestCase]:
    """The messages of the campaign's type in a ROS bag, as seeds (``fuzzer.ros.bags``)."""
    from fuzzer.ros.bags import read_seeds
    from fuzzer.ros.scenario_bags import read_scenarios

    msg_type, joints = session.config.message_type, session.reference.joint_names
    if session.config.op == "scenario":
        from fuzzer.input.libfuzzer_flags import default_max_len

        config = session.config
        limit = default_max_len(config.op, config.max_steps)  # -max_len: a longer seed was cut short
        messages = read_scenarios(bag, session.validate, config.max_steps, joints, limit, config.filtering)
    else:
        messages = read_seeds(bag, msg_type, session.validate, joints)
    return [TestCase(msg_type, m, sequence=i, origin="rosbag") for i, m in enumerate(messages)]


def write_bag_seeds(session: Session, bag: Path, corpus: Path) -> list[TestCase]:
    """``--seeds-from-bag``: the bag's seeds (``bag_seeds``) written into ``corpus``, said, and
    those the campaign's filter will drop said too (a bag of NaN states was "wrote 2 seeds",
    then nothing but libFuzzer's "no interesting inputs were found")."""
    from fuzzer.input.filtering import is_reasonable

    seeds = bag_seeds(session, bag)
    write_seeds(corpus, seeds)
    reporting.info(f"wrote {len(seeds)} seeds from {bag} to {corpus}")
    filtered = sum(not is_reasonable(case.message) for case in seeds) if session.config.filtering else 0
    if filtered:
        reporting.warn(
            f"{filtered} of the {len(seeds)} seeds from {bag} hold a value that is not finite or "
            "absurd: filtered, never run (--no-filter runs them)"
        )
    return seeds


def write_seeds(corpus: Path, seeds: list[TestCase]) -> None:
    """Write the generated seeds into the corpus folder, without fsync: the same seed and robot
    make them again, and a short file left by a power loss is skipped as malformed (``prescan``)."""
    from fuzzer.signals import stop_requested

    for case in seeds:
        if stop_requested():  # a kept Ctrl-C or SIGTERM: it waited for the last of 200,000 files
            raise KeyboardInterrupt
        data = case.encode()
        name = f"seed-{case.sequence:05d}-{hashlib.sha1(data).hexdigest()[:10]}"
        atomic_write(corpus / name, data, durable=False)


def prescan(session: Session, corpus: tuple[Path, ...]) -> tuple[int, list[TestCase]]:
    """Warn about every corpus file that is not a valid test case of this campaign.

    libFuzzer still feeds them in; they are skipped as malformed. Returns
    (number of usable files, the generated seeds found among them).

    Raises
    ------
    ConfigError
        A corpus file is a link to a file outside its folder (libFuzzer would read it).
    """
    usable, seeds = 0, []
    msg_type = session.config.message_type
    for directory in corpus:
        clean_temporaries(directory)
        for path in sorted(p for p in directory.iterdir() if p.is_file() and not p.name.startswith(".")):
            if path.is_symlink() and not contained(directory, path):
                # said "skipping" while libFuzzer, which reads every file of the folder, ran it
                raise ConfigError(
                    f"corpus file {path} is a link to a file outside the corpus folder, which "
                    "libFuzzer would read as an input; remove the link or copy the file in"
                )
            try:
                if path.stat().st_size > MAX_BYTES:  # read whole, a 3 GB file filled the memory
                    raise TestCaseError(f"larger than a test case may be ({MAX_BYTES} bytes)")
                case = read_case(path)
                if case.msg_type != msg_type:
                    raise TestCaseError(f"message type {case.msg_type}, this campaign fuzzes {msg_type}")
                session.validate(case.message)
            except (OSError, ValueError) as exc:
                reporting.warn(f"skipping corpus file {path}: {exc}")
                continue
            usable += 1
            if case.origin == "hypothesis":
                seeds.append(case)
    return usable, seeds
