#!/usr/bin/env python3
"""A target of RROSFuzz as a ROS node (rospy): ``native``, ``python`` or any ``module:attribute``.

Started by the engine's ROS transport (``fuzzer/ros/transport.py``, which
documents the protocol), with the project's interpreter::

    python ros/target_node.py --spec python --urdf robot.urdf --name t1 [--tip-link LINK]

It answers each JSON request on ``/rrosfuzz/<name>/request`` with the outcome
of ``fuzzer.execution.targets.Runner.run`` on ``/rrosfuzz/<name>/response``. Requests are
data only (``call_from_json``); nothing in them is evaluated.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import sys
from contextlib import nullcontext
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fuzzer.execution.dead_zone import twin_with_kdl_dead_zone
from fuzzer.execution.records import Outcome, Status
from fuzzer.execution.targets import Runner
from fuzzer.input.mapping import CallError, call_from_json
from fuzzer.ros import env
from fuzzer.ros.protocol import decode, encode


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spec", required=True)
    parser.add_argument("--urdf", required=True)
    parser.add_argument("--name", required=True)
    parser.add_argument("--tip-link")
    parser.add_argument("--engine", help="the engine's node name: requests from other nodes are ignored")
    args = parser.parse_args(argv)
    rospy = env.import_module("rospy")
    std_msgs = env.import_module("std_msgs.msg")
    rospy.init_node(f"rrosfuzz_{args.name}", disable_signals=True, disable_rosout=True, log_level=rospy.WARN)
    topic = f"/rrosfuzz/{args.name}"
    ready = rospy.Publisher(f"{topic}/ready", std_msgs.String, queue_size=1, latch=True)
    response = rospy.Publisher(f"{topic}/response", std_msgs.String, queue_size=10)
    try:
        runner = Runner.create(args.spec, args.urdf, args.tip_link)
    except Exception as exc:  # noqa: BLE001 - reported to the engine, which names the target
        ready.publish(
            std_msgs.String(
                json.dumps({"pid": os.getpid(), "spec": args.spec, "error": f"{type(exc).__name__}: {exc}"})
            )
        )
        rospy.sleep(1.0)
        return 1
    requests: queue.Queue[Any] = queue.Queue()

    def take(message: Any) -> None:
        """A request of the engine's (the ROS graph may be shared: any node may publish here)."""
        header = getattr(message, "_connection_header", None) or {}
        if args.engine is None or header.get("callerid") == args.engine:
            requests.put(message)

    rospy.Subscriber(f"{topic}/request", std_msgs.String, take, queue_size=10)
    facts = {
        "pid": os.getpid(),
        "spec": args.spec,
        "joint_names": list(runner.model.joint_names),
        "error": "",
    }
    ready.publish(std_msgs.String(json.dumps(facts)))
    while not rospy.is_shutdown():
        try:
            message = requests.get(timeout=0.5)
        except queue.Empty:
            continue
        answer = handle(runner, message.data)
        if answer is not None:
            response.publish(std_msgs.String(encode(*answer)))
    return 0


def handle(runner: Runner, text: str) -> tuple[int, dict[str, Any]] | None:
    """The answer (id, payload) to one request (None without an id: nobody waits for it)."""
    try:
        request = decode(text)
        ident = request["id"]
    except ValueError:
        return None
    try:
        if request.get("op") == "ping":
            outcome = Outcome(Status.OK)
        elif request.get("op") == "fresh":
            fresh = runner.fresh()
            runner.model = fresh.model
            outcome = Outcome(Status.OK)
        else:
            call, seed = call_from_json(request.get("call"))
            with twin_with_kdl_dead_zone() if request.get("kdl_dead_zone") is True else nullcontext():
                outcome = runner.run(call, seed)
    except CallError as exc:
        outcome = Outcome(Status.CRASHED, "BadRequest", None, str(exc)[:500])
    except Exception as exc:  # noqa: BLE001 - the target's failure, reported as its outcome
        outcome = Outcome(Status.CRASHED, type(exc).__name__, None, str(exc)[:500])
    return ident, {"outcome": outcome.to_json()}


if __name__ == "__main__":
    sys.exit(main())
