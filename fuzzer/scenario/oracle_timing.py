"""Whether a target's trajectory is timed as the contract times its own positions.

``fuzzer.scenario.oracle_ik`` calls a divergence of what the contract computes from a
trajectory's positions (point count, ``time_from_start``, velocities, accelerations) a known
limitation when the two targets' IK answers or start states differ as numbers within the
tolerance: the timing's sensitivity to its inputs is unbounded as segments shrink, so no
tolerance on the difference of the two timings can hold. That rule alone would also explain
away a target that times its path wrongly, e.g. at full speed whatever the scaling factors
(MoveIt's ``compute_cartesian_path`` did: moveit/moveit#1065), since two IK implementations
almost never agree to 1e-12.

So the rule asks one more thing: on each target, the trajectory's duration is the duration
the contract gives that target's own positions with that target's scaling factors in effect
(docs/api.md, "plan()" and "compute_cartesian_path()"). The reference is the twin's timing
functions (``python_impl.trajectory``), run on each target's reported points; a fault in them
would make the correct target's timing fail this check, so it can only keep a divergence, never
explain one away. The duration is compared, not every time: it is a sum and a square root of
sums (well conditioned), while times in the deceleration phase take a square root of a
difference that cancels (an absolute rounding of about 1e-8 s).
"""

from __future__ import annotations

import math

import numpy as np

from fuzzer.execution.records import Outcome
from fuzzer.scenario.oracle_facts import Context, ScenarioFacts
from robot_api.errors import RobotAPIError
from robot_api.records import JointLimit, JointType

RETIME_TOLERANCE = 1e-9
"""Relative tolerance of a duration against the reference's (plus ``RETIME_ABSOLUTE`` s)."""
RETIME_ABSOLUTE = 1e-12
"""Absolute slack (s) of the duration check."""


def limits_of(facts: ScenarioFacts) -> tuple[JointLimit, ...]:
    """The facts' joints as the contract's ``JointLimit`` records (planning velocities)."""
    return tuple(
        JointLimit(f"joint_{j}", JointType(spec.type), spec.lower, spec.upper, spec.velocity)
        for j, spec in enumerate(facts.joints)
    )


def reference_duration(kind: str, rows: np.ndarray, before: Context, facts: ScenarioFacts) -> float | None:
    """The duration (s) the contract gives a ``plan`` from ``rows[0]`` to ``rows[-1]`` or a
    ``cartesian_path`` through ``rows`` (M, dof), with ``before``'s scaling factors; None when
    the contract would refuse them (a planning error, a bad value)."""
    from python_impl.trajectory import plan_trajectory, time_parameterize

    limits = limits_of(facts)
    scaling = before.velocity_scaling, before.acceleration_scaling
    try:
        if kind == "plan":
            timed = plan_trajectory(limits, rows[0].tolist(), rows[-1].tolist(), *scaling)
        else:
            timed = time_parameterize(limits, rows.tolist(), *scaling)
    except (RobotAPIError, ArithmeticError, ValueError):
        return None
    return float(timed.time_from_start[-1])


def timed_as_contract(kind: str, outcome: Outcome, before: Context, facts: ScenarioFacts) -> bool:
    """Whether ``outcome`` (one target's ``plan`` or ``cartesian_path`` step) lasts what the
    contract's timing of its own positions gives, within ``RETIME_TOLERANCE`` (relative)."""
    if kind not in ("plan", "cartesian_path"):
        return False
    dof = len(facts.joints)
    times = np.asarray(outcome.values.get("trajectory.time_from_start", ()), dtype=float)
    flat = np.asarray(outcome.values.get("trajectory.positions", ()), dtype=float)
    if not dof or times.size == 0 or flat.size != times.size * dof or not np.isfinite(flat).all():
        return False
    expected = reference_duration(kind, flat.reshape(-1, dof), before, facts)
    if expected is None:
        return False
    actual = float(times[-1])
    slack = RETIME_TOLERANCE * max(abs(actual), abs(expected)) + RETIME_ABSOLUTE
    return math.isfinite(actual) and abs(actual - expected) <= slack
