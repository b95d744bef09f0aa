"""The paired A/B driver (``benchmarks.bench_ab``): its statistic, its file, its command line,
and one real pair of trials of two settings of this tree."""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
from pathlib import Path

import pytest

from benchmarks import ab_table, bench_ab
from benchmarks.bench_zoo import Run
from benchmarks.deep_stats import compare

ROOT = Path(__file__).resolve().parents[1]


ARM = '"root": "/x", "commit": "c1", "env": []'
HEAD = (
    '{"format": "rrosfuzz-bench-ab", "arms": [{"name": "a", ' + ARM + '}, {"name": "b", ' + ARM + "}], "
    '"engines": ["full", "uniform"], "budget": 10, "machine": "m"}\n'
)


def _run(bug: str, seed: int, detected: float | None, first: float | None = 0.1) -> Run:
    return Run(bug, "full", seed, 10.0, detected, 1, 10, 1.0, "fk", -9, 1, first_input=first)


def test_paired_calls_a_consistent_small_gain_faster_that_an_unpaired_test_misses() -> None:
    # the pairs' levels spread widely (the minute's load), the second arm 2 ms sooner in each
    a = [0.15 + 0.01 * i for i in range(12)]
    b = [x - 0.002 for x in a]
    p, diff, sooner, verdict = ab_table.paired(a, b)
    assert verdict == "faster" and p < 0.01 and sooner == 1.0
    assert diff == pytest.approx(-0.002)
    assert compare(b, a)[2] == "tie"  # the unpaired Mann-Whitney U cannot see it
    assert ab_table.paired(b, a)[3] == "slower"


def test_paired_ties() -> None:
    assert ab_table.paired([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]) == (1.0, 0.0, 0.5, "tie")
    p, _, _, verdict = ab_table.paired([0.2, 0.3, 0.4, 0.5, 0.6], [0.21, 0.29, 0.41, 0.49, 0.6])
    assert verdict == "tie" and p > 0.5


def _file(
    path: Path, rows: list[tuple[str, Run]], *, cut: bool = False, engines: tuple[str, str] = ("full", "full")
) -> None:
    header = {
        "format": ab_table.FORMAT,
        "arms": [
            {"name": "old", "root": "/x", "commit": "c1", "env": []},
            {"name": "new", "root": "/x", "commit": "c1", "env": ["A=1"]},
        ],
        "engines": list(engines),
        "budget": 10.0,
        "machine": "m",
    }
    lines = [json.dumps(header)] + [json.dumps({"arm": arm, **asdict(run)}) for arm, run in rows]
    text = "\n".join(lines) + "\n"
    path.write_text(text[:-10] if cut else text)


def test_from_json_tabulates_pairs_and_leaves_out_a_line_cut_short(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = []
    for seed in range(8):
        rows += [
            ("old", _run("wrap_past_pi", seed, 0.20 + 0.01 * seed)),
            ("new", _run("wrap_past_pi", seed, 0.19 + 0.01 * seed)),
        ]
    rows.append(("old", _run("wrap_past_pi", 99, None)))  # half a pair: not counted
    path = tmp_path / "ab.jsonl"
    _file(path, rows, cut=True)
    header, runs = ab_table.read(path)
    assert header["engines"] == ["full", "full"] and len(runs) == 16
    by_bug = bench_ab.main(["--from-json", str(path)])
    assert len(by_bug["wrap_past_pi"]) == 8
    out = capsys.readouterr().out
    assert "| wrap_past_pi | 8 (8/8, 8/8 found) | launch |" in out
    assert "| -10.0 | 1.00 |" in out and "| faster |" in out


def test_from_json_pools_files_and_counts_a_seed_of_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two runs of the same seeds pooled: 16 pairs, not the 8 a (bug, seed) key would keep."""
    paths = []
    for run_index in range(2):
        rows = []
        for seed in range(8):
            rows += [
                ("old", _run("wrap_past_pi", seed, 0.20 + 0.01 * seed + 0.001 * run_index)),
                ("new", _run("wrap_past_pi", seed, 0.19 + 0.01 * seed)),
            ]
        paths.append(tmp_path / f"ab{run_index}.jsonl")
        _file(paths[-1], rows)
    by_bug = bench_ab.main(["--from-json", *map(str, paths)])
    assert len(by_bug["wrap_past_pi"]) == 16
    out = capsys.readouterr().out
    assert "2 files pooled" in out and "| wrap_past_pi | 16 (16/16, 16/16 found) | launch |" in out
    assert len(bench_ab.main(["--from-json", str(paths[0])])["wrap_past_pi"]) == 8


def test_files_of_other_tests_are_not_pooled(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rows = [("old", _run("wrap_past_pi", 0, 0.2)), ("new", _run("wrap_past_pi", 0, 0.19))]
    first, other = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    _file(first, rows)
    _file(other, rows, engines=("full", "uniform"))
    with pytest.raises(SystemExit) as exit_:
        bench_ab.main(["--from-json", str(first), str(other)])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert str(other) in err and "engines" in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("", "its first line is not a bench_ab header"),
        ('{"format": "other"}\n', "its first line is not a bench_ab header"),
        ('{"format": "rrosfuzz-bench-ab", "arms": [{"name": "a"}]}\n', "does not name two arms"),
        (HEAD + '{"arm": "c"}\n', "line 2: not a trial of one of the arms"),
        (
            '{"format": "rrosfuzz-bench-ab", "arms": [{"name": "a"}, {"name": "b"}]}\n',
            "arm root is not a string",
        ),
        (HEAD.replace('"env": []', '"env": [1]', 1), "arm env is not a list of strings"),
        (HEAD.replace('["full", "uniform"]', "[]"), "does not name two engines"),
        (HEAD.replace('"budget": 10', '"budget": "10"'), "budget '10' is not a finite number of seconds"),
        (HEAD.replace('"budget": 10', '"budget": 1' + "0" * 400), "is not a finite number of seconds"),
        (HEAD.replace('"budget": 10', '"budget": NaN'), "budget nan is not a finite number of seconds"),
        (HEAD.replace(', "machine": "m"', ""), "does not name the machine"),
        (
            HEAD + '{"arm": "a", "bug": "b", "engine": "full", "seed": 1, "budget": 10, "detected_at": -1, '
            '"signatures": 1, "executions": 1, "elapsed": 1, "op": "fk", "returncode": 0}\n',
            "line 2: detected_at: -1 is not a finite number of seconds >= 0",
        ),
        (
            HEAD + '{"arm": "a", "bug": 3}\n',
            "line 2: bug: 3 is not str",
        ),
        (HEAD + "[1,\n", "not a bench_ab file (line 2: Expecting"),
    ],
)
def test_a_bad_file_is_named(
    tmp_path: Path, text: str, says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "ab.jsonl"
    path.write_text(text)
    with pytest.raises(SystemExit) as exit_:
        bench_ab.main(["--from-json", str(path)])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert says in err and str(path) in err and "Traceback" not in err


RUNNABLE = ["--arm", "a", ".", "--arm", "b", ".", "X=1", "--bugs", "wrap_past_pi", "--out", "o.jsonl"]
"""A command line that would run (the cases below add one bad option to it)."""


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--arm", "a", "."], "two --arm NAME DIR [VAR=VALUE ...] are needed, not 1"),
        (["--arm", "a", ".", "--arm", "b"], "--arm b: NAME DIR [VAR=VALUE ...] expected"),
        (["--arm", "a", ".", "--arm", "a", ".", "X=1"], "the two arms need different names"),
        (["--arm", "a", ".", "--arm", "b", "."], "the same tree with the same settings"),
        (["--arm", "a", ".", "--arm", "b", ".", "1X=1"], "'1X=1' is not an environment setting"),
        (["--arm", "a", ".", "--arm", "b", "NOSUCH"], "NOSUCH is not an RROSFuzz tree"),
        (["--arm", "a", ".", "--arm", "b", "bare"], "bare has no .venv/bin/python"),
        (["--arm", "a", ".", "--arm", "b", ".", "X=1"], "--bugs and --out are needed"),
        ([*RUNNABLE, "--trials", "0"], "--trials must be a finite number above 0"),
        ([*RUNNABLE, "--first-seed", "0"], "--first-seed must be 1 or more, not 0 (libFuzzer takes -seed=0"),
        ([*RUNNABLE, "--budget", "0.5"], "--budget must be a whole number of seconds (libFuzzer's"),
        (
            [*RUNNABLE, "--bugs", "wrap_past_pi", "narrow_band", "wrap_past_pi"],
            "--bugs names wrap_past_pi more than once",
        ),
    ],
)
def test_a_bad_command_line_is_named_before_anything_runs(
    argv: list[str],
    says: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def no_trial(*_: object, **__: object) -> None:
        raise AssertionError("a trial ran")

    monkeypatch.setattr(bench_ab, "run_one", no_trial)
    (tmp_path / "bare").mkdir()
    (tmp_path / "bare" / "fuzz_diff.py").write_text("")
    monkeypatch.chdir(tmp_path)
    argv = [str(ROOT) if a == "." else a for a in argv]
    with pytest.raises(SystemExit) as exit_:
        bench_ab.main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err


def test_a_file_of_another_test_is_not_resumed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "ab.jsonl"
    _file(out, [])
    argv = [
        "--arm",
        "a",
        str(ROOT),
        "--arm",
        "b",
        str(ROOT),
        "X=1",
        "--bugs",
        "wrap_past_pi",
        "--out",
        str(out),
    ]
    with pytest.raises(SystemExit):
        bench_ab.main(argv)
    assert "exists: --resume goes on with it" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        bench_ab.main([*argv, "--resume"])
    assert "another test (arms:" in capsys.readouterr().err
    argv[-1] = str(tmp_path)  # a folder: named as one, with or without --resume
    for extra in ([], ["--resume"]):
        with pytest.raises(SystemExit):
            bench_ab.main([*argv, *extra])
        assert f"--out {tmp_path} is a folder" in capsys.readouterr().err


@pytest.mark.parametrize("serial", [False, True])
def test_two_settings_of_this_tree_run_as_pairs_and_resume(
    serial: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if not (ROOT / ".venv" / "bin" / "python").is_file():
        pytest.skip("this tree has no .venv (make setup)")
    out = tmp_path / "ab.jsonl"
    argv = [
        "--arm", "plain", str(ROOT),
        "--arm", "set", str(ROOT), "RROSFUZZ_BENCH_AB_TEST=1",
        "--bugs", "axis_not_normalized", "--trials", "2", "--budget", "20", "--out", str(out),
    ] + (["--serial"] if serial else [])  # fmt: skip
    by_bug = bench_ab.main(argv)
    pairs = by_bug["axis_not_normalized"]
    assert len(pairs) == 2 and {a.seed for a, _ in pairs} == {1, 2}
    assert all(r.detected_at is not None and r.first_input is not None for pair in pairs for r in pair)
    header, runs = ab_table.read(out)
    assert [a["env"] for a in header["arms"]] == [[], ["RROSFUZZ_BENCH_AB_TEST=1"]]
    assert header["serial"] is serial
    assert sorted(side for side, _ in runs) == ["a", "a", "b", "b"]
    capsys.readouterr()
    again = bench_ab.main([*argv, "--resume"])  # nothing left to run: the same pairs, tabulated
    assert "0 of 2 pairs to run" in capsys.readouterr().out
    assert again.keys() == by_bug.keys() and len(again["axis_not_normalized"]) == 2
    flipped = [x for x in argv if x != "--serial"] + ([] if serial else ["--serial"])
    with pytest.raises(SystemExit):  # the other mode is another test
        bench_ab.main([*flipped, "--resume"])
    assert "another test (serial:" in capsys.readouterr().err


def test_a_trial_runs_in_its_arm_s_tree_with_its_python_and_settings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from benchmarks import bench_zoo
    from benchmarks.bench_deep import BUGS

    seen: list[tuple[list[str], Path]] = []

    def fake(cmd: list[str], artifacts: Path, timeout: float, cwd: Path) -> int:
        seen.append((cmd, cwd))
        return 0

    monkeypatch.setattr(bench_zoo, "run_until_detection", fake)
    tree = tmp_path / "tree"
    bench_zoo.run_one(
        BUGS["wrap_past_pi"], "full", 3, 1.0, stop_at_detection=True, root=tree, python="/py", env=["X=1"]
    )
    bench_zoo.run_one(
        BUGS["wrap_past_pi"], "uniform", 3, 1.0, stop_at_detection=True, root=tree, python="/py"
    )
    (full, cwd), (uniform, _) = seen
    assert cwd == tree and full[:4] == ["env", "X=1", "/py", str(tree / "fuzz_diff.py")]
    assert uniform[:3] == ["/py", "-m", "benchmarks.baselines"] and "-seed=3" in full


def test_resume_drops_a_last_line_cut_short_before_the_next_pair_is_appended(tmp_path: Path) -> None:
    out = tmp_path / "ab.jsonl"
    pair = [("old", _run("wrap_past_pi", 0, 0.2)), ("new", _run("wrap_past_pi", 0, 0.19))]
    _file(out, [*pair, ("old", _run("wrap_past_pi", 1, 0.2))], cut=True)  # killed while writing
    header = {**json.loads(out.read_text().split("\n")[0]), "serial": False}
    done = bench_ab._open(argparse.ArgumentParser(), out, header, resume=True)
    assert list(done) == [("wrap_past_pi", 0)]
    with out.open("a") as handle:  # as _run appends the pair it runs again
        for arm, run in [("old", _run("wrap_past_pi", 1, 0.2)), ("new", _run("wrap_past_pi", 1, 0.18))]:
            handle.write(json.dumps({"arm": arm, **asdict(run)}) + "\n")
    assert len(ab_table.read(out)[1]) == 4


def test_the_paired_verdict_goes_the_way_the_signed_ranks_do() -> None:
    """21 pairs where b is under 1 ms sooner and 19 where it is 1-19 s later: the Wilcoxon test is
    significant because b is later (W+ 589 against W- 231), where the share of pairs b wins
    (0.525) said "faster"."""
    a = [1.0] * 40
    b = [1.0 - 0.0005] * 21 + [1.0 + s for s in range(1, 20)]
    p, _, sooner, verdict = ab_table.paired(a, b)
    assert p < 0.05 and sooner > 0.5 and verdict == "slower"
    assert ab_table.paired(b, a)[3] == "faster"


def test_a_detection_past_the_budget_counts_as_the_budget() -> None:
    """As in the trial tables (``deep_stats.censored``): a pair's time is capped at the budget,
    a miss counted as the budget; a detection at 10.4 s of a 10-s trial kept its 10.4."""
    assert ab_table._censored(10.4, 10.0) == 10.0
    assert ab_table._censored(None, 10.0) == 10.0
    assert ab_table._censored(0.25, 10.0) == 0.25
