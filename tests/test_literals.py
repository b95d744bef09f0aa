"""The numbers the Python targets compare against, read from their source (fuzzer.generation.literals)."""

from __future__ import annotations

import math
import random
import sys
import types
from pathlib import Path

import pytest

from fuzzer.generation import literals
from fuzzer.generation.literals import (
    band_middles,
    compared_numbers,
    literal_configurations,
    module_numbers,
    parsed,
)

SOURCE = """
LOW, HIGH = 0.86131, 0.86133
LIMIT = -2.5
FLAG = True

def f(v, q):
    if 4.0 <= v < 4.05 and q[0] > LIMIT:
        return [x + 1 if LOW <= x < HIGH else x for x in q]
    if v == -1e-3 or v is True or v < float("inf") or v != "a":
        return 7.5  # not compared: no number
    return v > UNKNOWN
"""


def test_the_compared_numbers_are_the_literals_and_module_constants_of_comparisons() -> None:
    numbers = compared_numbers(SOURCE)
    assert sorted(numbers) == sorted([4.0, 4.05, -2.5, 0.86131, 0.86133, -1e-3])
    assert 7.5 not in numbers and 1.0 not in numbers  # an assignment or a sum is not a comparison


def test_a_source_that_does_not_parse_has_none_and_is_never_run() -> None:
    assert compared_numbers("def (:\n") == []
    assert compared_numbers("import os\nos.remove('/nonexistent') if 1 < 2 else None\n") == [1.0, 2.0]


def test_a_band_between_two_numbers_gives_its_middle_first() -> None:
    """``4.0 <= v < 4.05`` and ``LOW <= x < HIGH`` are bands; ``q[0] > LIMIT`` is not (one
    side), nor ``1 < 2 < v`` (no unknown in the middle) nor ``a < b < c`` (no number)."""
    assert band_middles(SOURCE) == [pytest.approx(4.025), pytest.approx(0.86132)]
    assert band_middles("1 < 2 < v\na < b < c\nv <= 3 <= w\n") == []
    assert band_middles("def (:\n") == []
    name = "fuzzer_test_literals_bands"
    module = types.ModuleType(name)
    sys.modules[name] = module
    try:
        module.__file__ = __file__
        plain, banded = module_numbers([name]), module_numbers([name], bands=True)
        middles = band_middles(Path(__file__).read_text())
        assert banded[: len(middles)] == middles
        assert [v for v in banded if v in plain] == plain  # then the numbers, in their order
    finally:
        del sys.modules[name]


def test_module_numbers_read_loaded_python_modules_only() -> None:
    assert module_numbers(["no.such.module", "math"]) == []  # not loaded / not a .py file
    name = "fuzzer_test_literals_module"
    module = types.ModuleType(name)
    sys.modules[name] = module
    try:
        module.__file__ = "/nonexistent/module.py"
        assert module_numbers([name]) == []  # unreadable: none, no error
    finally:
        del sys.modules[name]


def test_a_sources_numbers_are_parsed_once_then_read_from_the_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    expected = (band_middles(SOURCE), compared_numbers(SOURCE))
    assert parsed(SOURCE, None) == expected and not list(tmp_path.iterdir())  # no cache: no file
    assert parsed(SOURCE, tmp_path) == expected
    files = list(tmp_path.glob("literals-*.json"))
    assert len(files) == 1

    def no_parse(source: str) -> list[list[float | None]]:
        raise AssertionError("parsed again")

    monkeypatch.setattr(literals, "_comparisons", no_parse)
    assert parsed(SOURCE, tmp_path) == expected  # the same numbers, bit for bit, from the file
    with pytest.raises(AssertionError, match="parsed again"):
        parsed(SOURCE + "\nx = 1 < 2\n", tmp_path)  # other text: another file


@pytest.mark.parametrize(
    "content",
    [
        b"",
        b"not json",
        b'["rrosfuzz-compared-numbers-v0", [], []]',
        b'["rrosfuzz-compared-numbers-v1", [1.0], [2.0], [3.0]]',
        b'["rrosfuzz-compared-numbers-v1", [1.0], {"a": 1}]',
        b'["rrosfuzz-compared-numbers-v1", [1.0], ["2.0"]]',
        b'["rrosfuzz-compared-numbers-v1", [1.0], [true]]',
        b'["rrosfuzz-compared-numbers-v1", [1.0], [NaN]]',
        b'["rrosfuzz-compared-numbers-v1", [1.0], [1e999]]',
        b"\xff\xfe",
    ],
)
def test_a_bad_cache_file_means_parsing_and_is_written_again(tmp_path: Path, content: bytes) -> None:
    expected = (band_middles(SOURCE), compared_numbers(SOURCE))
    parsed(SOURCE, tmp_path)
    (path,) = tmp_path.glob("literals-*.json")
    path.write_bytes(content)
    assert parsed(SOURCE, tmp_path) == expected
    assert parsed(SOURCE, tmp_path / "missing" / "folder") == expected  # made when missing
    assert literals._load(path) == expected  # written again


def test_an_unwritable_cache_folder_means_no_cache(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert parsed(SOURCE, blocker / "cache") == (band_middles(SOURCE), compared_numbers(SOURCE))


def test_the_cache_keeps_its_newest_files(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(literals, "CACHE_KEEP", 3)
    for i in range(5):
        parsed(f"v < {i}.5\n", tmp_path)
    assert len(list(tmp_path.glob("literals-*.json"))) == 3


def test_configurations_put_each_number_on_every_joint_that_holds_it_then_one_joint_at_a_time() -> None:
    lower, upper = [-6.0, -6.0, -1.0], [6.0, 6.0, 3.0]
    made = literal_configurations([0.0, 4.0, 1.5, 9.0], lower, upper, 64)
    middle = (0.0, 0.0, 1.0)
    assert made[0] == (4.0, 4.0, middle[2])  # joint 2's limits do not hold 4.0
    assert made[1] == (1.5, 1.5, 1.5)
    assert made[2:] == [(4.0, 0.0, 1.0), (0.0, 4.0, 1.0), (1.5, 0.0, 1.0), (0.0, 1.5, 1.0), (0.0, 0.0, 1.5)]
    assert all(lo <= v <= hi for q in made for v, lo, hi in zip(q, lower, upper, strict=True))
    unlimited = literal_configurations([2.0], [-math.inf], [math.inf], 64)
    assert unlimited == [(2.0,)]
    many = literal_configurations([0.1 * k for k in range(1, 200)], [-30.0] * 6, [30.0] * 6, 16)
    assert many == [(0.1 * k,) * 6 for k in range(1, 17)]  # every joint at a number first


def test_the_dry_run_puts_a_targets_numbers_after_its_first_uniform_configurations() -> None:
    """``per_joint_band``'s band starts at a module constant of ``benchmarks/zoo/deep.py``. A
    ``move`` dry run evaluates the literal configurations after its first ``HEAD`` uniform
    ones, before the rest of them and before the aligned configurations and boundary probes
    (after those until 2026-11-30, 100 inputs in); an ``fk`` one, which has no uniform
    configurations, after its boundary probes."""
    from benchmarks.zoo.deep import CORRECTED_FROM, CORRECTED_TO
    from fuzzer import dry_run
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.selection.state import ALIGNED, BOUNDARY, LITERAL, UNIFORM

    session = Session.open(RunConfig(op="move", targets=("native", "benchmarks.zoo.deep:per_joint_band")))
    stages = dry_run.Stages(session, "rrosfuzz", 1, 8, 0, lambda *_: None)  # type: ignore[arg-type]
    first = stages.first_cases()
    at = stages._literal_at
    assert 0 < at == dry_run.HEAD < dry_run.LEAD
    assert all(c.lineage == (UNIFORM,) for c in first[: dry_run.LEAD])
    assert first[dry_run.LEAD].lineage == (ALIGNED,)
    fk = dry_run.Stages(
        Session.open(RunConfig(op="fk", targets=("native", "benchmarks.zoo.deep:narrow_band"))),
        "rrosfuzz",
        1,
        8,
        0,
        lambda *_: None,  # type: ignore[arg-type]
    )
    probed = fk.first_cases()
    assert fk._literal_at == len(probed) and probed[-1].lineage == (BOUNDARY,)
    literal = stages.literal_cases()
    assert 0 < len(literal) <= dry_run.LITERALS and all(c.lineage == (LITERAL,) for c in literal)
    numbers = [c.sequence for c in [*first, *stages.second_cases([]), *literal]]
    assert len(set(numbers)) == len(numbers)  # numbered after every other input
    assert any(CORRECTED_FROM in _values(c.message) for c in literal)  # a joint in the band
    # the bands' middles first (0.305, 0.86132, 4.025 in benchmarks/zoo/deep.py), then the numbers
    middle = (CORRECTED_FROM + CORRECTED_TO) / 2
    at_middle = [i for i, c in enumerate(literal) if middle in _values(c.message)]
    at_number = [i for i, c in enumerate(literal) if CORRECTED_FROM in _values(c.message)]
    assert at_middle and at_number and max(at_middle) < min(at_number)
    assert at_middle[0] < 3
    default = dry_run.Stages(Session.open(RunConfig(op="move")), "rrosfuzz", 1, 8, 0, lambda *_: None)  # type: ignore[arg-type]
    default.first_cases()
    assert default.literal_cases() == []  # the twin's package module compares against no number


def _values(message: object) -> list[float]:
    """Every float of a message (nested dicts and lists)."""
    if isinstance(message, dict):
        return [v for x in message.values() for v in _values(x)]
    if isinstance(message, list):
        return [v for x in message for v in _values(x)]
    return [message] if isinstance(message, float) else []


def _scenario_stages(target: str, seed: int = 1, max_steps: int = 16):  # type: ignore[no-untyped-def]
    from fuzzer import dry_run
    from fuzzer.execution.session import RunConfig, Session

    config = RunConfig(op="scenario", robot="probot_anno", targets=("native", target), max_steps=max_steps)
    return dry_run.Stages(Session.open(config), "rrosfuzz", seed, 8, 0, lambda *_: None)  # type: ignore[arg-type]


def test_a_scenario_dry_run_starts_its_first_uniform_scripts_at_the_targets_numbers() -> None:
    """After the tutorial scripts, the first uniform scripts each go to a literal configuration
    (a band's middle first: ``ik_seed_band``'s seed band [0.3, 0.31)), then make a Cartesian
    path from there (an IK seeded with that state), then run the uniform script; the rest of
    the uniform scripts, and a target without compared numbers, are as before."""
    from fuzzer import dry_run
    from fuzzer.generation.scripts import START_STEPS, uniform_script
    from fuzzer.scenario import steps as scenario_steps
    from fuzzer.selection.state import LITERAL, UNIFORM

    stages = _scenario_stages("benchmarks.zoo.deep:ik_seed_band")
    session = stages.session
    parts = list(stages._first_parts(literals=True))
    assert [name for name, _ in parts] == [dry_run.TUTORIAL_PART, dry_run.LITERAL_PART, dry_run.UNIFORM_PART]
    tutorials, started, rest = (part for _, part in parts)
    assert 0 < len(started) <= dry_run.LITERALS and len(started) + len(rest) == dry_run.SCRIPTS
    rng = random.Random(1 + dry_run.SWEEP_SEED)
    uniform = [uniform_script(session, rng) for _ in range(dry_run.SCRIPTS)]
    assert [c.message for c in rest] == uniform[len(started) :]
    numbers = [c.sequence for c in (*started, *rest)]
    assert numbers == list(range(8 + len(tutorials), 8 + len(tutorials) + dry_run.SCRIPTS))
    for case, script in zip(started, uniform, strict=False):
        steps = case.message["steps"]
        assert [s["topic"] for s in steps[:START_STEPS]] == ["/joint_target", "/go", "/cartesian_path"]
        assert steps[START_STEPS:] == script["steps"][: session.config.max_steps - START_STEPS]
        assert case.lineage == (UNIFORM, LITERAL)
        scenario_steps.validate(case.message, session.registry, session.config.max_steps)
    first = started[0].message["steps"][0]["msg"]["position"]
    assert 0.3 <= first[0] < 0.31 and first[0] == pytest.approx(0.305)
    plain = list(_scenario_stages("python")._first_parts(literals=True))
    assert [len(part) for name, part in plain if name == dry_run.LITERAL_PART] == [0]  # no numbers
    short = list(
        _scenario_stages("benchmarks.zoo.deep:ik_seed_band", max_steps=START_STEPS - 1)._first_parts(True)
    )
    assert [len(part) for name, part in short if name == dry_run.LITERAL_PART] == [0]  # no room


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_first_script_from_a_bands_middle_shows_ik_seed_band(seed: int) -> None:
    """The planted fault: IK answers with its seed when the seed's joint_1 is in [0.3, 0.31).
    The first literal script goes to 0.305 and solves a Cartesian path from there."""
    from benchmarks.dry_run_order import detects
    from fuzzer import dry_run

    stages = _scenario_stages("benchmarks.zoo.deep:ik_seed_band", seed)
    started = dict(stages._first_parts(literals=True))[dry_run.LITERAL_PART]
    assert detects(stages.session.evaluator(), started[0])


def test_scripts_from_literal_configurations_show_no_divergence_between_correct_targets() -> None:
    """The deep zoo module's literal scripts (at joint values near limits, at 0.001, at a band's
    middle) run on the correct twin against KDL: nothing that counts as a detection."""
    from benchmarks.dry_run_order import detects
    from fuzzer import dry_run
    from fuzzer.generation.scripts import with_start

    started = dict(_scenario_stages("benchmarks.zoo.deep:ik_seed_band")._first_parts(literals=True))[
        dry_run.LITERAL_PART
    ]
    correct = _scenario_stages("python").session
    evaluator = correct.evaluator()
    for case in started:
        values = case.message["steps"][0]["msg"]["position"]
        message = with_start(correct, {"steps": case.message["steps"][3:]}, values, random.Random(7))
        assert message is not None
        assert not detects(evaluator, case.child(message, "control")), values
