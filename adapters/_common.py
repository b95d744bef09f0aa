"""Helpers shared by the adapters around the Python kinematics libraries.

Only the contract's side lives here (the URDF bytes a library's own parser
reads, the pose and IK criterion of the contract, evaluated on the library's
matrices, and the adapters' common skeleton: :class:`LibraryModel`'s checks and
IK wrapper around the library's calls, :class:`SerialChainModel` for kinpy and
pytorch-kinematics, :func:`make_api`); every kinematic quantity still comes from
the library.
"""

from __future__ import annotations

import math
import os
import types
from collections.abc import Sequence
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import NDArray

import python_impl
from python_impl.angles import normalize_angle
from python_impl.transforms import (
    homogeneous,
    quaternion,
    quaternion_matrix,
    rotation_angle,
    rotation_vector,
)
from python_impl.urdf import is_path_source
from robot_api.constants import IK_EPS
from robot_api.errors import ErrorCode, InvalidInputError, URDFError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, IKStatus, JointType, Pose

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


def finite_or_seed(values: Sequence[float], seed: Sequence[float]) -> tuple[list[float], bool]:
    """An IK answer, or the clamped ``seed`` when a value is not finite (an absurd target such as
    1e308 m made an iterate inf or NaN), and whether it was finite: the contract's rule
    (docs/api.md: "never NaN"; ``NO_SOLUTION``), as ``native`` and the twin keep it."""
    if all(math.isfinite(v) for v in values):
        return list(values), True
    return list(seed), False


def ik_result(
    converged: bool, values: Sequence[float], reached: Matrix, position: Matrix, rotation: Matrix
) -> IKResult:
    """The IKResult of the contract's loop (pinocchio, PyKDL): errors as ``native`` computes them.

    Parameters
    ----------
    converged : bool
        The loop's status.
    values : sequence of float, shape (dof,)
        The answer.
    reached : ndarray, shape (4, 4)
        The library's transform of the link for ``values``.
    position : ndarray, shape (3,)
        Target position (m).
    rotation : ndarray, shape (3, 3)
        Target rotation.

    Returns
    -------
    IKResult
        Status, values, position error (m, ``sqrt`` of the sum of squares, NaN passes through)
        and orientation error (rad).
    """
    with np.errstate(all="ignore"):
        d = reached[:3, 3] - position
        position_error = math.sqrt(float(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
    orientation_error = rotation_angle(reached[:3, :3].T @ rotation)
    status = IKStatus.SUCCESS if converged else IKStatus.NO_SOLUTION
    return IKResult(status, tuple(values), position_error, orientation_error)


def refuse_mimic_joints(model: python_impl.RobotModel, why: str) -> None:
    """Raise ``URDFError(URDF_UNSUPPORTED)``, saying ``why``, if the model's chain has mimic joints."""
    if model.mimic_joints:
        raise URDFError(
            f"{why}; the chain to '{model.tip_link}' has {', '.join(m.name for m in model.mimic_joints)}",
            ErrorCode.URDF_UNSUPPORTED,
        )


class IkTarget(NamedTuple):
    """An IK target in the root frame, in the forms the libraries take."""

    matrix: Matrix
    """Homogeneous transform (4, 4), metres."""
    position: list[float]
    """Position (m), shape (3,)."""
    orientation: list[float]
    """Unit quaternion (x, y, z, w)."""


IkAnswer = tuple[list[float], bool | None]
"""A library's IK answer for the variables before the link, and its status (None: it has none)."""


class LibraryModel(python_impl.RobotModel):
    """A model whose poses are a library's 4x4 transforms.

    An adapter names the library's transform of one configuration in :meth:`_matrix`
    (or overrides :meth:`pose_of` and :meth:`_row_matrix`), a library with batched FK
    overrides :meth:`_matrices`, and a library with an IK solver names its call in
    :meth:`_ik_answer`. The public methods, their checks and their documentation are shared.
    """

    __slots__ = ()  # keeps the subclasses' slot layouts (pybullet's declares __weakref__)

    def _matrix(self, values: list[float] | Matrix, link: int) -> Matrix:
        """The library's transform (4, 4) of link index ``link`` for checked values."""
        raise NotImplementedError

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values, by the library's FK."""
        return matrix_pose(self._matrix(values, link))

    def _row_matrix(self, row: Matrix, link: int) -> Matrix:
        """The library's transform (4, 4) of link index ``link`` for one row of checked values."""
        return self._matrix(row, link)

    def _matrices(self, q: Matrix, link: int) -> Matrix:
        """The library's transforms (N, 4, 4) of link index ``link`` for checked rows q (N, dof), N >= 1.

        One row at a time (:meth:`_row_matrix`) unless the library's FK takes batches.
        """
        out = np.empty((q.shape[0], 4, 4))
        for i, row in enumerate(q):
            out[i] = self._row_matrix(row, link)
        return out

    def forward_kinematics_batch(self, joint_values: Matrix, link: str | None = None) -> Matrix:
        """Poses of a link for many configurations, by the library's FK (see the module docstring).

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
        if q.shape[0] == 0:
            return np.zeros((0, 4, 4))
        return self._matrices(q, index)

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose``, by the library's IK (see the module docstring).

        Parameters
        ----------
        pose : Pose or (position, orientation)
            Target; the quaternion (x, y, z, w) is normalized.
        seed : sequence of float, shape (dof,), optional
            Start of the search, clamped into the limits; ``home_values`` by default.
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        IKResult
            The library's answer (continuous joints normalized into (-pi, pi]), and its position
            (m) and orientation (rad) errors by the library's FK. ``SUCCESS`` when the library
            reports success; for a library without a status, or with no variable before ``link``
            (no solver call), when the answer meets the contract's criterion by the library's FK.
        """
        position, orientation, q, index, nvars = self._ik_start(pose, seed, link)
        target = homogeneous(quaternion_matrix(*orientation), (position[0], position[1], position[2]))
        values = list(q)
        converged: bool | None = None
        if nvars > 0:
            answer, converged = self._ik_answer(IkTarget(target, position, orientation), q, index, nvars)
            values[:nvars] = answer
        for i, lim in enumerate(self.joint_limits[:nvars]):
            if lim.type == JointType.CONTINUOUS and math.isfinite(values[i]):
                values[i] = normalize_angle(values[i])
        values, finite = finite_or_seed(values, q)
        reached = self._matrix(values, index)
        if not finite:
            converged = False
        elif converged is None:
            converged = meets_criterion(reached, target)
        status = IKStatus.SUCCESS if converged else IKStatus.NO_SOLUTION
        return IKResult(status, tuple(values), *ik_errors(reached, target))

    def _ik_answer(self, target: IkTarget, q: list[float], index: int, nvars: int) -> IkAnswer:
        """The library's IK call, for :meth:`inverse_kinematics`.

        Parameters
        ----------
        target : IkTarget
            The target in the root frame: transform (4, 4), position (m), quaternion (x, y, z, w).
        q : list of float, shape (dof,)
            The seed, clamped into the limits, continuous joints normalized.
        index : int
            Index of the link in ``link_names``.
        nvars : int
            Number of variables before the link (at least 1).

        Returns
        -------
        values : list of float, shape (nvars,)
            The library's answer for the first ``nvars`` variables.
        converged : bool or None
            The library's status, or None when it has none (the contract's criterion decides).
        """
        raise NotImplementedError


def _quiet(message: str) -> None:
    """urdf_parser_py's error hook while the adapter loads (its messages are informational)."""


class SerialChainModel(LibraryModel):
    """A model on a library's serial chains from the URDF root to a link (kinpy, and its port
    pytorch-kinematics): one chain per link, built once by :meth:`_build_chain` with the
    library's ``urdf_parser_py`` (``_PARSER``) silenced; FK of any link reads the tip's chain,
    whose variables must be the contract's.
    """

    __slots__ = ("_chains", "_data", "_tip")
    _LIBRARY: ClassVar[str] = "?"
    _NO_MIMIC: ClassVar[str] = "?"
    """Why a chain with mimic joints is refused (the start of the load error)."""
    _PARSER: ClassVar[Any] = None
    """The library's ``urdf_parser_py.xml_reflection.core`` module (its ``on_error`` hook)."""

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        refuse_mimic_joints(self, self._NO_MIMIC)
        self._data = urdf_bytes(urdf)
        self._chains: dict[int, Any] = {}
        self._tip = len(self.link_names) - 1
        if self._tip == 0:
            raise URDFError(
                f"{self._LIBRARY} cannot build a serial chain that ends at its root",
                ErrorCode.URDF_UNSUPPORTED,
            )
        chain = self._chain_to(self._tip)
        names = tuple(chain.get_joint_parameter_names())
        if names != self.joint_names:
            owner = f"{self._LIBRARY}'" if self._LIBRARY.endswith("s") else f"{self._LIBRARY}'s"
            raise URDFError(
                f"{owner} chain has the variables {names}, the contract {self.joint_names}",
                ErrorCode.URDF_UNSUPPORTED,
            )

    def _build_chain(self, data: bytes, link: str) -> Any:
        """The library's serial chain from the URDF root to ``link`` (raises anything when it cannot)."""
        raise NotImplementedError

    def _chain_to(self, index: int) -> Any:
        """The serial chain to link index ``index``, built once, with the parser's messages silenced."""
        if index not in self._chains:
            link = self.link_names[index]
            hook = self._PARSER.on_error
            self._PARSER.on_error = _quiet
            try:
                self._chains[index] = self._build_chain(self._data, link)
            except Exception as exc:  # noqa: BLE001 - whatever the library raises, it cannot read this URDF
                raise URDFError(
                    f"{self._LIBRARY} cannot build the chain to '{link}': {type(exc).__name__}: {exc}",
                    ErrorCode.URDF_UNSUPPORTED,
                ) from None
            finally:
                self._PARSER.on_error = hook
        return self._chains[index]


def make_api(model_cls: type[python_impl.RobotModel], module: str) -> types.SimpleNamespace:
    """The ``api`` namespace of an adapter: its RobotModel and a MoveGroup that accepts only it."""

    class MoveGroup(python_impl.MoveGroup):
        """moveit_commander's MoveGroupCommander over a simulated arm whose poses come from the library.

        Parameters
        ----------
        model : RobotModel
            A model of this adapter.
        """

        def __init__(self, model: python_impl.RobotModel) -> None:
            if not isinstance(model, model_cls):
                raise InvalidInputError(
                    f"model: expected an {module}.RobotModel, got {type(model).__name__}",
                    ErrorCode.INVALID_ARGUMENT,
                )
            super().__init__(model)

    MoveGroup.__module__ = module
    MoveGroup.__qualname__ = "MoveGroup"
    return types.SimpleNamespace(RobotModel=model_cls, MoveGroup=MoveGroup)
