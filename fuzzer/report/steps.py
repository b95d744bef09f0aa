"""Scenario steps as text (``--op scenario``): pure, shared by triage, replay and the report.

A scenario divergence is read as a list of steps, one line each: index, topic, a
short summary of the step's message, and each target's outcome label there; the
first divergent step (``Comparison.step``) is marked. Every string taken from a
file is made printable here (control characters escaped) and cut to a bounded
length; the HTML page escapes it again for markup.

This module imports nothing heavy (no numpy, no matplotlib), so ``triage`` stays fast.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from fuzzer.execution.records import Outcome
from fuzzer.reporting import shown

SCENARIO_TYPE = "rrosfuzz/Scenario"
ARGUMENT_CHARS = 72
"""An argument summary longer than this is cut (with ``...``)."""
LISTED_STEPS = 24
"""At most this many steps are listed in text (the first divergent step is always among them)."""
NOT_RUN = "-"
"""The label of a step a target did not run (an earlier step crashed)."""


@dataclass(frozen=True)
class StepLine:
    """One step of a scenario as people read it.

    Attributes
    ----------
    index : int
        0-based position in the scenario.
    topic : str
        The step's topic, e.g. ``/go`` (printable characters only).
    arguments : str
        A short summary of its message (at most ``ARGUMENT_CHARS`` characters).
    labels : tuple of str
        Each target's outcome label at this step (``Outcome.label``), ``-`` when not run.
    """

    index: int
    topic: str
    arguments: str
    labels: tuple[str, str]


@dataclass(frozen=True)
class ScenarioSteps:
    """The steps of a scenario divergence and where the targets first part ways."""

    steps: tuple[StepLine, ...]
    first: int | None
    """Index of the first divergent step (``Comparison.step``), None when unknown."""
    step_kind: str = ""
    field: str = ""
    targets: tuple[str, str] = ("a", "b")

    @property
    def divergent_step(self) -> StepLine | None:
        if self.first is None or not 0 <= self.first < len(self.steps):
            return None
        return self.steps[self.first]

    def headline(self) -> str:
        """``first divergent step 3 (/go, kind go): ok vs failed``."""
        step = self.divergent_step
        if step is None:
            where = "unknown" if self.first is None else f"{self.first} (beyond the {len(self.steps)} steps)"
            return f"first divergent step {where}"
        kind = f", kind {clean(self.step_kind)}" if self.step_kind else ""
        return f"first divergent step {step.index} ({step.topic}{kind}): {step.labels[0]} vs {step.labels[1]}"

    def lines(self, limit: int = LISTED_STEPS) -> list[str]:
        """The headline, then one line per step (``>`` marks the first divergent one)."""
        out = [self.headline(), f"{len(self.steps)} step(s) ({self.targets[0]} | {self.targets[1]}):"]
        width = max((len(s.topic) for s in self.steps), default=0)
        previous = -1
        for i in shown_steps(len(self.steps), self.first, limit):
            if i != previous + 1:
                out.append(f"      ... {i - previous - 1} step(s)")
            s = self.steps[i]
            mark = ">" if i == self.first else " "
            args = f"  {s.arguments}" if s.arguments else ""
            out.append(f"  {mark}{i:3d} {s.topic:<{width}}{args}  [{s.labels[0]} | {s.labels[1]}]")
            previous = i
        if previous + 1 < len(self.steps):
            out.append(f"      ... {len(self.steps) - previous - 1} more step(s)")
        return out

    def to_json(self) -> dict[str, Any]:
        return {
            "first_step": self.first,
            "step_kind": self.step_kind,
            "steps": [
                {"index": s.index, "topic": s.topic, "arguments": s.arguments, "outcomes": list(s.labels)}
                for s in self.steps
            ],
        }


def shown_steps(count: int, first: int | None, limit: int = LISTED_STEPS) -> list[int]:
    """The step indices to list when there are too many: the start, and the steps up to and
    just after the first divergent one."""
    if count <= limit:
        return list(range(count))
    if first is None or not 0 <= first < count or first + 2 < limit:
        return list(range(limit))
    head = limit // 4
    tail = list(range(max(head, first - (limit - head) + 3), min(count, first + 3)))
    return list(range(head)) + tail


def clean(text: str, limit: int = ARGUMENT_CHARS) -> str:
    """``text`` with control and other unprintable characters escaped, cut at ``limit``."""
    out = shown(text)
    return out if len(out) <= limit else out[: limit - 3] + "..."


def _num(value: Any) -> str:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return "?"
    return f"{value:.4g}" if math.isfinite(value) else str(float(value))


def _vec(values: Any, keys: Sequence[str] = ()) -> str:
    if isinstance(values, dict):
        values = [values.get(k) for k in keys]
    if not isinstance(values, list):
        return "?"
    return "(" + ", ".join(_num(v) for v in values) + ")"


def _frame(msg: dict[str, Any]) -> str:
    header = msg.get("header")
    frame = header.get("frame_id") if isinstance(header, dict) else None
    return f" link={json.dumps(frame)}" if isinstance(frame, str) and frame else ""


def arguments(msg: Any) -> str:
    """A short, printable summary of a step's message, by the shape of its ROS type."""
    if not isinstance(msg, dict):
        return clean(json.dumps(msg, default=str))
    pose = msg.get("pose")
    if isinstance(pose, dict):  # geometry_msgs/PoseStamped
        text = f"xyz={_vec(pose.get('position'), 'xyz')} q={_vec(pose.get('orientation'), 'xyzw')}"
        return clean(text + _frame(msg))
    if isinstance(msg.get("point"), dict):  # geometry_msgs/PointStamped
        return clean(f"xyz={_vec(msg['point'], 'xyz')}" + _frame(msg))
    poses = msg.get("poses")
    if isinstance(poses, list):  # geometry_msgs/PoseArray
        ends = [p.get("position") if isinstance(p, dict) else None for p in poses[:1] + poses[-1:]]
        path = " .. ".join(_vec(p, "xyz") for p in ends[: 1 if len(poses) == 1 else 2])
        return clean(f"{len(poses)} pose(s) {path}".rstrip())
    if "position" in msg and ("name" in msg or "velocity" in msg):  # sensor_msgs/JointState
        names = msg.get("name")
        prefix = f"name={json.dumps(names)} " if isinstance(names, list) and names else ""
        return clean(prefix + f"position={_vec(msg.get('position'))}")
    if set(msg) == {"data"}:  # std_msgs/String, Float64
        data = msg["data"]
        return clean(json.dumps(data) if isinstance(data, str) else _num(data))
    rest = {k: v for k, v in msg.items() if k != "header"}
    return clean(json.dumps(rest, default=str)) if rest else ""


def _step_topic(step: Any) -> tuple[str, Any]:
    """(topic, message) of a test case step ``{topic, msg}`` or a call step ``{kind, message}``."""
    if not isinstance(step, dict):
        return "?", step
    topic = step.get("topic")
    if not isinstance(topic, str):
        kind = step.get("kind")
        topic = f"/{kind}" if isinstance(kind, str) else "?"
    return clean(topic, 40), step.get("msg", step.get("message"))


def scenario_steps(
    raw_steps: Sequence[Any],
    outcomes: Sequence[Outcome | None],
    first: int | None,
    step_kind: str = "",
    field: str = "",
    targets: Sequence[str] = ("a", "b"),
) -> ScenarioSteps:
    """The step list of a scenario from its steps and the two targets' scenario outcomes.

    Parameters
    ----------
    raw_steps : sequence
        The test case's steps (``{"topic", "msg"}``) or the call's (``{"kind", "message"}``).
    outcomes : sequence of Outcome or None
        Each target's scenario outcome (its ``steps`` give the labels); None when unknown.
    first : int or None
        The first divergent step.
    """
    rows = []
    for i, step in enumerate(raw_steps):
        topic, msg = _step_topic(step)
        labels = []
        for outcome in (*outcomes, None, None)[:2]:
            steps = outcome.steps if outcome is not None else ()
            labels.append(clean(steps[i].label, 60) if i < len(steps) else NOT_RUN)
        rows.append(StepLine(i, topic, arguments(msg), (labels[0], labels[1])))
    names = [clean(str(t), 60) for t in targets][:2] + ["a", "b"][len(targets) :]
    return ScenarioSteps(tuple(rows), first, step_kind, field, (names[0], names[1]))


def scenario_of(sidecar: dict[str, Any] | None) -> ScenarioSteps | None:
    """The step list a scenario sidecar records, or None for any other sidecar."""
    if not isinstance(sidecar, dict):
        return None
    testcase, call = sidecar.get("testcase"), sidecar.get("call")
    raw: Any = None
    if isinstance(testcase, dict) and testcase.get("msg_type") == SCENARIO_TYPE:
        message = testcase.get("message")
        raw = message.get("steps") if isinstance(message, dict) else None
    if not isinstance(raw, list) and isinstance(call, dict) and call.get("kind") == "ScenarioCall":
        raw = call.get("steps")
    if not isinstance(raw, list):
        return None
    outcomes: list[Outcome | None] = []
    targets: list[str] = []
    for item in sidecar.get("outcomes") or []:
        try:
            outcomes.append(Outcome.from_json(item))
        except (KeyError, TypeError, ValueError, AttributeError):
            outcomes.append(None)
        targets.append(str(item.get("target", "?")) if isinstance(item, dict) else "?")
    comparison = sidecar.get("comparison") if isinstance(sidecar.get("comparison"), dict) else {}
    assert isinstance(comparison, dict)
    step, kind, field = comparison.get("step"), comparison.get("step_kind"), comparison.get("field")
    return scenario_steps(
        raw,
        outcomes,
        step if isinstance(step, int) and not isinstance(step, bool) else None,
        kind if isinstance(kind, str) else "",
        field if isinstance(field, str) else "",
        targets or ("a", "b"),
    )
