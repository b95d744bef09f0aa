"""The benchmarks' command lines: a bad count, budget, folder or robot is the parser's error,
named, before anything runs (these checks ran nothing before: 0 rounds ended on a median of
nothing, a negative budget ran, a bad robot or tip link was a traceback)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from benchmarks import baselines, bench_engine, bench_evaluate, bench_native_cov, bench_targets, bench_zoo

CASES: list[tuple[Callable[[], object], list[str], str]] = [
    (bench_engine.main, ["--seconds", "0"], "--seconds must be a finite number above 0, not 0"),
    (bench_targets.main, ["--rounds", "0"], "--rounds must be a finite number above 0, not 0"),
    (bench_targets.main, ["--repeat", "-1"], "--repeat must be a finite number above 0, not -1"),
    (bench_targets.main, ["--robot", "nosuch"], "robot 'nosuch' is neither a URDF file nor a known robot"),
    (bench_evaluate.main, ["--rounds", "0"], "--rounds must be a finite number above 0, not 0"),
    (bench_evaluate.main, ["--seconds", "nan"], "--seconds must be a finite number above 0, not nan"),
    (bench_native_cov.main, ["--seeds", "0"], "--seeds must be a finite number above 0, not 0"),
    (bench_native_cov.main, ["--budget", "-1"], "--budget must be a finite number above 0, not -1.0"),
]


@pytest.mark.parametrize(("main", "argv", "says"), CASES)
def test_a_bad_option_is_named_before_anything_runs(
    main: Callable[[], object],
    argv: list[str],
    says: str,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(sys, "argv", [main.__module__, *argv])
    with pytest.raises(SystemExit) as exit_info:
        main()
    said = capsys.readouterr()
    assert exit_info.value.code == 2 and says in said.err
    assert said.out == ""  # nothing measured, nothing printed as a result


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (["--seconds", "0"], "--seconds must be a finite number above 0, not 0.0"),
        (["--targets", "native"], "--targets takes two targets, as in native,python, not 'native'"),
        (["--robot", "nosuch"], "--robot: robot 'nosuch' is neither a URDF file nor a known robot"),
        (["--tip-link", "nosuch"], "tip link 'nosuch' is not in the URDF"),
    ],
)
def test_a_baseline_run_with_a_bad_option_is_named_not_a_traceback(
    extra: list[str],
    says: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["baselines", "uniform", "--seconds", "1", "--artifacts", str(tmp_path / "a"), *extra]
    monkeypatch.setattr(sys, "argv", argv)
    with pytest.raises(SystemExit) as exit_info:
        baselines.main()
    said = capsys.readouterr().err
    assert exit_info.value.code == 2 and says in said and "Traceback" not in said


def test_a_baseline_run_whose_artifacts_folder_cannot_be_made_is_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    blocked = tmp_path / "a-file"
    blocked.write_text("")
    monkeypatch.setattr(
        sys, "argv", ["baselines", "uniform", "--seconds", "1", "--artifacts", str(blocked / "a")]
    )
    with pytest.raises(SystemExit) as exit_info:
        baselines.main()
    assert (
        exit_info.value.code == 2 and f"{blocked / 'a'}: cannot hold the results" in capsys.readouterr().err
    )


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (["--seeds", "0"], "--seeds must be a finite number above 0, not 0"),
        (["--budget", "inf"], "--budget must be a finite number above 0, not inf"),
        (["--jobs", "0"], "--jobs must be 1 or more, not 0"),
    ],
)
def test_bench_zoo_names_a_count_or_budget_of_nothing(
    extra: list[str],
    says: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def no_trial(*_: object, **__: object) -> None:
        raise AssertionError("a trial ran")

    monkeypatch.setattr(bench_zoo, "run_one", no_trial)
    with pytest.raises(SystemExit) as exit_info:
        bench_zoo.main(["--mode", "quick", "--out", str(tmp_path / "zoo.json"), *extra])
    assert exit_info.value.code == 2 and says in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
