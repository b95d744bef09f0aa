"""The stateful zoo bugs: each shows through the API in two calls or in a trajectory, and
none shows in the single-call ``--op move`` path on a fresh group."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict
from typing import Any

import numpy as np
import pytest

import native
import python_impl
from benchmarks.zoo import BY_NAME, CONTROLS, STATEFUL, ZOO
from fuzzer.execution.oracle import compare
from fuzzer.execution.records import Kind
from fuzzer.execution.targets import Runner, load_target
from fuzzer.execution.tolerance import Tolerance
from fuzzer.input.mapping import MoveCall
from python_impl.trajectory import plan_trajectory
from robot_api.constants import ACCELERATION_LIMIT
from robot_api.records import JointType
from robot_api.robots import resolve

TARGET = [0.5, 0.3, 0.2, 0.1, 0.4, 0.2]
SECOND = [-0.4, 0.6, 0.9, -0.3, 0.7, -0.5]
GAP = Tolerance().radians
"""The campaign's default tolerance (rad, m): a larger difference is a divergence."""


def groups(name: str) -> tuple[Any, Any]:
    """(native group, variant group) on the bug's robot, both fresh (at home)."""
    bug = BY_NAME[name]
    variant = load_target(bug.target)
    urdf = resolve(bug.robot)
    return native.MoveGroup(native.RobotModel(urdf)), variant.MoveGroup(variant.RobotModel(urdf))


def gap(a: Any, b: Any) -> float:
    return float(np.max(np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))))


def move(g: Any, q: list[float]) -> bool:
    g.set_joint_value_target(q)
    return bool(g.go())


# -- each fault, shown in a short script --------------------------------------------------------


def show_continuous_accumulates(ref: Any, bad: Any) -> None:
    for g in (ref, bad):
        q = list(g.get_current_joint_values())
        for value in (3.0, -3.0):  # across +-pi: the short way is +0.28 rad
            q[0] = value
            assert move(g, q)
    assert ref.get_current_joint_values()[0] == pytest.approx(-3.0)
    assert bad.get_current_joint_values()[0] == pytest.approx(2 * math.pi - 3.0)  # outside (-pi, pi]


def show_start_state_home(ref: Any, bad: Any) -> None:
    plans = []
    for g in (ref, bad):
        assert move(g, TARGET)
        g.set_joint_value_target(SECOND)
        plans.append(g.plan().trajectory.positions[0])
    assert gap(plans[0], TARGET) < GAP and gap(plans[1], [0.0] * 6) == 0.0  # starts at home
    assert ref.go() is True and bad.go() is False  # execution refuses a start 0.5 rad off
    assert gap(bad.get_current_joint_values(), TARGET) < GAP


def show_cached_pose(ref: Any, bad: Any) -> None:
    for g in (ref, bad):
        assert move(g, TARGET)
        g.get_current_pose()
        assert move(g, SECOND)
    assert gap(ref.get_current_joint_values(), bad.get_current_joint_values()) < GAP
    assert gap(ref.get_current_pose().position, bad.get_current_pose().position) > 0.01


def show_cartesian_ignores_scaling(ref: Any, bad: Any) -> None:
    paths = []
    for g in (ref, bad):
        g.set_max_velocity_scaling_factor(0.05)
        g.set_max_acceleration_scaling_factor(0.1)
        pose = g.get_current_pose()
        down = (pose.position[0], pose.position[1], pose.position[2] - 0.05)
        trajectory, fraction = g.compute_cartesian_path([(down, pose.orientation)], 0.01)
        assert fraction == 1.0
        paths.append(trajectory)
    assert gap(paths[0].positions, paths[1].positions) < GAP  # the same path ...
    assert paths[1].time_from_start[-1] < 0.6 * paths[0].time_from_start[-1]  # ... much faster


def show_acceleration_scaling_ignored(ref: Any, bad: Any) -> None:
    plans = []
    for g in (ref, bad):
        g.set_max_acceleration_scaling_factor(0.2)
        g.set_joint_value_target(TARGET)
        plans.append(g.plan().trajectory)
    assert gap(plans[0].positions[-1], plans[1].positions[-1]) < GAP  # the same end point
    limit = ACCELERATION_LIMIT * 0.2 * (1 + 1e-9)
    assert np.abs(plans[0].accelerations).max() <= limit < np.abs(plans[1].accelerations).max()


def show_duplicate_start_point(ref: Any, bad: Any) -> None:
    plans = []
    for g in (ref, bad):
        g.set_joint_value_target(TARGET)
        plans.append(g.plan().trajectory)
    assert len(plans[1].time_from_start) == len(plans[0].time_from_start) + 1
    assert not np.all(np.diff(plans[1].time_from_start) > 0)  # not strictly increasing
    assert ref.execute(plans[0]) is True
    with pytest.raises(Exception, match="strictly increasing"):
        bad.execute(plans[1])


def show_execute_stops_short(ref: Any, bad: Any) -> None:
    for g in (ref, bad):
        g.set_joint_value_target(TARGET)
        assert g.execute(g.plan().trajectory) is True
    assert gap(ref.get_current_joint_values(), TARGET) < 1e-12
    assert gap(bad.get_current_joint_values(), TARGET) > GAP


def show_remember_aliases_state(ref: Any, bad: Any) -> None:
    for g in (ref, bad):
        g.remember_joint_values("start")
        assert move(g, TARGET)
        g.set_named_target("start")
    assert gap(ref.get_joint_value_target(), [0.0] * 6) == 0.0
    assert gap(bad.get_joint_value_target(), TARGET) < GAP  # the "remembered" state moved along


def show_pose_goal_scaled_twice(ref: Any, bad: Any) -> None:
    urdf = resolve(BY_NAME["pose_goal_scaled_twice"].robot)
    model = python_impl.RobotModel(urdf)
    goal = model.forward_kinematics([1.5, 0.2, 0.0, 0.5, 0.0, 0.3, 0.0], None)
    plans = []
    for g in (ref, bad):  # long enough a move to reach cruise speed: its velocity bound counts
        g.set_max_velocity_scaling_factor(0.5)
        g.set_pose_target((tuple(goal.position), tuple(goal.orientation)))
        plans.append(g.plan().trajectory)

    def lasts(plan: Any, scaling: float) -> float:  # the contract's plan between its ends
        ends = [np.asarray(plan.positions[k]).tolist() for k in (0, -1)]
        return float(plan_trajectory(model.joint_limits, *ends, scaling, 1.0).time_from_start[-1])

    for plan in plans:  # each reaches the pose
        reached = model.forward_kinematics(np.asarray(plan.positions[-1]).tolist(), None)
        assert gap(reached.position, goal.position) < 1e-5
    assert plans[0].time_from_start[-1] == pytest.approx(lasts(plans[0], 0.5), rel=1e-9)
    assert plans[1].time_from_start[-1] == pytest.approx(lasts(plans[1], 0.25), rel=1e-9)
    assert plans[1].time_from_start[-1] > 1.2 * lasts(plans[1], 0.5)  # slower than asked
    scaled = np.array([lim.velocity for lim in model.joint_limits]) * 0.5
    assert np.all(np.abs(plans[1].velocities) <= scaled)  # within the scaled limits


SHOW: dict[str, Callable[[Any, Any], None]] = {
    "continuous_accumulates": show_continuous_accumulates,
    "start_state_home": show_start_state_home,
    "cached_pose": show_cached_pose,
    "cartesian_ignores_scaling": show_cartesian_ignores_scaling,
    "acceleration_scaling_ignored": show_acceleration_scaling_ignored,
    "duplicate_start_point": show_duplicate_start_point,
    "execute_stops_short": show_execute_stops_short,
    "pose_goal_scaled_twice": show_pose_goal_scaled_twice,
    "remember_aliases_state": show_remember_aliases_state,
}


def test_every_stateful_bug_is_registered_for_the_scenario_op() -> None:
    assert set(SHOW) == {b.name for b in STATEFUL} and len(STATEFUL) >= 6
    for bug in STATEFUL:
        assert bug in ZOO and bug.op == "scenario" and bug.source.startswith("https://github.com/")
        assert bug.target == f"benchmarks.zoo.stateful:{bug.name}" and not bug.is_control
    assert BY_NAME["silent_clamp"].target == "benchmarks.zoo.bugs:silent_clamp"  # unchanged
    scenario_controls = {(c.robot, c.target) for c in CONTROLS if c.op == "scenario"}
    expected = {b.robot for b in STATEFUL} | {"ur5"}  # UR5: SCENARIO_UR5, beside the zoo's arms
    assert scenario_controls == {(r, "benchmarks.zoo.bugs:control") for r in expected}


@pytest.mark.parametrize("name", sorted(SHOW))
def test_the_fault_shows_on_a_live_group(name: str) -> None:
    SHOW[name](*groups(name))


@pytest.mark.parametrize("name", sorted(SHOW))
def test_the_unmodified_twin_passes_the_same_script(name: str) -> None:
    """The scripts test the fault, not a difference the twin already has: with the control
    in place of the variant, every one of them fails."""
    ref, _ = groups(name)
    control = load_target("benchmarks.zoo.bugs:control")
    twin = control.MoveGroup(control.RobotModel(resolve(BY_NAME[name].robot)))
    with pytest.raises(AssertionError):
        SHOW[name](ref, twin)


def move_calls(robot: str) -> list[MoveCall]:
    """Single moves from home: plain, scaled, by name, out of bounds, to the far side of pi."""
    calls = [
        MoveCall(None, tuple(TARGET)),
        MoveCall(None, tuple(SECOND), 0.3, 0.2),
        MoveCall(None, tuple(TARGET), 1.0, 1e-7),  # would last too long: go() fails on both
        MoveCall(None, (5.0, 0.0, 0.0, 0.0, 0.0, 0.0)),  # out of bounds (probot) / wraps (kinova)
        MoveCall(("joint_2",), (0.7,), 0.5),
    ]
    if robot == "xarm7":  # seven joints, named joint1..joint7
        calls = [
            MoveCall(None, (*TARGET, 0.3)),
            MoveCall(None, (*SECOND, 0.8), 0.3, 0.2),
            MoveCall(None, (*TARGET, 0.3), 1.0, 1e-7),
            MoveCall(None, (0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0)),  # joint2 out of bounds
            MoveCall(("joint2",), (0.7,), 0.5),
        ]
    if robot == "kinova":
        home = list(native.RobotModel(resolve(robot)).home_values)
        calls = [
            MoveCall(None, (3.0, *home[1:])),
            MoveCall(None, (-3.1, *home[1:3], 3.1, home[4], -2.9), 0.4, 0.6),
            MoveCall(None, (7.0, *home[1:])),
            MoveCall(None, (-math.pi, *home[1:]), 1.0, 1e-7),
        ]
    return calls


@pytest.mark.parametrize("name", sorted(SHOW))
def test_one_move_on_a_fresh_group_does_not_show_it(name: str) -> None:
    bug = BY_NAME[name]
    urdf = resolve(bug.robot)
    reference = Runner.create("native", urdf, None)
    variant = Runner.create(bug.target, urdf, None)
    limits = reference.model.joint_limits
    prismatic = tuple(lim.type == JointType.PRISMATIC for lim in limits)
    continuous = tuple(lim.type == JointType.CONTINUOUS for lim in limits)
    statuses = set()
    for call in move_calls(bug.robot):
        a, b = reference.run(call), variant.run(call)
        verdict = compare(a, b, Tolerance(), prismatic, "move", continuous)
        assert verdict.kind is Kind.AGREE, (call, a, b, verdict)
        statuses.add(a.label)
    assert len(statuses) >= 2  # the calls reach more than one outcome (moved; failed or rejected)


# -- the benchmarks' plumbing for the stateful bugs ---------------------------------------------


def test_sweeps_run_stateful_bugs_with_the_scenario_op_and_ops_mode_runs_both() -> None:
    from benchmarks import bench_zoo

    names = tuple(b.name for b in STATEFUL)
    jobs = bench_zoo.plan_jobs(("silent_clamp", *names[:2]), bench_zoo.ENGINES, 1)
    ran = {(bug.name, bug.op, engine) for bug, engine, _ in jobs}
    assert ("silent_clamp", "move", "uniform") in ran  # one-call bugs: every engine, own op
    assert {(n, "scenario", e) for n in names[:2] for e in bench_zoo.ENGINES} == {
        r for r in ran if r[0] != "silent_clamp"
    }  # every engine, the baselines included (benchmarks.baselines has --op scenario)
    mode = bench_zoo.MODES["ops"]
    controls = tuple(c.name for c in CONTROLS if c.op == "scenario")  # the false positives beside
    assert mode.bugs == (*names, *controls) and len(controls) == 4  # Kinova, PROBOT Anno, UR5, xArm7
    jobs = bench_zoo.plan_jobs(mode.bugs, mode.engines, 2, mode.ops)
    assert len(jobs) == len(mode.bugs) * 2 * 2
    assert {(bug.name, bug.op) for bug, _, _ in jobs} == {
        (n, op) for n in mode.bugs for op in ("move", "scenario")
    }
    assert all(bug.target == BY_NAME[bug.name].target for bug, _, _ in jobs)


def test_ops_markdown_says_which_op_detects_each_bug(tmp_path: Any) -> None:
    from benchmarks import bench_zoo

    def run(bug: str, op: str, seed: int, found: bool) -> bench_zoo.Run:
        fields = ("value go.joint_values: 0.5 rad",) if found else ()
        return bench_zoo.Run(
            bug,
            "full",
            seed,
            30.0,
            4.0 + seed if found else None,
            int(found),
            300,
            30.0,
            op,
            0,
            int(found),
            fields=fields,
        )

    bugs = ("cached_pose", "execute_stops_short")
    runs = [
        run(b, op, s, op == "scenario" and (b == "cached_pose" or s == 1))
        for b in bugs
        for op in ("move", "scenario")
        for s in (1, 2, 3)
    ]
    cells = bench_zoo.summarize_ops(runs, bugs, ("move", "scenario"))
    assert cells["cached_pose/scenario"]["detected"] == 3 and cells["cached_pose/move"]["detected"] == 0
    assert cells["execute_stops_short/scenario"]["detected"] == 1
    result = {
        "bugs": list(bugs),
        "ops": ["move", "scenario"],
        "budget": 30.0,
        "seeds": 3,
        "jobs": 2,
        "cpus": 2,
        "command": "x",
        "cells": cells,
        "runs": [asdict(r) for r in runs],
        "load": "1.00 / 2.00",
    }
    text = bench_zoo.markdown(result)
    assert "| cached_pose | probot_anno | - (0/3) | 6.0 (3/3) | 1 | `--op scenario` value go.joint" in text
    assert "| execute_stops_short | probot_anno | - (0/3) | >30 (1/3) | 0 |" in text
    assert "- `--op move`: 0 of 2" in text and "- `--op scenario`: 2 of 2" in text
    page = tmp_path / "BENCHMARKS.md"
    page.write_text("# Benchmarks\n\nother text\n", encoding="utf-8")
    bench_zoo.write_markdown(text, page, mode="ops")
    bench_zoo.write_markdown(text.replace("cached_pose |", "cached_pose (again) |"), page, mode="ops")
    content = page.read_text(encoding="utf-8")
    assert content.count("## Which ops detect the stateful bugs") == 1 and "other text" in content
    assert "cached_pose (again)" in content and content.count("<!-- bench_zoo_ops:begin -->") == 1


def test_the_scenario_speed_benchmark_measures_steps_by_kind() -> None:
    from benchmarks import bench_scenario
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.scenario.steps import to_call

    session = Session.open(RunConfig(op="scenario"))
    cases = bench_scenario.scenarios(session, 1, 4)
    calls = [to_call(case.message) for case in cases]
    timed = bench_scenario.time_executor(session, calls)
    assert set(timed) == {"native", "python"}
    kinds = [s.kind for c in calls for s in c.steps]
    for figures in timed.values():
        assert figures["execs"] == 4 and figures["steps"] == len(kinds) and figures["seconds"] > 0
    costs = bench_scenario.step_costs(session, calls)
    assert {k: int(c["count"]) for k, c in costs["native"].items()} == {k: kinds.count(k) for k in set(kinds)}
    result = {
        "runs": 1,
        "robot": "probot_anno",
        "cpu": 0,
        "scenarios_per_run": 4,
        "executor": [timed],
        "step_costs": costs,
        "profile": ["0.1 | 0.2 | 3 | `f` (x.py:1)"],
        "campaigns": [],
        "campaign_seconds": 20.0,
        "load": ["1", "2", "3"],
        "uptime": "up",
    }
    text = bench_scenario.markdown(result)
    assert "| (a) executor alone, native |" in text and "| (a) executor alone, python |" in text
    assert all(f"| {k} |" in text for k in set(kinds)) and "(b) whole campaign" not in text
