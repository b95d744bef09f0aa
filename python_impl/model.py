"""The twin's RobotModel: a kinematic chain from URDF, in pure Python + numpy."""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
from numpy.typing import NDArray

from python_impl import convert, kinematics
from python_impl.angles import normalize_angle
from python_impl.chain import Chain, build_chain
from python_impl.transforms import homogeneous, quaternion, quaternion_matrix
from python_impl.urdf import is_path_source, load_urdf
from robot_api.errors import ErrorCode, InvalidInputError, UnknownNameError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, IKStatus, JointLimit, JointType, MimicJoint, Pose


class RobotModel:
    """A kinematic chain loaded from URDF (hardened XML parser, urdfdom's rules).

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF is unreadable, malformed or unsupported.
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_chain", "_home", "_nvars_cache")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        source, is_path = is_path_source(urdf)
        text = convert.to_string(source, "urdf")
        tip = convert.to_optional_string(tip_link, "tip_link")
        self._chain: Chain = build_chain(load_urdf(text, is_path), tip)
        self._home = tuple(min(max(0.0, lim.lower), lim.upper) for lim in self._chain.limits)
        self._nvars_cache: dict[int, int] = {}

    @property
    def chain(self) -> Chain:
        """The twin's internal chain description (not part of the API)."""
        return self._chain

    @property
    def name(self) -> str:
        """Robot name from the URDF."""
        return self._chain.name

    @property
    def root_link(self) -> str:
        """First link of the chain (the planning frame)."""
        return self._chain.root

    @property
    def tip_link(self) -> str:
        """Last link of the chain (the end effector)."""
        return self._chain.tip

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint variables in order, length ``dof``."""
        return tuple(lim.name for lim in self._chain.limits)

    @property
    def link_names(self) -> tuple[str, ...]:
        """Links of the chain from root to tip."""
        return self._chain.link_names

    @property
    def dof(self) -> int:
        """Number of joint variables."""
        return self._chain.dof

    @property
    def joint_limits(self) -> tuple[JointLimit, ...]:
        """Limits of each variable, length ``dof``."""
        return self._chain.limits

    @property
    def mimic_joints(self) -> tuple[MimicJoint, ...]:
        """Mimic joints on the chain."""
        return self._chain.mimics

    @property
    def home_values(self) -> tuple[float, ...]:
        """The "home" configuration: 0 clamped into each joint's limits."""
        return self._home

    # -- argument checks shared by the methods and by MoveGroup ------------------------------

    def check_vector(self, values: list[float], what: str) -> None:
        """Raise WRONG_LENGTH / NON_FINITE for a converted joint vector."""
        if len(values) != self.dof:
            raise InvalidInputError(
                f"{what}: expected {self.dof} joint values, got {len(values)}", ErrorCode.WRONG_LENGTH
            )
        for name, v in zip(self.joint_names, values, strict=True):
            if not math.isfinite(v):
                raise InvalidInputError(
                    f"{what}: value of joint '{name}' is not finite", ErrorCode.NON_FINITE
                )

    def link_index(self, link: Any) -> int:
        """Index of a link of the chain (the tip for None)."""
        name = convert.to_optional_string(link, "link")
        if name is None:
            return len(self._chain.link_names) - 1
        try:
            return self._chain.link_names.index(name)
        except ValueError:
            raise UnknownNameError(
                f"link '{name}' is not on the chain from '{self.root_link}' to '{self.tip_link}'",
                ErrorCode.UNKNOWN_LINK,
            ) from None

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values."""
        t = kinematics.fk(self._chain, np.array(values, dtype=np.float64), link)
        x, y, z = t[:3, 3].tolist()
        return Pose((x, y, z), quaternion(t[:3, :3]))

    # -- the API ---------------------------------------------------------------------------

    def forward_kinematics(self, joint_values: JointValues, link: str | None = None) -> Pose:
        """Pose of a link for one configuration.

        Parameters
        ----------
        joint_values : sequence of float or ndarray, shape (dof,)
            Joint values (rad, m). Limits are not enforced.
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        Pose
            Position (m) and unit quaternion (x, y, z, w), ``w >= 0``, in the root frame.
        """
        values = convert.to_vector(joint_values, "joint values")
        self.check_vector(values, "joint values")
        return self.pose_of(values, self.link_index(link))

    def forward_kinematics_batch(
        self, joint_values: NDArray[np.float64], link: str | None = None
    ) -> NDArray[np.float64]:
        """Poses of a link for many configurations.

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
        return kinematics.fk_batch(self._chain, q, self.link_index(link))

    def _batch_input(self, rows: Any) -> NDArray[np.float64]:
        what = "joint value rows"
        if isinstance(rows, list | tuple):
            data = []
            for i, row in enumerate(convert.items(rows, what)):
                values = convert.to_vector(row, what)
                if len(values) != self.dof:
                    raise InvalidInputError(
                        f"row {i} has {len(values)} joint values, expected {self.dof}", ErrorCode.WRONG_LENGTH
                    )
                data.append(values)
            q = np.array(data, dtype=np.float64).reshape(len(data), self.dof)
        elif isinstance(rows, np.ndarray):
            if rows.ndim != 2:
                raise convert.bad(what, "expected a 2-D array (N, dof)")
            if rows.dtype.kind not in ("f", "i", "u"):
                raise convert.bad(what, f"array of kind '{rows.dtype.kind}' is not real")
            if rows.shape[1] != self.dof:
                raise InvalidInputError(
                    f"{what}: expected {self.dof} columns, got {rows.shape[1]}", ErrorCode.WRONG_LENGTH
                )
            convert.refuse_masked(rows, what)
            q = convert.as_float64(rows, what)
        else:
            raise convert.bad(what, f"expected a 2-D array or a list of rows, got {type(rows).__name__}")
        finite = np.isfinite(q).all(axis=1)
        if not finite.all():
            raise InvalidInputError(
                f"{what}: row {int(np.argmin(finite))} is not finite", ErrorCode.NON_FINITE
            )
        return q

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose`` (Newton-Raphson, truncated pseudo-inverse).

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
            Status, joint values (within limits), position (m) and orientation (rad) errors.
        """
        position, orientation, q, index, nvars = self._ik_start(pose, seed, link)
        target = homogeneous(quaternion_matrix(*orientation), (position[0], position[1], position[2]))
        ok, values, perr, oerr = kinematics.ik(self._chain, target, q, index, nvars)
        return IKResult(IKStatus.SUCCESS if ok else IKStatus.NO_SOLUTION, tuple(values), perr, oerr)

    def _ik_start(
        self, pose: Pose, seed: JointValues | None, link: str | None
    ) -> tuple[list[float], list[float], list[float], int, int]:
        """The contract's IK step 1, shared with the adapters (docs/api.md, "Inverse kinematics").

        Returns
        -------
        position : list of float, shape (3,)
            Target position (m).
        orientation : list of float, shape (4,)
            Target unit quaternion (x, y, z, w).
        q : list of float, shape (dof,)
            The seed (``home_values`` by default), clamped into the limits,
            continuous joints normalized into (-pi, pi].
        index : int
            Index of ``link`` in ``link_names``.
        nvars : int
            Number of variables before ``link`` (the ones IK may move).
        """
        position, orientation = convert.to_pose(pose)
        q = list(self._home)
        if seed is not None:
            q = convert.to_vector(seed, "seed")
            self.check_vector(q, "seed")
        index = self.link_index(link)
        nvars = self._ik_variables(index)
        for i, lim in enumerate(self._chain.limits):
            q[i] = (
                normalize_angle(q[i])
                if lim.type == JointType.CONTINUOUS
                else min(max(q[i], lim.lower), lim.upper)
            )
        return position, orientation, q, index, nvars

    def _ik_variables(self, link: int) -> int:
        if link not in self._nvars_cache:
            segments = range(link)
            if any(self._chain.mimic[s] for s in segments):
                raise InvalidInputError(
                    f"inverse kinematics to '{self._chain.link_names[link]}' passes through a mimic joint, "
                    "which is not supported",
                    ErrorCode.UNSUPPORTED_OPERATION,
                )
            self._nvars_cache[link] = sum(int(self._chain.variable[s] >= 0) for s in segments)
        return self._nvars_cache[link]


def ik_rotation_errors(
    model: RobotModel, pose: Pose, seed: JointValues | None = None, link: str | None = None
) -> tuple[float, ...]:
    """Rotation error (rad, in [0, pi]) of every Newton-Raphson iterate of
    ``model.inverse_kinematics(pose, seed, link)``, in order.

    A replay of the documented algorithm for the fuzzer's oracle, which looks for iterates in
    KDL's half-turn dead zone (docs/api.md, "Known limitations"); a function rather than a
    method, so that it is no part of ``robot_api.protocol`` nor of the adapters built on this
    model. Same parameters and errors as ``inverse_kinematics``.
    """
    position, orientation, q, index, nvars = model._ik_start(pose, seed, link)
    target = homogeneous(quaternion_matrix(*orientation), (position[0], position[1], position[2]))
    errors: list[float] = []
    kinematics.ik(model.chain, target, q, index, nvars, errors)
    return tuple(errors)
