"""A run configuration and everything built from it: targets, messages, evaluator.

Shared by campaigns and by replay, so a crash file replays under exactly the
configuration its sidecar records.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import platform
import subprocess
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from fuzzer.execution.records import Outcome
from fuzzer.execution.targets import Runner
from fuzzer.execution.tolerance import Tolerance
from fuzzer.input.mapping import DEFAULT_MSG_TYPE, RobotFacts, mapping_for
from fuzzer.input.msgdef import MessageRegistry
from fuzzer.scenario import steps as scenario_steps
from robot_api import robots
from robot_api.records import JointType

DEBIAN_PACKAGES = ("liborocos-kdl-dev", "liburdfdom-dev", "libeigen3-dev")


class ConfigError(ValueError):
    """A configuration that cannot run (the CLI reports it and exits with 2)."""


@dataclass(frozen=True)
class RunConfig:
    """What a campaign or a replay runs."""

    op: str = "move"
    robot: str = robots.DEFAULT_ROBOT
    tip_link: str | None = None
    targets: tuple[str, str] = ("native", "python")
    tolerance: Tolerance = field(default_factory=Tolerance)
    msg_type: str = ""
    msg_path: tuple[str, ...] = ()
    filtering: bool = True
    transport: str = "inprocess"
    """How targets run: ``inprocess``, or ``ros`` (each a ROS node: ``fuzzer.ros.transport``).
    Recorded in sidecars for information; a crash file replays in-process unless
    ``--transport ros`` is given."""
    max_steps: int = scenario_steps.MAX_STEPS
    """``--op scenario``: the most steps a test case may have (1..256)."""

    @property
    def message_type(self) -> str:
        return self.msg_type or DEFAULT_MSG_TYPE[self.op]

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["targets"] = list(self.targets)
        data["msg_path"] = list(self.msg_path)
        data["msg_type"] = self.message_type
        data["tolerance"] = {"m": self.tolerance.metres, "rad": self.tolerance.radians}
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunConfig:
        tol = data.get("tolerance", {})
        targets = tuple(data.get("targets", ("native", "python")))
        if len(targets) != 2:
            raise ConfigError(f"a sidecar names {len(targets)} targets, expected 2")
        return cls(
            op=data.get("op", "move"),
            robot=data.get("robot", robots.DEFAULT_ROBOT),
            tip_link=data.get("tip_link"),
            targets=(targets[0], targets[1]),
            tolerance=Tolerance(float(tol.get("m", 1e-6)), float(tol.get("rad", 1e-6))),
            msg_type=data.get("msg_type", ""),
            msg_path=tuple(data.get("msg_path", ())),
            filtering=bool(data.get("filtering", True)),
            max_steps=max_steps_of(data.get("max_steps", scenario_steps.MAX_STEPS)),
        )


def message_types(op: str, msg_type: str) -> list[str]:
    """The message types a configuration reads: the op's input type, or for a scenario its
    topics' types (a scenario is not a registry type)."""
    if op == "scenario":
        return sorted({t.msg_type for t in scenario_steps.TOPICS.values()})
    return [msg_type or DEFAULT_MSG_TYPE.get(op, "")]


def unread_msg_path(op: str, msg_type: str, msg_path: tuple[str, ...]) -> str | None:
    """Why the message folders ``msg_path`` cannot matter to a configuration, or None when
    they may: every type it reads, and every type those use, is a definition the project ships
    (``fuzzer/msgs``), which is searched first. So a folder is never read there, and a crash
    file need not name it (a relative one, recorded as typed, broke replay elsewhere)."""
    from fuzzer.input.msgdef import MsgError

    if not msg_path:
        return None
    types = message_types(op, msg_type)
    shipped = MessageRegistry(())
    try:
        for name in types:
            shipped.get(name)
    except (MsgError, ValueError):
        return None
    what = f"{types[0]} and every type it uses" if len(types) == 1 else "every type a scenario uses"
    return (
        f"--msg-path {', '.join(msg_path)}: not read: {what} are definitions the project ships "
        "(fuzzer/msgs), which are searched first; the folder is not recorded in crash files"
    )


def answered_ops(spec: str, op: str) -> None:
    """Refuse a target that declares the ops it answers (an ``OPS`` tuple beside its
    ``RobotModel``) when ``op`` is not one of them: ``ros_tf`` answers FK only, and each ``ik``
    input (or scenario step that solves IK) against it was a counted finding (26,111 in 20 s).

    Raises
    ------
    ConfigError
        Naming the target and the ops it answers.
    TargetError
        The target cannot be imported (``targets.load_target``).
    """
    from fuzzer.execution.targets import load_target

    ops = getattr(load_target(spec), "OPS", None)
    if isinstance(ops, tuple) and op not in ops:
        raise ConfigError(f"--targets: {spec!r} answers --op {', '.join(map(str, ops))} only, not --op {op}")


def batches(spec: str) -> bool:
    """Whether target ``spec`` computes ``forward_kinematics_batch`` at once, as the batched
    sweeps assume: a target may say it does not (``BATCHED = False`` beside its ``RobotModel``;
    ``ros_tf`` answers row by row through tf2, and its sweeps took 25.8 s of a 26-s campaign,
    which then ran past -max_total_time on its seeds alone)."""
    from fuzzer.execution.targets import TargetError, load_target

    try:
        return getattr(load_target(spec), "BATCHED", True) is not False
    except TargetError:
        return False


def max_steps_of(value: Any) -> int:
    """A recorded or given ``max_steps``, checked.

    Raises
    ------
    ConfigError
        Not an integer in 1..``MAX_STEPS_LIMIT`` (256).
    """
    limit = scenario_steps.MAX_STEPS_LIMIT
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= limit:
        raise ConfigError(f"max_steps must be an integer from 1 to {limit}, not {value!r}")
    return value


@dataclass
class Session:
    """Everything needed to evaluate test cases under one configuration."""

    config: RunConfig
    urdf: Path
    runners: tuple[Runner, Runner]
    registry: MessageRegistry

    @classmethod
    def open(cls, config: RunConfig) -> Session:
        from fuzzer.execution.targets import TargetError
        from fuzzer.input.msgdef import MsgError
        from robot_api.errors import RobotAPIError

        scenario = config.op == "scenario"
        if scenario and config.transport == "ros":
            raise ConfigError("--transport ros with --op scenario is not supported yet")
        if config.transport == "ros" and "ros_tf" in config.targets:
            raise ConfigError(
                "--targets ros_tf already answers through ROS (robot_state_publisher and tf2 on the "
                "campaign's master): use it with --transport inprocess (its node cannot run inside "
                "another target node)"
            )
        max_steps_of(config.max_steps)
        try:
            urdf = robots.resolve(config.robot)
        except RobotAPIError as exc:
            raise ConfigError(f"--robot: {exc}") from None
        try:
            mapping_for(config.op, config.message_type)
            registry = MessageRegistry(config.msg_path)
            for msg_type in message_types(config.op, config.message_type):
                registry.get(msg_type)
        except (ValueError, MsgError) as exc:
            raise ConfigError(f"--msg-type: {exc}") from None
        runners: list[Any] = []
        create: Any = Runner.create
        ros_failure: tuple[type[Exception], ...] = ()
        if config.transport == "ros":
            from fuzzer.ros import env as ros_env
            from fuzzer.ros.transport import NodeStartError, RosRunner

            create, ros_failure = RosRunner.create, (ros_env.RosUnavailableError, NodeStartError)
        for spec in config.targets:
            try:
                answered_ops(spec, config.op)
                runners.append(create(spec, urdf, config.tip_link))
            except ConfigError:
                raise
            except TargetError as exc:
                raise ConfigError(f"--targets: {exc}") from None
            except RuntimeError as exc:
                if isinstance(exc, ros_failure):
                    raise ConfigError(f"--transport ros: {exc}") from None
                raise ConfigError(
                    f"target {spec!r}: its RobotModel({urdf.name}) raised {type(exc).__name__}: {exc}"
                ) from None
            except RobotAPIError as exc:
                raise ConfigError(
                    f"target {spec!r} cannot load {urdf}: {type(exc).__name__}: {exc}"
                ) from None
            except Exception as exc:  # noqa: BLE001 - a broken target's constructor is a usage error
                raise ConfigError(
                    f"target {spec!r}: its RobotModel({urdf.name}) raised {type(exc).__name__}: {exc}"
                ) from None
        same_robot(runners[0], runners[1], urdf.name)
        return cls(config, urdf, (runners[0], runners[1]), registry)

    @property
    def reference(self) -> Any:
        """The first target's model (joint names and limits come from it)."""
        return self.runners[0].model

    @property
    def prismatic(self) -> tuple[bool, ...]:
        return tuple(lim.type == JointType.PRISMATIC for lim in self.reference.joint_limits)

    def validate(self, message: Any) -> None:
        """Check a test case's message for this configuration.

        Raises
        ------
        ValueError
            Naming the problem (for a scenario, the step index and topic).
        """
        if self.config.op == "scenario":
            scenario_steps.validate(message, self.registry, self.config.max_steps)
        else:
            self.registry.validate(self.config.message_type, message)

    def evaluator(self) -> Any:
        from fuzzer.execution.evaluate import Evaluator

        return Evaluator(
            op=self.config.op,
            runners=self.runners,
            mapping=mapping_for(self.config.op, self.config.message_type),
            tolerance=self.config.tolerance,
            validate=self.validate,
            filtering=self.config.filtering,
            prismatic=self.prismatic,
        )

    def facts(self) -> RobotFacts:
        model = self.reference

        def reachable(q: tuple[float, ...]) -> tuple[tuple[float, ...], tuple[float, ...]]:
            pose = model.forward_kinematics(list(q))
            return tuple(pose.position), tuple(pose.orientation)

        limits = model.joint_limits
        return RobotFacts(
            joint_names=tuple(model.joint_names),
            lower=tuple(lim.lower for lim in limits),
            upper=tuple(lim.upper for lim in limits),
            link_names=tuple(model.link_names),
            reachable=reachable,
        )

    def robot_digest(self) -> str:
        return hashlib.sha256(self.urdf.read_bytes()).hexdigest()


def same_robot(a: Any, b: Any, name: str) -> None:
    """Refuse two targets that read different joints or links from one URDF: every input would
    diverge for that reason alone (docs/api.md, "Known divergences": a tab, newline or carriage
    return written as such in a name is a space to the twin's expat and kept by urdfdom).

    Raises
    ------
    ConfigError
        Naming the first name that differs, as each target read it.
    """
    for what, noun in (("joint_names", "joint"), ("link_names", "link")):
        first, second = (getattr(getattr(r, "model", None), what, None) for r in (a, b))
        if first is None or second is None:
            continue  # a target that does not say (a ROS node's proxy): nothing to compare
        first, second = list(first), list(second)
        if first == second:
            continue
        at = next(
            (i for i, (x, y) in enumerate(zip(first, second, strict=False)) if x != y),
            min(len(first), len(second)),
        )
        shown = [repr(names[at]) if at < len(names) else "none" for names in (first, second)]
        raise ConfigError(
            f"the targets read different robots from {name}: {noun} {at} is {shown[0]} to {a.name} "
            f"and {shown[1]} to {b.name} ({len(first)} and {len(second)} {noun}s); every input would "
            "diverge for that alone (a tab, newline or carriage return written as such in a name is a "
            "space to an XML parser that normalizes attributes: write it as &#9;, &#10; or &#13;, or "
            "not at all)"
        )


def tip_hint(urdf: Path) -> str:
    """What a campaign on a chain without joints should do instead: the default tip rule stops
    at a tie (Baxter's two arms), and "0 divergences" of 69,143 executions that tested nothing
    read as a pass."""
    from python_impl.chain import deepest_links
    from python_impl.urdf import load_urdf

    try:
        links = deepest_links(load_urdf(str(urdf), True))
    except Exception:  # noqa: BLE001 - a hint only: the robot loaded already, as the targets read it
        links = []
    choose = f"; pass --tip-link {' or '.join(links)}" if links else ""
    return f"every input makes the same call, and nothing is tested{choose}"


@functools.cache
def versions() -> dict[str, str]:
    """Versions worth recording with an artifact, looked up once per process (about 14 ms:
    package metadata and ``dpkg-query``). A campaign asks when it writes its first sidecar,
    not at start-up, where it would delay the first input. Treat the dictionary as read-only:
    it is shared."""
    out = {"python": platform.python_version()}
    for dist in ("rrosfuzz", "numpy", "atheris", "hypothesis"):
        try:
            out[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            out[dist] = "not installed"
    try:
        listing = subprocess.run(
            ["dpkg-query", "-W", "-f", "${Package} ${Version}\n", *DEBIAN_PACKAGES],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        ).stdout
        for line in listing.splitlines():
            name, _, version = line.partition(" ")
            out[name] = version
    except (OSError, subprocess.SubprocessError):
        pass
    return out


def outcome_json(runner: Runner, outcome: Outcome) -> dict[str, Any]:
    return {"target": runner.name, **outcome.to_json()}
