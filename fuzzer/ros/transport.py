"""The ROS transport (``--transport ros``): every target runs as a ROS node.

The engine joins the master of ``ROS_MASTER_URI`` (when one answers) or starts
one on a free loopback port (``fuzzer.ros.node``), and starts each target as a
node (``ros/target_node.py``, rospy, any target spec). Protocol, per target
node ``/rrosfuzz/<name>``:

* ``/rrosfuzz/<name>/ready`` (``std_msgs/String``, latched): the node's JSON
  ``{"pid": int, "spec": str, "joint_names": [...], "error": str}`` once its
  model is built (``error`` non-empty: the constructor failed; the node exits);
* ``/rrosfuzz/<name>/request`` (``std_msgs/String``): the engine publishes one
  request per test case, ``"<n>\n<JSON>"`` with the JSON ``{"id": n, "op": "run",
  "call": call_to_json(call, ik_seed)}`` (with ``"kdl_dead_zone": true`` inside the oracle's
  KDL dead-zone re-run: the rospy node runs its twin with that dead zone, as the engine does
  in process; ``fuzzer.execution.dead_zone``), or ``{"id": n, "op": "fresh"}`` (rebuild
  the model), or ``{"id": n, "op": "ping"}`` (answered with an ``ok`` outcome: the
  engine's handshake after the ready message, repeated until answered);
* ``/rrosfuzz/<name>/response`` (``std_msgs/String``): the node answers
  ``"<n>\n{"id": n, "outcome": Outcome.to_json()}"``, the outcome of
  ``fuzzer.execution.targets.Runner.run``: the same records, oracle and artifacts as in
  process. A rejected call's outcome may carry the contract's code only (the C++
  node); the engine names its class (``robot_api.errors.error_class``).

The JSON is plain JSON (RFC 8259): a non-finite float travels as
``{"$float": "nan" | "inf" | "-inf"}``. Which node runs a target:
``native`` runs in the C++ node (``ros/cpp``, roscpp, linking ``native/src``
directly; built on first use into ``build/ros-cpp`` by CMake), every other spec
(``python``, ``module:attribute``) in the rospy node ``ros/target_node.py``.

The engine waits ``REQUEST_TIMEOUT`` seconds for the answer with the request's
id. A node that dies (a segfault, an abort, ``os._exit``) or does not answer in
time is an outcome ``crashed`` (``NodeDied`` with its exit status, or
``NodeTimeout``): the engine's usual crash handling saves the input as a crash
artifact; the node is stopped (its process group killed) and restarted before
the next call. Every node dies with the engine (``fuzzer.ros.processes``).
The robot facts the engine needs (joint names, limits, reachable poses for
seeds) come from an in-process ``python_impl`` model of the same URDF; every
test case runs over ROS.
"""

from __future__ import annotations

import fcntl
import itertools
import json
import os
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import python_impl
from fuzzer import reporting
from fuzzer.execution import dead_zone
from fuzzer.execution.records import Outcome, Status
from fuzzer.input.mapping import Call, call_to_json
from fuzzer.ros import env, node, processes
from fuzzer.ros.protocol import decode, encode, outcome_of

ROOT = Path(__file__).resolve().parents[2]
NODE_SCRIPT = ROOT / "ros" / "target_node.py"
CPP_SOURCE = ROOT / "ros" / "cpp"
CPP_BUILD = ROOT / "build" / "ros-cpp"
CPP_NODE = CPP_BUILD / "rrosfuzz_native_node"
REQUEST_TIMEOUT = 20.0
"""Seconds a node may take to answer one test case (libFuzzer's -timeout is 20 s too)."""
START_TIMEOUT = 60.0
"""Seconds a node may take to start (Python, numpy, the target's import, its model)."""
MASTER_CHECK_SECONDS = 1.0
"""While a node starts, how often the engine asks whether the master still answers: a node
cannot register without it, and a restart waited ``START_TIMEOUT`` (past libFuzzer's
``-timeout``: a timeout file and a thread dump, not the documented exit 2)."""
PING_SECONDS = 0.25
"""How long one handshake ping waits for its answer before the next one is sent."""

_names = itertools.count()


WAITS_PER_INPUT = 4
"""A node's answer is awaited at most libFuzzer's ``-timeout`` / this (s): a hang's wait, its
confirmation's on fresh targets, and the two nodes' restarts fit in one input's time."""


def fit_request_timeout(timeout: float) -> None:
    """Shorten ``REQUEST_TIMEOUT`` to fit libFuzzer's ``-timeout`` (s, > 0): a silent node is a
    ``crashed:NodeTimeout`` crash file only if its wait, and the confirming re-run's, end before
    it (at 20 s both, a hang was a timeout file without a sidecar and a thread dump, exit 70)."""
    global REQUEST_TIMEOUT
    REQUEST_TIMEOUT = min(REQUEST_TIMEOUT, timeout / WAITS_PER_INPUT)


class NodeStartError(RuntimeError):
    """A target node that could not start (the message has its log's tail)."""


def lost_reason(runners: Sequence[Any]) -> str | None:
    """Why a target's node died and could not be started again (its master gone, say), or None:
    the campaign stops after the input that found it (exit 2), that input's divergence recorded.
    Raised inside the input, it was lost (the confirming re-run met it: no crash file)."""
    for runner in runners:
        lost = getattr(getattr(runner, "node", None), "lost", None)
        if lost is not None:
            return str(lost)  # it names the target
    return None


def build_cpp_node() -> Path:
    """Build the C++ node (``ros/cpp``) into ``build/ros-cpp`` if needed; its path.

    Raises
    ------
    NodeStartError
        CMake failed (the message has the end of its output).
    """
    CPP_BUILD.mkdir(parents=True, exist_ok=True)
    with open(CPP_BUILD / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # -fork workers build it once
        steps = [
            ["cmake", "-S", str(CPP_SOURCE), "-B", str(CPP_BUILD)],
            ["cmake", "--build", str(CPP_BUILD), "-j2"],
        ]
        if (CPP_BUILD / "CMakeCache.txt").exists():
            steps = steps[1:]
        for step in steps:
            done = subprocess.run(step, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                tail = "\n".join((done.stdout + done.stderr).splitlines()[-15:])
                raise NodeStartError(
                    f"building the C++ node failed ({' '.join(step)}); {env.INSTALL_HINT}:\n{tail}"
                )
    return CPP_NODE


@dataclass
class TargetNode:
    """One target running as a ROS node, and the engine's side of its topics."""

    spec: str
    urdf: str
    tip_link: str | None
    name: str = field(default_factory=lambda: f"t{os.getpid()}_{next(_names)}")
    process: processes.Process | None = None
    restarts: int = 0
    _ids: itertools.count[int] = field(default_factory=itertools.count)
    _answers: dict[int, dict[str, Any]] = field(default_factory=dict)
    _ready: dict[str, Any] | None = None
    _changed: threading.Condition = field(default_factory=threading.Condition)
    _topics: list[Any] = field(default_factory=list)
    _pending: set[int] = field(default_factory=set)
    _foreign: dict[str, str] = field(default_factory=dict)
    """The first node of another name heard on each of this node's topics (``from_node``)."""
    _warned: set[str] = field(default_factory=set)
    lost: str | None = None
    """Why the node could not be started again after it died (``lost_reason``), else None."""

    @property
    def topic(self) -> str:
        return f"/rrosfuzz/{self.name}"

    @property
    def node_name(self) -> str:
        """The node's ROS name (``rospy.init_node``/``ros::init`` in ``ros/``)."""
        return f"/rrosfuzz_{self.name}"

    def _from_node(self, message: Any, topic: str) -> bool:
        """Whether a message on one of this node's topics was published by this node. The ROS
        graph may be shared: any node may publish there, and a well-formed answer of another
        was taken as the target's (its values in the crash files, the campaign's findings)."""
        header = getattr(message, "_connection_header", None) or {}
        caller = header.get("callerid") if isinstance(header, dict) else None
        if caller == self.node_name:
            return True
        with self._changed:
            self._foreign.setdefault(topic, str(caller))
        return False

    def _warn_foreign(self) -> None:
        """Say (once per topic, from the campaign's thread) that another node publishes here."""
        for topic, caller in list(self._foreign.items()):
            if topic not in self._warned:
                self._warned.add(topic)
                reporting.warn(
                    f"--transport ros: {caller} publishes on {self.topic}/{topic}, which is the target "
                    f"node {self.node_name}'s: its messages are ignored (the ROS graph is shared)"
                )

    def start(self) -> None:
        """Start the node and wait until it is ready and connected.

        Raises
        ------
        NodeStartError
            The node exited or did not become ready in ``START_TIMEOUT`` seconds.
        """
        ros = node.context()
        rospy = ros.rospy
        std_msgs = env.import_module("std_msgs.msg")
        if not self._topics:
            self._request = rospy.Publisher(f"{self.topic}/request", std_msgs.String, queue_size=10)
            self._topics = [
                self._request,
                rospy.Subscriber(f"{self.topic}/response", std_msgs.String, self._on_response, queue_size=10),
                rospy.Subscriber(f"{self.topic}/ready", std_msgs.String, self._on_ready, queue_size=1),
            ]
        with self._changed:
            self._ready = None
        engine = ["--engine", str(ros.name)]  # the node takes requests from this node only
        if self.spec == "native":
            argv = [str(build_cpp_node()), "--urdf", self.urdf, "--name", self.name, *engine]
        else:
            argv = [
                sys.executable,
                str(NODE_SCRIPT),
                "--spec",
                self.spec,
                "--urdf",
                self.urdf,
                "--name",
                self.name,
                *engine,
            ]
        if self.tip_link is not None:
            argv += ["--tip-link", self.tip_link]
        environment = {
            **ros.environment,
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
        }
        self.process = processes.spawn(f"target-{self.name}", argv, environment, ros.master.log_dir)
        deadline = time.monotonic() + START_TIMEOUT
        ready, master_gone = False, False
        next_check = time.monotonic() + MASTER_CHECK_SECONDS
        with self._changed:
            while not ready and self.process.alive() and time.monotonic() < deadline:
                if self._ready is not None and self._ready.get("error"):
                    break
                if time.monotonic() > next_check:  # a node cannot start without the master
                    next_check = time.monotonic() + MASTER_CHECK_SECONDS
                    if not processes.master_answers(ros.master.uri):
                        master_gone = True
                        break
                if self._ready is None or self._ready.get("pid") != self.process.pid:
                    self._changed.wait(0.05)
                    continue
                ready = self._ping()
            self._answers.clear()
            self._pending.clear()
        if self._ready is not None and self._ready.get("error"):
            self.process.stop()
            raise NodeStartError(f"target {self.spec!r} as a ROS node: {self._ready['error']}")
        if not ready:
            exited = not self.process.alive()
            status = self.process.popen.returncode if exited else None
            self.process.stop()
            why = (
                f"exited (status {status}) before it was ready"
                if exited
                else "could not register"
                if master_gone
                else f"did not start in {START_TIMEOUT} s"
            )
            master = ros.master.uri
            answers = not master_gone and processes.master_answers(master)
            gone = "" if answers else f"; the ROS master at {master} does not answer"
            raise NodeStartError(
                f"target {self.spec!r}: its ROS node {why}{gone}; log:\n{self.process.log_tail()}"
            )

    def _ping(self) -> bool:
        """One handshake: a ``ping`` request answered within ``PING_SECONDS`` (the node's
        subscription to the request topic is connected; a stale connection count is not proof)."""
        std_msgs = env.import_module("std_msgs.msg")
        ident = next(self._ids)
        self._pending.add(ident)
        self._request.publish(std_msgs.String(encode(ident, {"op": "ping"})))
        until = time.monotonic() + PING_SECONDS
        while ident not in self._answers and time.monotonic() < until:
            self._changed.wait(0.02)
        self._pending.discard(ident)
        return ident in self._answers

    def _on_ready(self, message: Any) -> None:
        if not self._from_node(message, "ready"):
            return
        try:
            ready = json.loads(message.data)
        except (TypeError, ValueError, RecursionError):
            return  # not the node's (it writes JSON): nothing to wait for
        if not isinstance(ready, dict):
            return
        with self._changed:
            self._ready = ready
            self._changed.notify_all()

    def _on_response(self, message: Any) -> None:
        if not self._from_node(message, "response"):
            return
        try:
            answer = decode(message.data)
            ident = answer["id"]
        except (TypeError, ValueError, RecursionError):
            return
        with self._changed:
            if ident in self._pending:  # an answer to nothing asked is no answer (nor kept)
                self._answers[ident] = answer
                self._changed.notify_all()

    def request(self, payload: dict[str, Any], again: bool = False) -> Outcome:
        """Send one request and wait for its answer; a dead or silent node is a crash outcome,
        and so is a node that could not be started again (``lost``: ``NodeLost``; the campaign
        stops after the input, ``lost_reason``). A node that exits with status 0 while it runs a
        request was shut down from outside (``rosnode kill``, another node taking its name: a
        crash file with exit 1 before): said, started again, and the request sent once more
        (``again``); a target that exits 0 twice is a crash outcome."""
        if self.process is None or not self.process.alive():
            if self.lost is None:
                self._restart_or_lose()
            if self.lost is not None:
                return Outcome(Status.CRASHED, "NodeLost", None, self.lost[:500])
        assert self.process is not None
        std_msgs = env.import_module("std_msgs.msg")
        ident = next(self._ids)
        deadline = time.monotonic() + REQUEST_TIMEOUT
        with self._changed:
            self._pending.add(ident)
            self._request.publish(std_msgs.String(encode(ident, payload)))
            while ident not in self._answers:
                if not self.process.alive():
                    status = self.process.popen.returncode
                    self._pending.discard(ident)
                    self._restart_or_lose()
                    if status == 0 and not again and self.lost is None:
                        reporting.warn(
                            f"--transport ros: the target node {self.node_name} exited with status 0 "
                            "during an input, as a node shut down from outside does (rosnode kill, or "
                            "another node taking its name); it was started again and the input sent again"
                        )
                        return self.request(payload, again=True)
                    return Outcome(
                        Status.CRASHED, "NodeDied", None, f"the target's ROS node died (status {status})"
                    )
                if time.monotonic() > deadline:
                    self._pending.discard(ident)
                    self._restart_or_lose()
                    return Outcome(
                        Status.CRASHED,
                        "NodeTimeout",
                        None,
                        f"no answer from the target's node in {REQUEST_TIMEOUT} s",
                    )
                self._changed.wait(0.05)
            self._pending.discard(ident)
            answer = self._answers.pop(ident)
        if self._foreign:
            self._warn_foreign()
        return outcome_of(answer)

    def _restart_or_lose(self) -> None:
        """Start the node again; if it cannot be, keep why (``lost``), so that the outcome of this
        request is returned (a restart that raised lost it: an uncaught ``NodeStartError``, exit 77
        "a target died", the divergence gone)."""
        try:
            self.restart()
        except NodeStartError as exc:
            self.lost = str(exc)

    def restart(self) -> None:
        """Stop the node (its whole process group) and start it again."""
        if self.process is not None:
            self.process.stop()
        self.restarts += 1
        with self._changed:
            self._answers.clear()
            self._pending.clear()
        self.start()

    def stop(self) -> None:
        if self.process is not None:
            self.process.stop()
        for topic in self._topics:
            topic.unregister()
        self._topics = []


@dataclass
class RosRunner:
    """A target that runs as a ROS node; the engine's ``Runner`` interface (``run``, ``fresh``)."""

    name: str
    node: TargetNode
    model: Any

    @classmethod
    def create(cls, spec: str, urdf: str | os.PathLike[str], tip_link: str | None) -> RosRunner:
        """Start ``spec`` as a node on ``urdf``; the facts come from a local ``python_impl`` model.

        Raises
        ------
        NodeStartError, RosUnavailableError
            The node or ROS could not start.
        """
        target = TargetNode(spec, str(urdf), tip_link)
        target.start()
        return cls(spec, target, python_impl.RobotModel(urdf, tip_link))

    @property
    def home(self) -> tuple[float, ...]:
        return tuple(self.model.home_values)

    @property
    def urdf(self) -> str:
        """The robot file the node runs on (as ``Runner.urdf``: the oracle's IK status check
        replays iterates on a twin model of it; without it, over ROS that check was skipped and
        a status split explained in process was counted)."""
        return self.node.urdf

    @property
    def tip_link(self) -> str | None:
        return self.node.tip_link

    def run(self, call: Call, ik_seed: tuple[float, ...] | None = None) -> Outcome:
        """Execute ``call`` in the node; never raises (failures become the outcome). Inside the
        oracle's KDL dead-zone re-run (``dead_zone.active``) the request asks the node to run
        its twin with that dead zone too (``kdl_dead_zone``)."""
        payload: dict[str, Any] = {"op": "run", "call": call_to_json(call, ik_seed)}
        if dead_zone.active():
            payload["kdl_dead_zone"] = True
        return self.node.request(payload)

    def fresh(self) -> RosRunner:
        """The node rebuilds its model (no state from earlier calls)."""
        outcome = self.node.request({"op": "fresh"})
        if outcome.status != Status.OK:
            raise RuntimeError(f"target {self.name!r}: rebuilding its model failed: {outcome.message}")
        return self
