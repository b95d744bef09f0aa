"""The API around pytorch-kinematics (``pytorch_kinematics``, float64): FK and IK from it.

Use it as ``--targets native,adapters.pytorch_kinematics_adapter:api``.

What comes from where
---------------------
* **From pytorch-kinematics**: URDF reading (``build_serial_chain_from_urdf``,
  its bundled ``urdf_parser_py``), the ``SerialChain`` (moved to float64 with
  ``.to(dtype=torch.float64)``), forward kinematics
  (``SerialChain.forward_kinematics``, batched on the CPU) and inverse kinematics
  (``PseudoInverseIK``: damped least squares on the geometric Jacobian).
* **From the contract** (the twin's non-kinematic code, ``python_impl``): URDF
  validation and errors, chain selection, joint names and order, limits,
  ``home_values``, ``link_names``, argument checks, and ``MoveGroup`` (planning is
  in joint space; its poses come from this library's FK).

Conventions normalized (and nothing else)
-----------------------------------------
============================ ================================================================
pytorch-kinematics           what the adapter does
convention
============================ ================================================================
float32 by default           the chain is moved to float64 (``.to(dtype=torch.float64)``) and
                             every tensor the adapter builds is float64. This does *not* undo
                             the float32 rounding done while parsing (see below)
quaternions are (w, x, y, z) poses are read as 4x4 matrices (``Transform3d.get_matrix()``) and
                             the rotation block becomes the contract's (x, y, z, w), canonical
                             sign (``w >= 0``), by the twin's matrix-to-quaternion conversion;
                             IK targets go in as a float64 ``Transform3d(matrix=...)``
joint vector                 the serial chain's vector holds the movable joints of the path,
                             root to tip: the contract's variables in the same order (checked
                             at load); for a link before the tip, its first entries
frames are named after links FK of any link reads ``forward_kinematics(q, end_only=False)[link]``
                             of the tip's serial chain; IK to link ``L`` uses (once built)
                             ``build_serial_chain_from_urdf(urdf, L)``
root frame                   the serial chain resets its root frame to the identity: the URDF
                             root link, the contract's root frame
URDF text                    handed over as bytes (its lxml parser refuses a ``str`` with an
                             XML encoding declaration)
units                        metres and radians on both sides (nothing to convert)
continuous joints            made revolute joints by the library; IK answers are normalized
                             into (-pi, pi] (representation only)
IK status                    ``IKSolution.converged_any`` -> ``SUCCESS``, else ``NO_SOLUTION``
IK tolerances and budget     ``pos_tolerance = rot_tolerance = IK_EPS`` (defaults 1e-3 m and
                             1e-2 rad would call a millimetre off a success; the library tests
                             norms, so its success implies the contract's per-component
                             criterion) and ``max_iterations = IK_MAX_ITERATIONS`` (default 50)
IK seed                      the contract's step 1 (clamped into the limits, continuous joints
                             normalized) is the only retry config (``retry_configs``, one
                             retry): no random restarts, deterministic. All other parameters
                             are the library's defaults (LM damping 0.1, joint limits enforced
                             afterwards by 2 pi wrapping and clamped refinement)
IK to a link with no         no solver call, the status is the contract's criterion at the seed
variable before it           (as in the contract)
parser messages              its ``urdf_parser_py`` writes "Unknown tag ..." to stderr for every
                             non-kinematic tag it does not model; silenced while loading (its
                             ``on_error`` hook, restored afterwards)
============================ ================================================================

Unsupported, by design
----------------------
* **Mimic joints**: pytorch-kinematics ignores ``<mimic>`` (the joint would be
  an independent variable). A chain with a mimic joint is rejected at load with
  ``URDFError(URDF_UNSUPPORTED)``.
* A URDF the library cannot turn into a serial chain with the contract's
  variables (a chain that ends at its root, which its serial chain cannot)
  is rejected at load with ``URDFError(URDF_UNSUPPORTED)``.

Known library semantics (left visible on purpose)
-------------------------------------------------
* **Precision: float32 at parse time.** ``urdf._convert_transform`` builds every
  joint origin from ``torch.tensor(rpy, dtype=torch.float32)`` and a float32
  ``Transform3d`` (its default dtype), and ``frame.Joint`` normalizes axes in
  float32. ``.to(float64)`` converts the already rounded numbers, so FK carries
  float32 rounding of the URDF constants (about 1e-7 m and rad on these arms)
  although every run-time operation is float64. Joint limits (``chain.low`` and
  ``chain.high``, used by IK) are rounded to float32 too.
* **Link origins**: its ``urdf_parser_py`` reads an ``<origin>`` element directly
  inside ``<link>`` (not part of URDF; urdfdom ignores it) and applies it as an
  offset of that link's frame, which moves every link after it too.
"""

from __future__ import annotations

import math
import os
import types
from typing import Any

import numpy as np
import pytorch_kinematics as pk
import pytorch_kinematics.urdf_parser_py.xml_reflection.core as _xml_core
import torch
from numpy.typing import NDArray

import python_impl
from adapters._common import ik_errors, matrix_pose, meets_criterion, urdf_bytes
from python_impl.angles import normalize_angle
from python_impl.transforms import homogeneous, quaternion_matrix
from robot_api.constants import IK_EPS, IK_MAX_ITERATIONS
from robot_api.errors import ErrorCode, InvalidInputError, URDFError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, IKStatus, JointType, Pose

Matrix = NDArray[np.float64]

DTYPE = torch.float64


def _quiet(message: str) -> None:
    """urdf_parser_py's error hook while the adapter loads (its messages are informational)."""


def _serial_chain(data: bytes, link: str) -> Any:
    """The library's float64 serial chain from the URDF root to ``link``, parser messages silenced."""
    hook = _xml_core.on_error
    _xml_core.on_error = _quiet
    try:
        return pk.build_serial_chain_from_urdf(data, link).to(dtype=DTYPE)
    except Exception as exc:  # noqa: BLE001 - whatever it raises, it cannot read this URDF
        raise URDFError(
            f"pytorch-kinematics cannot build the chain to '{link}': {type(exc).__name__}: {exc}",
            ErrorCode.URDF_UNSUPPORTED,
        ) from None
    finally:
        _xml_core.on_error = hook


class RobotModel(python_impl.RobotModel):
    """A chain loaded from URDF whose kinematics are pytorch-kinematics' (see the module docstring).

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF is unreadable, malformed, unsupported by the contract, has a mimic
        joint on the chain, or cannot be read by pytorch-kinematics (``URDF_UNSUPPORTED``).
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_chains", "_data", "_tip")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        if self.mimic_joints:
            raise URDFError(
                f"pytorch-kinematics ignores mimic joints; the chain to '{self.tip_link}' has "
                f"{', '.join(m.name for m in self.mimic_joints)}",
                ErrorCode.URDF_UNSUPPORTED,
            )
        self._data = urdf_bytes(urdf)
        self._chains: dict[int, Any] = {}
        self._tip = len(self.link_names) - 1
        if self._tip == 0:
            raise URDFError(
                "pytorch-kinematics cannot build a serial chain that ends at its root",
                ErrorCode.URDF_UNSUPPORTED,
            )
        chain = self._chain_to(self._tip)
        names = tuple(chain.get_joint_parameter_names())
        if names != self.joint_names:
            raise URDFError(
                f"pytorch-kinematics' chain has the variables {names}, the contract {self.joint_names}",
                ErrorCode.URDF_UNSUPPORTED,
            )

    def _chain_to(self, index: int) -> Any:
        if index not in self._chains:
            self._chains[index] = _serial_chain(self._data, self.link_names[index])
        return self._chains[index]

    def _matrices(self, q: NDArray[np.float64], link: int) -> Matrix:
        """FK of link index ``link`` for q of shape (N, dof), N >= 1: shape (N, 4, 4)."""
        with torch.no_grad():
            frames = self._chains[self._tip].forward_kinematics(
                torch.as_tensor(q, dtype=DTYPE), end_only=False
            )
            matrix = frames[self.link_names[link]].get_matrix()
        out: Matrix = np.array(np.broadcast_to(matrix.numpy(), (q.shape[0], 4, 4)), dtype=np.float64)
        return out

    def _matrix(self, values: list[float] | NDArray[np.float64], link: int) -> Matrix:
        q = np.asarray(values, dtype=np.float64)[: self.dof].reshape(1, self.dof)
        out: Matrix = self._matrices(q, link)[0]
        return out

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values, by this library's FK."""
        return matrix_pose(self._matrix(values, link))

    def forward_kinematics_batch(
        self, joint_values: NDArray[np.float64], link: str | None = None
    ) -> NDArray[np.float64]:
        """Poses of a link for many configurations (the library's batched FK).

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
        """Joint values that put ``link`` at ``pose``, by the library's ``PseudoInverseIK``.

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
            ``SUCCESS`` when the library reports convergence.
        """
        position, orientation, q, index, nvars = self._ik_start(pose, seed, link)
        target = homogeneous(quaternion_matrix(*orientation), (position[0], position[1], position[2]))
        values = list(q)
        converged = False
        if nvars > 0:
            solver = pk.PseudoInverseIK(
                self._chain_to(index),
                retry_configs=torch.tensor([q[:nvars]], dtype=DTYPE),
                pos_tolerance=IK_EPS,
                rot_tolerance=IK_EPS,
                max_iterations=IK_MAX_ITERATIONS,
            )
            solution = solver.solve(pk.Transform3d(matrix=torch.tensor(target, dtype=DTYPE), dtype=DTYPE))
            values[:nvars] = solution.solutions[0, 0].tolist()
            converged = bool(solution.converged_any[0])
        for i, lim in enumerate(self.joint_limits[:nvars]):
            if lim.type == JointType.CONTINUOUS and math.isfinite(values[i]):
                values[i] = normalize_angle(values[i])
        reached = self._matrix(values, index)
        if nvars == 0:
            converged = meets_criterion(reached, target)
        status = IKStatus.SUCCESS if converged else IKStatus.NO_SOLUTION
        return IKResult(status, tuple(values), *ik_errors(reached, target))


class MoveGroup(python_impl.MoveGroup):
    """moveit_commander's MoveGroupCommander over a simulated arm whose poses come from pytorch-kinematics.

    Parameters
    ----------
    model : RobotModel
        A model of this adapter.
    """

    def __init__(self, model: RobotModel) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidInputError(
                "model: expected an adapters.pytorch_kinematics_adapter.RobotModel, "
                f"got {type(model).__name__}",
                ErrorCode.INVALID_ARGUMENT,
            )
        super().__init__(model)


api = types.SimpleNamespace(RobotModel=RobotModel, MoveGroup=MoveGroup)
"""The implementation to plug in: ``--targets native,adapters.pytorch_kinematics_adapter:api``."""
