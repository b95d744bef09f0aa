"""The full engine's dry run (fuzzer/dry_run.py): the generated seeds are evaluated in a child
process while libFuzzer starts; what the child cannot survive, libFuzzer reports."""

from __future__ import annotations

import faulthandler
import json
import os
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from fuzzer import dry_run
from fuzzer.execution.session import RunConfig, Session
from fuzzer.generation.boundary import OFFSETS
from fuzzer.generation.corpus import boundary_cases
from fuzzer.generation.sweep import CONFIRM, ROWS
from fuzzer.selection.state import ALIGNED, BOUNDARY, LITERAL, SPACEFILL, UNIFORM
from tests.support import ROOT, fuzz, python

ZOO_ARM = str(ROOT / "benchmarks" / "robots" / "zoo_arm.urdf")
EVERY_INPUT = "benchmarks.zoo.bugs:axis_not_normalized"
"""A fault that every fk input of the zoo arm shows (a joint axis used without normalizing)."""
SWEPT = "sweep:uniform"


def _records(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


@pytest.mark.parametrize(
    ("op", "transport", "mutator", "several", "stop", "expected"),
    [
        ("fk", "inprocess", "rrosfuzz", False, False, True),
        ("move", "inprocess", "rrosfuzz", False, False, True),
        ("ik", "inprocess", "rrosfuzz", False, False, True),  # its start-up imports scipy after the fork
        ("scenario", "inprocess", "rrosfuzz", False, False, True),  # a first stage of scripts
        ("move", "ros", "rrosfuzz", False, False, False),
        ("move", "inprocess", "libfuzzer", False, False, False),  # the baselines keep libFuzzer's start
        ("move", "inprocess", "weights", False, False, False),
        ("move", "inprocess", "rrosfuzz", True, False, False),  # -fork / -jobs
        ("move", "inprocess", "rrosfuzz", False, True, False),  # --stop-on-divergence
    ],
)
def test_the_dry_run_is_for_the_full_engine_on_cheap_ops_in_one_process(
    op: str, transport: str, mutator: str, several: bool, stop: bool, expected: bool
) -> None:
    config = RunConfig(op=op, transport=transport)
    assert dry_run.applies(config, mutator, several, stop) is expected


def _one_cpu() -> None:
    """``preexec_fn``: run the campaign on one CPU, where it waits for its dry run (the order
    of the two processes' first inputs is then certain, whatever else the machine runs)."""
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="needs os.sched_setaffinity (Linux)")
def test_the_dry_run_files_what_the_seeds_show_before_libfuzzer_runs_them(tmp_path: Path) -> None:
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    args = ["-max_total_time=2", "-seed=1", f"--artifacts={artifacts}", "--no-progress", f"--robot={ZOO_ARM}"]
    run = fuzz(
        str(corpus),
        *args,
        "--op=fk",
        f"--targets=native,{EVERY_INPUT}",
        timeout=300,
        preexec_fn=_one_cpu,  # one system call in the child: safe between fork and exec
    )
    assert run.returncode == 1, run.stderr[-3000:]  # new divergences
    assert "Traceback" not in run.stderr
    assert "evaluate probes, uniform inputs and the seeds before libFuzzer" in run.stderr
    stats = _records(artifacts / "stats.jsonl")
    campaign = stats[-1]["pid"]  # the campaign's final snapshot is the last line
    dry = {r["pid"] for r in stats} - {campaign}
    assert len(dry) == 2, "two dry-run processes (stages) logged their counters"
    first, second = sorted(dry, key=lambda pid: min(r["first_input"] for r in stats if r["pid"] == pid))
    last = {pid: [r for r in stats if r["pid"] == pid][-1] for pid in dry}
    early, late = dry_run.EARLY["fk"], dry_run.LATE["fk"]
    # every sweep flags rows of a fault every input shows; CONFIRM of them go to the single call
    # (the first stage's sweeps: one of FIRST_ROWS rows, the early ones, the late ones)
    ran = last[first]["executed_by_strategy"]
    assert ran == {
        UNIFORM: 1,  # one uniform configuration before the fork, in the campaign's process
        SWEPT: (early + 1 + late) * CONFIRM,
        ALIGNED: dry_run.ALIGNED["fk"],
        BOUNDARY: ran[BOUNDARY],
        LITERAL: ran[LITERAL],
    }
    assert ran[BOUNDARY] > 0, "the boundary probes"
    # benchmarks/zoo/bugs.py compares against 3.0 and 1.0: the zoo arm's joints that hold them
    assert 0 < ran[LITERAL] <= dry_run.LITERALS, "configurations at the target's compared numbers"
    rest = dry_run.TOTAL_SWEEPS["fk"] - early - late
    assert rest > 0, "the second stage keeps sweeps of its own"
    assert last[second]["executed_by_strategy"] == {"seed": 32, SWEPT: rest * CONFIRM}
    assert [last[pid]["sweep"]["compared"] for pid in (first, second)] == [
        dry_run.FIRST_ROWS + (early + late) * ROWS,
        rest * ROWS,
    ]
    first_of_campaign = min(r["first_input"] for r in stats if r["pid"] == campaign)
    assert max(min(r["first_input"] for r in stats if r["pid"] == pid) for pid in dry) < first_of_campaign
    divergences = _records(artifacts / "divergences.jsonl")
    # the first input is evaluated in the campaign's process (fuzzer/execution/guard.py), then
    # the first child's sweeps go first
    assert divergences[0]["pid"] == campaign and divergences[0]["strategy"] == UNIFORM
    assert next(r for r in divergences if r["pid"] == first)["strategy"] == SWEPT, "a sweep goes first"
    assert "seed" in {r["strategy"] for r in divergences if r["pid"] == second}
    # the campaign meets the same seeds again: one crash file per signature all the same
    signatures = {r["sig"] for r in divergences}
    assert {r["pid"] for r in divergences} == {first, second, campaign}
    crashes = sorted(p for p in artifacts.glob("crash-*") if p.suffix != ".json")
    assert len(crashes) == len(signatures)
    assert all(Path(f"{p}.json").is_file() for p in crashes)
    for crash in crashes:  # listed in the campaign's summary, which waited for the child
        assert crash.name in run.stderr


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="needs os.sched_setaffinity (Linux)")
def test_an_ik_dry_run_evaluates_the_orientation_probes_first(tmp_path: Path) -> None:
    """An IK campaign's dry run starts with the four orientation probes (first stage, before the
    seeds exist), which show a target that uses the quaternion without normalizing it; its
    second stage evaluates the seeds."""
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-max_total_time=1",
        "-seed=1",
        f"--artifacts={artifacts}",
        "--no-progress",
        "--op=ik",
        "--targets=native,benchmarks.zoo.bugs:quaternion_not_normalized",
        timeout=300,
        preexec_fn=_one_cpu,
    )
    assert run.returncode == 1, run.stderr[-3000:]
    stats = _records(artifacts / "stats.jsonl")
    campaign = stats[-1]["pid"]
    child = [r for r in stats if r["pid"] != campaign]
    assert child[0]["executed_by_strategy"] == {BOUNDARY: 1}, "an orientation probe first"
    stages = [[r for r in child if r["pid"] == pid] for pid in dict.fromkeys(r["pid"] for r in child)]
    # the four orientation probes and the reach probe, then the seeds
    assert [stage[-1]["executed_by_strategy"] for stage in stages] == [{BOUNDARY: 5}, {"seed": 32}]
    # the twin's IK memory, counted per process (the oracle's checks look problems up too)
    memos = [last["ik_memo"] for last in (*(stage[-1] for stage in stages), stats[-1])]
    assert all(m["misses"] > 0 and m["hits"] >= 0 and m["kept"] > 0 for m in memos), memos
    first = _records(artifacts / "divergences.jsonl")[0]
    assert first["pid"] == child[0]["pid"] and first["strategy"] == BOUNDARY


def test_the_baselines_have_no_dry_run(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=100",
        "-seed=1",
        f"--artifacts={artifacts}",
        "--no-progress",
        "--mutator=weights",
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert "dry run" not in run.stderr
    assert len({r["pid"] for r in _records(artifacts / "stats.jsonl")}) == 1


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def test_a_child_that_dies_leaves_the_campaign_running() -> None:
    def crash() -> None:  # as a native crash on a seed would
        # pytest's faulthandler would print "Fatal Python error: Aborted" and a stack into the
        # test log for this intended abort (a campaign's child keeps that report)
        faulthandler.disable()
        os.abort()

    dry = dry_run.DryRun.start(crash, budget=30)
    assert dry is not None
    assert dry.wait() == -signal.SIGABRT
    assert dry.wait() is None, "reaped once"
    assert _gone(dry.pid)


def test_a_child_that_hangs_ends_at_its_budget_even_in_compiled_code() -> None:
    dry = dry_run.DryRun.start(signal.pause, budget=1)  # blocked in a system call, never back in Python
    assert dry is not None
    assert dry.wait() == -signal.SIGALRM  # the alarm's default action, not a Python handler
    assert _gone(dry.pid)


def test_a_child_that_ignores_its_alarm_is_killed_when_its_budget_is_spent() -> None:
    def stubborn() -> None:
        signal.signal(signal.SIGALRM, signal.SIG_IGN)
        while True:
            time.sleep(0.05)

    dry = dry_run.DryRun.start(stubborn, budget=1)
    assert dry is not None
    assert dry.wait() == -signal.SIGKILL
    assert _gone(dry.pid)


def test_stop_ends_a_working_child_at_once_and_reaps_it() -> None:
    # a usage error after the fork (seeds Hypothesis cannot draw): the children stop with it
    dry = dry_run.DryRun.start(lambda: time.sleep(60), budget=60)
    assert dry is not None
    dry.stop()
    assert os.waitstatus_to_exitcode(dry.status or 0) == -signal.SIGKILL
    assert _gone(dry.pid)
    dry.stop()  # once ended, again is nothing
    assert dry.wait() is None, "reaped once"


def test_a_child_that_raises_exits_1_quietly_without_the_parents_exit_hooks(tmp_path: Path) -> None:
    # in a fresh interpreter, so that the exit hooks are the test's own
    marker = tmp_path / "hooks"
    program = f"""
import atexit, os
from fuzzer import dry_run
def hook():
    with open({str(marker)!r}, "a") as f:
        f.write(f"{{os.getpid()}}\\n")
atexit.register(hook)
def fail():
    raise ValueError("a seed's evaluation raised")
dry = dry_run.DryRun.start(fail, budget=30)
print(dry.wait(), os.getpid(), flush=True)
"""
    done = python(program, timeout=60)
    assert done.returncode == 0, done.stderr
    status, parent = done.stdout.split()
    assert status == "1"
    assert "Traceback" not in done.stderr  # libFuzzer runs that seed next and reports what it raises
    assert marker.read_text().split() == [parent], "the exit hooks ran once, in the parent"


@pytest.mark.parametrize("op", sorted(dry_run.DRY_RUN_OPS))
def test_the_dry_run_forks_before_hypothesis_is_imported(tmp_path: Path, op: str) -> None:
    """Importing Hypothesis takes about 0.12 s on one CPU, which only the seeds need: the first
    stage's child is forked before it (``fuzzer.input.mapping`` imports it in the functions that
    build strategies), so the first input comes that much sooner (docs/benchmarks-log.md, twenty-first
    session). The campaign runs as ``fuzz_diff.py`` does, up to the fork."""
    art = f"--artifacts={tmp_path / 'art'}"
    argv = [str(tmp_path / "corpus"), "-runs=0", f"--op={op}", art, "--no-progress"]
    program = f"""
import os, sys
from fuzzer import dry_run
from fuzzer.cli import main
from fuzzer.execution.session import versions
def launch(self, work):
    print("forked with hypothesis" if "hypothesis" in sys.modules else "forked without hypothesis")
    print("numpy.random", "numpy.random" in sys.modules, "versions", versions.cache_info().currsize)
    sys.stdout.flush()
    os._exit(0)
dry_run.Stages._launch = launch
main({argv!r})
"""
    done = python(program)
    assert done.returncode == 0, done.stderr[-3000:]
    # nor numpy.random (7-10 ms), nor the versions for the sidecars (14 ms: asked at the first)
    expected = ["forked without hypothesis", "numpy.random False versions 0"]
    assert done.stdout.splitlines() == expected, done.stdout + done.stderr[-3000:]


def test_targets_opened_before_atheris_are_instrumented_all_the_same() -> None:
    """The campaign now opens its session before importing Atheris (the dry run needs the
    targets first); ``instrument`` rewrites their functions in place afterwards, so every
    function of the twin and the oracle alive in the campaign is instrumented (the ``__repr__``
    that ``dataclasses`` makes with ``reprlib`` never was, in either order)."""
    program = """
import gc, types
from fuzzer.execution.session import RunConfig, Session
from fuzzer.selection.instrument import instrument
INSTRUMENTED = ("python_impl", "fuzzer.execution.oracle")
for op in ("fk", "move", "scenario"):
    config = RunConfig(op=op)
    session = Session.open(config)
    instrument(config)
    session.evaluator()
    done, missing = 0, set()
    for obj in gc.get_objects():
        module = getattr(obj, "__module__", None) or ""
        if isinstance(obj, types.FunctionType) and module.startswith(INSTRUMENTED):
            if "__ATHERIS_INSTRUMENTED__" in obj.__code__.co_consts:
                done += 1
            elif "__create_fn__" not in obj.__qualname__:
                missing.add(obj.__qualname__)
    print(op, done, sorted(missing))
"""
    done = python(program, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    assert len(lines) == 3, done.stdout
    for line in lines:
        _, count, missing = line.split(" ", 2)
        assert missing == "[]", line
        assert int(count) > 100, line


@pytest.mark.parametrize("point", ["claim", "sidecar"])
def test_a_dry_run_killed_while_writing_a_crash_file_loses_nothing(tmp_path: Path, point: str) -> None:
    """The child claims a signature and dies in the write window (``KILL_HOOK``): the campaign
    cannot claim that signature again, so it completes the file from the child's temporaries
    once the child is gone, and reports it (exit 1) in the same run."""
    from fuzzer.artifacts.store import KILL_HOOK, sidecar_path

    artifacts = tmp_path / "artifacts"
    run = fuzz(
        str(tmp_path / "corpus"),
        "-runs=300",
        "-seed=1",
        f"--artifacts={artifacts}",
        "--no-progress",
        "--robot=kinova",
        "--targets=native,tests.plugins.faults:wrap_continuous",
        timeout=300,
        # every dry-run input in a child: the first is otherwise the campaign's own (and the
        # campaign's first claim, fuzzer/execution/guard.py)
        env={KILL_HOOK: f"{point}:1", dry_run.ENV: dry_run.CHILDREN},
    )
    assert run.returncode == 1, run.stderr[-3000:]
    assert "Traceback" not in run.stderr
    crashes = sorted(p for p in artifacts.glob("crash-*") if p.suffix != ".json")
    assert crashes and all(sidecar_path(p).is_file() for p in crashes)
    assert not list(artifacts.glob(".tmp-*")), "no temporary left behind"
    markers = [m for m in (artifacts / ".signatures").iterdir() if not m.name.startswith(".")]
    named = {m.read_text().strip() for m in markers}
    assert named == {p.name for p in crashes}, "every claimed signature has its crash file"
    for crash in crashes:
        assert crash.name in run.stderr


def test_the_boundary_probes_of_the_dry_run_move_one_joint_of_the_middle_past_a_limit() -> None:
    session = Session.open(RunConfig(op="move"))
    limits = session.reference.joint_limits
    middle = [(lim.lower + lim.upper) / 2 for lim in limits]
    cases = boundary_cases(session, dry_run.BOUNDARY_ROUNDS, first=32)
    assert len(cases) == 2 * 2 * len(limits)  # two rounds, both limits of each joint
    seen = set()
    for n, case in enumerate(cases):
        assert (case.origin, case.lineage, case.sequence) == (SPACEFILL, (BOUNDARY,), 32 + n)
        position = case.message["position"]
        moved = [j for j, (v, m) in enumerate(zip(position, middle, strict=True)) if v != m]
        assert len(moved) == 1, position
        (j,) = moved
        lim = limits[j]
        offset = round(max(position[j] - lim.upper, lim.lower - position[j]), 12)
        assert offset in OFFSETS[: dry_run.BOUNDARY_ROUNDS], (j, position[j])
        seen.add((j, position[j] > lim.upper, offset))
    assert len(seen) == len(cases), "every joint, side and offset once"
    assert boundary_cases(Session.open(RunConfig(op="scenario")), dry_run.BOUNDARY_ROUNDS) == []


@pytest.mark.parametrize("op", sorted(dry_run.DRY_RUN_OPS))
def test_the_campaign_makes_the_first_stages_inputs_again_only_to_number_a_second_stage(
    monkeypatch: pytest.MonkeyPatch, op: str
) -> None:
    """The child makes the first stage's inputs; the campaign makes them again after the fork
    only where a second stage is numbered after them. A scenario has none: its tutorial and
    uniform scripts (about 2 ms) would be made for nothing."""
    made: list[str] = []

    def first_cases(self: dry_run.Stages) -> list[Any]:
        made.append(op)
        return []

    monkeypatch.setattr(dry_run, "launch", lambda work, timeout: None)  # no child
    monkeypatch.setattr(dry_run.Stages, "first_cases", first_cases)
    stages = dry_run.Stages(Session.open(RunConfig(op=op)), "rrosfuzz", 1, 32, 0, lambda seeds, made: None)
    stages.first()
    assert made == ([op] if op in dry_run.SECOND_STAGE_OPS else [])
