"""``fuzz_diff.py view CRASH``: a divergence in RViz, one arm per target, overlaid.

It starts a master (on a free loopback port), two ``robot_state_publisher``
nodes (namespaces ``/target_0`` and ``/target_1``), publishes each target's
final joint state to its node, and starts RViz with ``ros/rviz/view.rviz``:
target 0 red, target 1 blue, in the shared frame ``rrosfuzz_view``.

Each node gets a *skeleton* URDF written here from the chain ``python_impl``
parsed (the crash's robot and tip): the same joints (origins, axes, types,
limits, mimic rules), every link and joint name prefixed with ``t0/`` or
``t1/`` (so the two trees never share a frame), and a coloured cylinder from
each link's origin to the next joint (the shipped robots have no visuals of
their own, and mesh paths would not resolve here). Nothing of the crash file's
robot is copied as XML text: names are escaped, numbers formatted.

Which joint state each target shows: its outcome's ``joint_values`` (``move``,
``ik``), else the call's joint values (``fk``; then both arms are the same and
the divergence is in the pose each target reported, drawn as an arrow per
target on ``/rrosfuzz/target_k/pose``).
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from fuzzer import reporting
from fuzzer.artifacts.store import atomic_write
from fuzzer.cli_options import campaign_robot_option, trust_option
from fuzzer.execution.session import ConfigError
from fuzzer.input.paths import check_output_file, file_problem, given_path
from fuzzer.ros import env, processes

ROOT = Path(__file__).resolve().parents[2]
RVIZ_CONFIG = ROOT / "ros" / "rviz" / "view.rviz"
FRAME = "rrosfuzz_view"
COLOURS = ("1 0.1 0.1 0.8", "0.1 0.3 1 0.8")
"""RGBA of target 0 (red) and target 1 (blue)."""
RADIUS = 0.02
MIN_PIXELS = 200
"""Pixels of each colour a screenshot needs to count an arm as drawn (an arm covers thousands)."""


def _num(value: float) -> str:
    return repr(float(value))


def _cylinder(xyz: tuple[float, float, float]) -> str:
    """A visual cylinder from the link's origin to ``xyz`` (empty for a zero offset)."""
    d = np.array(xyz, dtype=float)
    length = float(np.linalg.norm(d))
    if not math.isfinite(length) or length < 1e-9:
        return f'<visual><geometry><sphere radius="{RADIUS * 1.5}"/></geometry></visual>'
    u = d / length
    pitch = math.acos(max(-1.0, min(1.0, float(u[2]))))  # z axis onto u: yaw about z, then pitch
    yaw = math.atan2(float(u[1]), float(u[0]))
    mid = d / 2.0
    return (
        f'<visual><origin xyz="{_num(mid[0])} {_num(mid[1])} {_num(mid[2])}" '
        f'rpy="0 {_num(pitch)} {_num(yaw)}"/>'
        f'<geometry><cylinder radius="{RADIUS}" length="{_num(length)}"/></geometry></visual>'
    )


def skeleton_urdf(model: Any, tree: Any, prefix: str, colour: str) -> str:
    """The chain of ``model`` as a URDF of prefixed names with coloured cylinder visuals."""
    links = list(model.link_names)
    joints = [tree.parent_joint[link] for link in links[1:]]
    offsets: dict[str, list[tuple[float, float, float]]] = {link: [] for link in links}
    for joint in joints:
        offsets[joint.parent].append(joint.xyz)
    material = f'<material name={quoteattr(prefix + "colour")}><color rgba="{colour}"/></material>'
    parts = [f"<robot name={quoteattr(prefix + 'view')}>", material, f"<link name={quoteattr(FRAME)}/>"]
    for link in links:
        visuals = "".join(
            _cylinder(xyz).replace("</visual>", f"<material name={quoteattr(prefix + 'colour')}/></visual>")
            for xyz in offsets[link] or [(0.0, 0.0, 0.0)]
        )
        parts.append(f"<link name={quoteattr(prefix + link)}>{visuals}</link>")
    parts.append(
        f'<joint name={quoteattr(prefix + "view_root")} type="fixed"><parent link={quoteattr(FRAME)}/>'
        f"<child link={quoteattr(prefix + links[0])}/></joint>"
    )
    for j in joints:
        body = [
            f"<parent link={quoteattr(prefix + j.parent)}/><child link={quoteattr(prefix + j.child)}/>",
            f'<origin xyz="{" ".join(map(_num, j.xyz))}" rpy="{" ".join(map(_num, j.rpy))}"/>',
        ]
        if j.type != "fixed":
            body.append(f'<axis xyz="{" ".join(map(_num, j.axis))}"/>')
        if j.limits is not None:
            lim = j.limits
            body.append(
                f'<limit lower="{_num(lim.lower)}" upper="{_num(lim.upper)}" effort="{_num(lim.effort)}" '
                f'velocity="{_num(lim.velocity)}"/>'
            )
        if j.mimic is not None:
            body.append(
                f"<mimic joint={quoteattr(prefix + j.mimic.joint)} multiplier="
                f'"{_num(j.mimic.multiplier)}" offset="{_num(j.mimic.offset)}"/>'
            )
        parts.append(
            f"<joint name={quoteattr(prefix + j.name)} type={quoteattr(j.type)}>{''.join(body)}</joint>"
        )
    parts.append("</robot>")
    return "\n".join(parts)


def states_of(case: Any, sidecar: dict[str, Any], model: Any) -> list[list[float]]:
    """Each target's joint state to show (its outcome's joint values, else the call's)."""
    call = sidecar.get("call", {}) if isinstance(sidecar.get("call"), dict) else {}
    fallback = call.get("joint_values") or call.get("positions") or list(model.home_values)
    out = []
    for k in range(2):
        outcomes = sidecar.get("outcomes", [])
        values = outcomes[k].get("values", {}) if k < len(outcomes) and isinstance(outcomes[k], dict) else {}
        q = values.get("joint_values", fallback)
        if not (isinstance(q, list) and len(q) == model.dof and all(isinstance(v, int | float) for v in q)):
            q = list(model.home_values)
        out.append([float(v) if math.isfinite(v) else 0.0 for v in q])
    return out


def screenshot_ppm(display: str, path: Path) -> np.ndarray:
    """The X display's root window as an RGB array (ImageMagick's ``import``), also saved as ``path``."""
    import subprocess

    data = subprocess.run(
        ["import", "-display", display, "-window", "root", "-depth", "8", "ppm:-"],
        capture_output=True,
        timeout=60,
        check=True,
    ).stdout
    atomic_write(path, data, durable=False)  # written whole and renamed: a link there is replaced
    header: list[bytes] = []
    pos = 0
    while len(header) < 4:  # P6 width height maxval, whitespace separated, '#' comments
        while data[pos : pos + 1].isspace():
            pos += 1
        if data[pos : pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end : end + 1].isspace():
            end += 1
        header.append(data[pos:end])
        pos = end
    width, height = int(header[1]), int(header[2])
    return np.frombuffer(data[pos + 1 : pos + 1 + width * height * 3], dtype=np.uint8).reshape(
        height, width, 3
    )


def coloured_pixels(image: np.ndarray) -> tuple[int, int]:
    """Pixels clearly red and clearly blue in RViz's 3D view (the two arms; RViz shades them,
    the grid is grey). The 3D view is the bounding box of the background colour (40, 40, 40)."""
    background = np.all(image == 40, axis=2)
    rows, cols = np.nonzero(background)
    if rows.size:
        image = image[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]
    r, g, b = (image[..., i].astype(float) for i in range(3))
    red = int(np.count_nonzero((r > 90) & (r > 2 * g) & (r > 2 * b)))
    blue = int(np.count_nonzero((b > 90) & (b > 2 * r) & (b > 1.3 * g)))
    return red, blue


def start_xvfb(log_dir: str) -> tuple[str, processes.Process]:
    """Xvfb on the first free display from :90 (1200x800x24)."""
    for number in range(90, 190):
        if Path(f"/tmp/.X{number}-lock").exists() or Path(f"/tmp/.X11-unix/X{number}").exists():
            continue
        display = f":{number}"
        xvfb = processes.spawn(
            f"xvfb-{number}",
            ["Xvfb", display, "-screen", "0", "1200x800x24", "-nolisten", "tcp"],
            {},
            log_dir,
        )
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline and xvfb.alive():
            if Path(f"/tmp/.X11-unix/X{number}").exists():
                return display, xvfb
            time.sleep(0.05)
        xvfb.stop()
    raise ConfigError("view: no Xvfb display could be started (scripts/ros-ensure.sh --viz installs Xvfb)")


def load(crash: Path, trust: bool = False, robot: str | None = None) -> tuple[Any, dict[str, Any], Any, Any]:
    """The crash's test case, its sidecar, and the chain (model and parsed tree) it ran on
    (``robot``: ``--robot``, the campaign's file given again)."""
    from fuzzer.artifacts.sidecar import read_sidecar
    from fuzzer.artifacts.trust import sidecar_model
    from fuzzer.input.testcase import read_case
    from python_impl.urdf import load_urdf

    try:
        case = read_case(crash)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{crash}: not a crash file: {exc}") from None
    sidecar = read_sidecar(crash) or {}
    config = sidecar.get("config", {})
    urdf, model = sidecar_model(config, crash, trust, robot, sidecar.get("robot_sha256"))
    return case, sidecar, model, load_urdf(str(urdf), True)


def run_view(
    crash: Path, screenshot: Path | None, seconds: float, trust: bool = False, robot: str | None = None
) -> int:
    """Show ``crash`` in RViz until RViz closes. With ``screenshot``: under Xvfb, save the
    screen every second until both arms are drawn (``MIN_PIXELS`` of each colour) or
    ``seconds`` have passed; 0 if they are, 1 if not. ``trust``: ``--trust-sidecar``, the
    sidecar's robot read wherever it is; ``robot``: ``--robot``."""
    env.require()
    if shutil.which("rviz") is None or (screenshot is not None and shutil.which("Xvfb") is None):
        raise ConfigError(
            "view: RViz (and Xvfb for --screenshot) are not installed: scripts/ros-ensure.sh --viz"
        )
    case, sidecar, model, tree = load(crash, trust, robot)
    states = states_of(case, sidecar, model)
    log_dir = processes.log_folder(prefix="rrosfuzz-view-")
    try:
        display = os.environ.get("DISPLAY", "")
        if screenshot is not None:
            display, _xvfb = start_xvfb(log_dir)
        if not display:
            raise ConfigError(
                "view: no X display (DISPLAY is not set); use --screenshot FILE to run under Xvfb"
            )
        master = processes.start_master(log_dir)
        env.apply_environment(master.environment)
        rospy = env.import_module("rospy")
        sensor_msgs = env.import_module("sensor_msgs.msg")
        rospy.init_node("rrosfuzz_view", disable_signals=True, disable_rosout=True, log_level=rospy.WARN)
        publishers = []
        for k in range(2):
            prefix = f"t{k}/"
            rospy.set_param(f"/target_{k}/robot_description", skeleton_urdf(model, tree, prefix, COLOURS[k]))
            processes.spawn(
                f"robot_state_publisher_{k}",
                [str(env.RSP_EXECUTABLE), f"__ns:=/target_{k}"],
                master.environment,
                log_dir,
            )
            publishers.append(
                rospy.Publisher(f"/target_{k}/joint_states", sensor_msgs.JointState, queue_size=1)
            )
        poses = _pose_publishers(rospy, sidecar, model)
        stop = threading.Event()

        def publish() -> None:
            while not stop.is_set():
                now = rospy.Time.now()
                for k, publisher in enumerate(publishers):
                    message = sensor_msgs.JointState()
                    message.header.stamp = now
                    message.name = [f"t{k}/{name}" for name in model.joint_names]
                    message.position = states[k]
                    publisher.publish(message)
                for publisher, pose in poses:
                    pose.header.stamp = now
                    publisher.publish(pose)
                stop.wait(0.1)

        threading.Thread(target=publish, daemon=True).start()
        rviz = processes.spawn(
            "rviz", ["rviz", "-d", str(RVIZ_CONFIG)], {**master.environment, "DISPLAY": display}, log_dir
        )
        reporting.info(f"RViz on master {master.uri}: target 0 red, target 1 blue (logs in {log_dir})")
        if screenshot is None:
            rviz.popen.wait()
            stop.set()
            return 0
        deadline = time.monotonic() + seconds
        red = blue = 0
        while time.monotonic() < deadline and min(red, blue) < MIN_PIXELS:  # until both arms show
            time.sleep(1.0)
            if not rviz.alive():
                raise ConfigError(f"view: RViz exited:\n{rviz.log_tail()}")
            red, blue = coloured_pixels(screenshot_ppm(display, screenshot))
        stop.set()
        reporting.out(f"screenshot {screenshot}: {red} red and {blue} blue pixels")
        return 0 if min(red, blue) >= MIN_PIXELS else 1
    finally:
        processes.shutdown_all()


def _pose_publishers(rospy: Any, sidecar: dict[str, Any], model: Any) -> list[tuple[Any, Any]]:
    geometry_msgs = env.import_module("geometry_msgs.msg")
    out = []
    for k, outcome in enumerate(sidecar.get("outcomes", [])[:2]):
        values = outcome.get("values", {}) if isinstance(outcome, dict) else {}
        p, q = values.get("position", []), values.get("orientation", [])
        if (
            len(p) != 3
            or len(q) != 4
            or not all(isinstance(v, int | float) and math.isfinite(v) for v in p + q)
        ):
            continue
        pose = geometry_msgs.PoseStamped()
        pose.header.frame_id = f"t{k}/{model.root_link}"
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = p
        o = pose.pose.orientation
        o.x, o.y, o.z, o.w = q
        out.append(
            (rospy.Publisher(f"/rrosfuzz/target_{k}/pose", geometry_msgs.PoseStamped, queue_size=1), pose)
        )
    return out


def view_main(argv: Sequence[str]) -> int:
    """``fuzz_diff.py view CRASH [--screenshot PNG] [--seconds N]``."""
    parser = argparse.ArgumentParser(
        prog="fuzz_diff.py view",
        description="show a divergence in RViz, both targets' arms overlaid (scripts/ros-ensure.sh --viz)",
    )
    parser.add_argument("crash", type=given_path)
    parser.add_argument(
        "--screenshot",
        type=given_path,
        help="run under Xvfb, save the screen (PPM) to this file once both arms are drawn, and exit",
    )
    parser.add_argument(
        "--seconds", type=float, default=60.0, help="with --screenshot: the longest wait for both arms (60)"
    )
    campaign_robot_option(parser)
    trust_option(parser, overrides=False)
    args = parser.parse_args(argv)
    problem = file_problem(args.crash)
    if problem is not None:  # a FIFO said "no such file"
        raise ConfigError(f"{args.crash}: {problem}")
    if not (math.isfinite(args.seconds) and 0 < args.seconds <= 600):
        raise ConfigError("--seconds must be in (0, 600]")
    if args.screenshot is not None:  # before RViz starts, not after (a FIFO there blocked it)
        check_output_file(args.screenshot, args.crash, "--screenshot")
    return run_view(args.crash, args.screenshot, args.seconds, args.trust_sidecar, args.robot)
