"""The bug zoo and the benchmark harness (a tiny run; the real one is `make bench`)."""

from __future__ import annotations

import json
import signal
import sys
import time
from pathlib import Path

import pytest

import native
from benchmarks import bench_zoo, journal, trials, zoo_tables
from benchmarks.zoo import BY_NAME, CONTROL, ZOO
from fuzzer.execution.targets import load_target


def test_the_zoo_has_at_least_twelve_documented_bugs() -> None:
    assert len(ZOO) >= 12 and len({b.name for b in ZOO}) == len(ZOO)
    for bug in ZOO:
        assert bug.description and bug.source and bug.source != "SOURCE"
        impl = load_target(bug.target)  # every variant loads as a target
        impl.RobotModel(bench_zoo.ROOT / "robot_api" / "robots" / "probot_anno.urdf")


@pytest.mark.parametrize("name", ["axis_not_normalized", "missing_axis_z", "missing_lower_unlimited"])
def test_urdf_bugs_change_the_zoo_arm(name: str) -> None:
    """Each URDF-default bug really differs from native on the zoo arm (at some configuration)."""
    bug = BY_NAME[name]
    variant = load_target(bug.target).RobotModel(bug.robot)
    reference = native.RobotModel(bug.robot)
    if name == "missing_lower_unlimited":
        assert variant.joint_limits[1].lower < 0.0 == reference.joint_limits[1].lower
    else:
        q = [0.3, 0.4, 0.5, 0.6, 0.7, 0.05]
        assert variant.forward_kinematics(q).position != reference.forward_kinematics(q).position


def test_time_comparison_margins() -> None:
    inf = float("inf")
    assert zoo_tables.compare_times(1.0, inf) == "faster"
    assert zoo_tables.compare_times(inf, inf) == "tie"
    assert zoo_tables.compare_times(1.6, 1.7) == "tie"  # within 0.25 s
    assert zoo_tables.compare_times(2.0, 6.0) == "faster"
    assert zoo_tables.compare_times(9.0, 3.0) == "slower"


def test_a_baseline_gets_no_verdict_on_a_bug_it_did_not_run() -> None:
    """A results file from before the baselines had a scenario op: a scenario bug they did not
    run is no win of the full engine over them (once, the missing cell counted as a baseline
    that never detected: "faster")."""
    runs = [
        bench_zoo.Run(bug, engine, 1, 10.0, 1.0, 1, 10, 10.0, BY_NAME[bug].op, 0)
        for bug, engines in (
            ("start_state_home", ("full", "libfuzzer")),
            ("off_by_tolerance", ("full", "paper")),
        )
        for engine in engines
    ]
    engines, bugs = ("full", "libfuzzer", "paper"), ("start_state_home", "off_by_tolerance")
    sweep = journal.Sweep("test", bugs, engines, 1, 10.0, "c" * 40, "bench_zoo")
    result = {**bench_zoo.result_of(sweep, runs), "jobs": 1, "cpus": 2, "machine": "x", "command": "c"}
    text = zoo_tables.markdown(result)
    assert "- vs libfuzzer, 1 bugs: 0 faster, 1 tie, 0 slower" in text
    assert "- vs paper, 1 bugs: 0 faster, 1 tie, 0 slower" in text


def test_a_small_benchmark_run(tmp_path: Path) -> None:
    out = tmp_path / "zoo.json"
    result = bench_zoo.main(
        [
            "--bugs",
            "off_by_tolerance",
            CONTROL.name,
            "--engines",
            "full",
            "uniform",
            "--seeds",
            "1",
            "--budget",
            "6",
            "--out",
            str(out),
        ]
    )
    assert json.loads(out.read_text())["runs"] and out.with_suffix(".png").is_file()
    cells = result["cells"]
    assert cells["off_by_tolerance/full"]["detected"] == 1
    assert cells["control/full"]["detected"] == 0 and cells["control/uniform"]["detected"] == 0
    assert cells["off_by_tolerance/full"]["median_exec_per_s"] > 0
    assert "| off_by_tolerance | move |" in bench_zoo.markdown(result)


# -- run_one(stop_at_detection=True), without a real campaign -------------------------------------

FAKE_TRIAL = """
import json, os, sys, time
artifacts = sys.argv[1]
kind, sleep, code = sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
os.makedirs(artifacts, exist_ok=True)
def log(name, record):
    with open(os.path.join(artifacts, name), "a") as handle:
        handle.write(json.dumps(record) + "\\n")
now = time.time()
log("stats.jsonl", {"pid": os.getpid(), "first_input": now, "execs": 3, "elapsed": 0.1,
                    "seed": {"libfuzzer": 42, "harness": 0}})
log("stats.jsonl", {"pid": os.getpid() + 1, "execs": 0, "elapsed": 0.1})  # a dry run's: no seed
log("divergences.jsonl", {"kind": kind, "sig": "s", "t": now + 0.2, "field": "q", "difference": 0.5})
time.sleep(sleep)
sys.exit(code)
"""


def _fake(monkeypatch: pytest.MonkeyPatch, kind: str, sleep: float, code: int) -> None:
    """``bench_zoo.command`` runs a script that logs a first input and a divergence of ``kind``,
    then sleeps ``sleep`` s and exits with ``code``."""

    def command(bug: object, engine: str, seed: int, budget: float, workdir: Path, *_: object) -> list[str]:
        return [sys.executable, "-c", FAKE_TRIAL, str(workdir / "artifacts"), kind, str(sleep), str(code)]

    monkeypatch.setattr(bench_zoo, "command", command)


def test_a_trial_stops_at_its_first_detection(monkeypatch: pytest.MonkeyPatch) -> None:
    """The trial is killed once its logs show a detection and a first input (it would sleep 60 s
    more); the time to detection is the logged one, and the start-up too."""
    _fake(monkeypatch, "value", 60.0, 0)
    began = time.monotonic()
    run = bench_zoo.run_one(BY_NAME["silent_clamp"], "full", 0, 1.0, stop_at_detection=True)
    assert time.monotonic() - began < 30.0  # killed, not slept out
    assert run.returncode == -signal.SIGKILL
    assert run.detected_at is not None and run.first_input is not None
    assert run.detected_at - run.first_input == pytest.approx(0.2)
    assert run.divergences == 1 and run.executions == 3
    assert run.libfuzzer_seed == 42  # the campaign's, as its log records it


def test_a_non_detection_does_not_stop_a_trial(monkeypatch: pytest.MonkeyPatch) -> None:
    _fake(monkeypatch, "known_limitation", 2.0, 7)
    run = bench_zoo.run_one(BY_NAME["silent_clamp"], "full", 0, 1.0, stop_at_detection=True)
    assert run.returncode == 7 and run.detected_at is None and run.first_input is not None


def test_logs_are_read_incrementally(tmp_path: Path) -> None:
    """A partial last line waits for its end; unparsable lines are skipped."""
    path = tmp_path / "log.jsonl"
    assert trials.read_new(path, 0) == ([], 0)
    path.write_bytes(b'{"a": 1}\nnot json\n{"b"')
    records, offset = trials.read_new(path, 0)
    assert records == [{"a": 1}] and offset == len(b'{"a": 1}\nnot json\n')
    with open(path, "ab") as handle:
        handle.write(b": 2}\n")
    assert trials.read_new(path, offset) == ([{"b": 2}], path.stat().st_size)
    progress = trials.watch(trials.Progress(), tmp_path)
    assert not progress.detected and not progress.done


def test_a_control_run_that_reports_keeps_its_artifacts(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A false positive's crash files outlive the trial's temporary folder; a bug's detection,
    or a control run that reports nothing, leaves nothing behind."""
    _fake(monkeypatch, "value", 0.0, 0)
    control = BY_NAME["control@scenario/probot_anno"]
    bench_zoo.run_one(control, "full", 4, 1.0, keep_failures=tmp_path)
    kept = tmp_path / "control_scenario_probot_anno-full-seed4"
    assert sorted(p.name for p in kept.iterdir()) == ["divergences.jsonl", "stats.jsonl"]
    bench_zoo.run_one(BY_NAME["silent_clamp"], "full", 4, 1.0, keep_failures=tmp_path)
    _fake(monkeypatch, "known_limitation", 0.0, 0)
    bench_zoo.run_one(control, "full", 5, 1.0, keep_failures=tmp_path)
    assert [p.name for p in tmp_path.iterdir()] == [kept.name]
