"""The API around kinpy: FK and IK from kinpy, everything else from the contract.

Use it as ``--targets native,adapters.kinpy_adapter:api``.

What comes from where
---------------------
* **From kinpy**: URDF reading (``kinpy.build_serial_chain_from_urdf``, kinpy's
  bundled ``urdf_parser_py``), the ``SerialChain``, forward kinematics
  (``SerialChain.forward_kinematics``, quaternion arithmetic through
  ``transformations``) and inverse kinematics (``SerialChain.inverse_kinematics``:
  SciPy BFGS on a matrix residual).
* **From the contract** (the twin's non-kinematic code, ``python_impl``): URDF
  validation and errors, chain selection, joint names and order, limits,
  ``home_values``, ``link_names``, argument checks, and ``MoveGroup`` (planning is
  in joint space; its poses come from kinpy's FK).

Conventions normalized (and nothing else)
-----------------------------------------
============================ ================================================================
kinpy convention             what the adapter does
============================ ================================================================
``Transform.rot`` is a       poses are read through ``Transform.matrix()`` and its rotation
quaternion (w, x, y, z),     block becomes the contract's (x, y, z, w), canonical sign (``w >=
scalar first, sign free      0``), by the twin's matrix-to-quaternion conversion; IK targets go
                             in as ``Transform(rot=(w, x, y, z), pos=...)`` (reordered)
joint vector                 kinpy's serial-chain vector holds the movable joints of the path,
                             root to tip: the contract's variables in the same order (checked
                             at load); for a link before the tip, its first entries
frames are named             FK of any link of the chain reads ``forward_kinematics(q,
``<link>_frame``, FK         end_only=False)[link]`` of the tip's serial chain; IK to link
returns a dict by link name  ``L`` builds (once) ``build_serial_chain_from_urdf(urdf, L)``
root frame                   kinpy's root is the URDF root link with an identity transform:
                             the contract's root frame
URDF text                    kinpy's parser (lxml) refuses a ``str`` with an XML encoding
                             declaration: the adapter hands it the document as bytes
units                        metres and radians on both sides (nothing to convert)
continuous joints            kinpy makes them revolute joints; IK answers are normalized into
                             (-pi, pi] (representation only)
IK has no status             kinpy returns only ``x`` of ``scipy.optimize.minimize``. The
                             adapter reports ``SUCCESS`` exactly when the contract's criterion
                             holds for that vector, evaluated with kinpy's own FK: every
                             component of the error twist within ``IK_EPS`` (1e-6)
IK seed                      the contract's step 1 (clamped into the limits, continuous joints
                             normalized) becomes ``initial_state``
IK solver parameters         none exist (BFGS with SciPy's defaults)
IK to a link with no         no solver call, the status is the contract's criterion at the seed
variable before it           (as in the contract)
parser messages              kinpy's ``urdf_parser_py`` writes "Unknown tag ..." to stderr for
                             every non-kinematic tag it does not model; they are silenced while
                             loading (its ``on_error`` hook, restored afterwards)
============================ ================================================================

Unsupported, by design
----------------------
* **Mimic joints**: kinpy has no mimic support (the mimic joint would be an
  independent variable). A chain with a mimic joint is rejected at load with
  ``URDFError(URDF_UNSUPPORTED)``.
* A URDF kinpy cannot turn into a serial chain with the contract's variables
  (a chain that ends at its root, which kinpy's serial chain cannot) is
  rejected at load with ``URDFError(URDF_UNSUPPORTED)``.

Known library semantics (left visible on purpose)
-------------------------------------------------
* **Link origins**: kinpy's ``urdf_parser_py`` reads an ``<origin>`` element
  directly inside ``<link>`` (not part of URDF; urdfdom ignores it) and kinpy
  applies it as an offset of that link's own pose in FK (the links after it do
  not move).
* **IK**: no joint limits (answers may leave them), no tolerance, and BFGS stops
  on SciPy's gradient tolerance, usually well before the contract's 1e-6.
* Prismatic axes are not normalized (``pos = q * axis``); revolute axes are
  (``quaternion_about_axis``).
"""

from __future__ import annotations

import math
import os
import types
from typing import Any

import kinpy
import kinpy.urdf_parser_py.xml_reflection.core as _xml_core
import numpy as np
from numpy.typing import NDArray

import python_impl
from adapters._common import RowwiseFkModel, ik_errors, matrix_pose, meets_criterion, urdf_bytes
from python_impl.angles import normalize_angle
from python_impl.transforms import homogeneous, quaternion_matrix
from robot_api.errors import ErrorCode, InvalidInputError, URDFError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, IKStatus, JointType, Pose

Matrix = NDArray[np.float64]


def _quiet(message: str) -> None:
    """urdf_parser_py's error hook while the adapter loads (its messages are informational)."""


def _serial_chain(data: bytes, link: str) -> Any:
    """kinpy's serial chain from the URDF root to ``link``, with the parser's messages silenced."""
    hook = _xml_core.on_error
    _xml_core.on_error = _quiet
    try:
        return kinpy.build_serial_chain_from_urdf(data, link)
    except Exception as exc:  # noqa: BLE001 - whatever kinpy raises, it cannot read this URDF
        raise URDFError(
            f"kinpy cannot build the chain to '{link}': {type(exc).__name__}: {exc}",
            ErrorCode.URDF_UNSUPPORTED,
        ) from None
    finally:
        _xml_core.on_error = hook


class RobotModel(RowwiseFkModel):
    """A chain loaded from URDF whose kinematics are kinpy's (see the module docstring).

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF is unreadable, malformed, unsupported by the contract, has a
        mimic joint on the chain, or cannot be read by kinpy (``URDF_UNSUPPORTED``).
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_chains", "_data", "_tip")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        if self.mimic_joints:
            raise URDFError(
                f"kinpy has no mimic joints; the chain to '{self.tip_link}' has "
                f"{', '.join(m.name for m in self.mimic_joints)}",
                ErrorCode.URDF_UNSUPPORTED,
            )
        self._data = urdf_bytes(urdf)
        self._chains: dict[int, Any] = {}
        self._tip = len(self.link_names) - 1
        if self._tip == 0:
            raise URDFError(
                "kinpy cannot build a serial chain that ends at its root", ErrorCode.URDF_UNSUPPORTED
            )
        chain = self._chain_to(self._tip)
        names = tuple(chain.get_joint_parameter_names())
        if names != self.joint_names:
            raise URDFError(
                f"kinpy's chain has the variables {names}, the contract {self.joint_names}",
                ErrorCode.URDF_UNSUPPORTED,
            )

    def _chain_to(self, index: int) -> Any:
        if index not in self._chains:
            self._chains[index] = _serial_chain(self._data, self.link_names[index])
        return self._chains[index]

    def _matrix(self, values: list[float] | NDArray[np.float64], link: int) -> Matrix:
        frames = self._chains[self._tip].forward_kinematics(
            [float(v) for v in values[: self.dof]], end_only=False
        )
        return np.asarray(frames[self.link_names[link]].matrix(), dtype=np.float64)

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values, by kinpy's FK."""
        return matrix_pose(self._matrix(values, link))

    def _row_matrix(self, row: NDArray[np.float64], link: int) -> NDArray[np.float64]:
        """The library's transform of link index ``link`` for one row (batch FK)."""
        return self._matrix(row, link)

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose``, by kinpy's ``inverse_kinematics``.

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
            ``SUCCESS`` when kinpy's answer meets the contract's criterion (by kinpy's FK).
        """
        position, orientation, q, index, nvars = self._ik_start(pose, seed, link)
        target = homogeneous(quaternion_matrix(*orientation), (position[0], position[1], position[2]))
        values = list(q)
        if nvars > 0:
            x, y, z, w = orientation
            goal = kinpy.Transform(rot=[w, x, y, z], pos=np.array(position))
            answer = self._chain_to(index).inverse_kinematics(goal, np.array(q[:nvars]))
            values[:nvars] = np.asarray(answer, dtype=np.float64).tolist()
        for i, lim in enumerate(self.joint_limits[:nvars]):
            if lim.type == JointType.CONTINUOUS and math.isfinite(values[i]):
                values[i] = normalize_angle(values[i])
        reached = self._matrix(values, index)
        status = IKStatus.SUCCESS if meets_criterion(reached, target) else IKStatus.NO_SOLUTION
        return IKResult(status, tuple(values), *ik_errors(reached, target))


class MoveGroup(python_impl.MoveGroup):
    """moveit_commander's MoveGroupCommander over a simulated arm whose poses come from kinpy.

    Parameters
    ----------
    model : RobotModel
        A model of this adapter.
    """

    def __init__(self, model: RobotModel) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidInputError(
                f"model: expected an adapters.kinpy_adapter.RobotModel, got {type(model).__name__}",
                ErrorCode.INVALID_ARGUMENT,
            )
        super().__init__(model)


api = types.SimpleNamespace(RobotModel=RobotModel, MoveGroup=MoveGroup)
"""The implementation to plug in: ``--targets native,adapters.kinpy_adapter:api``."""
