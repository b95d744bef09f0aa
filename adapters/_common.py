"""Helpers shared by the adapters around the Python kinematics libraries.

Only the contract's side lives here (the URDF bytes a library's own parser
reads, the pose and IK criterion of the contract, evaluated on the library's
matrices); every kinematic quantity still comes from the library.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

import python_impl
from python_impl.transforms import quaternion, rotation_angle, rotation_vector
from python_impl.urdf import is_path_source
from robot_api.constants import IK_EPS
from robot_api.errors import ErrorCode, URDFError
from robot_api.records import Pose

Matrix = NDArray[np.float64]


def urdf_bytes(urdf: Any) -> bytes:
    """The URDF document the contract just accepted, as bytes for the library's own parser."""
    source, is_path = is_path_source(urdf)
    assert isinstance(source, str)  # the contract's checks ran first
    if not is_path:
        return source.encode("utf-8")
    try:
        with open(source, "rb") as handle:
            return handle.read()
    except OSError as exc:  # the file went away between two reads
        raise URDFError(f"cannot read URDF file '{source}': {exc}", ErrorCode.URDF_INVALID) from None


def matrix_pose(t: Matrix) -> Pose:
    """The contract's pose (position, canonical quaternion) of a 4x4 transform."""
    x, y, z = (float(v) for v in t[:3, 3])
    return Pose((x, y, z), quaternion(t[:3, :3]))


def canonical_quaternion(coeffs: Sequence[float]) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) with the contract's sign, from a library's (x, y, z, w)
    of either sign (KDL's ``GetQuaternion()``, pinocchio's ``coeffs()``)."""
    x, y, z, w = (float(c) for c in coeffs)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    if w < 0.0 or (w == 0.0 and next((c for c in (x, y, z) if c != 0.0), 0.0) < 0.0):
        x, y, z, w = -x, -y, -z, -w
    return (x, y, z, w + 0.0)


def meets_criterion(reached: Matrix, target: Matrix) -> bool:
    """The contract's convergence criterion: every error twist component within IK_EPS."""
    rot = reached[:3, :3]
    twist = np.concatenate([target[:3, 3] - reached[:3, 3], rot @ rotation_vector(rot.T @ target[:3, :3])])
    return bool(np.all(np.abs(twist) <= IK_EPS))


def ik_errors(reached: Matrix, target: Matrix) -> tuple[float, float]:
    """The contract's IK errors: distance (m) and rotation angle (rad) from reached to target."""
    return (
        float(np.linalg.norm(reached[:3, 3] - target[:3, 3])),
        rotation_angle(reached[:3, :3].T @ target[:3, :3]),
    )


class RowwiseFkModel(python_impl.RobotModel):
    """A model whose batch FK is the library's single-configuration FK, one row at a time.

    An adapter names the library's transform in :meth:`_row_matrix`; the batch method, its
    checks (``_batch_input``, ``link_index``) and its documentation are shared.
    """

    __slots__ = ()  # keeps the subclasses' slot layouts (pybullet's declares __weakref__)

    def _row_matrix(self, row: Matrix, link: int) -> Matrix:
        """The library's transform (4, 4) of link index ``link`` for one row of checked values."""
        raise NotImplementedError

    def forward_kinematics_batch(self, joint_values: Matrix, link: str | None = None) -> Matrix:
        """Poses of a link for many configurations (the library's FK, one row at a time).

        Parameters
        ----------
        joint_values : ndarray, shape (N, dof), or list of N rows
            Joint values (rad, m).
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        ndarray, shape (N, 4, 4)
            Homogeneous transforms in the root frame.
        """
        q = self._batch_input(joint_values)
        index = self.link_index(link)
        out = np.empty((q.shape[0], 4, 4))
        for i, row in enumerate(q):
            out[i] = self._row_matrix(row, index)
        return out
