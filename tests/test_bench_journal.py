"""bench_deep's journal: a sweep of hours keeps every finished trial and goes on with --resume."""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace

import pytest

from benchmarks import bench_deep, bench_zoo, deep_stats, journal, sweeps, trials
from benchmarks.bench_zoo import Run
from benchmarks.zoo import CONTROL, Bug

QUICK = ["--mode", "quick", "--trials", "2", "--jobs", "1"]
"""2 bugs x 2 engines x 2 trials: 8 trials."""


class Interrupted(Exception):
    """Stands for a sweep killed part way (a reboot, a session's end)."""


class FakeTrials:
    """``run_one`` without a process: each trial takes a minute of a fake clock; ``fail_at``
    interrupts the sweep at that call."""

    def __init__(self, fail_at: int | None = None) -> None:
        self.calls: list[tuple[str, str, int]] = []
        self.now = 0.0
        self.fail_at = fail_at

    def monotonic(self) -> float:
        return self.now

    def __call__(self, bug: Bug, engine: str, seed: int, budget: float, *_: object, **__: object) -> Run:
        if self.fail_at is not None and len(self.calls) == self.fail_at:
            raise Interrupted
        self.calls.append((bug.name, engine, seed))
        self.now += 60.0
        at = 1.0 + seed if engine == "full" else None
        return Run(
            bug.name, engine, seed, budget, at, int(at is not None), 10, 1.0, bug.op, -9, first_input=0.5
        )


@pytest.fixture
def fake(monkeypatch: pytest.MonkeyPatch) -> FakeTrials:
    trials = FakeTrials()
    monkeypatch.setattr(bench_deep, "run_one", trials)
    monkeypatch.setattr(sweeps, "time", SimpleNamespace(monotonic=trials.monotonic))
    # the tree under test may have uncommitted changes: one commit, the same code (the rule
    # itself: the last test, on a repository of its own)
    monkeypatch.setattr(journal, "commit_of", lambda root: "c" * 40)
    monkeypatch.setattr(journal, "same_code", lambda root, commit: commit == "c" * 40)
    return trials


def _sweep(results: Path, *extra: str) -> list[Run]:
    return bench_deep.main([*QUICK, "--results", str(results), *extra])


def test_a_sweep_cut_short_goes_on_with_resume_and_runs_only_what_is_missing(
    fake: FakeTrials, tmp_path: Path
) -> None:
    everything = _sweep(tmp_path / "whole")  # the order and records of an uninterrupted sweep
    assert len(everything) == 8 and not (tmp_path / "whole" / "deep-quick.jsonl").exists()
    order = list(fake.calls)
    fake.calls.clear()
    fake.fail_at = 3
    with pytest.raises(Interrupted):
        _sweep(tmp_path)
    held = journal.read(tmp_path / "deep-quick.jsonl")[1]
    assert [(r.bug, r.engine, r.seed) for r in held] == order[:3]  # each trial kept as it ended
    assert not (tmp_path / "deep-quick.json").exists()
    fake.calls.clear()
    fake.fail_at = None
    runs = _sweep(tmp_path, "--resume")
    assert fake.calls == order[3:]
    assert runs == everything  # the same records in the same order as one sweep's
    assert [journal.run_of(row) for row in json.loads((tmp_path / "deep-quick.json").read_text())] == runs
    assert not (tmp_path / "deep-quick.jsonl").exists()  # deep-quick.json holds them all


def test_stop_after_starts_no_trial_past_its_minutes(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = _sweep(tmp_path, "--stop-after", "2.5")  # trials end at minutes 1, 2, 3
    assert len(runs) == 3 and len(fake.calls) == 3
    said = capsys.readouterr().out
    assert "3 of 8 trials done" in said and "about 0.1 hours at this run's pace" in said  # 5 x 60 s
    assert f"--from-json {tmp_path / 'deep-quick.jsonl'} tabulates them so far" in said
    assert len(journal.read(tmp_path / "deep-quick.jsonl")[1]) == 3
    # a journal so far is tabulated as a results file, its counts per cell as they are
    journal_so_far = str(tmp_path / "deep-quick.jsonl")
    elsewhere = ["--results", str(tmp_path / "t")]  # not the repository's benchmarks/results
    shown = bench_deep.main(["--mode", "quick", "--from-json", journal_so_far, *elsewhere])
    assert "A sweep in progress: the 3 trials its journal holds so far" in capsys.readouterr().out
    with pytest.raises(SystemExit):  # a partial table does not replace BENCHMARKS.md's
        bench_deep.main(["--from-json", journal_so_far, "--write-md", *elsewhere])
    assert "a journal so far is no finished table" in capsys.readouterr().err
    assert sorted(shown, key=lambda r: (r.bug, r.engine, r.seed)) == sorted(
        runs, key=lambda r: (r.bug, r.engine, r.seed)
    )
    assert len(_sweep(tmp_path, "--resume")) == 8


def test_tabulating_a_file_writes_no_plot_over_the_tables_own(
    fake: FakeTrials, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _sweep(tmp_path / "done")
    monkeypatch.setattr(bench_deep, "RESULTS", tmp_path / "repository")  # benchmarks/results
    tables = tmp_path / "repository"
    tables.mkdir()
    (tables / "deep-quick.png").write_bytes(b"the table's own plot")
    bench_deep.main(["--mode", "quick", "--from-json", str(tmp_path / "done" / "deep-quick.json")])
    assert (tables / "deep-quick.png").read_bytes() == b"the table's own plot"
    bench_deep.main(
        ["--from-json", str(tmp_path / "done" / "deep-quick.json"), "--results", str(tmp_path / "t")]
    )
    assert (tmp_path / "t" / "deep-quick.png").is_file()  # asked for: written


def test_an_unfinished_journal_is_neither_overwritten_nor_resumed_by_another_sweep(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    _sweep(tmp_path, "--stop-after", "1.5")
    path = tmp_path / "deep-quick.jsonl"
    kept = path.read_bytes()
    for extra, says in (
        ((), "holds an unfinished sweep: --resume"),
        (("--resume", "--trials", "3"), "written for another sweep (trials 2, this run's 3)"),
        (("--resume", "--restart"), "exclude each other"),
        (("--stop-after", "0"), "--stop-after must be a positive number"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            _sweep(tmp_path, *extra)
        assert exit_info.value.code == 2 and says in capsys.readouterr().err, extra
        assert path.read_bytes() == kept
    monkeypatch.setattr(journal, "same_code", lambda root, commit: False)  # the engine changed since
    with pytest.raises(SystemExit):
        _sweep(tmp_path, "--resume")
    assert f"written by commit {'c' * 40}, and this tree" in capsys.readouterr().err
    assert path.read_bytes() == kept
    with pytest.raises(SystemExit):
        _sweep(tmp_path / "elsewhere", "--resume")
    assert "nothing to resume" in capsys.readouterr().err
    _sweep(tmp_path, "--restart", "--stop-after", "0.5")
    assert (tmp_path / "deep-quick.jsonl.old").read_bytes() == kept
    second = path.read_bytes()
    _sweep(tmp_path, "--restart", "--stop-after", "0.5")  # a second restart keeps both
    assert (tmp_path / "deep-quick.jsonl.old").read_bytes() == kept
    assert (tmp_path / "deep-quick.jsonl.old.2").read_bytes() == second


def test_first_seed_runs_other_seeds_in_files_of_their_own(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = _sweep(tmp_path, "--first-seed", "10")
    assert sorted({r.seed for r in runs}) == [10, 11] and len(runs) == 8
    assert sorted({seed for _, _, seed in fake.calls}) == [10, 11]
    assert (tmp_path / "deep-quick-seeds10-11.json").exists() and (
        tmp_path / "deep-quick-seeds10-11.png"
    ).exists()
    assert not (tmp_path / "deep-quick.json").exists()  # the tables' seeds' file is not touched
    for extra, says in (
        (("--first-seed", "10", "--write-md"), "--write-md takes the tables' seeds"),
        (("--first-seed", "-1"), "--first-seed must be 0 or more"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            _sweep(tmp_path / "refused", *extra)
        assert exit_info.value.code == 2 and says in capsys.readouterr().err, extra
    assert not (tmp_path / "refused").exists()
    # a journal keeps its seeds: resumed with other seeds, it is another sweep's
    _sweep(tmp_path / "part", "--first-seed", "10", "--stop-after", "1.5")
    held = tmp_path / "part" / "deep-quick-seeds10-11.jsonl"
    assert json.loads(held.read_text().splitlines()[0])["first_seed"] == 10
    held.rename(tmp_path / "part" / "deep-quick-seeds20-21.jsonl")
    with pytest.raises(SystemExit):
        _sweep(tmp_path / "part", "--first-seed", "20", "--resume")
    assert "written for another sweep (first_seed 10, this run's 20)" in capsys.readouterr().err
    # a journal written before --first-seed existed holds seeds from 0
    header = journal.Sweep("quick", ("b",), ("full",), 2, 10.0, "c" * 40).header()
    del header["first_seed"]
    assert journal.sweep_of(header, "bench_deep").first_seed == 0
    with pytest.raises(journal.JournalError, match="first_seed"):
        journal.sweep_of({**header, "first_seed": "10"}, "bench_deep")
    # a damaged header's counts: 10**7 trials were planned before anything was read (memory filled)
    for bad in ({"trials": 10**7}, {"trials": 0}, {"first_seed": -1}, {"budget": float("nan")}):
        with pytest.raises(journal.JournalError, match=r"out of range|budget"):
            journal.sweep_of({**header, **bad}, "bench_deep")


def test_a_journal_resumes_only_on_the_kind_of_machine_that_began_it(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(journal, "machine_of", lambda: "AMD EPYC, 2 CPUs")
    _sweep(tmp_path, "--stop-after", "1.5")
    path = tmp_path / "deep-quick.jsonl"
    lines = path.read_text().splitlines(keepends=True)
    assert json.loads(lines[0])["machine"] == "AMD EPYC, 2 CPUs"
    monkeypatch.setattr(journal, "machine_of", lambda: "Intel Xeon, 2 CPUs")
    with pytest.raises(SystemExit):
        _sweep(tmp_path, "--resume")
    said = capsys.readouterr().err
    assert "its trials ran on another machine (AMD EPYC, 2 CPUs; this one: Intel Xeon, 2 CPUs)" in said
    assert path.read_text().splitlines(keepends=True) == lines
    # a journal from before machines were kept (no "machine") resumes anywhere
    header = json.loads(lines[0])
    del header["machine"]
    path.write_text(json.dumps(header) + "\n" + "".join(lines[1:]))
    assert len(_sweep(tmp_path, "--resume")) == 8


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (("--trials", "0"), "--trials must be a finite number above 0, not 0"),
        (("--trials", "-2"), "--trials must be a finite number above 0, not -2"),
        (("--budget", "0"), "--budget must be a finite number above 0, not 0.0"),
        (("--budget", "-5"), "--budget must be a finite number above 0, not -5.0"),
        (("--budget", "nan"), "--budget must be a finite number above 0, not nan"),
        (("--budget", "inf"), "--budget must be a finite number above 0, not inf"),
        (("--jobs", "0"), "--jobs must be 1 or more, not 0"),
        (("--jobs", "-1"), "--jobs must be 1 or more, not -1"),
    ],
)
def test_a_count_or_budget_of_nothing_is_named_and_nothing_runs(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: tuple[str, ...], says: str
) -> None:
    # before, 0 meant the mode's default, and a negative budget or number of jobs ran anyway
    with pytest.raises(SystemExit) as exit_info:
        bench_deep.main(["--mode", "quick", "--results", str(tmp_path), *extra])
    assert exit_info.value.code == 2 and says in capsys.readouterr().err
    assert fake.calls == [] and list(tmp_path.iterdir()) == []


def test_a_results_folder_that_cannot_be_made_is_named_before_any_trial(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    for main, extra in (
        (bench_deep.main, ["--mode", "quick", "--results", str(blocked / "results")]),
        (bench_zoo.main, ["--mode", "quick", "--out", str(blocked / "results" / "zoo.json")]),
    ):
        with pytest.raises(SystemExit) as exit_info:
            main(extra)
        said = capsys.readouterr().err
        assert exit_info.value.code == 2 and f"{blocked / 'results'}: cannot hold the results" in said
        assert "Traceback" not in said
    assert fake.calls == [] and blocked.read_text() == "not a folder"


def _changed(line: str, **changes: object) -> str:
    """A journal line with some fields of its trial changed."""
    return json.dumps({**json.loads(line), **changes}) + "\n"


def test_a_last_line_cut_short_runs_again_and_a_bad_line_is_named(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _sweep(tmp_path, "--stop-after", "2.5")
    path = tmp_path / "deep-quick.jsonl"
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:-1]) + lines[-1][:20])  # killed while writing its third trial
    assert len(journal.read(path)[1]) == 2
    fake.calls.clear()
    assert len(_sweep(tmp_path, "--resume")) == 8 and len(fake.calls) == 6
    for bad, says in (
        ('{"journal": "something else"}\n', "not a bench_deep journal"),
        (lines[0] + "[1, 2]\n" + lines[1], "line 2: not a trial"),
        (lines[0] + '{"bug": "x"}\n\n', "line 2: not a trial"),
        (lines[0] + _changed(lines[1], detected_at="soon"), "'soon' is not int or float or null"),
        (lines[0] + _changed(lines[1], seed=True), "seed: True is not int"),
        (lines[0] + _changed(lines[1], fields=[1]), "fields: not a list of strings"),
        ("\x00\xff\n", "not a bench_deep journal"),
        (lines[0] + _changed(lines[1], elapsed=0), "elapsed: 0 is not a finite number of seconds > 0"),
        (lines[0] + _changed(lines[1], budget=-10), "budget: -10 is not a finite number of seconds > 0"),
        (lines[0] + _changed(lines[1], detected_at=10**400), "is not a finite number of seconds >= 0"),
        (lines[0] + "[" * 100_000 + "\n" + lines[1], "line 2: not a trial"),  # nested past the limit
        ("[" * 100_000 + "\n", "not a bench_deep journal"),
    ):
        path.write_text(bad)
        with pytest.raises(SystemExit):
            _sweep(tmp_path, "--resume")
        assert says in capsys.readouterr().err, bad


def _git(repo: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-c", "user.name=t", "-c", "user.email=t@t", *args],
        cwd=repo,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()


def test_the_same_code_means_the_commit_or_a_later_one_with_only_results_and_prose(tmp_path: Path) -> None:
    repo = tmp_path / "repo"
    (repo / "benchmarks" / "results").mkdir(parents=True)
    (repo / "engine.py").write_text("A = 1\n")
    (repo / "benchmarks" / "results" / "r.json").write_text("[]\n")
    (repo / "NOTES.md").write_text("x\n")
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "commit", "-q", "-m", "one")
    first = journal.commit_of(repo)
    assert len(first) == 40 and journal.same_code(repo, first)
    (repo / "benchmarks" / "results" / "r.json").write_text("[1]\n")
    (repo / "NOTES.md").write_text("y\n")
    _git(repo, "commit", "-qam", "results and notes")
    assert journal.same_code(repo, first)  # a session's partial results and notes
    # results a sweep writes into the tree (make bench's earlier steps) leave it clean
    (repo / "benchmarks" / "results" / "r.json").write_text("[2]\n")
    assert not journal.commit_of(repo).endswith("+dirty")
    (repo / "engine.py").write_text("A = 2\n")
    assert journal.commit_of(repo).endswith("+dirty") and not journal.same_code(repo, first)
    _git(repo, "commit", "-qam", "engine")
    assert not journal.same_code(repo, first)
    assert not journal.same_code(repo, first + "+dirty") and not journal.same_code(repo, "0" * 40)
    assert journal.commit_of(tmp_path / "nowhere") == "unknown"


def test_one_sweep_at_a_time_writes_a_journal(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A second sweep on the same results folder, while the first runs, stops with an error
    instead of running the same trials into the same file; the first one's lock goes with it."""
    seen: list[str] = []

    def second_sweep_meanwhile(bug: Bug, engine: str, seed: int, budget: float, **_: object) -> Run:
        if not seen:
            with pytest.raises(SystemExit):
                _sweep(tmp_path, "--resume")
            seen.append(capsys.readouterr().err)
        return fake(bug, engine, seed, budget)

    bench_deep.run_one = second_sweep_meanwhile  # type: ignore[assignment]  # restored by the fixture
    assert len(_sweep(tmp_path)) == 8 and len(seen) == 1
    assert "another bench_deep is running this sweep now" in seen[0]
    assert not (tmp_path / "deep-quick.jsonl.lock").exists() and not (tmp_path / "deep-quick.jsonl").exists()
    # a refused start (another sweep's journal, no --resume) leaves no lock behind either
    _sweep(tmp_path, "--stop-after", "0.5")
    with pytest.raises(SystemExit):
        _sweep(tmp_path)
    assert not (tmp_path / "deep-quick.jsonl.lock").exists()
    assert len(_sweep(tmp_path, "--resume")) == 8


def test_a_journal_so_far_is_tabulated_with_its_gaps_named(tmp_path: Path) -> None:
    """A partial sweep may hold a bug's baseline trials and none of the full engine's yet, or
    the other way round: the cells say so instead of the statistics dividing by zero."""
    mode = deep_stats.Mode(("narrow_band", "ik_seed_band"), 3, 60.0, ("full", "uniform", "libfuzzer"))
    runs = [Run("narrow_band", "uniform", i, 60.0, 1.0 + i, 1, 10, 1.0, "fk", -9) for i in range(3)]
    runs += [Run("ik_seed_band", "full", i, 60.0, None, 0, 10, 60.0, "scenario", 0) for i in range(2)]
    text = deep_stats.markdown(runs, mode, "cmd")
    first = next(line for line in text.splitlines() if line.startswith("| narrow_band "))
    assert [c.strip() for c in first.strip("|").split("|")][1:] == [
        "n/a (no trials)",
        "2.0 (3/3)",
        "n/a (no trials)",
        "n/a",
        "n/a",
    ]
    second = next(line for line in text.splitlines() if line.startswith("| ik_seed_band "))
    assert second.count("n/a (no trials)") == 2  # uniform and libFuzzer's mutator ran no trial yet
    deep_stats.plot(runs, mode, tmp_path / "partial.png")


def test_bench_zoo_keeps_a_journal_too_and_runs_in_a_seeded_random_order(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``make bench``'s first step (about two hours in full mode) goes on where it stopped as
    the deep one does; its runs go in a seeded random order and come back in the plan's."""
    monkeypatch.setattr(bench_zoo, "run_one", fake)
    sweep = ["--bugs", "off_by_tolerance", CONTROL.name, "--engines", "full", "uniform", "--seeds", "2"]
    sweep += ["--jobs", "1", "--budget", "5"]
    whole = bench_zoo.main([*sweep, "--out", str(tmp_path / "whole" / "zoo.json")])
    plan = [
        (b.name, e, s)
        for b, e, s in bench_zoo.plan_jobs(("off_by_tolerance", CONTROL.name), ("full", "uniform"), 2)
    ]
    assert [(r["bug"], r["engine"], r["seed"]) for r in whole["runs"]] == plan and len(plan) == 8
    order = list(fake.calls)
    assert sorted(order) == sorted(plan) and order != plan  # run in another order than the plan's
    assert not (tmp_path / "whole" / "zoo.jsonl").exists()  # zoo.json holds them all
    out = ["--out", str(tmp_path / "zoo.json")]
    fake.calls.clear()
    part = bench_zoo.main([*sweep, *out, "--stop-after", "2.5"])
    assert part == {"runs": part["runs"], "complete": False} and fake.calls == order[:3]
    said = capsys.readouterr().out
    assert "3 of 8 trials done" in said and not (tmp_path / "zoo.json").exists()
    # the stop names bench_zoo's own way to tabulate a journal so far, and it does
    assert f"--render {tmp_path / 'zoo.jsonl'} tabulates them so far" in said
    shown = bench_zoo.main(["--render", str(tmp_path / "zoo.jsonl")])
    assert shown["runs"] == part["runs"]
    said = capsys.readouterr().out
    assert (
        said.startswith("A sweep in progress: 3 of its 8 runs so far")
        and "| off_by_tolerance | move |" in said
    )
    for extra, says in (
        (("--write-md",), "a journal so far is no finished table"),  # BENCHMARKS.md keeps its table
    ):
        with pytest.raises(SystemExit):
            bench_zoo.main(["--render", str(tmp_path / "zoo.jsonl"), *extra])
        assert says in capsys.readouterr().err
    # a finished result that is not a table's (two bugs of the quick mode's three): refused too,
    # where it replaced BENCHMARKS.md's table
    with pytest.raises(SystemExit):
        bench_zoo.main(["--render", str(tmp_path / "whole" / "zoo.json"), "--write-md"])
    assert "not a table's bugs, engines and seeds" in capsys.readouterr().err
    kept = (tmp_path / "zoo.jsonl").read_bytes()
    header = json.loads(kept.split(b"\n")[0])
    for name, text, says in (
        ("no-header.jsonl", kept.split(b"\n", 1)[1], "not a bench_zoo journal"),
        ("bad-engines.jsonl", kept.replace(b'"engines": [', b'"engines": [1, ', 1), "the header's engines"),
        (
            "unknown.jsonl",
            kept.replace(b'"off_by_tolerance"', b'"no_such_bug"', 1),
            "unknown bugs ['no_such_bug']",
        ),
        ("garbage.json", b"\xff[", "not a bench_zoo result or journal"),
        ("missing.json", None, "not a bench_zoo result or journal"),
    ):
        if text is not None:
            (tmp_path / name).write_bytes(text)
        with pytest.raises(SystemExit):  # a clear error naming the file, not a traceback
            bench_zoo.main(["--render", str(tmp_path / name)])
        err = capsys.readouterr().err
        assert says in err and name in err, (name, err)
    assert header["engines"] == ["full", "uniform"]
    for extra, says in (
        ((), "holds an unfinished sweep: --resume"),
        (("--resume", "--replay"), "written for another sweep (replay False, this run's True)"),
        (("--resume", "--seeds", "3"), "written for another sweep (trials 2, this run's 3)"),
    ):
        with pytest.raises(SystemExit):
            bench_zoo.main([*sweep, *out, *extra])
        assert says in capsys.readouterr().err, extra
        assert (tmp_path / "zoo.jsonl").read_bytes() == kept
    (tmp_path / "deep").mkdir()
    (tmp_path / "deep" / "deep-quick.jsonl").write_bytes(kept)
    with pytest.raises(SystemExit):  # another tool's journal is not taken for this one's
        bench_deep.main([*QUICK, "--results", str(tmp_path / "deep"), "--resume"])
    assert "not a bench_deep journal" in capsys.readouterr().err
    fake.calls.clear()
    done = bench_zoo.main([*sweep, *out, "--resume"])
    assert fake.calls == order[3:] and done["runs"] == whole["runs"] and done["cells"] == whole["cells"]
    assert not (tmp_path / "zoo.jsonl").exists() and not (tmp_path / "zoo.jsonl.lock").exists()


def test_bench_zoo_first_seed_runs_other_seeds_in_files_of_their_own(
    fake: FakeTrials, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Controls beyond the tables' seeds 1..N: ``--first-seed`` runs seeds from there, in files of
    their own, and a journal from before it (seeds from 1) still resumes as what it held."""
    monkeypatch.setattr(bench_zoo, "run_one", fake)
    monkeypatch.setattr(bench_zoo, "RESULTS", tmp_path)
    sweep = ["--mode", "controls", "--bugs", CONTROL.name, "--engines", "full", "--seeds", "3"]
    sweep += ["--jobs", "1", "--budget", "5"]
    result = bench_zoo.main([*sweep, "--first-seed", "11"])
    assert sorted(seed for _, _, seed in fake.calls) == [11, 12, 13]
    assert sorted(r["seed"] for r in result["runs"]) == [11, 12, 13] and result["first_seed"] == 11
    assert (tmp_path / "zoo-controls-seeds11-13.json").exists() and not (
        tmp_path / "zoo-controls.json"
    ).exists()
    assert "x 3 seed(s) (11-13)," in capsys.readouterr().out
    for extra, says in (
        (("--first-seed", "11", "--write-md"), "--write-md takes the tables' seeds (from 1)"),
        (("--first-seed", "0"), "--first-seed must be 1 or more (libFuzzer's -seed=0 is the clock's)"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            bench_zoo.main([*sweep, *extra])
        assert exit_info.value.code == 2 and says in capsys.readouterr().err, extra
    # the default is the tables' seeds, from 1, in the tables' file
    fake.calls.clear()
    out = ["--out", str(tmp_path / "part" / "zoo.json")]
    bench_zoo.main([*sweep, *out, "--stop-after", "1.5"])
    first_two = {seed for _, _, seed in fake.calls}  # in the sweep's seeded random order
    assert len(first_two) == 2 and first_two < {1, 2, 3}
    held = tmp_path / "part" / "zoo.jsonl"
    lines = held.read_text().splitlines(keepends=True)
    header = json.loads(lines[0])
    assert header["first_seed"] == 1
    with pytest.raises(SystemExit):  # resumed with other seeds, it is another sweep's
        bench_zoo.main([*sweep, *out, "--first-seed", "2", "--resume"])
    assert "written for another sweep (first_seed 1, this run's 2)" in capsys.readouterr().err
    # a journal written before --first-seed (first_seed 0, bench_deep's default, or none) held
    # seeds from 1: it resumes with the default and runs only the one it lacks
    for old in (0, None):
        if old is None:
            del header["first_seed"]
        else:
            header["first_seed"] = old
        held.write_text(json.dumps(header) + "\n" + "".join(lines[1:]))
        assert journal.sweep_of(header, "bench_zoo").first_seed == 1
        fake.calls.clear()
        done = bench_zoo.main([*sweep, *out, "--resume"])
        assert [seed for _, _, seed in fake.calls] == sorted({1, 2, 3} - first_two), old
        assert sorted(r["seed"] for r in done["runs"]) == [1, 2, 3]
        (tmp_path / "part" / "zoo.json").unlink()
    assert journal.sweep_of({**header, "first_seed": 0}, "bench_deep").first_seed == 0


def test_each_trial_running_at_a_time_has_a_cpu_of_its_own(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two trials at a time on two cores: each pinned to its own (as FuzzBench gives each trial
    its own), so that neither takes the other's time; unpinned when there are too few CPUs."""
    monkeypatch.setattr(sweeps, "cores", lambda workers: [5, 7][:workers])
    seen: list[tuple[int | None, float, float]] = []

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        began = time.monotonic()
        time.sleep(0.05)
        seen.append((cpu, began, time.monotonic()))
        bug, engine, seed = job
        return Run(bug.name, engine, seed, 1.0, None, 0, 1, 1.0, bug.op, 0)

    bug = bench_deep.BUGS["narrow_band"]
    jobs = [(bug, engine, seed) for engine in ("full", "uniform") for seed in range(4)]
    sweep = journal.Sweep("quick", ("narrow_band",), ("full", "uniform"), 4, 1.0, "c" * 40)
    book, _ = journal.open_sweep(tmp_path / "j.jsonl", sweep, tmp_path, resume=False, restart=False)
    progress = sweeps.run_sweep(book, jobs, [], trial, workers=2)
    assert progress.complete and {cpu for cpu, _, _ in seen} == {5, 7}
    for i, (cpu, began, ended) in enumerate(seen):
        for other, b, e in seen[i + 1 :]:
            assert cpu != other or e <= began or ended <= b, "two trials ran on one CPU at once"
    mine = sorted(os.sched_getaffinity(0))
    monkeypatch.undo()
    assert sweeps.cores(len(mine) + 1) is None  # more trials at a time than CPUs: none pinned
    if shutil.which("taskset") is not None:
        assert sweeps.cores(1) == mine[:1]
        shown = subprocess.run(
            sweeps.pinned(
                [sys.executable, "-c", "import os; print(sorted(os.sched_getaffinity(0)))"], mine[-1]
            ),
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        assert shown.strip() == str([mine[-1]])
    assert sweeps.pinned(["x"], None) == ["x"]


@pytest.fixture
def ctrl_c(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[], None]]:
    """SIGINT raises ``KeyboardInterrupt``, as in a terminal. A shell starts a background job (a
    CI step, say) with SIGINT ignored, and a sweep then leaves it so.

    Yields a Ctrl-C for a thread other than the main one: SIGINT to this process, returning
    once the sweep's handler has run in the main thread (they used to sleep a while instead,
    which a loaded machine could outlast: two SIGINTs pending are one)."""
    handled = threading.Semaphore(0)
    install = sweeps._handle_sigint

    def handle_and_say(handler: Callable[..., None]) -> Callable[..., object] | int | None:
        def then_say(*args: object) -> None:
            try:
                handler(*args)
            finally:
                handled.release()

        return install(then_say)

    def press() -> None:
        os.kill(os.getpid(), signal.SIGINT)
        assert handled.acquire(timeout=60.0), "the sweep's SIGINT handler never ran"

    monkeypatch.setattr(sweeps, "_handle_sigint", handle_and_say)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield press
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_starts_no_other_trial_and_keeps_the_finished_ones(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ctrl_c: Callable[[], None]
) -> None:
    """Ctrl-C during a sweep (``KeyboardInterrupt`` in the main thread): the trial running ends
    and is kept, no other starts, and the sweep says how to go on, with a shell's status 130
    rather than a traceback (it used to wait for every queued trial: hours)."""
    started: list[int] = []

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        bug, engine, seed = job
        started.append(seed)
        if seed == 1:
            ctrl_c()  # while the main thread waits for the trials
        return Run(bug.name, engine, seed, 1.0, None, 0, 1, 1.0, bug.op, 0)

    bug = bench_deep.BUGS["narrow_band"]
    jobs = [(bug, "full", seed) for seed in range(6)]
    sweep = journal.Sweep("quick", ("narrow_band",), ("full",), 6, 1.0, "c" * 40)
    path = tmp_path / "j.jsonl"
    book, _ = journal.open_sweep(path, sweep, tmp_path, resume=False, restart=False)
    progress = sweeps.run_sweep(book, jobs, [], trial, workers=1)
    assert progress.interrupted and not progress.complete
    assert started == [0, 1] and [r.seed for r in progress.runs] == [0, 1]
    assert [r.seed for r in journal.read(path)[1]] == [0, 1], "both finished trials are in the journal"
    assert progress.stopped(path, None, "--from-json").startswith("interrupted: 2 of 6 trials done")

    monkeypatch.setattr(journal, "same_code", lambda root, commit: commit == "c" * 40)
    args = SimpleNamespace(resume=True, restart=False, jobs=1, stop_after=None)
    again: list[int] = []

    def stop_at_once(job: sweeps.Job, cpu: int | None) -> Run:
        again.append(job[2])
        ctrl_c()
        return trial(job, cpu)

    with pytest.raises(SystemExit) as stopped:
        sweeps.sweep_in_journal(
            argparse.ArgumentParser(), args, path, sweep, tmp_path, jobs, stop_at_once, "-"
        )
    assert stopped.value.code == 130 and again == [2], "resumed where it stopped, then interrupted again"


def test_a_trials_processes_run_in_a_session_of_their_own(tmp_path: Path) -> None:
    """A terminal's Ctrl-C goes to the sweep's process group. A trial's campaign ran in that
    group in bench_zoo's full mode, so the first Ctrl-C cut the trials running short (3 s of 10,
    exit 130) and the sweep kept them as whole trials."""
    seen = tmp_path / "sid"
    code = f"import os; open({str(seen)!r}, 'w').write(f'{{os.getsid(0)}} {{os.getpgrp()}}')"
    assert trials.run_to_end([sys.executable, "-c", code], 60, tmp_path) == 0
    sid, group = map(int, seen.read_text().split())
    assert sid != os.getsid(0) and group != os.getpgrp()


def test_a_second_ctrl_c_kills_the_trials_running_and_keeps_none_of_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ctrl_c: Callable[[], None]
) -> None:
    """The first Ctrl-C lets the trials running finish (up to a budget plus its margin); a second
    one kills them, and the journal keeps only the trials that had finished. It used to end in
    a traceback, with the trials' processes left running."""
    started = tmp_path / "started"
    statuses: list[int] = []

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        bug, engine, seed = job
        if seed == 1:
            code = f"import time; open({str(started)!r}, 'w'); time.sleep(30)"
            statuses.append(trials.run_to_end([sys.executable, "-c", code], 60, tmp_path))
        return Run(bug.name, engine, seed, 1.0, None, 0, 1, 1.0, bug.op, 0)

    def press_ctrl_c_twice() -> None:
        deadline = time.monotonic() + 60.0  # a trial that never starts fails the test, never hangs it
        while not started.exists():
            if time.monotonic() > deadline:
                return
            time.sleep(0.02)
        ctrl_c()
        ctrl_c()

    bug = bench_deep.BUGS["narrow_band"]
    jobs = [(bug, "full", seed) for seed in range(3)]
    sweep = journal.Sweep("quick", ("narrow_band",), ("full",), 3, 1.0, "c" * 40)
    path = tmp_path / "j.jsonl"
    book, _ = journal.open_sweep(path, sweep, tmp_path, resume=False, restart=False)
    presser = threading.Thread(target=press_ctrl_c_twice)
    presser.start()
    progress = sweeps.run_sweep(book, jobs, [], trial, workers=1)
    presser.join()
    assert statuses == [-signal.SIGKILL], "the trial's process was killed"
    assert progress.interrupted and [r.seed for r in progress.runs] == [0]
    assert [r.seed for r in journal.read(path)[1]] == [0], "the killed trial is not in the journal"
    monkeypatch.setattr(journal, "same_code", lambda root, commit: commit == "c" * 40)
    book, done = journal.open_sweep(path, sweep, tmp_path, resume=True, restart=False)
    again = sweeps.run_sweep(
        book, jobs, done, lambda job, cpu: Run(bug.name, "full", job[2], 1.0, None, 0, 1, 1.0, bug.op, 0), 1
    )
    assert again.complete, "the next sweep starts trials again"


def test_compile_tree_writes_the_bytecode_a_trial_imports(tmp_path: Path) -> None:
    """A sweep byte-compiles the tree once, so that no trial compiles it again (where Python
    writes no bytecode itself, as with PYTHONDONTWRITEBYTECODE)."""
    import importlib.util

    (tmp_path / "fuzzer" / "sub").mkdir(parents=True)
    package = tmp_path / "fuzzer"
    modules = [package / "__init__.py", package / "sub" / "m.py", tmp_path / "fuzz_diff.py"]
    for module in modules:
        module.write_text("X = 1\n")
    (tmp_path / "elsewhere.py").write_text("X = 1\n")
    sweeps.compile_tree(tmp_path)
    for module in modules:
        assert Path(importlib.util.cache_from_source(str(module))).is_file(), module
    assert not Path(importlib.util.cache_from_source(str(tmp_path / "elsewhere.py"))).exists()


def test_compile_tree_compiles_again_a_module_changed_within_the_second(tmp_path: Path) -> None:
    """An edit or a checkout in the second of the last compile (same modification time, another
    size): compileall called its bytecode fresh, the importer (which checks the size too) stale,
    and every trial of a sweep compiled the module again."""
    import importlib.util
    import os

    module = tmp_path / "fuzzer" / "m.py"
    module.parent.mkdir()
    module.write_text("X = 1\n")
    sweeps.compile_tree(tmp_path)
    stamp = module.stat().st_mtime_ns
    module.write_text("X = 12345\n")  # another arm's content, within the same second
    os.utime(module, ns=(stamp, stamp))
    sweeps.compile_tree(tmp_path)
    header = Path(importlib.util.cache_from_source(str(module))).read_bytes()[:16]
    recorded = int.from_bytes(header[8:12], "little"), int.from_bytes(header[12:16], "little")
    assert recorded == (stamp // 10**9, module.stat().st_size), "bytecode of the current source"
    assert not sweeps.stale(module)
    module.write_text("X = 2\n")  # and back, again within the second
    os.utime(module, ns=(stamp, stamp))
    assert sweeps.stale(module), "the importer would not load this bytecode"


def test_a_trial_whose_engine_never_started_stops_the_sweep(tmp_path: Path) -> None:
    """A refused command line (exit 2, no input evaluated) was kept as a miss at the budget:
    an engine that could not start read as one that never finds the bug."""

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        bug, engine, seed = job
        status = 2 if engine == "full" and seed == 1 else 0
        return Run(bug.name, engine, seed, 1.0, None, 0, 1, 1.0, bug.op, status)

    bug = bench_deep.BUGS["narrow_band"]
    jobs = [(bug, "full", seed) for seed in range(3)]
    sweep = journal.Sweep("quick", ("narrow_band",), ("full",), 3, 1.0, "c" * 40)
    book, _ = journal.open_sweep(tmp_path / "j.jsonl", sweep, tmp_path, resume=False, restart=False)
    with pytest.raises(sweeps.NotStarted, match="full did not start on narrow_band \\(seed 1, exit 2\\)"):
        sweeps.run_sweep(book, jobs, [], trial, workers=1)
    kept = journal.read(tmp_path / "j.jsonl")[1]
    assert 0 in [r.seed for r in kept] and 1 not in [r.seed for r in kept]


def test_a_journal_tabulated_so_far_counts_each_planned_trial_once(tmp_path: Path) -> None:
    """A line written twice and a trial of a seed outside the sweep's were counted into the cells
    (0.4 (3/3) for two trials); --resume already held each planned trial once."""
    sweep = journal.Sweep("quick", ("narrow_band",), ("full", "uniform"), 2, 1.0, "c" * 40)
    path = tmp_path / "deep-quick.jsonl"
    book, _ = journal.open_sweep(path, sweep, tmp_path, resume=False, restart=False)
    for engine in ("full", "uniform"):
        for seed in range(2):
            book.add(
                Run("narrow_band", engine, seed, 1.0, 0.4 if engine == "full" else None, 1, 1, 1.0, "fk", 0)
            )
    book.close()
    lines = path.read_text().splitlines()
    extra = json.loads(lines[1])
    extra["seed"] = 7
    path.write_text("\n".join([*lines, lines[1], json.dumps(extra)]) + "\n")
    runs = bench_deep.load_runs(path)
    assert sorted((r.engine, r.seed) for r in runs) == [
        ("full", 0),
        ("full", 1),
        ("uniform", 0),
        ("uniform", 1),
    ]


def test_sigterm_stops_the_sweep_as_two_ctrl_c(tmp_path: Path) -> None:
    """A plain ``kill`` or ``timeout`` ended the sweep's process alone: its trials, in sessions of
    their own, ran on with their temporary folders. Now SIGTERM kills them (``trials.stop_all``),
    keeps none, starts no other, and the sweep says it was terminated (exit 143)."""
    import signal as signals

    def trial(job: sweeps.Job, cpu: int | None) -> Run:
        bug, engine, seed = job
        if seed == 0:
            os.kill(os.getpid(), signals.SIGTERM)
            time.sleep(0.2)  # the handler runs in the main thread meanwhile
        return Run(bug.name, engine, seed, 1.0, None, 0, 1, 1.0, bug.op, 0)

    bug = bench_deep.BUGS["narrow_band"]
    jobs = [(bug, "full", seed) for seed in range(3)]
    sweep = journal.Sweep("quick", ("narrow_band",), ("full",), 3, 1.0, "c" * 40)
    book, _ = journal.open_sweep(tmp_path / "j.jsonl", sweep, tmp_path, resume=False, restart=False)
    before = signals.getsignal(signals.SIGTERM)
    try:
        progress = sweeps.run_sweep(book, jobs, [], trial, workers=1)
    finally:
        trials.allow_starts()  # stop_all's refusal of new processes ends with the sweep's process
    assert progress.terminated and progress.interrupted and progress.runs == []
    assert signals.getsignal(signals.SIGTERM) == before, "the handler it replaced is back"
