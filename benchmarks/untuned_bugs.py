"""Six bugs planted by a helper who had not seen the engine (sixty-third session, BENCHMARKS.md,
"Bugs the engine was not tuned on"), written without the zoo's code.

Each is the Python twin with one behaviour changed inside a region the search must find.
Use as ``--targets native,benchmarks.untuned_bugs:NAME`` from the repository (the helper ran it
as ``mybugs:NAME`` from a folder of its own).
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np

import python_impl
from robot_api.records import IKResult, IKStatus, Pose

Model = python_impl.RobotModel
Group = python_impl.MoveGroup
ERR = 1e-3  # size of a wrong answer (rad or m)


class _Kernel(Model):
    """FK kernel shared by forward_kinematics (pose_of) and forward_kinematics_batch."""

    def bad_values(self, q: np.ndarray) -> np.ndarray:  # (N, 6) -> (N, 6)
        return q

    def bad_positions(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:  # (N, 3) -> (N, 3)
        return p

    def pose_of(self, values: list[float], link: int) -> Pose:
        q = np.array([values], dtype=np.float64)
        pose = super().pose_of(self.bad_values(q)[0].tolist(), link)
        p = self.bad_positions(q, np.array([pose.position], dtype=np.float64))[0]
        return Pose((float(p[0]), float(p[1]), float(p[2])), pose.orientation)

    def forward_kinematics_batch(self, joint_values: Any, link: str | None = None) -> np.ndarray:
        q = self._batch_input(joint_values)
        out = super().forward_kinematics_batch(self.bad_values(q), link)
        out[:, :3, 3] = self.bad_positions(q, out[:, :3, 3])
        return out


# -- B1 gated_band: joint_4 encoder offset in a band 0.2% of its range wide, at e/10 of the
#    range (no round number inside), applied only when joint_2 is negative (a per-direction
#    compensation table with one bad cell). P(uniform) = 0.002 * 0.5 = 1e-3.

J4_FROM_FRAC, J4_WIDTH_FRAC = math.e / 10.0, 0.002


class _GatedBand(_Kernel):
    def bad_values(self, q: np.ndarray) -> np.ndarray:
        lim = self.joint_limits[3]
        span = lim.upper - lim.lower
        lo = lim.lower + J4_FROM_FRAC * span
        rows = (q[:, 1] < 0.0) & (q[:, 3] >= lo) & (q[:, 3] < lo + J4_WIDTH_FRAC * span)
        out = q.copy()
        out[rows, 3] += ERR
        return out


gated_band = SimpleNamespace(RobotModel=_GatedBand, MoveGroup=Group)


# -- B2 sum_band_orient: flange roll wrong when joint_1 + joint_6 is within 3.4e-3 rad of pi/7
#    (a "tool yaw" shortcut that combines base and flange angles); only the orientation is
#    wrong: joint_6's extra 1 mrad turns the tool about its own axis, the tool point stays.
#    P(uniform) = 2 * 3.4e-3 * (2pi - pi/7) / (2pi)^2 = 1.005e-3.

SUM_AT, SUM_HALF_WIDTH = math.pi / 7.0, 3.4e-3


class _SumBandOrient(_Kernel):
    def bad_values(self, q: np.ndarray) -> np.ndarray:
        rows = np.abs(q[:, 0] + q[:, 5] - SUM_AT) < SUM_HALF_WIDTH
        out = q.copy()
        out[rows, 5] += ERR
        return out


sum_band_orient = SimpleNamespace(RobotModel=_SumBandOrient, MoveGroup=Group)


# -- B3 floor_clamp: the tool point's z clamped to a "table height" of -0.098683 m (a
#    workspace floor applied inside FK); only poses below it are wrong. P(uniform) ~ 1e-3.

FLOOR_Z = -0.098683


class _FloorClamp(_Kernel):
    def bad_positions(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        out = p.copy()
        out[:, 2] = np.maximum(out[:, 2], FLOOR_Z)
        return out


floor_clamp = SimpleNamespace(RobotModel=_FloorClamp, MoveGroup=Group)


# -- B4 second_go_sign: on the second go() of a group's life, joint_4's goal is negated (a
#    direction flag that toggles per move instead of per joint). Scenario-only.


class _SecondGoSign(Group):
    def __init__(self, model: Any) -> None:
        super().__init__(model)
        self._go_calls = 0
        self._in_go = False

    def go(self, joints: Any = None, wait: bool = True) -> bool:
        self._go_calls += 1
        self._in_go = self._go_calls == 2
        try:
            return super().go(joints, wait)
        finally:
            self._in_go = False

    def _goal(self) -> list[float]:
        goal = list(super()._goal())
        if self._in_go:
            lim = self._limits[3]
            goal[3] = min(max(-goal[3], lim.lower), lim.upper)
        return goal


second_go_sign = SimpleNamespace(RobotModel=Model, MoveGroup=_SecondGoSign)


# -- B5 ik_ball: IK reports NO_SOLUTION (and hands back its seed) for goals whose position
#    lies within 0.0254 m of a point inside the workspace (a spurious singularity guard).
#    P(uniform configuration's tool point in the ball) ~ 1e-3.

BALL_CENTER = (
    0.06767793775728574,
    0.027243143608664592,
    0.6955454262044135,
)  # FK of (0.7071, 0.4142, 0.5772, -1.2, 1.1, 0.3)
BALL_RADIUS = 0.0254


class _IkBall(Model):
    def inverse_kinematics(self, pose: Any, seed: Any = None, link: str | None = None) -> IKResult:
        position, _orientation, q, _index, _nvars = self._ik_start(pose, seed, link)
        if math.dist(position, BALL_CENTER) < BALL_RADIUS:
            reached = self.pose_of(list(q), self.link_index(link)).position
            return IKResult(
                IKStatus.NO_SOLUTION, tuple(float(v) for v in q), math.dist(reached, position), 0.0
            )
        return super().inverse_kinematics(pose, seed, link)


ik_ball = SimpleNamespace(RobotModel=_IkBall, MoveGroup=Group)


# -- B6 folded_corner: with joint_3 past 3.6 rad AND joint_5 past 3.7 rad (both far past 3.0,
#    which their limits allow: 3.8397 and 3.927), FK takes a wrong "folded" branch: the tool
#    point 1 mm too high. P(uniform) = (0.2397/4.5378) * (0.227/4.7124) = 2.54e-3.

J3_PAST, J5_PAST = 3.6, 3.7


class _FoldedCorner(_Kernel):
    def bad_positions(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        rows = (q[:, 2] > J3_PAST) & (q[:, 4] > J5_PAST)
        out = p.copy()
        out[rows, 2] += ERR
        return out


folded_corner = SimpleNamespace(RobotModel=_FoldedCorner, MoveGroup=Group)
