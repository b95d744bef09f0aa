"""rosbag in (--seeds-from-bag) and out (export-bag), with bags the tests write."""

from __future__ import annotations

import bz2
import json
import math
import os
import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from fuzzer.input.testcase import TestCase, decode
from tests.support import skip_or_fail

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.filterwarnings("ignore:notifyAll:DeprecationWarning")  # rospy 1.15


@pytest.fixture(scope="module")
def ros() -> Any:
    from fuzzer.ros import env

    gone = env.missing()
    if gone:
        skip_or_fail(f"ROS 1 is not installed ({', '.join(gone)}): run scripts/ros-ensure.sh")
    env.require()
    import rosbag
    import sensor_msgs.msg
    import std_msgs.msg

    return rosbag, sensor_msgs.msg, std_msgs.msg


def _state(sensor_msgs: Any, values: list[float], stamp: int) -> Any:
    m = sensor_msgs.JointState()
    m.header.stamp.secs = stamp
    m.header.frame_id = "link_3" if stamp % 2 else ""
    m.name = [f"joint_{i}" for i in range(1, 7)]
    m.position = values
    return m


def _fuzz(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    environment = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    return subprocess.run(
        [sys.executable, str(ROOT / "fuzz_diff.py"), *args],
        capture_output=True, text=True, timeout=180, cwd=cwd, env=environment, check=False,
    )  # fmt: skip


def test_bag_messages_become_seeds(ros: Any, tmp_path: Path) -> None:
    rosbag, sensor_msgs, std_msgs = ros
    bag_path = tmp_path / "recorded.bag"
    states = [[0.1 * k + 0.01 * i for i in range(6)] for k in range(3)]
    with rosbag.Bag(str(bag_path), "w") as bag:
        for k, values in enumerate(states):
            bag.write("/joint_states", _state(sensor_msgs, values, 10 + k))
            bag.write("/chatter", std_msgs.String(f"not a joint state {k}"))
    corpus = tmp_path / "corpus"
    run = _fuzz(str(corpus), "--op", "fk", "--seeds-from-bag", str(bag_path), "--artifacts",
                str(tmp_path / "art"), "-runs=20", "-seed=1", "--no-progress", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    assert f"wrote 3 seeds from {bag_path}" in run.stderr
    cases = [decode(p.read_bytes()) for p in corpus.iterdir() if p.is_file()]
    from_bag = sorted((c for c in cases if c.origin == "rosbag"), key=lambda c: c.sequence)
    assert [c.message["position"] for c in from_bag] == states
    assert [c.message["header"]["stamp"] for c in from_bag] == [
        {"secs": 10 + k, "nsecs": 0} for k in range(3)
    ]
    assert from_bag[1].message["header"]["frame_id"] == "link_3"
    assert not any(c.origin == "hypothesis" for c in cases)  # the bag's seeds replace Hypothesis'


def test_a_bag_of_non_finite_states_says_its_seeds_are_filtered(ros: Any, tmp_path: Path) -> None:
    """ "wrote 2 seeds", then every one filtered: only libFuzzer's "no interesting inputs were
    found" said so."""
    rosbag, sensor_msgs, _std_msgs = ros
    bag_path = tmp_path / "nan.bag"
    with rosbag.Bag(str(bag_path), "w") as bag:
        for k in range(2):
            bag.write("/joint_states", _state(sensor_msgs, [math.nan] + [0.1] * 5, 10 + k))
        bag.write("/joint_states", _state(sensor_msgs, [0.2] * 6, 12))
    run = _fuzz(str(tmp_path / "c"), "--op", "fk", "--seeds-from-bag", str(bag_path), "--artifacts",
                str(tmp_path / "a"), "-runs=5", "--no-progress", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    assert f"2 of the 3 seeds from {bag_path} hold a value that is not finite or absurd" in run.stderr


def test_a_bag_seed_longer_than_the_default_max_len_is_said(ros: Any, tmp_path: Path) -> None:
    """ "wrote 2 seeds", then "malformed 1": libFuzzer cut the longer one at the default -max_len,
    which only a -max_len given was checked against."""
    rosbag, sensor_msgs, _std_msgs = ros
    bag_path = tmp_path / "long.bag"
    with rosbag.Bag(str(bag_path), "w") as bag:
        long = _state(sensor_msgs, [0.1] * 6, 10)
        long.header.frame_id = "x" * 20_000
        bag.write("/joint_states", long)
        bag.write("/joint_states", _state(sensor_msgs, [0.2] * 6, 11))
    run = _fuzz(str(tmp_path / "c"), "--op", "fk", "--seeds-from-bag", str(bag_path), "--artifacts",
                str(tmp_path / "a"), "-runs=2", "--no-progress", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    assert "1 of 2 seeds are longer than -max_len=16384" in run.stderr


def test_unusable_bags_are_usage_errors(ros: Any, tmp_path: Path) -> None:
    rosbag, _sensor_msgs, std_msgs = ros
    only_strings = tmp_path / "strings.bag"
    with rosbag.Bag(str(only_strings), "w") as bag:
        bag.write("/chatter", std_msgs.String("hello"))
    garbage = tmp_path / "garbage.bag"
    garbage.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 4)
    for path, expected in (
        (
            only_strings,
            "no valid sensor_msgs/JointState message (the bag holds: std_msgs/String on /chatter)",
        ),
        (garbage, "not a readable bag"),
        (tmp_path / "missing.bag", "no such file"),
    ):
        run = _fuzz(str(tmp_path / "c"), "--op", "fk", "--seeds-from-bag", str(path), "-runs=1", cwd=tmp_path)
        assert run.returncode == 2, run.stderr[-2000:]
        assert expected in run.stderr and "Traceback" not in run.stderr


def test_a_bag_message_definition_is_never_compiled(
    ros: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    rosbag, sensor_msgs, _std_msgs = ros
    import genpy.dynamic

    from fuzzer.ros import bags

    hostile = tmp_path / "hostile.bag"
    data = _state(sensor_msgs, [0.0] * 6, 1)
    with rosbag.Bag(str(hostile), "w") as bag:  # same type name, another definition and MD5 sum
        header = {
            "type": "sensor_msgs/JointState",
            "md5sum": "0" * 32,
            "message_definition": "string __import__\n",
        }
        bag.write("/joint_states", ("sensor_msgs/JointState", b"\x00" * 16, "0" * 32, None), raw=True,
                  connection_header=header)  # fmt: skip
        bag.write("/good", data)

    def refuse(*_args: Any) -> Any:
        raise AssertionError("a bag's message definition was compiled")

    monkeypatch.setattr(genpy.dynamic, "generate_dynamic", refuse)
    seeds = bags.read_seeds(hostile, "sensor_msgs/JointState", lambda m: None)
    assert len(seeds) == 1 and seeds[0]["position"] == [0.0] * 6


def test_a_record_that_names_another_connection_is_not_compiled_either(
    ros: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The connection filter reads the index; a message record names its connection itself, and
    rosbag compiled the definition of the one it named (a helper's hostile bag, whose record of
    /joint_states said connection 1, a type whose definition ran Python: it wrote a file)."""
    import struct

    import genpy.dynamic

    from fuzzer.ros import bags

    rosbag, sensor_msgs, _std_msgs = ros
    hostile = tmp_path / "hostile.bag"
    evil = "evil/E"
    header = {"type": evil, "md5sum": "1" * 32, "message_definition": "int32 X\n"}
    with rosbag.Bag(str(hostile), "w") as bag:
        bag.write("/joint_states", _state(sensor_msgs, [0.1] * 6, 1))
        fake = type("Evil", (), {"_md5sum": "1" * 32})  # rosbag wants a class for a raw write
        bag.write("/evil", (evil, b"", "1" * 32, None, fake), raw=True, connection_header=header)
    data = bytearray(hostile.read_bytes())
    first = data.find(b"\x04\x00\x00\x00op=\x02")  # the first message record: /joint_states
    conn = data.find(b"conn=\x00\x00\x00\x00", first - 40, first + 60)
    data[conn + 5 : conn + 9] = struct.pack("<I", 1)  # now it says connection 1 (evil/E)
    hostile.write_bytes(bytes(data))

    def refuse(*_args: Any) -> Any:
        raise AssertionError("a bag's message definition was compiled")

    monkeypatch.setattr(genpy.dynamic, "generate_dynamic", refuse)
    with pytest.raises(bags.BagError, match="a message record of type evil/E"):
        bags.read_seeds(hostile, "sensor_msgs/JointState", lambda m: None)
    assert rosbag.bag._get_message_type.__module__ == "rosbag.bag"  # put back


def test_export_bag_writes_the_input_and_each_targets_answer(ros: Any, tmp_path: Path) -> None:
    rosbag, _sensor_msgs, _std_msgs = ros
    message = {
        "header": {"seq": 0, "stamp": {"secs": 42, "nsecs": 0}, "frame_id": ""},
        "name": [f"joint_{i}" for i in range(1, 7)], "position": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
        "velocity": [0.5], "effort": [],
    }  # fmt: skip
    crash = tmp_path / "crash-0123456789abcdef0123456789abcdef01234567"
    crash.write_bytes(TestCase("sensor_msgs/JointState", message).encode())
    q = [[0.1, 0.2, 0.3, 0.4, 0.5, 0.6], [0.1, 0.2, 0.3, 0.4, 0.5, math.pi]]
    outcomes = [
        {"target": t, "status": "ok", "values": {"joint_values": v, "position": [0.1 * k, 0.2, 0.3],
                                                  "orientation": [0.0, 0.0, 0.0, 1.0]}}
        for k, (t, v) in enumerate(zip(("native", "python"), q, strict=True))
    ]  # fmt: skip
    sidecar = {"config": {"op": "move", "robot": "probot_anno", "targets": ["native", "python"]},
               "signature": {"key": "k"}, "outcomes": outcomes}  # fmt: skip
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    out = crash.with_name(crash.name + ".bag")
    assert f"rosbag play {out}" in run.stdout
    got: dict[str, Any] = {}
    with rosbag.Bag(str(out)) as bag:
        for topic, msg, t in bag.read_messages():
            got[topic] = msg
            assert t.secs == 42
    assert list(got["/joint_states"].position) == message["position"]
    assert list(got["/joint_states"].velocity) == [0.5]
    for k in (0, 1):
        assert list(got[f"/rrosfuzz/target_{k}/joint_states"].position) == q[k]
        pose = got[f"/rrosfuzz/target_{k}/pose"]
        assert pose.header.frame_id == "base_link" and pose.pose.position.x == 0.1 * k
    info = subprocess.run(
        ["rosbag", "info", str(out)], capture_output=True, text=True, timeout=60, check=False
    )
    assert info.returncode == 0 and "/rrosfuzz/target_1/pose" in info.stdout, (
        info.stderr
    )  # Debian's own reader
    bad = _fuzz("export-bag", str(tmp_path / "nope"), cwd=tmp_path)
    assert bad.returncode == 2 and "no such file" in bad.stderr


def test_export_bag_writes_only_a_bag_file_and_names_what_it_cannot_use(ros: Any, tmp_path: Path) -> None:
    message = {
        "header": {"seq": 0, "stamp": {"secs": 42, "nsecs": 0}, "frame_id": ""},
        "name": [f"joint_{i}" for i in range(1, 7)], "position": [0.1] * 6, "velocity": [], "effort": [],
    }  # fmt: skip
    crash = tmp_path / "crash-0123456789abcdef0123456789abcdef01234567"
    crash.write_bytes(TestCase("sensor_msgs/JointState", message).encode())
    data = crash.read_bytes()
    sidecar = crash.with_name(crash.name + ".json")
    config = {"op": "move", "robot": "probot_anno", "targets": ["native", "python"]}
    sidecar.write_text(json.dumps({"config": config, "signature": {"key": "k"}, "outcomes": []}))
    refused = [
        (tmp_path, "a folder"),
        (crash, "the crash file's own data"),
        (sidecar, "the crash file's own data"),
        (tmp_path / "no" / "x.bag", "does not exist"),
    ]
    for output, says in refused:
        run = _fuzz("export-bag", str(crash), "-o", str(output), cwd=tmp_path)
        assert run.returncode == 2 and says in run.stderr and "Traceback" not in run.stderr, run.stderr[-800:]
    assert crash.read_bytes() == data  # it wrote the bag over the crash file, exit 0
    # a symlink planted at the bag's name is replaced, not followed out of the folder
    elsewhere = tmp_path / "elsewhere.txt"
    elsewhere.write_text("keep")
    link = crash.with_name(crash.name + ".bag")
    link.symlink_to(elsewhere)
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-800:]
    assert elsewhere.read_text() == "keep" and not link.is_symlink() and link.stat().st_size > 0
    # a sidecar whose tip link no longer loads; a message that is not its type
    sidecar.write_text(json.dumps({"config": {**config, "tip_link": "nope"}, "signature": {"key": "k"}}))
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 2 and "does not load" in run.stderr and "Traceback" not in run.stderr
    sidecar.write_text(json.dumps({"config": config, "signature": {"key": "k"}}))
    crash.write_bytes(TestCase("geometry_msgs/PoseStamped", message).encode())
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 2 and "is not a geometry_msgs/PoseStamped" in run.stderr, run.stderr[-800:]
    assert "Traceback" not in run.stderr
    # a robot file outside the working directory and the crash file's folder is not read,
    # unless the user vouches for the file
    outside = str(Path(__file__).resolve().parents[1] / "README.md")
    sidecar.write_text(json.dumps({"config": {**config, "robot": outside}, "signature": {"key": "k"}}))
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 2 and "README.md' leads outside" in run.stderr, run.stderr[-800:]
    run = _fuzz("export-bag", str(crash), "--trust-sidecar", cwd=tmp_path)
    assert run.returncode == 2 and "README.md does not load: URDFError" in run.stderr, run.stderr[-800:]
    assert "Traceback" not in run.stderr
    # a path relative to another working folder: given again with --robot, checked by SHA-256
    import hashlib
    import shutil

    from robot_api import robots

    urdf = tmp_path / "sub" / "my.urdf"
    urdf.parent.mkdir()
    shutil.copyfile(robots.resolve("probot_anno"), urdf)
    digest = hashlib.sha256(urdf.read_bytes()).hexdigest()
    recorded = {"config": {**config, "robot": "my.urdf"}, "signature": {"key": "k"}, "robot_sha256": digest}
    sidecar.write_text(json.dumps(recorded))
    crash.write_bytes(TestCase("sensor_msgs/JointState", message).encode())
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 2 and "'my.urdf' is neither a shipped robot" in run.stderr, run.stderr[-800:]
    run = _fuzz("export-bag", str(crash), "--robot", str(urdf), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-800:]
    run = _fuzz("export-bag", str(crash), "--robot", "ur5", cwd=tmp_path)
    assert run.returncode == 2 and "--robot ur5: not the robot file" in run.stderr, run.stderr[-800:]


def test_a_bag_s_chunks_and_messages_are_read_within_bounds(
    ros: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # an 8 KB bz2 bag declaring a 600 MB chunk took 1.3 GB to read; 3 x 10**7 positions made
    # seeds of 120 MB each, past the 1 MiB a test case may be (the bounds scaled down here)
    from fuzzer.ros import bags

    rosbag, sensor_msgs, _std_msgs = ros
    path = tmp_path / "big.bag"
    with rosbag.Bag(str(path), "w", compression="bz2") as bag:
        bag.write("/joint_states", _state(sensor_msgs, [0.1] * 6, 10))
        bag.write("/joint_states", _state(sensor_msgs, [0.0] * 1000, 11))  # 8 KB serialized
    monkeypatch.setattr(bags, "MAX_BYTES", 4096)
    seeds = bags.read_seeds(path, "sensor_msgs/JointState", lambda m: None)
    assert [len(s["position"]) for s in seeds] == [6]  # the large one skipped before it is read
    monkeypatch.setattr(bags, "MAX_CHUNK_BYTES", 1024)
    with pytest.raises(bags.BagError, match=r"a chunk of \d+ bytes uncompressed \(at most 1024"):
        bags.read_seeds(path, "sensor_msgs/JointState", lambda m: None)


def _lie_about_chunk_sizes(path: Path, declared: int) -> None:
    """Every chunk header's uncompressed ``size`` field rewritten to ``declared``."""
    data = bytearray(path.read_bytes())
    at = data.find(b"size=")
    assert at > 0
    while at > 0:
        data[at + 5 : at + 9] = struct.pack("<I", declared)
        at = data.find(b"size=", at + 9)
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("compression", ["bz2", "lz4"])
def test_a_chunk_that_lies_about_its_size_stops_at_the_bound(
    ros: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, compression: str
) -> None:
    # the bound on the declared size alone let a chunk declaring 100 bytes decompress whole
    from fuzzer.ros import bags

    rosbag, sensor_msgs, _std_msgs = ros
    path = tmp_path / "liar.bag"
    with rosbag.Bag(str(path), "w", compression=compression) as bag:
        for stamp in range(40):
            bag.write("/joint_states", _state(sensor_msgs, [0.001 * stamp] * 6, stamp + 1))
    before = bags.read_seeds(path, "sensor_msgs/JointState", lambda m: None)
    assert len(before) == 40
    _lie_about_chunk_sizes(path, 100)
    monkeypatch.setattr(bags, "MAX_CHUNK_BYTES", 1024)  # the chunk holds about 6 KB
    with pytest.raises(bags.BagError, match=r"a chunk decompresses past 1024 bytes"):
        bags.read_seeds(path, "sensor_msgs/JointState", lambda m: None)
    assert rosbag.bag.bz2 is bz2  # rosbag's own modules are back once the bag is read


def test_the_bounded_decompressors_give_what_the_whole_ones_give(ros: Any) -> None:
    import roslz4

    from fuzzer.ros.bag_limits import ChunkTooLargeError, bounded_bz2, bounded_lz4

    data = bytes(range(256)) * 300
    two_streams = bz2.compress(data) + bz2.compress(data[:1000])
    assert bounded_bz2(two_streams, 10**6) == bz2.decompress(two_streams)
    assert bounded_bz2(b"", 10) == bz2.decompress(b"")
    with pytest.raises(ChunkTooLargeError):
        bounded_bz2(two_streams, len(data))
    with pytest.raises(ValueError, match="end-of-stream"):
        bounded_bz2(bz2.compress(data)[:-20], 10**6)
    with pytest.raises(OSError):
        bounded_bz2(b"not bz2 at all", 10**6)
    packed = roslz4.compress(data * 20)
    assert bounded_lz4(roslz4, packed, 10**7) == roslz4.decompress(packed) == data * 20
    with pytest.raises(ChunkTooLargeError):
        bounded_lz4(roslz4, packed, 10**5)


def _scenario_crash(tmp_path: Path) -> tuple[Path, list[dict[str, Any]], list[list[float]]]:
    """A scenario crash file (joint target, go, velocity scaling, plan, execute) and its sidecar,
    whose two targets report a state after the first two steps."""
    from fuzzer.scenario.steps import MSG_TYPE

    header = {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
    steps = [
        {"topic": "/joint_target", "msg": {"header": header, "name": [], "position": [0.1] * 6,
                                           "velocity": [], "effort": []}},
        {"topic": "/go", "msg": {}},
        {"topic": "/velocity_scaling", "msg": {"data": 0.5}},
        {"topic": "/plan", "msg": {}},
        {"topic": "/execute", "msg": {}},
    ]  # fmt: skip
    crash = tmp_path / "crash-0123456789abcdef0123456789abcdef01234567"
    crash.write_bytes(TestCase(MSG_TYPE, {"steps": steps}).encode())
    q = [[0.1] * 6, [0.1, 0.1, 0.1, 0.1, 0.1, 0.2]]
    outcomes = [
        {"target": t, "status": "ok", "steps": [
            {"status": "ok", "values": {"joint_target": [0.1] * 6, "joint_values": [0.0] * 6}},
            {"status": "ok", "values": {"joint_values": v, "position": [0.1, 0.2, 0.3 + k],
                                        "orientation": [0.0, 0.0, 0.0, 1.0]}},
            {"status": "rejected", "values": {}},
        ]}
        for k, (t, v) in enumerate(zip(("native", "python"), q, strict=True))
    ]  # fmt: skip
    sidecar = {"config": {"op": "scenario", "robot": "probot_anno", "targets": ["native", "python"]},
               "signature": {"key": "k"}, "outcomes": outcomes}  # fmt: skip
    crash.with_name(crash.name + ".json").write_text(json.dumps(sidecar))
    return crash, steps, q


def test_a_scenario_exports_as_its_steps_and_reads_back_as_that_scenario(ros: Any, tmp_path: Path) -> None:
    """export-bag said "nothing to export" for a scenario (the main job's crash files), and
    --seeds-from-bag refused --op scenario; now a scenario goes to a bag step by step, one
    second apart, with each target's state after each step, and comes back as the same script."""
    rosbag, _sensor_msgs, _std_msgs = ros
    crash, steps, q = _scenario_crash(tmp_path)
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    out = crash.with_name(crash.name + ".bag")
    with rosbag.Bag(str(out)) as bag:
        got = [(topic, msg, t.to_sec()) for topic, msg, t in bag.read_messages()]
    step_topics = [(topic, t) for topic, _msg, t in got if topic.startswith("/rrosfuzz/scenario/")]
    assert step_topics == [("/rrosfuzz/scenario" + s["topic"], 1.0 + i) for i, s in enumerate(steps)]
    speed = next(msg for topic, msg, _t in got if topic == "/rrosfuzz/scenario/velocity_scaling")
    assert speed.data == 0.5
    for k in (0, 1):
        where = f"/rrosfuzz/target_{k}"
        states = [(list(m.position), t) for topic, m, t in got if topic == f"{where}/joint_states"]
        assert states == [([0.0] * 6, 1.0), (q[k], 2.0)]  # the third step reported none
        poses = [(m.pose.position.z, t) for topic, m, t in got if topic == f"{where}/pose"]
        assert poses == [(0.3 + k, 2.0)]
    corpus = tmp_path / "corpus"
    run = _fuzz(str(corpus), "--op", "scenario", "--seeds-from-bag", str(out), "--artifacts",
                str(tmp_path / "art"), "-runs=5", "-seed=1", "--no-progress", cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    assert f"wrote 1 seeds from {out}" in run.stderr
    cases = [decode(p.read_bytes()) for p in corpus.iterdir() if p.is_file()]
    seeds = [c for c in cases if c.origin == "rosbag"]
    assert [c.message["steps"] for c in seeds] == [steps]


def test_a_recording_becomes_successive_moves_in_scripts(ros: Any, tmp_path: Path) -> None:
    """A bag of recorded states (no scenario topics): each JointState or PoseStamped a move (a
    target and go), packed into scripts of at most --max-steps steps; a JointState naming the
    chain's joints in another order (as some drivers publish) is put in the chain's order, a
    gripper's joint left out, the robot's velocities and efforts dropped."""
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.ros import scenario_bags

    rosbag, sensor_msgs, std_msgs = ros
    import geometry_msgs.msg

    path = tmp_path / "recorded.bag"
    joints = [f"joint_{i}" for i in range(1, 7)]
    with rosbag.Bag(str(path), "w") as bag:
        for k in range(9):
            state = _state(sensor_msgs, [0.01 * k + 0.1 * i for i in range(6)], 10 + k)
            if k == 4:  # alphabetical, with a gripper joint, and the robot's own velocities
                state.name = ["gripper", *reversed(joints)]
                state.position = [0.5, *reversed(state.position)]
                state.velocity = [0.0] * 7
            bag.write("/joint_states", state)
        bag.write("/chatter", std_msgs.String("not a state"))
        pose = geometry_msgs.msg.PoseStamped()
        pose.pose.position.x, pose.pose.orientation.w = 0.2, 1.0
        bag.write("/tool_pose", pose)
    session = Session.open(RunConfig(op="scenario", max_steps=4))
    scenarios = scenario_bags.read_scenarios(path, session.validate, 4, joints)
    kinds = [[s["topic"] for s in sc["steps"]] for sc in scenarios]
    assert kinds == [["/joint_target", "/go"] * 2] * 4 + [["/joint_target", "/go", "/pose_target", "/go"]]
    moved = [sc["steps"][i]["msg"] for sc in scenarios for i in (0, 2)]
    assert moved[4]["name"] == joints
    assert moved[4]["position"] == pytest.approx([0.04 + 0.1 * i for i in range(6)])
    assert moved[4]["velocity"] == [] and moved[4]["effort"] == []
    assert moved[9]["pose"]["position"]["x"] == 0.2  # the pose, last in the bag
    with pytest.raises(ValueError, match="no valid scenario step"):
        scenario_bags.read_scenarios(path, session.validate, 1, joints)  # a move takes two steps


def test_a_scenario_bag_is_read_within_bounds_and_by_its_index(ros: Any, tmp_path: Path) -> None:
    """A helper's bags: a recording ahead of a bag's script steps hid them (the reading stopped
    at its limit first); one NaN state dropped its script's seven valid moves with it; steps past
    -max_len were packed into scripts libFuzzer cut short; 300 steps of 130,000 positions were
    kept, 1.6 GB; --max-steps 1 said "no valid JointState" of valid ones."""
    from fuzzer.execution.session import RunConfig, Session
    from fuzzer.ros import scenario_bags

    rosbag, sensor_msgs, std_msgs = ros
    joints = [f"joint_{i}" for i in range(1, 7)]
    session = Session.open(RunConfig(op="scenario", max_steps=4))
    mixed = tmp_path / "mixed.bag"
    with rosbag.Bag(str(mixed), "w") as bag:
        for k in range(30):
            bag.write("/joint_states", _state(sensor_msgs, [0.01 * k] * 6, 10 + k))
        bag.write("/rrosfuzz/scenario/velocity_scaling", std_msgs.Float64(0.5))
        bag.write("/rrosfuzz/scenario/go", std_msgs.Empty())
    read = scenario_bags.read_scenarios(mixed, session.validate, 4, joints)
    assert [[s["topic"] for s in sc["steps"]] for sc in read] == [["/velocity_scaling", "/go"]]
    recording = tmp_path / "recording.bag"
    with rosbag.Bag(str(recording), "w") as bag:
        bag.write("/joint_states", _state(sensor_msgs, [math.nan] + [0.1] * 5, 9))
        for k in range(4):
            bag.write("/joint_states", _state(sensor_msgs, [0.1 * k] * 6, 10 + k))
        bag.write(
            "/joint_states", _state(sensor_msgs, [0.2] * 6 + [0.0] * 3000, 20)
        )  # names 6, positions 3006
    read = scenario_bags.read_scenarios(recording, session.validate, 4, joints)
    moved = [sc["steps"][i]["msg"]["position"][0] for sc in read for i in range(0, len(sc["steps"]), 2)]
    assert moved == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.2]), "the NaN state alone is left out"
    small = scenario_bags.read_scenarios(recording, session.validate, 4, joints, max_bytes=1000)
    assert [len(sc["steps"]) for sc in small] == [2, 2, 2, 2], "one move a script; the 12 kB one left out"
    with pytest.raises(ValueError, match="a move takes two steps: --max-steps must be 2 or more"):
        scenario_bags.read_scenarios(recording, session.validate, 1, joints)
    assert len(scenario_bags.read_scenarios(recording, session.validate, 4, joints, filtering=False)) == 3


def test_what_a_bag_holds_is_said_in_a_bounded_line() -> None:
    from fuzzer.ros.bags import holdings

    held = [f"std_msgs/String on /t{i}" for i in range(50_000)]
    said = holdings(held)  # 50,000 topics made an error message of 1.4 MB
    assert said.startswith("std_msgs/String on /t0, ") and said.endswith(", ... (50000 in all)")
    assert len(said) < 1000 and holdings([]) == "no messages"


def test_an_exported_bag_beside_its_crash_file_is_not_taken_for_one(ros: Any, tmp_path: Path) -> None:
    """export-bag's default CRASH.bag was triage's most severe bucket, "crash without sidecar",
    and `show FOLDER` and `minimize art/crash-*` stopped on it."""
    from fuzzer.artifacts.store import ArtifactStore
    from fuzzer.input.paths import crash_inputs
    from fuzzer.processes import new_artifacts
    from fuzzer.triage.pipeline import collect

    crash, _steps, _q = _scenario_crash(tmp_path)
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    bag = crash.with_name(crash.name + ".bag")
    assert bag.is_file()
    assert crash_inputs([tmp_path]) == [crash] and crash_inputs([crash, bag]) == [crash]
    assert ArtifactStore(tmp_path).crash_files() == [crash]
    assert [b.representative for b in collect(tmp_path)] == [crash]
    assert bag not in new_artifacts(tmp_path, 0.0).crashes


def test_a_bag_that_cannot_be_written_exits_74(
    ros: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """As every output that cannot be written (it was 2, a usage error)."""
    import errno
    import tempfile

    from fuzzer import cli

    crash, _steps, _q = _scenario_crash(tmp_path)

    def read_only(*_args: Any, **_kwargs: Any) -> Any:
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(tempfile, "mkstemp", read_only)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["export-bag", str(crash), "-o", str(tmp_path / "x.bag")]) == 74
    assert "x.bag: cannot write the bag: Read-only file system" in capsys.readouterr().err


def test_an_exported_bag_is_readable_by_others_as_the_umask_says(ros: Any, tmp_path: Path) -> None:
    crash, _steps, _q = _scenario_crash(tmp_path)
    run = _fuzz("export-bag", str(crash), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    mask = os.umask(0)
    os.umask(mask)
    assert (crash.with_name(crash.name + ".bag").stat().st_mode & 0o777) == 0o666 & ~mask  # it was 0600
