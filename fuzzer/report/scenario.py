"""The report's part for scenario buckets (``--op scenario``): step table and trajectory plots.

A scenario bucket shows, below its outcomes:

* the step table (step, topic, arguments, each target's status), the first divergent
  step highlighted and marked in words;
* the values both targets reported at that step (trajectories summarised by length);
* for steps with trajectories (``/plan``, ``/cartesian_path``) a figure of both targets'
  joint positions (top row) and velocities (bottom row) over ``time_from_start``, one
  column per joint, the two targets overlaid. At most :data:`MAX_PLOTS` steps are drawn:
  the first divergent one and the trajectory steps nearest to it.

Everything comes from the sidecar (untrusted data): strings are escaped for HTML here,
figures are drawn without mathtext (:data:`PLAIN_TEXT`), and a trajectory whose lengths
do not fit (``positions`` must hold ``M * dof`` numbers for ``M`` times) gets a note
instead of a plot.
"""

from __future__ import annotations

import base64
import io
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fuzzer.execution.records import Outcome
from fuzzer.report.markup import esc
from fuzzer.report.steps import ScenarioSteps, clean, scenario_of

MAX_PLOTS = 4
"""At most this many trajectory steps are drawn per bucket."""
MAX_COLUMNS = 12
"""At most this many joints are drawn per figure (the first ones)."""
COLORS = ("#1f5fbf", "#e8710a")
TRAJECTORY_KEYS = ("time_from_start", "positions", "velocities", "accelerations")
PLAIN_TEXT: dict[Any, Any] = {"text.parse_math": False, "text.usetex": False}
"""Joint and target names from a sidecar are drawn as they are (no ``$...$`` mathtext)."""


@dataclass(frozen=True)
class Trajectory:
    """One target's trajectory at one step.

    Attributes
    ----------
    target : str
    time : tuple of float
        ``time_from_start`` (s), shape (M,).
    positions, velocities : tuple of tuple of float
        Shape (M, dof): rad or m, rad/s or m/s.
    """

    target: str
    time: tuple[float, ...]
    positions: tuple[tuple[float, ...], ...]
    velocities: tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class TrajectoryStep:
    """A step with at least one trajectory, as drawn."""

    index: int
    topic: str
    joint_names: tuple[str, ...]
    trajectories: tuple[Trajectory | None, Trajectory | None]
    """Per target (a, b); None when it has no drawable trajectory there."""
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class ScenarioView:
    """What the page shows of one scenario bucket (figures come separately, as PNG bytes)."""

    steps: ScenarioSteps
    values: tuple[tuple[str, str, str], ...]
    """At the first divergent step: (quantity, value of a, value of b), as text."""
    plots: tuple[TrajectoryStep, ...]
    omitted: int = 0
    """Trajectory steps not drawn (beyond :data:`MAX_PLOTS`)."""


def _step_outcomes(sidecar: Mapping[str, Any]) -> list[tuple[str, tuple[Outcome, ...]]]:
    """Each target's name and step outcomes ((), when unreadable)."""
    out: list[tuple[str, tuple[Outcome, ...]]] = []
    for item in [*list(sidecar.get("outcomes") or []), None, None][:2]:
        target = clean(str(item.get("target", "?")), 60) if isinstance(item, dict) else "?"
        try:
            steps = Outcome.from_json(item).steps if isinstance(item, dict) else ()
        except (KeyError, TypeError, ValueError, AttributeError):
            steps = ()
        out.append((target, steps))
    return out


def _shortened(sidecar: Mapping[str, Any], index: int) -> list[str]:
    """What the writer left out of step ``index``'s values (``fuzzer.artifacts.shorten``), per target."""
    out = []
    for item in list(sidecar.get("outcomes") or [])[:2]:
        steps = item.get("steps") if isinstance(item, dict) else None
        step = steps[index] if isinstance(steps, list) and index < len(steps) else None
        note = step.get("shortened") if isinstance(step, dict) else None
        if isinstance(note, str) and note:
            target = clean(str(item.get("target", "?")), 60)
            out.append(f"{target}: {clean(note, 200)} (replay the crash file for all)")
    return out


def _matrix(flat: Sequence[float], rows: int, dof: int) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(flat[r * dof : (r + 1) * dof]) for r in range(rows))


def trajectory(outcome: Outcome, target: str, dof: int) -> tuple[Trajectory | None, str]:
    """The trajectory of a step outcome, or None and why (an empty string: it has none).

    ``dof`` is the number of joints; 0 means: infer it from the lengths.
    """
    values = outcome.values
    time = values.get("trajectory.time_from_start")
    if time is None:
        return None, ""
    m = len(time)
    if m == 0:
        return None, f"{target}: empty trajectory"
    flat = {k: values.get(f"trajectory.{k}", ()) for k in ("positions", "velocities")}
    width = dof or len(flat["positions"]) // m
    for key, numbers in flat.items():
        if width == 0 or len(numbers) != m * width:
            return None, (
                f"{target}: {len(numbers)} {key} for {m} time point(s) and {width} joint(s): not drawn"
            )
    return (
        Trajectory(
            target, tuple(time), _matrix(flat["positions"], m, width), _matrix(flat["velocities"], m, width)
        ),
        "",
    )


def _text(value: Sequence[float] | None) -> str:
    if value is None:
        return "-"
    if len(value) > 8:
        return f"{len(value)} numbers"
    return "(" + ", ".join(f"{v:.10g}" if math.isfinite(v) else str(v) for v in value) + ")"


def _values_at(
    step: int | None, outcomes: list[tuple[str, tuple[Outcome, ...]]]
) -> tuple[tuple[str, str, str], ...]:
    if step is None:
        return ()
    got = [o[1][step].values if step < len(o[1]) else {} for o in outcomes]
    names = sorted(set(got[0]) | set(got[1]))
    return tuple((clean(n, 80), _text(got[0].get(n)), _text(got[1].get(n))) for n in names)


def _chosen(candidates: list[int], first: int | None) -> list[int]:
    """The trajectory steps to draw: the first divergent one, then the nearest to it."""
    anchor = first if first is not None else 0
    near = sorted(candidates, key=lambda i: (i != anchor, abs(i - anchor), i))
    return sorted(near[:MAX_PLOTS])


def view_of(sidecar: Mapping[str, Any] | None) -> ScenarioView | None:
    """The scenario view of a sidecar, or None when it is not a scenario's."""
    steps = scenario_of(dict(sidecar) if isinstance(sidecar, Mapping) else None)
    if steps is None or sidecar is None:
        return None
    outcomes = _step_outcomes(sidecar)
    names = sidecar.get("joint_names")
    joint_names = tuple(clean(str(n), 40) for n in names) if isinstance(names, list) else ()
    candidates = [
        i
        for i in range(len(steps.steps))
        if any(i < len(o[1]) and "trajectory.time_from_start" in o[1][i].values for o in outcomes)
    ]
    plots = []
    for i in _chosen(candidates, steps.first):
        found: list[Trajectory | None] = []
        notes: list[str] = []
        for target, outcome_steps in outcomes:
            if i >= len(outcome_steps):
                found.append(None)
                notes.append(f"{target}: step not run")
                continue
            item, note = trajectory(outcome_steps[i], target, len(joint_names))
            found.append(item)
            notes += [note] if note else []
        notes += _shortened(sidecar, i)
        plots.append(TrajectoryStep(i, steps.steps[i].topic, joint_names, (found[0], found[1]), tuple(notes)))
    return ScenarioView(steps, _values_at(steps.first, outcomes), tuple(plots), len(candidates) - len(plots))


# -- figures ------------------------------------------------------------------------------------------------


ROWS = (("positions", "position (rad or m)"), ("velocities", "velocity (rad/s or m/s)"))
MARKERS_UP_TO = 30
"""Points are marked only on trajectories of at most this many points."""


def _gap(drawn: list[tuple[int, Trajectory]], key: str, j: int) -> str:
    """``max |a - b|`` of one joint's series when both targets have one of the same length."""
    if len(drawn) != 2 or len(drawn[0][1].time) != len(drawn[1][1].time):
        return ""
    a, b = (np.array([p[j] if j < len(p) else math.nan for p in getattr(t, key)]) for _, t in drawn)
    with np.errstate(invalid="ignore"):
        gap = float(np.max(np.abs(a - b))) if a.size else 0.0
    return f"max |a-b| {gap:.3g}"


def figure(step: TrajectoryStep, first: bool = False) -> bytes | None:
    """Positions (top row) and velocities (bottom row) of both targets over time, one column
    per joint (at most :data:`MAX_COLUMNS`), as PNG bytes; None when neither has a trajectory.
    Each panel also states the largest gap between the targets when their samples pair up."""
    drawn = [(i, t) for i, t in enumerate(step.trajectories) if t is not None]
    if not drawn:
        return None
    dof = min(max(len(t.positions[0]) for _, t in drawn), MAX_COLUMNS)
    with matplotlib.rc_context(PLAIN_TEXT):
        fig = Figure(figsize=(1.2 + 2.6 * dof, 5.6), dpi=100, layout="constrained")
        FigureCanvasAgg(fig)
        axes = fig.subplots(2, dof, squeeze=False, sharex=True)
        for j in range(dof):
            name = step.joint_names[j] if j < len(step.joint_names) else f"joint #{j + 1}"
            for row, (key, label) in enumerate(ROWS):
                ax = axes[row][j]
                for i, t in drawn:
                    series = np.array(
                        [p[j] if j < len(p) else math.nan for p in getattr(t, key)], dtype=float
                    )
                    few = len(t.time) <= MARKERS_UP_TO
                    ax.plot(
                        t.time,
                        series,
                        color=COLORS[i],
                        ls="-" if i == 0 else "--",
                        marker=("o" if i == 0 else "s") if few else None,
                        markersize=5 if i == 0 else 3,
                        lw=3.0 if i == 0 else 1.4,
                        label=f"{'ab'[i]}: {t.target}",
                    )
                ax.text(0.02, 0.98, _gap(drawn, key, j), transform=ax.transAxes, va="top", fontsize=7.5)
                ax.grid(True, color="#dddddd", lw=0.8)
                ax.tick_params(labelsize=8)
                if row == 0:
                    ax.set_title(name, fontsize=10)
                else:
                    ax.set_xlabel("time from start (s)", fontsize=9)
                if j == 0:
                    ax.set_ylabel(label, fontsize=9)
        title = f"step {step.index} {step.topic}" + (" (first divergent step)" if first else "")
        fig.suptitle(title, fontsize=12)
        handles, labels = axes[0][0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=10, frameon=False)
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", metadata={"Software": None})
    return buffer.getvalue()


def file_name(key: str, index: int) -> str:
    """The PNG file of a bucket's trajectory figure at step ``index`` (safe characters only)."""
    return f"trajectory-{re.sub(r'[^A-Za-z0-9_-]', '_', key)}-step{index}.png"


def figures(key: str, view: ScenarioView) -> dict[str, bytes]:
    """Every trajectory figure of a scenario bucket, as PNG bytes by file name."""
    out: dict[str, bytes] = {}
    for step in view.plots:
        png = figure(step, step.index == view.steps.first)
        if png is not None:
            out[file_name(key, step.index)] = png
    return out


# -- HTML -------------------------------------------------------------------------------------------------


def _table(view: ScenarioView) -> str:
    steps = view.steps
    a, b = steps.targets
    head = (
        "<table><tr><th class='num'>Step</th><th>Topic</th><th>Arguments</th>"
        f"<th><span class='a'>a</span> {esc(a)}</th><th><span class='b'>b</span> {esc(b)}</th></tr>"
    )
    rows = []
    for s in steps.steps:
        hot = s.index == steps.first
        mark = "<br><b>first divergent</b>" if hot else ""
        css = " class='hot'" if hot else ""
        rows.append(
            f"<tr{css}>"
            f"<td class='num'>{s.index}{mark}</td><td><code>{esc(s.topic)}</code></td>"
            f"<td><code>{esc(s.arguments)}</code></td><td>{esc(s.labels[0])}</td><td>{esc(s.labels[1])}</td></tr>"
        )
    return head + "".join(rows) + "</table>"


def _hot(name: str, quantity: str) -> str:
    """The row class of a value the comparison's field names (``remember.named`` names ``named.*``)."""
    hot = bool(quantity) and (name == quantity or name.startswith(quantity + "."))
    return " class='hot'" if hot else ""


def _values(view: ScenarioView) -> str:
    if not view.values:
        return ""
    a, b = view.steps.targets
    quantity = view.steps.field.split(".", 1)[1] if "." in view.steps.field else ""
    rows = "".join(
        f"<tr{_hot(n, quantity)}><td><code>{esc(n)}</code></td><td><code>{esc(x)}</code></td>"
        f"<td><code>{esc(y)}</code></td></tr>"
        for n, x, y in view.values
    )
    return (
        f"<h3>Values at step {view.steps.first}</h3><table><tr><th>Quantity</th>"
        f"<th><span class='a'>a</span> {esc(a)}</th><th><span class='b'>b</span> {esc(b)}</th></tr>"
        f"{rows}</table>"
    )


def _plots(key: str, view: ScenarioView, pngs: Mapping[str, bytes]) -> str:
    parts = []
    for step in view.plots:
        name = file_name(key, step.index)
        notes = "".join(f"<li>{esc(n)}</li>" for n in step.notes)
        png = pngs.get(name)
        if png is None:
            parts.append(f"<div class='warn'>Step {step.index}: no trajectory to draw.<ul>{notes}</ul></div>")
            continue
        data = base64.b64encode(png).decode("ascii")
        alt = f"trajectories of both targets at step {step.index}"
        parts.append(
            f"<figure><img src='data:image/png;base64,{data}' alt='{esc(alt)}'><figcaption>"
            f"Step {step.index} (<code>{esc(step.topic)}</code>): joint positions (top) and velocities "
            "(bottom) over time from start, one column per joint; solid a, dashed b. Also saved as "
            f"<a href='{esc(name)}'>{esc(name)}</a>.<ul>{notes}</ul></figcaption></figure>"
        )
    if view.omitted:
        parts.append(f"<p class='note'>{view.omitted} more step(s) with a trajectory are not drawn.</p>")
    return "".join(parts)


def section(key: str, view: ScenarioView, pngs: Mapping[str, bytes]) -> str:
    """The HTML of a scenario bucket's steps, values and trajectory figures."""
    steps = view.steps
    where = f"{esc(steps.headline())}" + (f", on <code>{esc(steps.field)}</code>" if steps.field else "")
    return (
        f"<h3>Steps <small>({len(steps.steps)}; {where})</small></h3>{_table(view)}"
        "<p class='note'>Each target runs the steps in order on one new MoveGroup; the highlighted row is "
        "the first step where the targets' outcomes differ (later steps start from different states). "
        f"'-': the target did not run the step (an earlier step crashed).</p>{_values(view)}"
        + _plots(key, view, pngs)
    )
