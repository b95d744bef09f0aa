"""3D views of a bucket's representative: where each target left the arm (RVIZ's role).

The representative is re-run under its sidecar's configuration (sessions cached
per configuration). Each target's final joint values are then turned into the
positions of every link of its own model, root first, and drawn as two overlaid
polylines in one 3D axes with equal aspect:

* move: the target's final ``joint_values``, or its home when it rejected the
  call or has no values; the commanded configuration is drawn faintly when the
  call sets every joint;
* fk: the input joint values for both targets;
* ik: each target's returned ``joint_values`` (the last iterate when it found no
  solution), and the requested position as a star.
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import Axes3D

from fuzzer.artifacts.sidecar import SidecarError, validate_config
from fuzzer.artifacts.trust import config_from
from fuzzer.execution.evaluate import Verdict
from fuzzer.execution.records import Outcome, Status
from fuzzer.execution.session import Session
from fuzzer.execution.targets import Runner
from fuzzer.input.mapping import FkCall, IkCall, MoveCall
from fuzzer.input.testcase import TestCase, TestCaseError, from_json, read_case
from fuzzer.triage.pipeline import Bucket

COLORS = ("#1f5fbf", "#e8710a")
COMMAND_COLOR = "#7a7a7a"


@dataclass(frozen=True)
class Chain:
    """One configuration of one model, as the positions of its links (metres)."""

    label: str
    points: tuple[tuple[float, float, float], ...]
    joint_values: tuple[float, ...]
    note: str = ""


@dataclass(frozen=True)
class ArmScene:
    """Everything one 3D view shows."""

    chains: tuple[Chain, ...]
    joint_names: tuple[str, ...]
    commanded: Chain | None = None
    goal: tuple[float, float, float] | None = None
    rerun: str = ""
    """What the re-run gave, compared with the sidecar."""
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def tip_distance(self) -> float:
        """Distance between the two chains' last links (m)."""
        a, b = self.chains[0].points[-1], self.chains[1].points[-1]
        return math.dist(a, b)


class Sessions:
    """Sessions cached per configuration (a failure is cached as its message).

    A recorded configuration is untrusted (:mod:`fuzzer.artifacts.sidecar`): targets other than
    the builtins are imported only with ``trust``, robots only by shipped name or
    existing file.
    """

    def __init__(self, trust: bool = False, robots: Mapping[str, str] | None = None) -> None:
        self._cache: dict[str, Session | str] = {}
        self.trust = trust
        self.robots = dict(robots or {})
        """``--robot`` files by SHA-256: each replaces the robot of a sidecar that records its digest
        (a path relative to another working folder does not resolve here)."""

    def get(
        self, config: Mapping[str, Any], source: Path = Path("sidecar"), digest: object = None
    ) -> Session | str:
        given = {}
        if isinstance(digest, str) and digest.lower() in self.robots:  # the user's file: not checked
            given = {"robot": self.robots[digest.lower()]}  # against the folder, as --robot never is
        key = json.dumps([config, given], sort_keys=True, default=str)
        if key not in self._cache:
            try:
                validate_config(dict(config), source)
                recorded = config_from({"config": dict(config)}, source, given, self.trust)
                self._cache[key] = Session.open(recorded)
            except SidecarError as exc:
                self._cache[key] = str(exc)
            except Exception as exc:  # noqa: BLE001 - any failure becomes a note on the page
                self._cache[key] = f"{type(exc).__name__}: {exc}"
        return self._cache[key]


def chain(runner: Runner, values: Sequence[float], label: str, note: str = "") -> Chain:
    """Link positions of ``runner``'s model at ``values`` (raises on values it rejects)."""
    model = runner.model
    points = []
    for link in model.link_names:
        p = model.forward_kinematics(list(values), link).position
        points.append((float(p[0]), float(p[1]), float(p[2])))
    return Chain(label, tuple(points), tuple(float(v) for v in values), note)


def _safe_chain(runner: Runner, values: Sequence[float] | None, label: str, note: str) -> Chain:
    """The chain at ``values``, or at home (with a note) when there are none or FK rejects them."""
    if values is not None:
        try:
            return chain(runner, values, label, note)
        except Exception as exc:  # noqa: BLE001 - any target error: fall back to home
            note = f"cannot draw its values ({type(exc).__name__}): drawn at home"
    return chain(runner, runner.home, label, note or "no joint values: drawn at home")


def _final_values(call: Any, outcome: Outcome) -> tuple[tuple[float, ...] | None, str]:
    if isinstance(call, FkCall):
        return tuple(call.joint_values), "input joint values"
    values = outcome.values.get("joint_values")
    if outcome.status in (Status.REJECTED, Status.CRASHED) or not values:
        return None, f"{outcome.label}: drawn at home"
    if isinstance(call, IkCall) and outcome.status is Status.FAILED:
        return tuple(values), "no solution: last iterate"
    return tuple(values), ""


def _command(call: Any, joint_names: Sequence[str]) -> tuple[float, ...] | None:
    """The full joint command of a move call, in model order, or None."""
    if not isinstance(call, MoveCall) or len(call.positions) != len(joint_names):
        return None
    if call.names is None:
        return tuple(call.positions)
    if sorted(call.names) != sorted(joint_names) or len(set(call.names)) != len(call.names):
        return None
    given = dict(zip(call.names, call.positions, strict=True))
    return tuple(given[n] for n in joint_names)


def _test_case(bucket: Bucket) -> TestCase:
    try:
        return read_case(bucket.best)
    except (OSError, TestCaseError):
        assert bucket.sidecar is not None
        return from_json(bucket.sidecar.get("testcase"))


def scene(bucket: Bucket, sessions: Sessions) -> ArmScene | str:
    """The 3D view of a bucket's representative, or a note saying why there is none."""
    sidecar = bucket.sidecar
    if sidecar is None or not isinstance(sidecar.get("config"), dict):
        return "No sidecar: the configuration of this file is unknown, so it cannot be re-run here."
    digest = sidecar.get("robot_sha256")
    session = sessions.get(
        sidecar["config"], bucket.representative.with_name(bucket.representative.name + ".json"), digest
    )
    if isinstance(session, str):
        return f"Cannot re-run under the recorded configuration: {session}"
    notes = []
    try:
        if digest and session.robot_digest() != digest:
            notes.append(
                "The robot file changed since the campaign (SHA-256 differs): the view uses today's file."
            )
    except OSError:
        pass
    try:
        case = _test_case(bucket)
    except TestCaseError as exc:
        return f"The crash file is not a readable test case: {exc}"
    try:
        evaluation = session.evaluator().evaluate(case)
    except Exception as exc:  # noqa: BLE001 - a broken target must not break the report
        return f"Re-running failed: {type(exc).__name__}: {exc}"
    if evaluation.verdict != Verdict.EVALUATED or evaluation.call is None:
        return f"Re-running did not evaluate the test case ({evaluation.verdict}: {evaluation.reason})."
    call = evaluation.call
    a, b = evaluation.outcomes
    got = evaluation.signature.key if evaluation.signature else None
    rerun = f"re-run: {a.label} vs {b.label}; " + (
        "same signature as recorded"
        if got == bucket.key
        else ("the targets now agree" if got is None else f"a different signature ({got})")
    )
    try:
        chains = []
        for runner, outcome in zip(session.runners, evaluation.outcomes, strict=True):
            values, note = _final_values(call, outcome)
            chains.append(_safe_chain(runner, values, runner.name, note))
        reference = session.runners[0]
        names = tuple(reference.model.joint_names)
        command = _command(call, names)
        commanded = None
        if command is not None:
            commanded = _safe_chain(reference, command, "commanded target", "")
            if commanded.note:
                commanded = None
    except Exception as exc:  # noqa: BLE001 - a model that cannot do FK: say so, no picture
        return f"Cannot compute the arm's links: {type(exc).__name__}: {exc}"
    goal = tuple(float(x) for x in call.position) if isinstance(call, IkCall) else None
    point = (goal[0], goal[1], goal[2]) if goal and len(goal) == 3 else None
    if point is not None and not _on_scale(point, chains):
        notes.append(
            f"The requested position (IK), ({', '.join(f'{x:.4g}' for x in point)}) m, lies far off "
            "the arm: it is not drawn, so that the arm keeps its scale."
        )
        point = None
    return ArmScene(tuple(chains), names, commanded, point, rerun, tuple(notes))


GOAL_SCALE = 10.0
"""An IK goal is drawn when it lies within this many times the arm's reach from its base (a
fuzzed goal at -1.8e308 m made the picture's scale overflow, and the arm a dot)."""


def _on_scale(point: tuple[float, float, float], chains: Sequence[Chain]) -> bool:
    base = chains[0].points[0]
    reach = max((math.dist(base, p) for c in chains for p in c.points), default=0.0)
    distance = math.dist(base, point) if all(math.isfinite(x) for x in point) else math.inf
    return distance <= GOAL_SCALE * max(reach, 0.1)


def draw(view: ArmScene) -> bytes:
    """The 3D view as PNG bytes."""
    fig = Figure(figsize=(7.0, 7.0), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.02, 0.2, 0.92, 0.76), projection="3d")
    assert isinstance(ax, Axes3D)
    everything: list[tuple[float, float, float]] = []
    if view.commanded is not None:
        pts = np.array(view.commanded.points)
        ax.plot(
            pts[:, 0],
            pts[:, 1],
            pts[:, 2],
            color=COMMAND_COLOR,
            alpha=0.3,
            lw=14,
            ls="-",
            solid_capstyle="round",
            label="commanded target (wide, faint)",
        )
        everything += view.commanded.points
    styles = (("-", "o", 4.0, 9), ("--", "s", 2.2, 6))
    for i, item in enumerate(view.chains):
        pts = np.array(item.points)
        style, marker, width, size = styles[i % 2]
        label = item.label + (f" ({item.note})" if item.note else "")
        ax.plot(
            pts[:, 0],
            pts[:, 1],
            pts[:, 2],
            color=COLORS[i % 2],
            lw=width,
            ls=style,
            marker=marker,
            markersize=size,
            label=label,
        )
        ax.scatter(
            [pts[-1, 0]], [pts[-1, 1]], [pts[-1, 2]], color=COLORS[i % 2], s=90, marker="D", depthshade=False
        )
        everything += item.points
    if view.goal is not None:
        ax.scatter(
            [view.goal[0]],
            [view.goal[1]],
            [view.goal[2]],
            color="#c00000",
            marker="*",
            s=260,
            depthshade=False,
            label="requested position (IK)",
        )
        everything.append(view.goal)
    pts = np.array(everything)
    base = np.array(view.chains[0].points[0])
    ax.scatter(
        [base[0]],
        [base[1]],
        [base[2]],
        color="black",
        marker="^",
        s=80,
        depthshade=False,
        label="robot base (root link)",
    )
    center = (pts.max(axis=0) + pts.min(axis=0)) / 2
    half = max(float(np.max(pts.max(axis=0) - pts.min(axis=0))) / 2 * 1.1, 0.05)
    ax.set_xlim(center[0] - half, center[0] + half)
    ax.set_ylim(center[1] - half, center[1] + half)
    ax.set_zlim(center[2] - half, center[2] + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
    ax.set_xlabel("x (m)", fontsize=11)
    ax.set_ylabel("y (m)", fontsize=11)
    ax.set_zlabel("z (m)", fontsize=11)
    ax.view_init(elev=22, azim=-55)
    ax.tick_params(labelsize=9)
    ax.set_title(f"end links {view.tip_distance * 1000:.3g} mm apart", fontsize=12)
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", fontsize=10, frameon=False)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


@dataclass(frozen=True)
class ArmView:
    """What the page shows for one bucket: a picture, or none, and notes."""

    png: bytes | None
    notes: tuple[str, ...]


def render(bucket: Bucket, sessions: Sessions) -> ArmView:
    """Re-run and draw one bucket's representative; a note instead when that fails."""
    result = scene(bucket, sessions)
    if isinstance(result, str):
        return ArmView(None, (result,))
    try:
        png = draw(result)
    except Exception as exc:  # noqa: BLE001 - a drawing problem must not break the report
        return ArmView(None, (result.rerun, f"Drawing failed: {type(exc).__name__}: {exc}", *result.notes))
    return ArmView(
        png, (result.rerun, *(c.label + ": " + c.note for c in result.chains if c.note), *result.notes)
    )
