"""The benchmarks' command lines: a bad count, budget, folder, robot or target is the parser's
error, named, before anything runs. Before these checks, 0 rounds ended on a median of nothing,
a negative budget or number of jobs ran, 0 meant the mode's default, and a bad robot, tip link
or folder was a traceback."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from benchmarks import (
    baselines,
    bench_deep,
    bench_engine,
    bench_evaluate,
    bench_memory,
    bench_native_cov,
    bench_scenario,
    bench_targets,
    bench_zoo,
    dry_run_order,
    probe_ik_stall,
    profile,
)

ROOT = str(Path(__file__).resolve().parents[1])
"""This tree (an arm of ``bench_memory``)."""

BASELINE = ["uniform", "--seconds", "1", "--artifacts", "a"]
"""A baseline run's options (the folder relative to the test's own)."""

CASES: list[tuple[Callable[[], object], list[str], str]] = [
    (bench_engine.main, ["--seconds", "0"], "--seconds must be a finite number above 0, not 0"),
    (bench_targets.main, ["--rounds", "0"], "--rounds must be a finite number above 0, not 0"),
    (bench_targets.main, ["--repeat", "-1"], "--repeat must be a finite number above 0, not -1"),
    (bench_targets.main, ["--robot", "nosuch"], "robot 'nosuch' is neither a URDF file nor a known robot"),
    (bench_evaluate.main, ["--rounds", "0"], "--rounds must be a finite number above 0, not 0"),
    (bench_evaluate.main, ["--seconds", "nan"], "--seconds must be a finite number above 0, not nan"),
    (bench_evaluate.main, ["--ops", "scenario", "--corpus", "nosuch"], "and a folder: nosuch"),
    (bench_evaluate.main, ["--ops", "fk", "move", "--corpus", "."], "--corpus needs one --ops"),
    (bench_evaluate.main, ["--decompose", "--plain"], "--decompose measures the instrumented seeds"),
    (bench_native_cov.main, ["--seeds", "0"], "--seeds must be a finite number above 0, not 0"),
    (bench_native_cov.main, ["--budget", "-1"], "--budget must be a finite number above 0, not -1.0"),
    (bench_zoo.main, ["--mode", "quick", "--seeds", "0"], "--seeds must be a finite number above 0, not 0"),
    (
        bench_zoo.main,
        ["--mode", "quick", "--budget", "inf"],
        "--budget must be a finite number above 0, not inf",
    ),
    (bench_zoo.main, ["--mode", "quick", "--jobs", "0"], "--jobs must be 1 or more, not 0"),
    (bench_zoo.main, ["--out", "a-file/zoo.json"], "a-file: cannot hold the results"),
    # a campaign's length goes to libFuzzer's -max_total_time, whole seconds, 0 for no limit: 0.5 ran
    # each trial until its timeout (2026-12-05)
    (bench_zoo.main, ["--budget", "0.5"], "--budget must be a whole number of seconds (libFuzzer's"),
    (bench_deep.main, ["--budget", "2.5"], "--budget must be a whole number of seconds"),
    (bench_native_cov.main, ["--budget", "0.5"], "--budget must be a whole number of seconds"),
    (bench_scenario.main, ["--seconds", "0.5"], "--seconds must be a whole number of seconds"),
    (profile.main, ["--seconds", "0.5"], "--seconds must be a whole number of seconds"),
    (profile.main, ["--seconds", "nan"], "--seconds must be a finite number above 0, not nan"),
    # a name twice: planned twice, run once, and the sweep never ends (each --resume "interrupted")
    (bench_zoo.main, ["--bugs", "silent_clamp", "silent_clamp"], "--bugs names silent_clamp more than once"),
    (bench_deep.main, ["--engines", "full", "uniform", "uniform"], "--engines names uniform more than once"),
    (bench_native_cov.main, ["--configs", "control,control"], "--configs names control more than once"),
    # results that could not be written once the measurement was done, or that a journal took
    (bench_zoo.main, ["--out", "."], ". is a folder: name the results file"),
    (bench_zoo.main, ["--out", "zoo.jsonl"], "a .jsonl name is the sweep's journal"),
    (bench_scenario.main, ["--no-campaign", "--out", "."], ". is a folder: name the results file"),
    (profile.main, ["--out", "a-file/p.txt"], "a-file: cannot hold the results"),
    (dry_run_order.main, ["--bugs", "wrap_past_pi", "--out", "."], ". is a folder: name the results file"),
    (dry_run_order.main, ["--bugs", "wrap_past_pi", "--out", "a-file"], "a-file exists: name another --out"),
    # configurations outside the table's (which wrote an empty table over native-cov.json)
    (bench_native_cov.main, ["--configs", ","], "unknown configuration(s) (none given)"),
    (bench_native_cov.main, ["--configs", "mimic_ignored"], "unknown configuration(s) mimic_ignored"),
    (bench_engine.main, ["--seeds", "-1"], "--seeds must be 1 or more"),
    # sizes a sweep could not hold: planned whole (a MemoryError), run for good, or a journal refused
    (bench_deep.main, ["--mode", "quick", "--trials", "99999999"], "--trials must be at most 10000"),
    (bench_deep.main, ["--mode", "quick", "--budget", "1e308"], "--budget must be at most 2147483647 s"),
    (bench_zoo.main, ["--seeds", "10001"], "--seeds must be at most 10000, not 10001"),
    (profile.main, ["--seed", "0"], "--seed must be from 1 to 4294967295, not 0"),
    (profile.main, ["--seed", "99999999999"], "--seed must be from 1 to 4294967295"),
    (bench_deep.main, ["--first-seed", "99999999999"], "reach seed 100000000000, past 2147483648"),
    (bench_engine.main, ["--ops", "nosuch"], "invalid choice: 'nosuch'"),
    (bench_engine.main, ["--mutator", "nope"], "invalid choice: 'nope'"),
    (probe_ik_stall.main, ["probot_anno", "--seed", "-1"], "--seed must be 0 or more"),
    (bench_targets.main, ["--robot", "a-file"], "--robot a-file:"),
    (bench_scenario.main, ["--render", "a-file"], "a-file: not a bench_scenario result (JSONDecodeError"),
    (bench_scenario.main, ["--render", "."], ".: not a bench_scenario result (IsADirectoryError"),
    (
        bench_memory.main,
        ["--arm", "a", ROOT, "--out", "m.jsonl", "--seconds", "0"],
        "--seconds must be a finite",
    ),
    (bench_memory.main, ["--out", "m.jsonl"], "one or two --arm NAME DIR and --out FILE are needed"),
    (bench_memory.main, ["--arm", "a", ".", "--out", "m.jsonl"], "--arm a: . is not an RROSFuzz tree"),
    (
        bench_memory.main,
        ["--arm", "a", ROOT, "--arm", "a", ROOT, "--out", "m"],
        "the arms need different names",
    ),
    (bench_memory.main, ["--arm", "a", ROOT, "--out", "a-file"], "--out a-file exists: name a new file"),
    (bench_memory.main, ["--from-json", "a-file"], "--from-json a-file: not a file of this benchmark"),
    (bench_memory.main, ["--from-json", "."], "--from-json .: not a file of this benchmark"),
    (baselines.main, [*BASELINE, "--seconds", "0"], "--seconds must be a finite number above 0, not 0.0"),
    (baselines.main, [*BASELINE, "--targets", "native"], "--targets takes two targets, as in native,python"),
    (baselines.main, [*BASELINE, "--robot", "nosuch"], "--robot: robot 'nosuch' is neither a URDF file"),
    (baselines.main, [*BASELINE, "--tip-link", "nosuch"], "tip link 'nosuch' is not in the URDF"),
    (baselines.main, [*BASELINE, "--artifacts", "a-file/a"], "a-file/a: cannot hold the results"),
]


@pytest.mark.parametrize(("main", "argv", "says"), CASES)
def test_a_bad_option_is_named_before_anything_runs(
    main: Callable[[], object],
    argv: list[str],
    says: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def no_trial(*_: object, **__: object) -> None:
        raise AssertionError("a trial ran")

    monkeypatch.setattr(bench_zoo, "run_one", no_trial)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a-file").write_text("not a folder")
    monkeypatch.setattr(sys, "argv", [main.__module__, *argv])
    with pytest.raises(SystemExit) as exit_info:
        main()
    said = capsys.readouterr()
    assert exit_info.value.code == 2 and says in said.err and "Traceback" not in said.err
    assert said.out == ""  # nothing measured, nothing printed as a result
    # nothing written, not even an empty folder (a baseline run made its artifacts folder before
    # its session loaded the robot until 2026-11-30)
    assert [p.name for p in tmp_path.rglob("*")] == ["a-file"]
