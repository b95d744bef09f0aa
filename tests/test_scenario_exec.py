"""Scenario test cases (``--op scenario``): validation, the call, execution on a target, wiring."""

from __future__ import annotations

import copy
import itertools
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import python_impl
from fuzzer.execution.records import Status
from fuzzer.execution.session import ConfigError, RunConfig, Session
from fuzzer.execution.targets import Runner
from fuzzer.input.mapping import CallError, call_from_json, call_to_json, mapping_for
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.scenario.execute import NUDGE_FAILED, _same_bits, run_scenario
from fuzzer.scenario.nudge import Moved, Nudge
from fuzzer.scenario.steps import MAX_STEPS, MSG_TYPE, TOPICS, ScenarioCall, to_call, validate
from robot_api import robots

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = str(ROOT / "fuzz_diff.py")
REGISTRY = MessageRegistry()
HEADER = {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
Q1 = [0.3, -0.2, 0.4, 0.1, 0.5, -0.3]
TOL = 1e-6  # the campaign's default tolerance (rad, m)


def empty(topic: str) -> dict[str, Any]:
    return {"topic": topic, "msg": {}}


def text(topic: str, data: str) -> dict[str, Any]:
    return {"topic": topic, "msg": {"data": data}}


def number(topic: str, data: float) -> dict[str, Any]:
    return {"topic": topic, "msg": {"data": data}}


def joint_target(position: list[float], names: list[str] | None = None) -> dict[str, Any]:
    msg = {"header": HEADER, "name": names or [], "position": position, "velocity": [], "effort": []}
    return {"topic": "/joint_target", "msg": msg}


def pose_msg(position: tuple[float, ...], orientation: tuple[float, ...]) -> dict[str, Any]:
    return {
        "position": dict(zip("xyz", map(float, position), strict=True)),
        "orientation": dict(zip("xyzw", map(float, orientation), strict=True)),
    }


@pytest.fixture(scope="module")
def runners() -> tuple[Runner, Runner]:
    urdf = robots.resolve("probot_anno")
    return Runner.create("native", urdf, None), Runner.create("python", urdf, None)


# -- validation -------------------------------------------------------------------------------


def test_a_valid_scenario_passes_and_maps_to_its_call() -> None:
    message = {"steps": [joint_target(Q1), empty("/go"), text("/named_target", "home")]}
    validate(message, REGISTRY)
    call = mapping_for("scenario", MSG_TYPE)(message)
    assert call == to_call(message)
    assert isinstance(call, ScenarioCall)
    assert [s.kind for s in call.steps] == ["joint_target", "go", "named_target"]
    assert [s.topic for s in call.steps] == ["/joint_target", "/go", "/named_target"]
    assert call.steps[0].message["position"] == Q1
    assert all(spec.kind == topic[1:] for topic, spec in TOPICS.items())


@pytest.mark.parametrize(
    ("message", "expected"),
    [
        ([empty("/go")], "not a list"),
        ({"steps": {"topic": "/go"}}, "'steps' must be a list"),
        ({"steps": []}, "1..16 steps, this one 0"),
        ({"steps": [empty("/go")] * (MAX_STEPS + 1)}, f"1..16 steps, this one {MAX_STEPS + 1}"),
        ({"steps": [empty("/go")], "extra": 1}, "unexpected field(s) in a scenario: extra"),
        ({"steps": [empty("/go"), "go"]}, "step 1: expected an object"),
        ({"steps": [empty("/go"), {"topic": 3, "msg": {}}]}, "step 1: 'topic' must be a string"),
        ({"steps": [empty("/go"), empty("/fly")]}, "step 1 ('/fly'): unknown topic"),
        ({"steps": [{"topic": "/go"}]}, "step 0 (/go): missing 'msg'"),
        ({"steps": [{"topic": "/go", "msg": {}, "at": 1}]}, "step 0 (/go): unexpected field(s) at"),
        (
            {"steps": [empty("/go"), {"topic": "/go", "msg": {"x": 1}}]},
            "step 1 (/go): invalid std_msgs/Empty",
        ),
        ({"steps": [number("/velocity_scaling", 1)]}, "step 0 (/velocity_scaling): invalid std_msgs/Float64"),
        (
            {"steps": [empty("/plan"), {"topic": "/named_target", "msg": {"data": None}}]},
            "step 1 (/named_target)",
        ),
        (
            {"steps": [{"topic": "/cartesian_path", "msg": {"poses": []}}]},
            "step 0 (/cartesian_path): invalid",
        ),
    ],
)
def test_hostile_shapes_are_errors_naming_the_step(message: Any, expected: str) -> None:
    with pytest.raises(ValueError, match=None) as info:
        validate(message, REGISTRY)
    assert expected in str(info.value)


def test_max_steps_bounds_the_length() -> None:
    message = {"steps": [empty("/go")] * 20}
    validate(message, REGISTRY, max_steps=20)
    with pytest.raises(ValueError, match=r"1\.\.19 steps, this one 20"):
        validate(message, REGISTRY, max_steps=19)


def test_call_to_json_round_trips_and_rejects_damage() -> None:
    call = to_call({"steps": [joint_target(Q1), empty("/go"), text("/remember", "x")]})
    data = call_to_json(call)
    assert data["kind"] == "ScenarioCall"
    back, seed = call_from_json(copy.deepcopy(data))
    assert back == call and seed is None
    for bad, expected in [
        ({**data, "steps": []}, "1..256 steps"),
        ({**data, "steps": [empty("/warp")]}, "unknown topic"),
        ({**data, "steps": "go"}, "must be a list"),
        ({**data, "extra": 1}, "unexpected field"),
    ]:
        with pytest.raises(CallError, match=None) as info:
            call_from_json(bad)
        assert expected in str(info.value)


# -- execution --------------------------------------------------------------------------------


def fixed_script(model: Any) -> dict[str, Any]:
    """joint target, go, remember, named target, plan, execute, Cartesian path, pose target, go."""
    home = list(model.home_values)
    near = [h + d for h, d in zip(home, (0.05, -0.05, 0.05, 0.0, 0.05, 0.0), strict=True)]
    waypoint = model.forward_kinematics(near)
    goal = model.forward_kinematics(Q1)
    pose_target = {"header": HEADER, "pose": pose_msg(goal.position, goal.orientation)}
    cartesian = {"header": HEADER, "poses": [pose_msg(waypoint.position, waypoint.orientation)]}
    return {
        "steps": [
            joint_target(Q1),
            empty("/go"),
            text("/remember", "here"),
            text("/named_target", "home"),
            empty("/plan"),
            empty("/execute"),
            {"topic": "/cartesian_path", "msg": cartesian},
            {"topic": "/pose_target", "msg": pose_target},
            empty("/go"),
        ]
    }


def assert_close(a: tuple[float, ...], b: tuple[float, ...], tol: float, what: str) -> None:
    assert len(a) == len(b), what
    worst = max((abs(x - y) for x, y in zip(a, b, strict=True)), default=0.0)
    assert worst <= tol, f"{what}: {worst}"


def test_fixed_script_runs_and_both_targets_agree_step_by_step(runners: tuple[Runner, Runner]) -> None:
    message = fixed_script(runners[1].model)
    validate(message, REGISTRY)
    call = to_call(message)
    outcomes = [r.run(call) for r in runners]
    for outcome in outcomes:
        assert outcome.status is Status.OK
        assert [s.label for s in outcome.steps] == ["ok"] * len(call.steps)
        steps = outcome.steps
        assert_close(steps[0].values["joint_target"], tuple(Q1), 0.0, "joint target")
        assert_close(steps[1].values["joint_values"], tuple(Q1), 0.0, "go reaches the joint target")
        assert steps[1].values["success"] == (1.0,)
        assert steps[2].values["named.here"] == steps[1].values["joint_values"]
        home = tuple(runners[1].model.home_values)
        assert_close(steps[3].values["joint_target"], home, 0.0, "named target")
        plan = steps[4].values
        assert plan["success"] == (1.0,) and plan["error_code"] == (1.0,)
        dof = len(home)
        times = plan["trajectory.time_from_start"]
        assert len(plan["trajectory.positions"]) == len(times) * dof > dof
        assert times[0] == 0.0 and all(b > a for a, b in itertools.pairwise(times))
        assert_close(plan["trajectory.positions"][-dof:], home, 0.0, "plan ends at the goal")
        assert_close(steps[4].values["joint_values"], tuple(Q1), 0.0, "plan does not move")
        assert_close(steps[5].values["joint_values"], home, 0.0, "execute follows the plan")
        assert steps[5].values["in_effect.plan_last"] == plan["trajectory.positions"][-dof:]
        assert steps[6].values["fraction"] == (1.0,)
        reached = tuple(runners[1].model.forward_kinematics(Q1).position)
        assert_close(steps[8].values["position"], reached, 1e-5, "the pose target is reached")
        assert "in_effect.joint_goal" not in steps[8].values  # a pose target is active
        remembered = steps[2].values["named.here"]
        for i, step_outcome in enumerate(steps[3:], 3):  # a move shows what was remembered, as it was
            moved = call.steps[i].kind in ("go", "execute")
            assert ("named.here" in step_outcome.values) == moved, i
            if moved:
                assert step_outcome.values["named.here"] == remembered, i
        assert steps[5].values["joint_values"] != remembered  # and the arm did move away from it
        assert_close(outcome.values["joint_values"], steps[8].values["joint_values"], 0.0, "final state")
    a, b = outcomes
    for i, (x, y) in enumerate(zip(a.steps, b.steps, strict=True)):
        assert x.label == y.label
        assert x.values.keys() == y.values.keys(), i
        for key in x.values:
            assert_close(x.values[key], y.values[key], TOL, f"step {i} {key}")


def test_a_repeated_plan_is_recorded_once(runners: tuple[Runner, Runner]) -> None:
    """A plan with the same bits as the last one is recorded as that record again, not a copy
    (a script of many slow, repeated plans held a copy per step), and a new plan is its own."""
    home = list(runners[1].model.home_values)
    steps = [joint_target(Q1), number("/acceleration_scaling", 0.01), empty("/plan"), empty("/plan")]
    other = [joint_target(home), empty("/plan"), joint_target(Q1), empty("/plan")]
    call = to_call({"steps": [*steps, *other]})
    keys = [f"trajectory.{name}" for name in ("time_from_start", "positions", "velocities", "accelerations")]
    for runner in runners:
        outcome = runner.run(call)
        assert [s.label for s in outcome.steps] == ["ok"] * len(call.steps)
        first, again, to_home, later = (outcome.steps[i].values for i in (2, 3, 5, 7))
        alone = runner.run(to_call({"steps": steps[:3]})).steps[2].values
        for key in keys:
            assert len(first[key]) > 100 * len(home), key  # long enough to matter
            assert again[key] is first[key] and first[key] == alone[key], key
            assert to_home[key] is not first[key] and to_home[key] != first[key], key
            assert later[key] is not first[key] and later[key] == first[key], key  # only the last is kept
    assert not _same_bits(np.array([0.0]), np.array([-0.0]))
    assert _same_bits(np.array([np.nan]), np.array([np.nan]))


def test_rejected_steps_go_on(runners: tuple[Runner, Runner]) -> None:
    message = {
        "steps": [
            number("/velocity_scaling", 2.0),  # outside (0, 1]
            text("/named_target", "nowhere"),
            joint_target([9.0] * 6),  # out of bounds
            number("/goal_tolerance", -1.0),
            number("/goal_tolerance", 1e-3),
            joint_target(Q1),
            empty("/go"),
        ]
    }
    for runner in runners:
        outcome = run_scenario(runner, to_call(message))
        assert outcome.status is Status.OK
        statuses = [s.status for s in outcome.steps]
        assert statuses == [Status.REJECTED] * 4 + [Status.OK] * 3
        assert outcome.steps[0].error == "InvalidInputError"
        assert all(s.code is not None for s in outcome.steps[:4])
        go = outcome.steps[-1].values  # the rejected settings never took effect, the accepted one did
        assert go["in_effect.velocity_scaling"] == (1.0,) and go["in_effect.goal_tolerance"] == (1e-3,)
        assert go["in_effect.joint_goal"] == tuple(Q1)
        assert_close(outcome.values["joint_values"], tuple(Q1), 0.0, "the script went on")


def test_execute_without_a_plan_makes_no_call(runners: tuple[Runner, Runner]) -> None:
    for runner in runners:
        outcome = run_scenario(runner, to_call({"steps": [empty("/execute")]}))
        step = outcome.steps[0]
        assert step.status is Status.OK and step.values["success"] == (1.0,)
        assert "in_effect.plan_last" not in step.values
        assert step.values["joint_values"] == tuple(runner.home)


class _CrashingGroup(python_impl.MoveGroup):
    def go(self, joints: Any = None, wait: bool = True) -> bool:
        raise ZeroDivisionError("planted")


def test_a_crashed_step_ends_the_scenario() -> None:
    model = python_impl.RobotModel(robots.resolve("probot_anno"))
    impl = SimpleNamespace(RobotModel=python_impl.RobotModel, MoveGroup=_CrashingGroup)
    runner = Runner("crashing", impl, model)
    message = {"steps": [joint_target(Q1), empty("/go"), empty("/plan"), empty("/go")]}
    outcome = runner.run(to_call(message))
    assert outcome.status is Status.CRASHED and outcome.error == "ZeroDivisionError"
    assert [s.label for s in outcome.steps] == ["ok", "crashed:ZeroDivisionError:None"]
    assert outcome.values["joint_values"] == tuple(model.home_values)  # the final state is still read


def test_nudge_shifts_the_state_before_its_step(runners: tuple[Runner, Runner]) -> None:
    message = {"steps": [joint_target(Q1), text("/remember", "n"), empty("/go")]}
    for runner in runners:
        plain = run_scenario(runner, to_call(message))
        nudged = run_scenario(runner, to_call(message), nudge=Nudge(1, 1e-3))
        before = plain.steps[1].values["named.n"]
        after = nudged.steps[1].values["named.n"]
        limits = runner.model.joint_limits
        for j, (x, y) in enumerate(zip(before, after, strict=True)):
            expected = min(max(x + (1e-3 if j % 2 == 0 else -1e-3), limits[j].lower), limits[j].upper)
            assert math.isclose(y, expected, abs_tol=1e-12), j
        assert nudged.steps[0].values == plain.steps[0].values  # steps before the nudge unchanged


def reached(runner: Runner, q: list[float]) -> tuple[float, ...]:
    return tuple(runner.model.forward_kinematics(q).position)


@pytest.mark.parametrize("kind", ["pose_target", "position_target"])
def test_a_goal_nudge_moves_the_target_in_effect(runners: tuple[Runner, Runner], kind: str) -> None:
    shift = 1e-3
    for runner in runners:
        fk = runner.model.forward_kinematics(Q1)
        if kind == "pose_target":
            msg = {"header": HEADER, "pose": pose_msg(fk.position, fk.orientation)}
        else:
            msg = {"header": HEADER, "point": dict(zip("xyz", fk.position, strict=True))}
        goal = {"topic": f"/{kind}", "msg": msg}
        # the goal is set, then other steps, then the IK step the nudge comes before
        call = to_call({"steps": [goal, text("/remember", "r"), empty("/go")]})
        plain = run_scenario(runner, call)
        nudged = run_scenario(runner, call, nudge=Nudge(2, shift, Moved.POSITION))
        assert NUDGE_FAILED not in nudged.values
        assert plain.steps[2].status is nudged.steps[2].status is Status.OK
        before = plain.steps[2].values["position"]
        after = nudged.steps[2].values["position"]
        expected = (before[0] + shift, before[1] - shift, before[2] + shift)
        assert max(abs(x - y) for x, y in zip(after, expected, strict=True)) < 1e-5
        assert nudged.steps[1].values == plain.steps[1].values  # steps before the nudge unchanged


def test_a_goal_nudge_moves_a_paths_waypoints(runners: tuple[Runner, Runner]) -> None:
    shift = 1e-3
    for runner in runners:
        fk = runner.model.forward_kinematics(Q1)
        poses = [pose_msg(fk.position, fk.orientation)]
        path = {"topic": "/cartesian_path", "msg": {"header": HEADER, "poses": poses}}
        call = to_call({"steps": [joint_target(Q1), empty("/go"), path]})
        plain = run_scenario(runner, call)
        nudged = run_scenario(runner, call, nudge=Nudge(2, shift, Moved.POSITION))
        dof = len(Q1)
        last = [list(o.steps[2].values["trajectory.positions"][-dof:]) for o in (plain, nudged)]
        assert plain.steps[2].values["fraction"] == nudged.steps[2].values["fraction"] == (1.0,)
        assert reached(runner, last[0]) == pytest.approx(fk.position, abs=1e-5)
        moved = (fk.position[0] + shift, fk.position[1] - shift, fk.position[2] + shift)
        assert reached(runner, last[1]) == pytest.approx(moved, abs=1e-5)
        assert call.steps[2].message["poses"][0]["position"]["x"] == fk.position[0]  # the call is unchanged


def test_an_orientation_nudge_turns_the_pose_target_in_effect(runners: tuple[Runner, Runner]) -> None:
    shift = 1e-3
    for runner in runners:
        fk = runner.model.forward_kinematics(Q1)
        goal = {
            "topic": "/pose_target",
            "msg": {"header": HEADER, "pose": pose_msg(fk.position, fk.orientation)},
        }
        call = to_call({"steps": [goal, empty("/go")]})
        plain = run_scenario(runner, call)
        nudged = run_scenario(runner, call, nudge=Nudge(1, shift, Moved.ORIENTATION))
        assert NUDGE_FAILED not in nudged.values and nudged.steps[1].status is Status.OK
        assert nudged.steps[1].values["position"] == pytest.approx(
            plain.steps[1].values["position"], abs=1e-5
        )
        before = python_impl.transforms.quaternion_matrix(*plain.steps[1].values["orientation"])
        after = python_impl.transforms.quaternion_matrix(*nudged.steps[1].values["orientation"])
        turn = python_impl.transforms.rotation_vector(before.T @ after)
        expected = [shift / math.sqrt(3.0), -shift / math.sqrt(3.0), shift / math.sqrt(3.0)]
        assert turn.tolist() == pytest.approx(expected, abs=1e-5)  # about (1, -1, 1), in the tool frame
        position_only = {
            "topic": "/position_target",
            "msg": {"header": HEADER, "point": dict(zip("xyz", fk.position, strict=True))},
        }
        nothing = run_scenario(
            runner,
            to_call({"steps": [position_only, empty("/go")]}),
            nudge=Nudge(1, shift, Moved.ORIENTATION),
        )
        assert NUDGE_FAILED in nothing.values  # a position target has no orientation to turn


def test_a_goal_nudge_without_a_pose_goal_gives_no_evidence(runners: tuple[Runner, Runner]) -> None:
    for runner in runners:
        call = to_call({"steps": [joint_target(Q1), empty("/go")]})
        nudged = run_scenario(runner, call, nudge=Nudge(1, 1e-9, Moved.POSITION))
        assert NUDGE_FAILED in nudged.values
        assert nudged.steps == run_scenario(runner, call).steps


def test_seeds_are_valid_meaningful_scripts() -> None:
    from fuzzer.generation.corpus import make_seeds

    session = Session.open(RunConfig(op="scenario", max_steps=6))
    seeds = make_seeds(session, 12, seed=3)
    assert len(seeds) == 12 and make_seeds(session, 12, seed=3) == seeds
    limits = session.reference.joint_limits
    kinds: set[str] = set()
    for case in seeds:
        assert case.msg_type == MSG_TYPE
        session.validate(case.message)
        assert 1 <= len(case.message["steps"]) <= 6
        remembered = {"home"}
        for step in case.message["steps"]:
            kinds.add(step["topic"])
            msg = step["msg"]
            if step["topic"] == "/joint_target":
                assert all(
                    lim.lower <= v <= lim.upper for v, lim in zip(msg["position"], limits, strict=True)
                )
            elif step["topic"] == "/remember":
                remembered.add(msg["data"])
            elif step["topic"] == "/named_target":
                assert msg["data"] in remembered
            elif step["topic"] in ("/velocity_scaling", "/acceleration_scaling"):
                assert 0.0 < msg["data"] <= 1.0
    assert {"/joint_target", "/go"} <= kinds


def test_ros_transport_is_refused_for_scenarios() -> None:
    with pytest.raises(ConfigError, match="not supported yet"):
        Session.open(RunConfig(op="scenario", transport="ros"))
    with pytest.raises(ConfigError, match="max_steps"):
        Session.open(RunConfig(op="scenario", max_steps=0))
    config = RunConfig(op="scenario", max_steps=40)
    assert RunConfig.from_json(config.to_json()).max_steps == 40
    assert RunConfig.from_json({"op": "scenario"}).max_steps == MAX_STEPS
    with pytest.raises(ConfigError, match="max_steps"):
        RunConfig.from_json({**config.to_json(), "max_steps": 300})


# -- command line -----------------------------------------------------------------------------


def fuzz(cwd: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, SCRIPT, *args, "--no-progress"],
        cwd=cwd,
        env=env,
        text=True,
        capture_output=True,
        timeout=timeout,
        check=False,
    )


@pytest.mark.parametrize(
    ("value", "expected"),
    [("0", "must be from 1 to 256"), ("257", "must be from 1 to 256"), ("x", "not an integer")],
)
def test_max_steps_out_of_range_is_a_usage_error(tmp_path: Path, value: str, expected: str) -> None:
    run = fuzz(tmp_path, "corpus", "--op", "scenario", "--max-steps", value, "-runs=1")
    assert run.returncode == 2, run.stderr[-2000:]
    assert expected in run.stderr and "Traceback" not in run.stderr


def test_a_short_scenario_campaign_runs_end_to_end(tmp_path: Path) -> None:
    """Seeds, mutation, both targets, the oracle, crash files: exit 0 (nothing new) or 1 (new
    divergences, each with a scenario sidecar naming its first divergent step)."""
    corpus, artifacts = tmp_path / "corpus", tmp_path / "artifacts"
    corpus.mkdir()
    bad = {"rrosfuzz": 1, "msg_type": MSG_TYPE, "message": {"steps": [empty("/go"), empty("/fly")]}}
    (corpus / "bad-step").write_text(json.dumps(bad))
    run = fuzz(
        tmp_path, str(corpus), "--op", "scenario", "--max-steps", "5", "--seeds", "8",
        f"--artifacts={artifacts}", "-max_total_time=4", "-seed=2",
    )  # fmt: skip
    assert run.returncode in (0, 1), run.stderr[-3000:]
    assert "fuzzing scenario on probot_anno.urdf" in run.stderr
    assert "wrote 8 seeds from Hypothesis (rrosfuzz/Scenario)" in run.stderr
    # with 5 steps at most, one of MoveIt's tutorial scripts fits (fuzzer/generation/tutorial.py)
    assert "and 1 script(s) of MoveIt's tutorials" in run.stderr
    tutorial = [json.loads(p.read_text()) for p in corpus.glob("seed-00008-*")]
    assert len(tutorial) == 1 and tutorial[0]["origin"] == "tutorial", tutorial
    assert f"skipping corpus file {corpus / 'bad-step'}: step 1 ('/fly'): unknown topic" in run.stderr
    manifest = json.loads((corpus / ".rrosfuzz" / "manifest.json").read_text())
    assert manifest["config"]["op"] == "scenario" and manifest["config"]["max_steps"] == 5
    executions = next(line for line in run.stderr.splitlines() if "executions:" in line)
    assert int(executions.rsplit("malformed ", 1)[1]) >= 1  # the bad file is run and judged malformed
    sidecars = [json.loads(p.read_text()) for p in sorted(artifacts.glob("crash-*.json"))]
    if run.returncode == 1:  # (a known limitation gets a crash file too, but is not new)
        assert any(s["comparison"]["kind"] != "known_limitation" for s in sidecars)
    for sidecar in sidecars:
        steps = sidecar["testcase"]["message"]["steps"]
        assert sidecar["config"]["max_steps"] == 5 and 1 <= len(steps) <= 5
        assert 0 <= sidecar["comparison"]["step"] < len(steps)
        assert sidecar["comparison"]["step_kind"] == steps[sidecar["comparison"]["step"]]["topic"][1:]
