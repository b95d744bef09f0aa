"""The ros_tf target: robot_state_publisher + tf2 (real ROS 1 from apt) against native."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robot_api import robots
from robot_api.errors import ErrorCode, InvalidInputError
from tests.support import skip_or_fail

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.filterwarnings("ignore:notifyAll:DeprecationWarning")  # rospy 1.15


@pytest.fixture(scope="module")
def ros_tf():  # type: ignore[no-untyped-def]
    from fuzzer.ros import env

    gone = env.missing()
    if gone:
        skip_or_fail(f"ROS 1 is not installed ({', '.join(gone)}): run scripts/ros-ensure.sh")
    from adapters import ros_tf

    return ros_tf


def _agree(model, reference, rng, n: int, scale: float) -> float:  # type: ignore[no-untyped-def]
    worst = 0.0
    for _ in range(n):
        q = [float(x) for x in rng.uniform(-scale, scale, model.dof)]
        for link in (None, model.link_names[len(model.link_names) // 2]):
            a, b = model.forward_kinematics(q, link), reference.forward_kinematics(q, link)
            worst = max(worst, float(np.max(np.abs(np.subtract(a.position, b.position)))))
            worst = max(worst, float(np.max(np.abs(np.subtract(a.orientation, b.orientation)))))
    return worst


@pytest.mark.parametrize(
    ("robot", "tip", "scale"),
    [
        (robots.DEFAULT_ROBOT, None, 3.0),
        ("double_pendulum_continuous", None, 1e5),  # continuous joints far from zero
        ("panda", "panda_rightfinger", 0.04),  # a mimic joint whose master is a variable
        ("ur5", None, 6.0),  # fixed frames after the last joint (tool0)
    ],
)
def test_ros_tf_matches_native(ros_tf, robot: str, tip: str | None, scale: float) -> None:  # type: ignore[no-untyped-def]
    import native

    urdf = str(robots.resolve(robot))
    model, reference = ros_tf.RobotModel(urdf, tip), native.RobotModel(urdf, tip)
    assert model.joint_names == tuple(reference.joint_names)
    worst = _agree(model, reference, np.random.default_rng(7), 25, scale)
    assert worst <= 1e-9, f"{robot}: robot_state_publisher + tf2 differ from native by {worst}"


def test_ros_tf_root_is_identity_and_ik_is_unsupported(ros_tf) -> None:  # type: ignore[no-untyped-def]
    model = ros_tf.RobotModel(str(robots.resolve(robots.DEFAULT_ROBOT)))
    pose = model.forward_kinematics([0.3] * model.dof, model.root_link)
    assert pose.position == (0.0, 0.0, 0.0) and pose.orientation == (0.0, 0.0, 0.0, 1.0)
    with pytest.raises(InvalidInputError) as info:
        model.inverse_kinematics(((0.1, 0.0, 0.3), (0.0, 0.0, 0.0, 1.0)))
    assert info.value.code == ErrorCode.UNSUPPORTED_OPERATION
    batch = model.forward_kinematics_batch(np.zeros((3, model.dof)))
    assert batch.shape == (3, 4, 4) and np.allclose(
        batch[0], model.forward_kinematics([0.0] * model.dof).matrix
    )


def test_ros_missing_names_the_install_command(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from fuzzer.ros import env

    monkeypatch.setattr(env, "DIST_PACKAGES", tmp_path / "nothing")
    with pytest.raises(env.RosUnavailableError, match=r"scripts/ros-ensure\.sh"):
        env.require()


@pytest.mark.parametrize("op", ["ik", "move", "scenario"])
def test_ros_tf_is_refused_for_an_op_it_does_not_answer(op: str) -> None:
    """FK only: every ik input (and every scenario step that solves IK) against it was a counted
    finding, 26,111 in 20 s (a helper's campaign); now a usage error before any node starts."""
    from fuzzer.execution.session import ConfigError, RunConfig, Session

    with pytest.raises(ConfigError, match=f"'ros_tf' answers --op fk only, not --op {op}"):
        Session.open(RunConfig(op=op, targets=("native", "ros_tf")))


def test_ros_tf_gets_no_batched_sweeps() -> None:
    """Its batch is one tf2 round trip a row: the sweeps took 25.8 s of a 26-s campaign, 2 inputs
    a second (748 without them), and the campaign ran past -max_total_time."""
    from fuzzer.execution.session import batches

    assert not batches("ros_tf") and batches("native") and batches("python")
    assert not batches("no_such_module:api")


def _processes_with(marker: str) -> list[int]:
    """Live processes whose environment contains ``marker`` (our ROS_LOG_DIR)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            data = (entry / "environ").read_bytes()
            state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if marker.encode() in data and state != "Z":
            found.append(int(entry.name))
    return found


def test_campaign_with_ros_tf_runs_and_leaves_no_process(ros_tf, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    log_dir = tmp_path / "roslog"
    log_dir.mkdir()
    environment = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    environment["ROS_LOG_DIR"] = str(log_dir)
    run = subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), str(tmp_path / "corpus"), "--op", "fk",
         "--targets", "native,ros_tf", "--artifacts", str(tmp_path / "art"), "--seeds", "8",
         "-runs=300", "-seed=3", "--no-progress"],
        capture_output=True, text=True, timeout=300, env=environment, cwd=tmp_path, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-3000:]
    assert "native vs ros_tf" in run.stderr + run.stdout
    assert (log_dir / "rosmaster.log").exists() or any(log_dir.glob("rosmaster-*.log"))
    assert any(log_dir.glob("robot_state_publisher*.log"))
    assert _processes_with(str(log_dir)) == []


def test_a_dead_robot_state_publisher_is_a_crash_then_restarted(ros_tf) -> None:  # type: ignore[no-untyped-def]
    model = ros_tf.RobotModel(str(robots.resolve("ur3")))
    q = [0.2] * model.dof
    before = model.forward_kinematics(q)
    model._publisher.process.popen.kill()  # the node dies between two calls
    model._publisher.process.popen.wait()
    assert model.forward_kinematics(q) == before  # a new node, same answer
    node = model._publisher.process
    node.popen.kill()
    node.popen.wait()
    with pytest.raises(RuntimeError, match="robot_state_publisher died"):
        model._publisher.lookup(model.joint_names, q, model.link_names[0], model.link_names[-1])
