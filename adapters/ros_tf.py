"""The robot_api contract's forward kinematics through ROS: robot_state_publisher + tf2.

Use it as ``--targets native,ros_tf`` (or ``adapters.ros_tf:api``). FK only:
``inverse_kinematics`` raises the contract's ``UNSUPPORTED_OPERATION``. Needs
ROS 1 from apt (``scripts/ros-ensure.sh``); without it the constructor raises
:class:`~fuzzer.ros.env.RosUnavailableError` naming that command.

How one FK call runs
--------------------

1. On the first model of a URDF (per process), the URDF text goes to the
   parameter server as ``/rrosfuzz_tf/p<pid>_<n>/robot_description`` and
   Debian's ``robot_state_publisher`` node (``ros-robot-state-publisher``
   1.15, default parameters: ``publish_frequency`` 50 Hz, ``ignore_timestamp``
   false) starts in that namespace, its ``/tf`` and ``/tf_static`` remapped to
   the namespace's ``tf``/``tf_static`` so that several publishers never mix.
   The master is this process's (``fuzzer.ros.node``): started on a free
   loopback port, or joined through ``ROS_MASTER_URI``.
2. A call publishes a ``sensor_msgs/JointState`` on the namespace's
   ``joint_states``: ``name`` = the contract's variables (``joint_names``,
   mimic joints excluded: robot_state_publisher computes them from their
   ``<mimic>``), ``position`` = the values, ``header.stamp`` = a new stamp,
   ``STAMP_STEP`` after the previous one (robot_state_publisher drops a
   JointState whose stamp is less than ``1/publish_frequency`` after the last
   one it published for those joints).
3. robot_state_publisher computes each moving joint's transform (KDL
   ``Segment::pose(q)``, ``tf2::kdlToTransform``) and publishes them on ``tf``
   with that stamp; the fixed joints' transforms were published once on
   ``tf_static``. This process feeds both topics into a ``tf2_ros.Buffer``
   (what ``tf2_ros.TransformListener`` does, on the namespaced topics) and
   answers with ``lookup_transform_core(root_link, link, stamp)``: tf2 composes
   the transforms along the tree.

The pose's quaternion is normalized and given the contract's sign (``w >= 0``;
at ``w == 0`` the first non-zero of ``x, y, z`` positive); nothing else is
converted. Chain, variables, limits, home and argument checks follow the
contract through ``python_impl`` (as the other adapters). A transform that
does not arrive within ``LOOKUP_TIMEOUT`` seconds is a :class:`TimeoutError`
(a crash of the target for the engine), with tf2's own explanation.
"""

from __future__ import annotations

import itertools
import math
import os
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from adapters._common import LibraryModel, make_api, urdf_bytes
from robot_api.errors import ErrorCode, InvalidInputError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, Pose

__all__ = ["MoveGroup", "RobotModel", "api"]

STAMP_STEP = 0.05
"""Seconds between two JointState stamps (more than robot_state_publisher's 1/50 Hz)."""

LOOKUP_TIMEOUT = 5.0
"""Seconds a transform may take to come back (a loaded machine delays the nodes)."""

START_TIMEOUT = 30.0
"""Seconds robot_state_publisher may take to start and connect."""

_counter = itertools.count()
_publishers: dict[bytes, StatePublisher] = {}
_publishers_lock = threading.Lock()


def canonical_quaternion(x: float, y: float, z: float, w: float) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) with the contract's sign."""
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    if w < 0.0 or (w == 0.0 and next((c for c in (x, y, z) if c != 0.0), 0.0) < 0.0):
        x, y, z, w = -x, -y, -z, -w
    return (x + 0.0, y + 0.0, z + 0.0, w + 0.0)


@dataclass
class StatePublisher:
    """One robot_state_publisher node for one URDF, and this process's tf2 buffer of it."""

    namespace: str
    urdf: str
    process: Any = None
    buffer: Any = None
    publisher: Any = None
    subscribers: list[Any] = field(default_factory=list)
    stamp: Any = None
    changed: threading.Condition = field(default_factory=threading.Condition)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def start(self) -> None:
        """Put the URDF on the parameter server, start the node, connect the topics."""
        from fuzzer.ros import env, node, processes

        ros = node.context()
        rospy = ros.rospy
        tf2_ros = env.import_module("tf2_ros")
        tf2_msgs = env.import_module("tf2_msgs.msg")
        sensor_msgs = env.import_module("sensor_msgs.msg")
        ns = self.namespace
        ros.set_param(f"{ns}/robot_description", self.urdf)
        self.buffer = tf2_ros.Buffer(cache_time=rospy.Duration(30.0), debug=False)
        self.subscribers = [
            rospy.Subscriber(
                f"{ns}/tf", tf2_msgs.TFMessage, self._on_tf, callback_args=False, queue_size=100
            ),
            rospy.Subscriber(
                f"{ns}/tf_static", tf2_msgs.TFMessage, self._on_tf, callback_args=True, queue_size=100
            ),
        ]
        self.publisher = rospy.Publisher(f"{ns}/joint_states", sensor_msgs.JointState, queue_size=100)
        self.process = processes.spawn(
            f"robot_state_publisher{ns.replace('/', '_')}",
            [
                str(env.RSP_EXECUTABLE),
                f"__name:=robot_state_publisher_{ns.rsplit('/', 1)[-1]}",
                f"__ns:={ns}",
                f"/tf:={ns}/tf",
                f"/tf_static:={ns}/tf_static",
            ],
            ros.environment,
            ros.master.log_dir,
        )
        deadline = time.monotonic() + START_TIMEOUT
        while time.monotonic() < deadline:
            if not self.process.alive():
                raise RuntimeError(f"robot_state_publisher exited at start:\n{self.process.log_tail()}")
            if self.publisher.get_num_connections() > 0 and all(
                s.get_num_connections() > 0 for s in self.subscribers
            ):
                break
            time.sleep(0.02)
        else:
            self.close()
            raise TimeoutError(f"robot_state_publisher did not connect in {START_TIMEOUT} s")
        self.stamp = rospy.Time.now()

    def _on_tf(self, message: Any, static: bool) -> None:
        who = message._connection_header.get("callerid", "default_authority")
        with self.changed:
            for transform in message.transforms:
                if static:
                    self.buffer.set_transform_static(transform, who)
                else:
                    self.buffer.set_transform(transform, who)
            self.changed.notify_all()

    def lookup(self, names: tuple[str, ...], values: list[float], root: str, link: str) -> Any:
        """Publish a JointState, then look the link's transform up at its stamp."""
        from fuzzer.ros import env

        rospy = env.import_module("rospy")
        sensor_msgs = env.import_module("sensor_msgs.msg")
        with self.lock:  # one call at a time per publisher: stamps stay ordered
            if not self.process.alive():
                raise RuntimeError(f"robot_state_publisher died:\n{self.process.log_tail()}")
            self.stamp = self.stamp + rospy.Duration(STAMP_STEP)
            stamp = self.stamp
            message = sensor_msgs.JointState()
            message.header.stamp = stamp
            message.name = list(names)
            message.position = [float(v) for v in values]
            deadline = time.monotonic() + LOOKUP_TIMEOUT
            with self.changed:
                self.publisher.publish(message)
                while True:
                    ok, why = self.buffer.can_transform_core(root, link, stamp)
                    remaining = deadline - time.monotonic()
                    if ok:
                        break
                    if remaining <= 0:
                        raise TimeoutError(
                            f"tf2: no transform {root} -> {link} at {stamp.to_sec():.3f} "
                            f"within {LOOKUP_TIMEOUT} s: {why}"
                        )
                    self.changed.wait(min(remaining, 0.5))
            return self.buffer.lookup_transform_core(root, link, stamp)

    def close(self) -> None:
        for subscriber in self.subscribers:
            subscriber.unregister()
        if self.publisher is not None:
            self.publisher.unregister()
        if self.process is not None:
            self.process.stop()


def state_publisher(urdf: str) -> StatePublisher:
    """The robot_state_publisher of this URDF text in this process, started on first use."""
    key = urdf.encode("utf-8")
    with _publishers_lock:
        found = _publishers.get(key)
        if found is not None and found.process is not None and found.process.alive():
            return found
        publisher = StatePublisher(f"/rrosfuzz_tf/p{os.getpid()}_{next(_counter)}", urdf)
        publisher.start()
        _publishers[key] = publisher
        return publisher


class RobotModel(LibraryModel):
    """A kinematic chain from URDF whose FK is robot_state_publisher's, looked up through tf2.

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF breaks the contract.
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    RosUnavailableError
        ROS 1 is not installed (``scripts/ros-ensure.sh`` installs it).
    """

    __slots__ = ("_publisher", "_urdf_text")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        self._urdf_text = urdf_bytes(urdf).decode("utf-8")
        self._publisher = state_publisher(self._urdf_text)

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values: robot_state_publisher, then tf2.

        A robot_state_publisher that died (during an earlier call, which then raised) is
        started again first."""
        if not self._publisher.process.alive():
            self._publisher.close()
            self._publisher = state_publisher(self._urdf_text)
        names = self.link_names
        t = self._publisher.lookup(self.joint_names, values, names[0], names[link]).transform
        p, q = t.translation, t.rotation
        return Pose((float(p.x), float(p.y), float(p.z)), canonical_quaternion(q.x, q.y, q.z, q.w))

    def _row_matrix(self, row: NDArray[np.float64], link: int) -> NDArray[np.float64]:
        """The library's transform of link index ``link`` for one row (batch FK)."""
        return self.pose_of(row.tolist(), link).matrix

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Not provided: robot_state_publisher and tf2 do forward kinematics only.

        Raises
        ------
        InvalidInputError
            Always, with ``UNSUPPORTED_OPERATION``.
        """
        raise InvalidInputError(
            "inverse_kinematics: the ros_tf target does forward kinematics only "
            "(robot_state_publisher + tf2)",
            ErrorCode.UNSUPPORTED_OPERATION,
        )


api = make_api(RobotModel, __name__)
api.OPS = ("fk",)  # what it answers (fuzzer.execution.session.answered_ops): IK is unsupported
api.BATCHED = False  # a batch is one tf2 round trip a row: no batched sweeps (session.batches)
"""The implementation object for ``--targets adapters.ros_tf:api`` (alias ``ros_tf``)."""
MoveGroup = api.MoveGroup
