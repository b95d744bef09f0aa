"""rosbag in and out: bag messages as seeds, a divergence as a bag (Debian's ``python3-rosbag``).

A bag is untrusted data. It embeds the definition of each message type it
holds, and rosbag would compile a Python class from that text on first use
(``genpy.dynamic``); here it never does: only connections whose type name and
MD5 sum are those of Debian's compiled class for the campaign's type are read,
rosbag's class cache is filled with that class beforehand, and while a bag is
read rosbag's type lookup answers that class only (:func:`known_types_only`: a
message record may name another connection than the index does). Messages become
plain data (:func:`to_data`) and pass the campaign's own validation.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shlex
import tempfile
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from fuzzer import reporting
from fuzzer.cli_options import campaign_robot_option, trust_option
from fuzzer.execution.session import ConfigError
from fuzzer.input.paths import FolderUnwritable, PathError, check_output_file, file_problem, given_path
from fuzzer.input.testcase import MAX_BYTES
from fuzzer.ros import env
from fuzzer.ros.bag_limits import ChunkTooLargeError, bounded_chunks
from fuzzer.scenario.steps import MSG_TYPE

JOINT_STATE = "sensor_msgs/JointState"

TOPICS = {
    JOINT_STATE: "/joint_states",
    "geometry_msgs/PoseStamped": "/rrosfuzz/pose_target",
    "geometry_msgs/Pose": "/rrosfuzz/pose_target",
    "std_msgs/Float64MultiArray": "/rrosfuzz/joint_values",
}
"""Topic of each input type in an exported bag (``/joint_states``: what robot_state_publisher reads)."""

MAX_SEEDS = 1000
"""At most this many messages of a bag become seeds (the first ones)."""

MAX_CHUNK_BYTES = 64 << 20
"""The largest chunk a bag may declare or decompress to (rosbag writes 768 KiB chunks): rosbag
decompresses a chunk whole, and an 8 KB bz2 bag declaring 600 MB took 1.3 GB to read."""


class BagError(ConfigError):
    """A bag that cannot be read or written (the CLI exits with 2 and this message)."""


class UncompiledTypeError(Exception):
    """A message record of a type rosbag would compile from the bag's own definition."""


@contextlib.contextmanager
def known_types_only(rosbag: Any, classes: Sequence[Any]) -> Iterator[None]:
    """While reading: rosbag's ``_get_message_type`` (a module global its readers look up for
    every message record) answers the one of ``classes`` of a connection's type and MD5 sum,
    and raises :class:`UncompiledTypeError` for any other instead of compiling the bag's
    definition (``genpy.dynamic``). The connection filter alone did not stop it: a record may
    name another connection than the index says (a helper's hostile bag ran its definition's
    Python)."""
    module = rosbag.bag
    saved = module._get_message_type
    by_type = {(cls._type, cls._md5sum): cls for cls in classes}

    def known(info: Any) -> Any:
        cls = by_type.get((info.datatype, info.md5sum))
        if cls is not None:
            return cls
        raise UncompiledTypeError(f"{info.datatype} (MD5 sum {info.md5sum})")

    module._get_message_type = known
    try:
        yield
    finally:
        module._get_message_type = saved


def message_class(msg_type: str) -> Any:
    """Debian's compiled genpy class of ``pkg/Type``."""
    package, _, name = msg_type.partition("/")
    try:
        return getattr(env.import_module(f"{package}.msg"), name)
    except (ImportError, AttributeError):
        raise BagError(f"no ROS message class for {msg_type} in Debian's packages") from None


def to_data(message: Any) -> Any:
    """A genpy message as the engine's plain data (dicts, lists, numbers, strings)."""
    if hasattr(message, "__slots__") and hasattr(message, "_slot_types"):
        return {name: to_data(getattr(message, name)) for name in message.__slots__}
    if hasattr(message, "secs") and hasattr(message, "nsecs"):  # time, duration
        return {"secs": int(message.secs), "nsecs": int(message.nsecs)}
    if isinstance(message, bytes):  # uint8[] / char[]
        return list(message)
    if isinstance(message, list | tuple):
        return [to_data(item) for item in message]
    return message


def from_data(cls: Any, data: Any) -> Any:
    """The genpy message of class ``cls`` with the engine's plain data ``data``."""
    message = cls()
    for name, kind in zip(cls.__slots__, cls._slot_types, strict=True):
        value = data[name]
        current = getattr(message, name)
        base = kind.split("[", 1)[0]
        if kind in ("time", "duration"):
            current.secs, current.nsecs = int(value["secs"]), int(value["nsecs"])
        elif hasattr(current, "_slot_types"):
            setattr(message, name, from_data(type(current), value))
        elif kind.endswith("]") and base in ("uint8", "char"):
            setattr(message, name, bytes(value))
        elif kind.endswith("]") and "/" in base:
            item = message_class(base)
            setattr(message, name, [from_data(item, v) for v in value])
        else:
            setattr(message, name, value)
    return message


Chooser = Callable[[Sequence[tuple[str, str]]], Callable[[str, str], bool]]
"""Given a bag's connections, (topic, type) each, the filter of the ones to read."""


def iter_messages(
    path: Path, msg_types: Sequence[str], held: list[str], choose: Chooser | None = None
) -> Iterator[tuple[str, str, Any]]:
    """(topic, type, plain data) of each message of one of ``msg_types`` in a bag, in the bag's
    order, read with Debian's compiled classes only; ``held`` gets what the bag holds
    ("type on topic"), for messages. ``choose``: a filter of connections, made from the bag's
    index before a message is read (a scenario bag's step topics, else its recorded states: a
    PoseArray of 18,000 poses on another topic took 117 s of reading for nothing). Messages
    larger than a test case may be are skipped unread.

    Raises
    ------
    BagError
        The file is not a readable bag (or a chunk or record of it is refused).
    """
    rosbag = env.import_module("rosbag")
    classes = [message_class(name) for name in msg_types]
    for cls in classes:
        rosbag.bag._message_types[cls._md5sum] = cls  # never compile the bag's own definition
    wanted_types = {(cls._type, cls._md5sum) for cls in classes}

    accept: Callable[[str, str], bool] = lambda topic, datatype: True  # noqa: E731

    def wanted(topic: str, datatype: str, md5sum: str, msg_def: str, header: Any) -> bool:
        return (datatype, md5sum) in wanted_types and accept(topic, datatype)

    try:
        with (
            bounded_chunks(rosbag, MAX_CHUNK_BYTES),
            known_types_only(rosbag, classes),
            rosbag.Bag(str(path), "r") as bag,
        ):
            connections = [(str(c.topic), str(c.datatype)) for c in bag._connections.values()]
            held.extend(
                sorted({reporting.shown(f"{datatype} on {topic}") for topic, datatype in connections})
            )
            if choose is not None:
                accept = choose(connections)
            largest = max((h.uncompressed_size for h in bag._chunk_headers.values()), default=0)
            if largest > MAX_CHUNK_BYTES:  # as declared (one that lies stops in bounded_chunks)
                raise BagError(
                    f"--seeds-from-bag {path}: a chunk of {largest} bytes uncompressed "
                    f"(at most {MAX_CHUNK_BYTES} are read)"
                )
            for topic, raw, _t in bag.read_messages(connection_filter=wanted, raw=True):
                if len(raw[1]) > MAX_BYTES:  # its test case could not be larger than this
                    continue  # 3 x 10**7 joint positions made seeds of 120 MB each
                message = raw[4]()  # the class known_types_only answered for the record
                message.deserialize(raw[1])
                yield topic, message._type, to_data(message)
    except BagError:
        raise
    except UncompiledTypeError as exc:
        raise BagError(
            f"--seeds-from-bag {path}: a message record of type {exc}, whose definition would "
            f"have to be compiled from the bag (a record that contradicts the bag's index); not read"
        ) from None
    except ChunkTooLargeError:
        raise BagError(
            f"--seeds-from-bag {path}: a chunk decompresses past {MAX_CHUNK_BYTES} bytes "
            "(more than its header declares: at most that many are read)"
        ) from None
    except Exception as exc:  # noqa: BLE001 - rosbag, genpy, struct, bz2/lz4: all mean "not readable"
        raise BagError(f"--seeds-from-bag {path}: not a readable bag: {type(exc).__name__}: {exc}") from None


def read_seeds(
    path: Path, msg_type: str, validate: Any, joints: Sequence[str] | None = None
) -> list[dict[str, Any]]:
    """The ``msg_type`` messages of a bag (any topic), as seeds; the invalid ones are skipped.
    With ``joints`` (the chain's), a ``sensor_msgs/JointState`` is taken as a recorded state
    (:func:`recorded_state`).

    Raises
    ------
    BagError
        The file is not a readable bag, or holds no valid message of that type.
    """
    out: list[dict[str, Any]] = []
    held: list[str] = []
    for _topic, _type, data in iter_messages(path, [msg_type], held):
        if joints is not None and msg_type == JOINT_STATE:
            data = recorded_state(data, joints)
        try:
            validate(data)
        except ValueError:
            continue
        out.append(data)
        if len(out) >= MAX_SEEDS:
            break
    if not out:
        raise BagError(
            f"--seeds-from-bag {path}: no valid {msg_type} message (the bag holds: {holdings(held)})"
        )
    return out


def holdings(held: Sequence[str], shown: int = 20) -> str:
    """What a bag holds, for a message: the first ``shown`` connections and their count (a bag of
    50,000 topics made an error message of 1.4 MB)."""
    if not held:
        return "no messages"
    more = f", ... ({len(held)} in all)" if len(held) > shown else ""
    return ", ".join(held[:shown]) + more


def recorded_state(data: dict[str, Any], joints: Sequence[str]) -> dict[str, Any]:
    """A recorded ``sensor_msgs/JointState`` as the configuration the robot was in: when its
    names hold every joint of the chain, its positions in the chain's order under the chain's
    names (other joints, a gripper's, left out); without the velocities and efforts a robot
    publishes (a ``move`` would take their first values as scaling factors, most often 0, and
    test only its rejection). Its positions stay as they are when it names no joint (already
    in the chain's order) or not every one (a state both targets must refuse alike)."""
    out = {**data, "velocity": [], "effort": []}
    names, positions = data.get("name", []), data.get("position", [])
    if names and len(names) == len(positions) and set(joints) <= set(names) and len(set(names)) == len(names):
        where = {name: i for i, name in enumerate(names)}
        out["name"] = list(joints)
        out["position"] = [positions[where[joint]] for joint in joints]
    return out


def pose_stamped(values: dict[str, Any], frame: str) -> Any:
    geometry_msgs = env.import_module("geometry_msgs.msg")
    pose = geometry_msgs.PoseStamped()
    pose.header.frame_id = frame
    pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = values["position"]
    o = pose.pose.orientation
    o.x, o.y, o.z, o.w = values["orientation"]
    return pose


def export_bag(crash: Path, output: Path, trust: bool = False, robot: str | None = None) -> list[str]:
    """Write a divergence as a bag: its input, and each target's final joint state and pose.

    Topics: the input on ``TOPICS[msg_type]`` (``/joint_states`` for a JointState);
    per target ``k`` (0, 1), when its outcome has them,
    ``/rrosfuzz/target_k/joint_states`` (``sensor_msgs/JointState``) and
    ``/rrosfuzz/target_k/pose`` (``geometry_msgs/PoseStamped`` in the root link's
    frame). A scenario: its steps on ``/rrosfuzz/scenario/<step>``, one second apart, and
    each target's state after each step at the step's time (``fuzzer.ros.scenario_bags``).
    ``robot``: ``--robot``, the campaign's robot file given again (its SHA-256 checked).
    Returns the topics written.

    Raises
    ------
    BagError
        The crash file or its sidecar cannot be used, or the bag cannot be written.
    """
    from fuzzer.artifacts.sidecar import read_sidecar
    from fuzzer.artifacts.trust import sidecar_model
    from fuzzer.input.testcase import read_case

    try:
        case = read_case(crash)
    except (OSError, ValueError) as exc:
        raise BagError(f"{crash}: not a crash file: {exc}") from None
    sidecar = read_sidecar(crash) or {}
    config = sidecar.get("config", {})
    rosbag = env.import_module("rosbag")
    rospy = env.import_module("rospy")
    sensor_msgs = env.import_module("sensor_msgs.msg")
    _, model = sidecar_model(config, crash, trust, robot, sidecar.get("robot_sha256"))
    header = case.message.get("header")  # a header of 5 was an AttributeError's traceback
    stamp = header.get("stamp", {}) if isinstance(header, dict) else {}
    secs = stamp.get("secs", 0) if isinstance(stamp, dict) else 0
    start = rospy.Time(secs if isinstance(secs, int) and 0 < secs < 2**32 else 1, 0)
    records: list[tuple[str, Any, Any]] = []
    if case.msg_type != MSG_TYPE and case.msg_type not in TOPICS:  # it wrote the sidecar's states
        raise BagError(
            f"{crash}: its message type {case.msg_type!r} is none a campaign fuzzes "
            f"({', '.join([*TOPICS, MSG_TYPE])}); replay says what it is"
        )
    if case.msg_type == MSG_TYPE:
        from fuzzer.ros.scenario_bags import export_records

        records = export_records(crash, case.message, sidecar, model, start)
    elif case.msg_type in TOPICS:
        try:
            message = from_data(message_class(case.msg_type), case.message)
        except (LookupError, TypeError, ValueError, AttributeError) as exc:
            raise BagError(
                f"{crash}: its message is not a {case.msg_type}: {type(exc).__name__}: {exc}"
            ) from None
        records.append((TOPICS[case.msg_type], message, start))
    for k, outcome in enumerate(sidecar.get("outcomes", [])[:2] if case.msg_type != MSG_TYPE else []):
        values = outcome.get("values", {}) if isinstance(outcome, dict) else {}
        joints = values.get("joint_values")
        if isinstance(joints, list) and len(joints) == model.dof:
            state = sensor_msgs.JointState()
            state.header.stamp = start
            state.name, state.position = list(model.joint_names), [float(v) for v in joints]
            records.append((f"/rrosfuzz/target_{k}/joint_states", state, start))
        if len(values.get("position", [])) == 3 and len(values.get("orientation", [])) == 4:
            pose = pose_stamped(values, model.root_link)
            pose.header.stamp = start
            records.append((f"/rrosfuzz/target_{k}/pose", pose, start))
    if not records:
        raise BagError(f"{crash}: nothing to export ({case.msg_type}, no outcome values in its sidecar)")
    _check_output(output, crash)
    # written beside it and renamed over it once whole: a failure leaves an existing file as it
    # was, and a symlink planted at the name is replaced, never followed
    try:
        handle, name = tempfile.mkstemp(prefix=f".{output.name}.", suffix=".tmp", dir=output.parent)
    except OSError as exc:  # exit 74, as every output that cannot be written (it was 2)
        raise FolderUnwritable(f"{output}: cannot write the bag: {exc.strerror or exc}") from None
    os.close(handle)
    try:
        with rosbag.Bag(name, "w") as bag:
            for topic, message, when in records:
                bag.write(topic, message, when)
        os.chmod(name, 0o666 & ~_umask())  # mkstemp's 0600 kept another user's rosbag play out
        os.replace(name, output)
    except OSError as exc:  # a full disk
        Path(name).unlink(missing_ok=True)
        raise FolderUnwritable(f"{output}: cannot write the bag: {exc.strerror or exc}") from None
    except Exception as exc:  # noqa: BLE001 - genpy's serialization errors name the field
        Path(name).unlink(missing_ok=True)
        raise BagError(f"{output}: cannot write the bag: {type(exc).__name__}: {exc}") from None
    return list(dict.fromkeys(topic for topic, _, _ in records))


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _check_output(output: Path, crash: Path) -> None:
    """Raise BagError when ``output`` may not receive the bag (``paths.check_output_file``)."""
    try:
        check_output_file(output, crash, "-o")
    except PathError as exc:
        raise BagError(str(exc)) from None


def export_bag_main(argv: Sequence[str]) -> int:
    """``fuzz_diff.py export-bag CRASH [-o OUT.bag]``."""
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py export-bag",
        description="write a divergence as a bag for `rosbag play` (ROS 1 from apt: scripts/ros-ensure.sh)",
    )
    parser.add_argument("crash", type=given_path)
    parser.add_argument("-o", "--output", type=given_path, help="the bag to write (default: CRASH.bag)")
    campaign_robot_option(parser)
    trust_option(parser, overrides=False)
    args = parser.parse_args(argv)
    problem = file_problem(args.crash)
    if problem is not None:  # a FIFO said "no such file"
        raise BagError(f"{args.crash}: {problem}")
    try:
        env.require()
    except env.RosUnavailableError as exc:
        raise BagError(str(exc)) from None
    output = args.output or args.crash.with_name(args.crash.name + ".bag")
    topics = export_bag(args.crash, output, args.trust_sidecar, args.robot)
    # a file name is shown escaped (a line break in it printed a line of its own) and quoted
    reporting.out(reporting.bounded(reporting.shown(f"wrote {output}: {', '.join(topics)}")))
    reporting.out(reporting.shown(f"play it: rosbag play {shlex.quote(str(output))}"))
    return 0
