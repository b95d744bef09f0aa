"""The oracle of ``--op scenario``: every step's outputs, compared, and each target checked alone.

Differential check: the steps are compared in order and the first divergent step is reported
(``Comparison.step``, ``step_kind``, ``field = "<kind>.<quantity>"``). Per step: the status
(class and code of errors; a crash, or a side that ended earlier, is a ``crash``/``status``
divergence at that step), then each value in the order of :data:`ORDER`: a value present on
one side only, a trajectory's point count (exact), then the values, each within its tolerance:

=========================  ==================================  ==========  =================
quantity                   rule                                tolerance   unit
=========================  ==================================  ==========  =================
success, error_code        exact                               0           status
fraction                   absolute                            1e-9        fraction
trajectory.points          exact (a sample on the end's knife  0           points
                           edge dropped: ``end_knife_edge``)
trajectory.time_from_start absolute per point                  1e-9        s
trajectory.positions       per point, as joint values          campaign    rad (m)
trajectory.velocities      absolute per point and joint        1e-6        rad/s (m/s)
trajectory.accelerations   absolute per point and joint (at    1e-6        rad/s^2 (m/s^2)
                           a switch of the profile, either
                           side: ``oracle_switch``)
joint_target, named        as joint values                     campaign    rad (m)
joint_values, position,    ``fuzzer.execution.oracle.compare`` (modulo   campaign    rad (m), m, rad
orientation                2pi, q ~ -q, canonical boundary)
=========================  ==================================  ==========  =================

Values named ``in_effect.*`` are what the executor knew (the script's settings), not outputs
of a target, and are not compared. Divergences that documented limitations explain (IK's
answer is a pose, not a unique joint vector; knife edges of step counts) are classified, not
counted (``known_limitation``; ``fuzzer.scenario.oracle_ik``).

Property checks (``fuzzer.scenario.oracle_properties``) run on each target alone; a differential
divergence takes precedence at the same step, else the earliest step wins; a
``known_limitation`` gives way to a property violation at any step.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from fuzzer.execution import oracle
from fuzzer.execution.records import Comparison, Kind, Outcome, Status, as_array, floats
from fuzzer.execution.tolerance import Tolerance
from fuzzer.scenario import oracle_switch
from fuzzer.scenario.oracle_facts import ScenarioFacts, contexts
from fuzzer.scenario.oracle_ik import (
    FRACTION_TOLERANCE,
    absolute,
    apart_rows,
    classify,
    ik_answer_changed,
    joints_apart,
    solves_ik,
    value_divergence,
)
from fuzzer.scenario.oracle_properties import violation_at
from fuzzer.scenario.oracle_switch import ACCELERATION_TOLERANCE
from fuzzer.scenario.steps import ScenarioCall

TIME_TOLERANCE = 1e-9
"""time_from_start (s)."""
VELOCITY_TOLERANCE = 1e-6
"""Trajectory velocities (rad/s or m/s)."""

ORDER = (
    "success",
    "error_code",
    "fraction",
    "trajectory.points",
    "trajectory.time_from_start",
    "trajectory.positions",
    "trajectory.velocities",
    "trajectory.accelerations",
    "joint_target",
    "named",
    "joint_values",
    "position",
    "orientation",
)
"""Order in which a step's quantities are compared (the first divergent one is reported)."""

COARSE = ("status", "success", "error_code", "fraction", "trajectory.points")
"""What is compared of a path once an ``/execute`` of plans a path's ``known_limitation`` left has
taken the arms apart (``first_differential``): how far it got, not its points."""

IN_EFFECT = "in_effect."
"""Prefix of what the executor knew (script settings), not outputs of the target: not compared."""
POSE_VALUES = ("joint_values", "position", "orientation")


def _quantity(key: str) -> str:
    return "named" if key.startswith("named.") else key


def _rank(key: str) -> int:
    quantity = _quantity(key)
    return ORDER.index(quantity) if quantity in ORDER else len(ORDER)


def _rows(
    key: str, a: np.ndarray, b: np.ndarray, tol: Tolerance, facts: ScenarioFacts, dof: int
) -> Comparison | None:
    found: list[Comparison] = []
    rows_a, rows_b = a.reshape(-1, dof), b.reshape(-1, dof)
    for r in apart_rows(rows_a, rows_b, tol, facts).tolist():  # the others agree (none: no call)
        c = joints_apart(key, rows_a[r].tolist(), rows_b[r].tolist(), tol, facts)
        if c is not None:
            found.append(c)
    if not found:
        return None
    values = [c for c in found if c.kind is Kind.VALUE] or found
    # farthest beyond its limit, as within one row (metres and radians may have their own)
    worst = max(values, key=lambda c: c.difference / (tol.metres if c.unit == "m" else tol.radians))
    joints = tuple(sorted({j for c in values for j in c.joints}))
    return replace(worst, joints=joints, largest=max(c.largest for c in found))


TIMES = "trajectory.time_from_start"
SAMPLED = ("trajectory.positions", "trajectory.velocities", "trajectory.accelerations")
"""A trajectory's per-point quantities besides its times, each (M * dof,) row-major."""


def end_knife_edge(a: Outcome, b: Outcome, dof: int) -> tuple[Outcome, Outcome]:
    """``a`` and ``b`` with the sample a trajectory has on the knife edge of its end removed.

    The contract samples a plan at ``t = i * dt`` while ``t < T``, then at ``T`` (docs/api.md,
    ``plan``). When ``T`` is a multiple of ``dt`` within rounding, the two targets' ``T`` (each
    within ``TIME_TOLERANCE`` of the other) fall either side of the last ``i * dt``: one target
    has a sample a rounding error before its end that the other has not, and the counts differ
    by one. When they do, and the longer trajectory's last two times are less than
    ``TIME_TOLERANCE`` apart (and increasing), that second-to-last sample goes: the rest is
    compared as usual (its end point with the other's, every other point). A sample missing
    anywhere else, or an end that differs by more, is still a divergence."""
    times = [o.values.get(TIMES, ()) for o in (a, b)]
    if abs(len(times[0]) - len(times[1])) != 1:
        return a, b
    longer = 0 if len(times[0]) > len(times[1]) else 1
    t = np.asarray(times[longer], dtype=float)
    if t.size < 2 or not 0.0 < t[-1] - t[-2] < TIME_TOLERANCE:
        return a, b
    outcome = (a, b)[longer]
    values = {**outcome.values, TIMES: floats(np.delete(t, -2))}
    for key in SAMPLED:
        if key not in values:
            continue
        rows = as_array(values[key])
        if rows.size != t.size * dof:
            return a, b  # malformed: compared (and reported) as it is
        values[key] = floats(np.delete(rows.reshape(t.size, dof), -2, axis=0))
    trimmed = replace(outcome, values=values)
    return (trimmed, b) if longer == 0 else (a, trimmed)


def _switches(a: Outcome, b: Outcome, va: np.ndarray, vb: np.ndarray, dof: int) -> np.ndarray:
    """``vb`` (accelerations) with the entries on a switch of the profile taken from ``va``
    (``fuzzer.scenario.oracle_switch``); unchanged when they agree or a profile is incomplete."""
    if absolute("", va, vb, ACCELERATION_TOLERANCE, "") is None:
        return vb
    profiles = []
    for o, acc in ((a, va), (b, vb)):
        times = as_array(o.values.get(TIMES, ()))
        speeds = as_array(o.values.get("trajectory.velocities", ()))
        if not (times.size >= 3 and speeds.size == acc.size == times.size * dof):
            return vb
        profiles.append((times, speeds.reshape(-1, dof), acc.reshape(-1, dof)))
    return oracle_switch.canonical(profiles[0], profiles[1], ACCELERATION_TOLERANCE).reshape(-1)


def compare_step(kind: str, a: Outcome, b: Outcome, tol: Tolerance, facts: ScenarioFacts) -> Comparison:
    """The differential verdict on one step's two outcomes (``field`` is ``<kind>.<quantity>``).

    Parameters
    ----------
    kind : str
        Step kind (``go``, ``plan``...).
    a, b : Outcome
        The step's outcomes on the two targets; trajectories are flattened row-major, (M * dof,).
    tol : Tolerance
        Campaign tolerance (joint values, positions, orientations).
    facts : ScenarioFacts
        The robot's joints.
    """
    status = oracle.compare(Outcome(a.status, a.error, a.code), Outcome(b.status, b.error, b.code), tol)
    if status.divergent:
        return replace(status, field=f"{kind}.status")
    if a.status is Status.CRASHED:
        return Comparison(Kind.AGREE)
    found: list[Comparison] = []
    keys = sorted(
        (k for k in set(a.values) | set(b.values) if not k.startswith(IN_EFFECT)), key=lambda k: (_rank(k), k)
    )
    dof = len(facts.joints)
    a, b = end_knife_edge(a, b, dof)
    points = [len(o.values.get(TIMES, ())) for o in (a, b)]
    for key in keys:
        field_name = f"{kind}.{_quantity(key)}"
        if key not in a.values or key not in b.values:
            found.append(value_divergence(field_name, math.inf, "status"))
            break
        va, vb = as_array(a.values[key]), as_array(b.values[key])
        if key.startswith("trajectory."):
            if points[0] != points[1]:
                found.append(
                    value_divergence(f"{kind}.trajectory.points", abs(points[0] - points[1]), "points")
                )
                break
            if key != TIMES and not (va.size == vb.size == points[0] * dof):
                found.append(value_divergence(field_name, math.inf, "points"))
                break
        elif va.size != vb.size:
            found.append(value_divergence(field_name, math.inf, "status"))
            break
        c: Comparison | None
        if key in ("success", "error_code"):
            c = absolute(field_name, va, vb, 0.0, "status")
        elif key == "fraction":
            c = absolute(field_name, va, vb, FRACTION_TOLERANCE, "fraction")
        elif key == TIMES:
            c = absolute(field_name, va, vb, TIME_TOLERANCE, "s")
        elif key in ("trajectory.velocities", "trajectory.accelerations"):
            speed = key.endswith("velocities")
            unit, limit = ("rad/s", VELOCITY_TOLERANCE) if speed else ("rad/s^2", ACCELERATION_TOLERANCE)
            if not speed and dof:
                vb = _switches(a, b, va, vb, dof)
            c = absolute(field_name, va, vb, limit, unit, dof, facts.prismatic)
        elif key == "trajectory.positions" and dof:
            c = _rows(field_name, va, vb, tol, facts, dof)
        elif key == "joint_target" or key.startswith("named."):
            c = joints_apart(field_name, va.tolist(), vb.tolist(), tol, facts)
        elif key in POSE_VALUES:
            continue  # below, together (the oracle's own order and rules)
        else:
            c = absolute(field_name, va, vb, tol.radians, "")
        if c is not None:
            found.append(c)
            if c.kind is Kind.VALUE:
                break
    pose = {k: a.values[k] for k in POSE_VALUES if k in a.values and k in b.values}
    if pose and not any(c.kind is Kind.VALUE for c in found):
        c = oracle.compare(
            Outcome(Status.OK, values=pose),
            Outcome(Status.OK, values={k: b.values[k] for k in pose}),
            tol,
            facts.prismatic,
            continuous=facts.continuous,
        )
        if c.divergent:
            found.append(replace(c, field=f"{kind}.{c.field}"))
    chosen = next((c for c in found if c.kind is Kind.VALUE), found[0] if found else None)
    return chosen or Comparison(Kind.AGREE)


def _status_of_shorter(kind: str, shorter: Outcome) -> Comparison:
    ended = shorter.steps[-1] if shorter.steps else shorter
    crashed = ended.status is Status.CRASHED or shorter.status is Status.CRASHED
    return Comparison(Kind.CRASH if crashed else Kind.STATUS, f"{kind}.status")


def first_differential(
    call: ScenarioCall, a: Outcome, b: Outcome, tol: Tolerance, facts: ScenarioFacts
) -> Comparison:
    """The first divergent step (classified), or ``agree`` with the largest raw difference.

    A ``known_limitation`` at a ``cartesian_path`` step does not end the comparison: that step
    changes nothing on the group but each target's last plan, so the steps after it are
    compared as well (a later ``/plan`` that succeeds on both, or a later path that agrees
    and is not rejected on either, replaces that plan). After an ``/execute`` of the plans it
    left the two arms may stand apart (two IK answers of one pose, beyond the tolerance): from
    there on only how far each later path got is compared (``COARSE``: its status, success,
    error code, fraction and point count), which such a gap does not explain; the evaluator's
    nudge check then moves the state by the gap too, and a gap beyond the tolerance has the
    step re-run from each arm's state (``fuzzer.scenario.common_start``, as for arms one
    state apart by 2pi, which this oracle compares as one). A counted divergence found later is the
    verdict; otherwise the first ``known_limitation`` is.
    """
    largest = 0.0
    pending: Comparison | None = None
    tainted = coarse = False
    before = list(zip(contexts(call, a, facts), contexts(call, b, facts), strict=False))
    for i in range(max(len(a.steps), len(b.steps))):
        kind = call.steps[i].kind if i < len(call.steps) else "step"
        if i >= len(a.steps) or i >= len(b.steps):
            c = _status_of_shorter(kind, a if i >= len(a.steps) else b)
            return replace(c, step=i, step_kind=kind)
        c = compare_step(kind, a.steps[i], b.steps[i], tol, facts)
        largest = max(largest, c.largest)
        if coarse or (tainted and kind == "execute" and c.divergent):
            coarse = True  # the plans that differ took the arms apart: how far paths get only
            if kind == "cartesian_path" and c.divergent and c.field.split(".", 1)[-1] in COARSE:
                c = classify(call, i, a.steps[i], b.steps[i], c, before[i], facts, tol)
                if c.kind is not Kind.KNOWN_LIMITATION:
                    return replace(c, step=i, step_kind=kind)
            continue
        if c.divergent:
            c = classify(call, i, a.steps[i], b.steps[i], c, before[i], facts, tol)
            c = replace(c, step=i, step_kind=kind)
            if not (c.kind is Kind.KNOWN_LIMITATION and kind == "cartesian_path"):
                return c
            pending, tainted = pending or c, True
        elif (kind == "cartesian_path" and _replaced(a.steps[i], b.steps[i])) or (
            kind == "plan" and _succeeded(a.steps[i], b.steps[i])
        ):
            tainted = False
    if pending is not None:
        return pending
    # every step agreed: the group's constructor, or reading the final state, may still differ
    c = oracle.compare(Outcome(a.status, a.error, a.code), Outcome(b.status, b.error, b.code), tol)
    if c.divergent:
        return replace(c, field="scenario.status")
    return Comparison(Kind.AGREE, largest=largest)


def _succeeded(*steps: Outcome) -> bool:
    return all(tuple(step.values.get("success", ())) == (1.0,) for step in steps)


def _replaced(*steps: Outcome) -> bool:
    """Whether each of these path steps made a new last plan: a rejected or failed path leaves
    the old one, which a later ``/execute`` runs (``fuzzer.scenario.execute``)."""
    return all(step.status is Status.OK for step in steps)


def compare_scenario(
    call: ScenarioCall, a: Outcome, b: Outcome, tol: Tolerance, facts: ScenarioFacts
) -> Comparison:
    """The oracle's verdict on two runs of one scenario.

    Parameters
    ----------
    call : ScenarioCall
        The scenario (its steps give each step's kind and arguments).
    a, b : Outcome
        The two targets' scenario outcomes (``Outcome.steps``: one per executed step).
    tol : Tolerance
        Campaign tolerance (joint values and trajectory positions, rad or m; position m;
        orientation rad).
    facts : ScenarioFacts
        The robot's joints and limits, the targets' names, and FK for the IK rules.

    Returns
    -------
    Comparison
        With ``step``/``step_kind`` of the reported step; ``target`` for a property violation.
    """
    differential = first_differential(call, a, b, tol, facts)
    return prefer(differential, violation_at(call, (a, b), differential, facts, tol))


def prefer(differential: Comparison, violation: Comparison | None) -> Comparison:
    """A differential divergence first at the same step, else the earliest step; a divergence
    that is not counted (``known_limitation``, ``ill_conditioned``) gives way to a violation."""
    if violation is None or violation.step is None:
        return differential
    if not differential.divergent or differential.kind in (Kind.KNOWN_LIMITATION, Kind.ILL_CONDITIONED):
        return violation
    if differential.step is not None and violation.step < differential.step:
        return violation
    return differential


__all__ = [
    "compare_scenario",
    "compare_step",
    "first_differential",
    "ik_answer_changed",
    "prefer",
    "solves_ik",
]
