"""The ROS transport (--transport ros): targets as ROS nodes, crashes, timeouts, shutdown."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from fuzzer.execution.records import Outcome, Status
from fuzzer.execution.targets import Runner
from fuzzer.input.mapping import FkCall, IkCall, MoveCall
from fuzzer.input.testcase import TestCase
from robot_api import robots
from tests import ros_faulty_target as faulty
from tests.support import skip_or_fail
from tests.test_ros_tf import _processes_with

ROOT = Path(__file__).resolve().parents[1]
FAULTY = "tests.ros_faulty_target:api"
pytestmark = pytest.mark.filterwarnings("ignore:notifyAll:DeprecationWarning")  # rospy 1.15

CALLS = [
    FkCall((0.1, 0.2, 0.3, 0.4, 0.5, 0.6)),
    FkCall((0.1, 0.2, 0.3, 0.4, 0.5, math.nan)),
    FkCall((0.1,) * 6, "no_such_link"),
    FkCall((-2.5, 1e5, 0.3, -0.4, 3.0, 0.6), "link_3"),
    FkCall((0.1,) * 5),
    IkCall((0.2, 0.0, 0.4), (0.0, 0.0, 0.0, 1.0)),
    IkCall((0.2, 0.0, 0.4), (0.0, 0.0, 0.0, 0.0)),
    IkCall((math.inf, 0.0, 0.4), (0.0, 0.0, 0.0, 1.0)),
    MoveCall(None, (0.1, 0.2, 0.3, 0.4, 0.5, 0.6), 0.5, None),
    MoveCall(("joint_1",), (0.3,)),
    MoveCall(("joint_1", "nope"), (0.3, 0.1)),
    MoveCall(None, (9.0,) * 6),
]


@pytest.fixture(scope="module")
def transport():  # type: ignore[no-untyped-def]
    from fuzzer.ros import env

    gone = env.missing()
    if gone:
        skip_or_fail(f"ROS 1 is not installed ({', '.join(gone)}): run scripts/ros-ensure.sh")
    from fuzzer.ros import transport

    return transport


@pytest.mark.parametrize("spec", ["native", "python"])  # native: the C++ roscpp node; python: rospy
def test_nodes_answer_exactly_as_in_process(transport, spec: str) -> None:  # type: ignore[no-untyped-def]
    urdf = robots.resolve(robots.DEFAULT_ROBOT)
    over_ros = transport.RosRunner.create(spec, urdf, None)
    local = Runner.create(spec, urdf, None)
    try:
        for call in CALLS:
            assert over_ros.run(call) == local.run(call), call
        seed = (0.3, -0.2, 0.1, 0.0, 0.5, -0.1)
        assert over_ros.run(CALLS[5], seed) == local.run(CALLS[5], seed)
        assert over_ros.fresh() is over_ros and over_ros.run(CALLS[0]) == local.run(CALLS[0])
    finally:
        over_ros.node.stop()
    assert not over_ros.node.process.alive()


def test_dead_and_silent_nodes_are_crashes_and_restarted(transport, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(transport, "REQUEST_TIMEOUT", 2.0)
    runner = transport.RosRunner.create(FAULTY, robots.resolve(robots.DEFAULT_ROBOT), None)
    good = FkCall((0.1, 0.0, 0.0, 0.0, 0.0, 0.0))
    try:
        first_pid = runner.node.process.pid
        died = runner.run(FkCall((faulty.DIE, 0.0, 0.0, 0.0, 0.0, 0.0)))
        assert (died.status, died.error) == (Status.CRASHED, "NodeDied") and "status 3" in died.message
        assert runner.node.restarts == 1 and runner.node.process.pid != first_pid
        assert runner.run(good).status == Status.OK
        hung = runner.run(FkCall((faulty.HANG, 0.0, 0.0, 0.0, 0.0, 0.0)))
        assert (hung.status, hung.error) == (Status.CRASHED, "NodeTimeout")
        assert runner.node.restarts == 2 and runner.run(good).status == Status.OK
        raised = runner.run(FkCall((faulty.RAISE, 0.0, 0.0, 0.0, 0.0, 0.0)))
        assert (raised.status, raised.error, raised.message) == (
            Status.CRASHED,
            "RuntimeError",
            "injected fault",
        )
        assert runner.node.restarts == 2
    finally:
        runner.node.stop()


def test_a_node_shut_down_from_outside_is_started_again_and_asked_again(transport, capsys) -> None:  # type: ignore[no-untyped-def]
    """``rosnode kill`` of a target (a clean exit, status 0) was a crash file and exit 1."""
    from fuzzer.ros import node

    runner = transport.RosRunner.create(FAULTY, robots.resolve(robots.DEFAULT_ROBOT), None)
    Path(node.context().master.log_dir, "rrosfuzz-exited-once").unlink(missing_ok=True)  # an earlier run's
    try:
        outcome = runner.run(FkCall((faulty.EXIT_ONCE, 0.0, 0.0, 0.0, 0.0, 0.0)))
        assert outcome.status == Status.OK and runner.node.restarts == 1
        assert "exited with status 0 during an input" in capsys.readouterr().err
    finally:
        runner.node.stop()


def test_a_node_that_cannot_start_again_keeps_its_outcome_then_stops(
    transport, monkeypatch: pytest.MonkeyPatch
) -> None:  # type: ignore[no-untyped-def]
    """A helper killed the campaign's master, then a node: the restart's NodeStartError escaped
    the request, the NodeDied outcome with it (an uncaught exception, exit 77 "a target died",
    the divergence lost; later, the confirming re-run raised, and lost it too). The outcome is
    returned, later requests are NodeLost outcomes, and the campaign stops after the input."""
    runner = transport.RosRunner.create(FAULTY, robots.resolve(robots.DEFAULT_ROBOT), None)
    try:

        def refuse(self: object) -> None:
            raise transport.NodeStartError("its ROS node exited; the ROS master at http://x does not answer")

        monkeypatch.setattr(transport.TargetNode, "restart", refuse)
        died = runner.run(FkCall((faulty.DIE, 0.0, 0.0, 0.0, 0.0, 0.0)))
        assert (died.status, died.error) == (Status.CRASHED, "NodeDied")
        again = runner.run(FkCall((0.1, 0.0, 0.0, 0.0, 0.0, 0.0)))  # a confirming re-run, say
        assert (again.status, again.error) == (
            Status.CRASHED,
            "NodeLost",
        ) and "does not answer" in again.message
        said = transport.lost_reason([runner])
        assert said == "its ROS node exited; the ROS master at http://x does not answer"
    finally:
        runner.node.stop()


def test_other_nodes_on_a_target_s_topics_are_ignored_and_named(transport, capsys) -> None:  # type: ignore[no-untyped-def]
    """The ROS graph may be shared. A node that answered every request first, with the tool at
    (9, 9, 9), had its answers taken as the target's (2,459 divergences in a 30-s campaign of a
    probe); one malformed answer ended the campaign with a traceback; garbage on ``ready`` was
    logged 2,078 times in 20 s. Here the forger is this process's own node: not the target's."""
    from fuzzer.ros import env, node

    urdf = robots.resolve(robots.DEFAULT_ROBOT)
    runner = transport.RosRunner.create("python", urdf, None)
    local = Runner.create("python", urdf, None)
    target = runner.node
    rospy, std_msgs = node.context().rospy, env.import_module("std_msgs.msg")
    forger = rospy.Publisher(f"{target.topic}/response", std_msgs.String, queue_size=100)
    forged = Outcome(Status.OK, values={"position": (9.0, 9.0, 9.0), "orientation": (0.0, 0.0, 0.0, 1.0)})

    def forge(message: Any) -> None:
        ident = int(message.data.split("\n", 1)[0])
        forger.publish(std_msgs.String(transport.encode(ident, {"outcome": forged.to_json()})))
        forger.publish(std_msgs.String(transport.encode(ident + 1, {"outcome": {"status": "bogus"}})))

    listener = rospy.Subscriber(f"{target.topic}/request", std_msgs.String, forge, queue_size=100)
    try:
        deadline = time.monotonic() + 10
        while forger.get_num_connections() < 1 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert forger.get_num_connections() >= 1
        for call in CALLS:
            assert runner.run(call) == local.run(call), call
        assert f"publishes on {target.topic}/response" in capsys.readouterr().err
        ready = target._ready

        from types import SimpleNamespace

        garbage = SimpleNamespace(data="not json", _connection_header={"callerid": target.node_name})
        target._on_ready(garbage)  # the node's own name, and still no JSON: ignored, no traceback
        assert target._ready == ready
    finally:
        listener.unregister()
        forger.unregister()
        runner.node.stop()


def test_a_malformed_answer_is_a_crash_outcome(transport) -> None:  # type: ignore[no-untyped-def]
    for answer in ({"id": 1}, {"id": 1, "outcome": {"status": "bogus"}}, {"id": 1, "outcome": [1]}):
        outcome = transport.outcome_of(answer)
        assert (outcome.status, outcome.error) == (Status.CRASHED, "BadAnswer"), answer
    ok = transport.outcome_of({"id": 1, "outcome": {"status": "rejected", "code": 1}})
    assert ok.status == Status.REJECTED and ok.error


def test_protocol_encoding_round_trips_and_refuses_garbage(transport) -> None:  # type: ignore[no-untyped-def]
    payload = {
        "call": {"kind": "FkCall", "joint_values": [math.nan, math.inf, -math.inf, 0.1], "link": "NaN"}
    }
    text = transport.encode(7, payload)
    assert "NaN" not in text.split("\n", 1)[1].replace('"NaN"', "")  # plain JSON: no bare NaN token
    json.loads(text.split("\n", 1)[1])
    back = transport.decode(text)
    values = back["call"]["joint_values"]
    assert back["id"] == 7 and math.isnan(values[0]) and values[1:] == [math.inf, -math.inf, 0.1]
    assert back["call"]["link"] == "NaN"
    for garbage in ("", "1\n[]", '1\n{"id": "x"}', "1\n{not json"):
        with pytest.raises(ValueError):
            transport.decode(garbage)


def _case(path: Path, first: float) -> None:
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "name": [], "position": [first, 0.0, 0.0, 0.0, 0.0, 0.0], "velocity": [], "effort": [],
    }  # fmt: skip
    path.write_bytes(TestCase("sensor_msgs/JointState", message).encode())


def test_campaign_over_ros_saves_crashes_that_replay_in_process(transport, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    corpus, artifacts, log_dir = tmp_path / "corpus", tmp_path / "art", tmp_path / "roslog"
    corpus.mkdir()
    log_dir.mkdir()
    for i, first in enumerate((faulty.RAISE, faulty.DIE, 0.1)):
        _case(corpus / f"seed-{i}", first)
    environment = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    environment["ROS_LOG_DIR"] = str(log_dir)
    command = [sys.executable, str(ROOT / "fuzz_diff.py")]
    run = subprocess.run(
        [*command, str(corpus), "--op", "fk", "--transport", "ros", "--targets", f"python,{FAULTY}",
         "--artifacts", str(artifacts), "-runs=40", "-seed=1", "--no-progress"],
        capture_output=True, text=True, timeout=300, env=environment, cwd=ROOT, check=False,
    )  # fmt: skip
    output = run.stdout + run.stderr
    assert run.returncode == 1, output[-3000:]
    assert "as ROS nodes (master http://127.0.0.1:" in output
    errors = {}
    for sidecar in artifacts.glob("crash-*.json"):
        data = json.loads(sidecar.read_text())
        assert data["config"]["transport"] == "ros"
        errors[data["outcomes"][1]["error"]] = sidecar.with_suffix("")
    assert {"NodeDied", "RuntimeError"} <= set(errors), errors
    assert _processes_with(str(log_dir)) == []
    replay = subprocess.run(
        [*command, str(errors["RuntimeError"]), "--targets", f"python,{FAULTY}"],
        capture_output=True, text=True, timeout=120, env=environment, cwd=ROOT, check=False,
    )  # fmt: skip
    assert "still diverges (same signature)" in replay.stdout + replay.stderr, replay.stderr[-2000:]


def test_a_hanging_node_is_a_crash_file_within_libfuzzer_s_timeout(transport, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """The node's answer was awaited 20 s, libFuzzer's default -timeout too: a hang became a
    timeout file without a sidecar and a thread dump (exit 70), never the documented
    crashed:NodeTimeout. The wait is now a quarter of -timeout."""
    corpus, artifacts = tmp_path / "corpus", tmp_path / "art"
    corpus.mkdir()
    _case(corpus / "seed-hang", faulty.HANG)
    environment = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    environment["ROS_LOG_DIR"] = str(tmp_path)
    run = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), str(corpus), "--op", "fk", "--transport", "ros",
         "--targets", f"python,{FAULTY}", "--artifacts", str(artifacts), "-runs=3", "-timeout=8",
         "-seed=1", "--no-progress"],
        capture_output=True, text=True, timeout=300, env=environment, cwd=ROOT, check=False,
    )  # fmt: skip
    assert run.returncode == 1, run.stderr[-3000:]
    errors = [json.loads(p.read_text())["outcomes"][1]["error"] for p in artifacts.glob("crash-*.json")]
    assert errors == ["NodeTimeout"], (errors, run.stderr[-2000:])
    sidecar = next(artifacts.glob("crash-*.json")).read_text()
    assert "no answer from the target's node in 2.0 s" in sidecar
    assert not list(artifacts.glob("timeout-*"))


def test_an_ik_status_split_gets_the_same_verdict_over_ros(transport, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """The IK status check replays Newton-Raphson iterates on a twin model of the targets' robot
    file (``Evaluator.replay``); a ROS runner had no ``urdf``, so over ROS that check was skipped
    and this split, explained in process (an iterate meets a half turn), was a counted finding
    between the correct targets (a helper's ``--op ik --transport ros`` campaign)."""
    message = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "pose": {"position": {"x": 0.2799999999985158, "y": 0.0, "z": 0.4908553499954169},
                 "orientation": {"x": -0.7071067811758143, "y": 1.2986795316207019e-06,
                                 "z": 0.707106781185355, "w": 3.896027768872955e-06}},
    }  # fmt: skip
    case = tmp_path / "split"
    case.write_bytes(TestCase("geometry_msgs/PoseStamped", message).encode())
    environment = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    environment["ROS_LOG_DIR"] = str(tmp_path)
    verdicts = []
    for where in ("inprocess", "ros"):
        run = subprocess.run(
            [sys.executable, str(ROOT / "fuzz_diff.py"), str(case), "--op", "ik", "--tolerance", "1e-5",
             "--transport", where],
            capture_output=True, text=True, timeout=300, env=environment, cwd=ROOT, check=False,
        )  # fmt: skip
        assert "(signature " in run.stdout, run.stderr[-2000:]  # replayed, whatever the verdict
        verdicts.append(run.stdout.split("(signature ", 1)[-1].split(";")[0])
    assert verdicts[0] == verdicts[1] and "known_limitation on status" in verdicts[0], verdicts
    runner = transport.RosRunner.__new__(transport.RosRunner)
    runner.node = transport.TargetNode("python", "robot.urdf", "link_6")
    assert (runner.urdf, runner.tip_link) == ("robot.urdf", "link_6")


def test_the_rospy_node_runs_its_twin_with_kdl_s_dead_zone_when_asked(transport) -> None:  # type: ignore[no-untyped-def]
    """Inside the oracle's KDL dead-zone re-run, a request asks the node for the same swap in
    its own process (the swap in the engine's process did not reach a twin in a ROS node)."""
    from python_impl import kinematics

    sys.path.insert(0, str(ROOT / "ros"))
    try:
        import target_node
    finally:
        sys.path.remove(str(ROOT / "ros"))
    from fuzzer.execution import dead_zone

    seen: list[str] = []

    class Recorder:
        def run(self, call, seed):  # type: ignore[no-untyped-def]
            seen.append(kinematics.error_twist.__name__)
            return Local.run(call, seed)

    Local = Runner.create("python", robots.resolve(robots.DEFAULT_ROBOT), None)
    call = {"id": 1, "op": "run", "call": {"kind": "FkCall", "joint_values": [0.1] * 6, "link": None}}
    for flag in (False, True):
        request = {**call, "kdl_dead_zone": True} if flag else call
        ident, answer = target_node.handle(Recorder(), transport.encode(1, request))
        assert ident == 1 and answer["outcome"]["status"] == "ok", answer
    assert seen == ["error_twist", "with_dead_zone"]
    assert kinematics.error_twist.__name__ == "error_twist"
    sent: list[dict] = []  # type: ignore[type-arg]
    runner = transport.RosRunner.__new__(transport.RosRunner)
    runner.node = type("Node", (), {"request": lambda self, payload: sent.append(payload)})()
    runner.run(FkCall((0.1,) * 6))
    with dead_zone.twin_with_kdl_dead_zone():
        runner.run(FkCall((0.1,) * 6))
    assert ["kdl_dead_zone" in p for p in sent] == [False, True]


def test_transport_option_is_checked(tmp_path: Path) -> None:
    run = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), str(tmp_path), "--transport", "carrier-pigeon"],
        capture_output=True, text=True, timeout=60, cwd=ROOT, check=False,
    )  # fmt: skip
    assert run.returncode == 2 and "--transport" in run.stderr
    # ros_tf answers through ROS already: its node failed in rospy's init_node, named as the target's
    run = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), str(tmp_path / "c"), "--op", "fk", "--transport", "ros",
         "--targets", "native,ros_tf", f"--artifacts={tmp_path / 'a'}", "-runs=1"],
        capture_output=True, text=True, timeout=60, cwd=ROOT, check=False,
    )  # fmt: skip
    assert run.returncode == 2 and "use it with --transport inprocess" in run.stderr, run.stderr[-1500:]


def test_a_master_uri_that_answers_nothing_is_said(monkeypatch: pytest.MonkeyPatch, capsys) -> None:  # type: ignore[no-untyped-def]
    """One who meant to join their own master (to watch, to record) was given a private one
    without a word; a URI that is none (``http://[::1``) was blamed on the target's model."""
    from fuzzer.ros import processes

    monkeypatch.setattr(
        processes, "start_master", lambda log_dir: processes.Master("http://127.0.0.1:1/", log_dir)
    )
    for uri in ("http://[::1", "http://127.0.0.1:9/", "ftp://x"):
        monkeypatch.setenv("ROS_MASTER_URI", uri)
        assert not processes.master_answers(uri, timeout=0.5)
        assert processes.join_or_start_master(str(Path.cwd())).uri == "http://127.0.0.1:1/"
        assert f"ROS_MASTER_URI={uri!r}: no ROS master answers there" in capsys.readouterr().err
