"""Deep zoo bugs (issue 11): faults confined to narrow regions of the input space.

Each variant is ``python_impl`` with one behaviour changed only inside a region a campaign
must *find*: a band about 0.1% wide of one joint's range away from round values, a relation
between two joints, a branch on a computed float (a position of the tool, an ``atan2``
angle), a calibration-table entry, a near-singular wrist, a revolute joint past pi, a band
tested per joint inside a list comprehension, an IK that goes wrong only from certain seeds.
``benchmarks/zoo/__init__.py`` lists them with the public source of each class. Outside its
region every variant is the twin itself. The FK faults sit in the kernel that
``forward_kinematics`` and ``forward_kinematics_batch`` share (``_Deep``), so the batched
search of ``fuzzer.generation.sweep`` meets the same fault a single call does.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

import python_impl
from python_impl.angles import normalize_angle
from python_impl.trajectory import plan_trajectory
from robot_api.constants import ACCELERATION_LIMIT
from robot_api.records import IKResult, IKStatus, JointLimit, JointType, Pose, RobotTrajectory

Model = python_impl.RobotModel
Group = python_impl.MoveGroup
SHIFT = 1e-3
"""How wrong a faulty answer is (m or rad): far above the oracle's 1e-6."""


def _impl(model: type = Model, group: type = Group) -> Any:
    from types import SimpleNamespace

    return SimpleNamespace(RobotModel=model, MoveGroup=group)


class _Deep(Model):
    """A twin whose FK kernel carries a fault, on the single and the batch path alike (a real
    library's fault sits in the kernel both share): ``fault_values`` changes the joint values
    before the chain is evaluated, ``fault_positions`` the link positions after it. Both are
    vectorized over rows: ``q`` of shape (N, dof) in rad, positions (N, 3) in m."""

    def fault_values(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return q

    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        return p

    def pose_of(self, values: list[float], link: int) -> Pose:
        q = np.array([values], dtype=np.float64)
        pose = super().pose_of(self.fault_values(q)[0].tolist(), link)
        p = self.fault_positions(q, np.array([pose.position], dtype=np.float64))[0]
        return Pose((float(p[0]), float(p[1]), float(p[2])), pose.orientation)

    def forward_kinematics_batch(
        self, joint_values: NDArray[np.float64], link: str | None = None
    ) -> NDArray[np.float64]:
        q = self._batch_input(joint_values)
        out = super().forward_kinematics_batch(self.fault_values(q), link)
        out[:, :3, 3] = self.fault_positions(q, out[:, :3, 3])
        return out


def _shifted(p: NDArray[np.float64], rows: NDArray[np.bool_], dz: float = SHIFT) -> NDArray[np.float64]:
    out = p.copy()
    out[rows, 2] += dz
    return out


# -- 1. a band 0.1% wide of joint 2's range, at 61.73% of the range -------------------------


class _NarrowBand(_Deep):
    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        lim = self.joint_limits[1]
        start = lim.lower + 0.6173 * (lim.upper - lim.lower)
        band = (start <= q[:, 1]) & (q[:, 1] < start + 0.001 * (lim.upper - lim.lower))
        return _shifted(p, band)


narrow_band = _impl(model=_NarrowBand)


# -- 2. two joints in a relation: joint_1 - joint_3 within 1e-3 of sqrt(2) - 1 ---------------


class _JointRelation(_Deep):
    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        return _shifted(p, np.abs(q[:, 0] - q[:, 2] - (math.sqrt(2.0) - 1.0)) < 1e-3)


joint_relation = _impl(model=_JointRelation)


# -- 3. a branch on a computed float: the tool's x position in [0.1234, 0.1244) m ------------


class _ComputedBranch(_Deep):
    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        return _shifted(p, (p[:, 0] >= 0.1234) & (p[:, 0] < 0.1244))


computed_branch = _impl(model=_ComputedBranch)


# -- 4. atan2 quadrant: the tool's azimuth in (2.0, 2.01) rad mirrored -----------------------


class _Atan2Quadrant(_Deep):
    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        azimuth = np.arctan2(p[:, 1], p[:, 0])
        out = p.copy()
        rows = (azimuth > 2.0) & (azimuth < 2.01)
        out[rows, 0] = -out[rows, 0]
        return out


atan2_quadrant = _impl(model=_Atan2Quadrant)


# -- 5. a calibration table with one wrong entry: joint_3 at round(100 q) == 137 -------------


class _CalibrationEntry(_Deep):
    def fault_values(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        out = q.copy()
        out[np.round(q[:, 2] * 100) == 137, 2] += SHIFT
        return out


calibration_entry = _impl(model=_CalibrationEntry)


# -- 6. near-singular wrist: joint_5 within 2e-3 of 0 (but not 0) treated as 0 --------------


class _SmallAngleWrist(_Deep):
    def fault_values(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        out = q.copy()
        out[(np.abs(q[:, 4]) > 0.0) & (np.abs(q[:, 4]) < 2e-3), 4] = 0.0
        return out


small_angle_wrist = _impl(model=_SmallAngleWrist)


# -- 6b-6d. narrower still: the regions real reports describe ------------------------------


class _NarrowerBand(_Deep):
    """Joint_2 in a band 1e-5 of its range wide (at 38.29% of it)."""

    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        lim = self.joint_limits[1]
        start = lim.lower + 0.3829 * (lim.upper - lim.lower)
        band = (start <= q[:, 1]) & (q[:, 1] < start + 1e-5 * (lim.upper - lim.lower))
        return _shifted(p, band)


narrower_band = _impl(model=_NarrowerBand)


class _TightRelation(_Deep):
    """joint_2 + joint_4 within 2e-5 of 1/e (two joints in a relation, a 50x thinner slab)."""

    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        return _shifted(p, np.abs(q[:, 1] + q[:, 3] - math.exp(-1.0)) < 2e-5)


tight_relation = _impl(model=_TightRelation)


AMPLIFIED_AT = 0.6583
"""Where ``amplified_error``'s joint_5 error blows up (rad)."""


class _AmplifiedError(_Deep):
    """Rounding amplified near a singular value: the tool's z off by 1e-11 / |q5 - 0.6583| m.

    Above rounding noise almost everywhere (1e-11 m at 1 rad away) but above the oracle's
    1e-6 m only within 1e-5 rad of the point: a difference that grows toward the fault, as
    ``1 / sin`` terms do near a wrist singularity. The pattern search can follow it."""

    def fault_positions(self, q: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        out = p.copy()
        with np.errstate(divide="ignore"):
            out[:, 2] += np.minimum(SHIFT, 1e-11 / np.abs(q[:, 4] - AMPLIFIED_AT))
        return out


amplified_error = _impl(model=_AmplifiedError)


# -- 7. a revolute joint past pi: targets in [4.0, 4.05) rad wrapped into (-pi, pi] ----------


class _WrapPastPi(Group):
    def set_joint_value_target(self, arg1: Any, arg2: Any = None) -> None:
        super().set_joint_value_target(arg1, arg2)
        self._target = [
            normalize_angle(v) if lim.type == JointType.REVOLUTE and 4.0 <= v < 4.05 else v
            for v, lim in zip(self._target, self._limits, strict=True)
        ]


wrap_past_pi = _impl(group=_WrapPastPi)


# -- 8. a correction per joint, tested inside a list comprehension: targets in a band 2e-5 wide --

CORRECTED_FROM, CORRECTED_TO = 0.86131, 0.86133
"""``per_joint_band``'s band (rad): any joint's target in it is moved by ``SHIFT``."""


class _PerJointBand(Group):
    """The band sits in a list comprehension, as per-joint corrections in Python often do: a
    comparison Atheris alone never traced (``fuzzer.selection.cmp_gap``). About 2.3e-5 of
    uniform random targets of the default robot fall in it (the band over each joint's range,
    summed over the six joints)."""

    def set_joint_value_target(self, arg1: Any, arg2: Any = None) -> None:
        super().set_joint_value_target(arg1, arg2)
        self._target = [v + SHIFT if CORRECTED_FROM <= v < CORRECTED_TO else v for v in self._target]


per_joint_band = _impl(group=_PerJointBand)


# -- 9. IK from certain seeds: a seed with joint_1 in [0.3, 0.31) rad reports its seed -------


class _SeedBandIk(Model):
    """The fault returns before solving, as a seed wrongly taken for converged does: the
    arguments are checked first (the same errors as the twin's), then no Newton-Raphson
    iteration is run from a seed in the band. Until 2026-12-01 the fault solved first and
    threw the answer away; its answers were the same, but every in-band call of a long
    Cartesian path paid a solve from a seed the path had left behind (up to 100 iterations),
    and confirming one detecting script took seconds (docs/benchmarks-log.md, "Where
    `ik_seed_band`'s seconds go")."""

    def inverse_kinematics(self, pose: Pose, seed: Any = None, link: str | None = None) -> IKResult:
        self._ik_start(pose, seed, link)  # the twin's argument checks and errors, unchanged
        if seed is not None and len(seed) and 0.3 <= float(seed[0]) < 0.31:
            return IKResult(IKStatus.SUCCESS, tuple(float(v) for v in seed), 0.0, 0.0)
        return super().inverse_kinematics(pose, seed, link)


ik_seed_band = _impl(model=_SeedBandIk)


# -- 10-12. deep in a script: faults a scenario must reach through a call sequence ----------


class _ExecuteSkipsStartCheck(Group):
    """execute(plan) does not compare the plan's start with the current state: a plan made
    before the arm moved is run from its own start, the arm jumping there.

    A plan executed right after it is made starts where the arm is, and go() plans from the
    current state, so neither shows it: it takes a ``/plan``, a move, then ``/execute``."""

    def execute(self, plan: Any, wait: bool = True) -> bool:
        positions: Any = getattr(plan, "positions", None)
        times = getattr(plan, "time_from_start", ())
        shaped = isinstance(positions, np.ndarray) and positions.shape == (len(times), self._model.dof)
        if shaped and len(positions) and np.isfinite(positions[0]).all():
            self._current = [
                normalize_angle(v) if lim.type == JointType.CONTINUOUS else min(max(v, lim.lower), lim.upper)
                for v, lim in zip(positions[0].tolist(), self._limits, strict=True)
            ]
        return bool(super().execute(plan, wait))


execute_skips_start_check = _impl(group=_ExecuteSkipsStartCheck)


START_BAND_AT = 0.6821
"""Where ``plan_start_band``'s band starts, as a share of joint_2's range (0.1% of it wide)."""


class _PlanStartBand(Group):
    """plan() and go() read the current state through a calibration table with one wrong
    entry: with the *current* joint_2 in a band 0.1% of its range wide (at 68.21% of it) the
    trajectory starts 1 mrad off in joint_2.

    A fresh group is at home, outside the band, so one call never shows it: the arm must
    first be moved into the band, then a ``/plan`` made (go() still ends at its goal, the
    1 mrad being inside the execution's start tolerance)."""

    def _plan(self) -> RobotTrajectory:
        start = list(self._current)
        lim = self._limits[1]
        low = lim.lower + START_BAND_AT * (lim.upper - lim.lower)
        if low <= start[1] < low + 0.001 * (lim.upper - lim.lower):
            start[1] += SHIFT
        return plan_trajectory(
            self._limits, start, self._goal(), self._velocity_scaling, self._acceleration_scaling
        )


plan_start_band = _impl(group=_PlanStartBand)


SWITCH_BAND = 1e-3
"""How far past the profile switch ``profile_switch_band``'s fault reaches (relative)."""


def profile_ratio(
    limits: tuple[JointLimit, ...],
    start: list[float],
    goal: list[float],
    velocity: float,
    acceleration: float,
) -> float:
    """``A / v**2`` of the twin's synchronized profile (``plan_trajectory``'s bounds on the path
    coordinate): above 1 the move reaches its cruise speed (a trapezoid), below it does not (a
    triangle); 0 for no move."""
    vs = accel = math.inf
    for lim, a, b in zip(limits, start, goal, strict=True):
        d = normalize_angle(b - a) if lim.type == JointType.CONTINUOUS else b - a
        if d != 0.0:
            vs = min(vs, lim.velocity * velocity / abs(d))
            accel = min(accel, ACCELERATION_LIMIT * acceleration / abs(d))
    if vs == math.inf:
        return 0.0
    square = vs * vs
    return accel / square if square > 0.0 else math.inf  # a bound so small its square underflows


class _ProfileSwitchBand(Group):
    """A move just past the switch from the triangular to the trapezoidal velocity profile (the
    ratio ``A / v**2`` of the path's bounds in (1, 1.001)) is timed as a triangle: its peak
    speed exceeds the scaled velocity limit by up to 0.05%.

    The ratio is a computed float of the move's largest displacement and both scaling factors;
    at the default factors (1.0) no move of the default robot reaches the switch, so it takes
    a scaling factor, then a ``/plan`` whose move lies in a band about 0.1% wide."""

    def _plan(self) -> RobotTrajectory:
        goal = self._goal()
        velocity = self._velocity_scaling
        ratio = profile_ratio(self._limits, self._current, goal, velocity, self._acceleration_scaling)
        if 1.0 < ratio < 1.0 + SWITCH_BAND:
            velocity *= 1.0 + SWITCH_BAND  # the triangle's peak sqrt(A) is now within the bound
        return plan_trajectory(self._limits, self._current, goal, velocity, self._acceleration_scaling)


profile_switch_band = _impl(group=_ProfileSwitchBand)

__all__ = [
    "amplified_error",
    "atan2_quadrant",
    "calibration_entry",
    "computed_branch",
    "execute_skips_start_check",
    "ik_seed_band",
    "joint_relation",
    "narrow_band",
    "narrower_band",
    "per_joint_band",
    "plan_start_band",
    "profile_switch_band",
    "small_angle_wrist",
    "tight_relation",
    "wrap_past_pi",
]
