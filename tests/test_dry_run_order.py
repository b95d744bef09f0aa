"""benchmarks.dry_run_order: the first stage's first detection, counted in inputs."""

from __future__ import annotations

import pytest

from benchmarks import dry_run_order
from benchmarks.bench_deep import BUGS
from fuzzer.selection.state import BOUNDARY


def test_a_boundary_bug_is_first_shown_by_the_first_boundary_probe_and_never_by_uniform_sampling() -> None:
    """``off_by_tolerance`` (a target 5e-5 past a limit accepted): the first stage's first
    boundary probe is its first detection in every seed, and 30 uniform inputs show none."""
    bug = BUGS["off_by_tolerance"]
    session = dry_run_order.open_session(bug)
    for seed in (0, 1):
        result = dry_run_order.one_seed(bug, session, seed, uniform_inputs=30)
        cases = dry_run_order.first_stage(session, seed)
        probe = next(i for i, case in enumerate(cases) if dry_run_order.source_of(case) == BOUNDARY)
        assert (result.detected_at, result.source) == (probe, BOUNDARY)
        assert result.uniform_at is None and result.first_stage == len(cases)
        assert sum(result.sources.values()) == len(cases) and result.sources[BOUNDARY] > 0
    table = dry_run_order.summary([result], 30)
    assert f"| {BOUNDARY} |" in table and "p = 1" in table


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--bugs", "narrow_band"], "only move and scenario bugs have a first stage of single inputs"),
        (["--bugs", "no_such_bug"], "unknown bug(s): no_such_bug"),
        (["--bugs", "off_by_tolerance", "--seeds", "0"], "--seeds and --uniform-inputs must be at least 1"),
    ],
)
def test_bad_arguments_are_named(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        dry_run_order.main(argv)
    assert exited.value.code == 2 and message in capsys.readouterr().err


def test_a_miss_is_later_than_any_detection_of_either_arm() -> None:
    """A first stage that never detects (200 inputs) against uniform sampling detecting at
    250-259 of 400: the first stage's misses counted as 200 made it look significantly sooner."""
    results = [
        dry_run_order.SeedResult("b", seed, 200, None, None, {"uniform": 200}, 250 + seed)
        for seed in range(10)
    ]
    table = dry_run_order.summary(results, 400)
    rows = {line.split("|")[1].strip(): line for line in table.splitlines() if line.startswith("| ")}
    assert "| 400 |" in rows["first stage"] and "| 254.5 |" in rows["uniform sampling"]


def test_a_negative_first_seed_and_a_bug_named_twice_are_refused() -> None:
    with pytest.raises(SystemExit):
        dry_run_order.main(["--bugs", "wrap_past_pi", "--first-seed", "-1"])
    with pytest.raises(SystemExit):
        dry_run_order.main(["--bugs", "wrap_past_pi", "wrap_past_pi"])
