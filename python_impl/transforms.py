"""Rigid-body math of the twin, written from the textbook formulas (numpy only).

Conventions: rotation matrices act on column vectors; quaternions are (x, y, z, w);
RPY is URDF's fixed-axis roll-pitch-yaw, ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Matrix = NDArray[np.float64]


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Matrix:
    """Rotation matrix of URDF roll-pitch-yaw angles (rad), shape (3, 3)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def homogeneous(rotation: Matrix, translation: tuple[float, float, float]) -> Matrix:
    """4x4 transform from a (3, 3) rotation and a translation (m)."""
    m = np.eye(4)
    m[:3, :3] = rotation
    m[:3, 3] = translation
    return m


def unit(v: tuple[float, float, float]) -> NDArray[np.float64]:
    """``v / |v|``, scaled first so that tiny vectors do not underflow. ``v`` must be non-zero."""
    a = np.asarray(v, dtype=np.float64)
    a = a / np.max(np.abs(a))
    out: NDArray[np.float64] = a / math.sqrt(float(a @ a))
    return out


def skew(v: NDArray[np.float64]) -> Matrix:
    """Cross-product matrix ``[v]x``, shape (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def quaternion(r: Matrix) -> tuple[float, float, float, float]:
    """Canonical unit quaternion (x, y, z, w) of a rotation matrix.

    Shepperd's method (pivot on the largest of w, x, y, z), then the contract's
    sign: ``w >= 0``, and when ``w == 0`` the first non-zero of x, y, z positive.
    """
    m = r.tolist()
    m00, m01, m02 = m[0]
    m10, m11, m12 = m[1]
    m20, m21, m22 = m[2]
    trace = m00 + m11 + m22
    if trace >= m00 and trace >= m11 and trace >= m22:
        s = 2.0 * math.sqrt(1.0 + trace)
        w, x, y, z = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 >= m11 and m00 >= m22:
        s = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)
        w, x, y, z = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 >= m22:
        s = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)
        w, x, y, z = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)
        w, x, y, z = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    if w < 0.0 or (w == 0.0 and next((c for c in (x, y, z) if c != 0.0), 0.0) < 0.0):
        x, y, z, w = -x, -y, -z, -w
    return (x, y, z, w + 0.0)


def quaternion_matrix(x: float, y: float, z: float, w: float) -> Matrix:
    """Rotation matrix of a unit quaternion (x, y, z, w), shape (3, 3)."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def rotation_angle(r: Matrix) -> float:
    """Angle (rad, in [0, pi]) of a rotation matrix, via its canonical quaternion."""
    x, y, z, w = quaternion(r)
    return 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), w)


def rotation_vector(r: Matrix) -> NDArray[np.float64]:
    """Axis times angle (rad) of a rotation matrix: the matrix logarithm, shape (3,).

    Uses the quaternion, which stays accurate near 0 and near pi; at exactly pi
    the axis sign follows the quaternion's canonical sign.
    """
    x, y, z, w = quaternion(r)
    s = math.sqrt(x * x + y * y + z * z)
    if s == 0.0:
        return np.zeros(3)
    angle = 2.0 * math.atan2(s, w)
    return np.array([x, y, z]) * (angle / s)
