"""The API around PyBullet: link frames from Bullet's URDF importer and ``getLinkState``.

Use it as ``--targets native,adapters.pybullet_adapter:api``.

What comes from where
---------------------
* **From PyBullet**: URDF reading (``loadURDF`` of Bullet's own importer, in a
  private ``DIRECT`` client per model), joint placement (``resetJointState``) and
  forward kinematics (``getLinkState(..., computeForwardKinematics=True)``) and
  inverse kinematics (``calculateInverseKinematics``: damped least squares).
* **From the contract**: everything else (``adapters/_engines.py``).

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
PyBullet convention             what the adapter does
=============================== =============================================================
``loadURDF`` reads a file        the (geometry-free) document is written to a private temporary
                                file, loaded, and the file removed
base pose is the base's         the root link's frame is the base inertial frame composed with
*inertial* frame                the inverse of its local inertial frame (``getDynamicsInfo``
(``getBasePositionAndOrientation``) indices 3 and 4); the base is loaded with ``useFixedBase``
link state: centre of mass      the URDF link frame is read: ``worldLinkFramePosition`` and
first, link frame at 4 and 5    ``worldLinkFrameOrientation`` (indices 4 and 5)
quaternions (x, y, z, w)        turned into matrices by ``getMatrixFromQuaternion``
links are numbered by their     link names (``getJointInfo``'s index 12) and joint names map
parent joint; base is -1        the contract's links and variables to Bullet indices
fixed links                     kept (``URDF_MERGE_FIXED_LINKS`` is not passed)
inertia from the URDF           ``URDF_USE_INERTIA_FROM_FILE`` (no effect on frames)
geometry                        removed before loading (``_engines.kinematic_urdf``)
crashes                         an empty link or joint name (``loadURDF`` segfaults) is refused
                                with ``URDFError(URDF_UNSUPPORTED)`` before loading
IK has no status                PyBullet returns joint values only: ``SUCCESS`` exactly when the
                                contract's criterion (every error twist component within 1e-6)
                                holds for them by PyBullet's FK
IK frames and seed              the target is moved from the root frame into PyBullet's world;
                                the clamped seed is the joint state the solver starts from;
                                answers are one per movable joint, mapped back by joint index
IK parameters                   ``maxNumIterations=200`` (default 20), ``residualThreshold`` 1e-12;
                                no null-space limits (answers may leave the limits)
importer messages               Bullet prints a warning per link without ``<inertial>``: the
                                C-level stdout/stderr are silenced while loading
=============================== =============================================================

Known library semantics (left visible on purpose)
-------------------------------------------------
* **Single precision**: the URDF constants and the link frames come back rounded to
  float32 (``<origin xyz="0 0 0.0315">`` reads back as 0.03150000050663948), so FK
  agrees with ``native`` to about 6e-7, not 1e-9: campaigns use ``--tolerance=1e-5``.
* **Axes are not normalized**: see ``FINDINGS.md`` (a non-unit axis is not URDF).
* **IK** rarely reaches the contract's 1e-6 (single precision, damped least
  squares): 0 to 7 of 30 nearby-seed targets on PROBOT Anno, UR5 and Panda, where
  ``native`` solves 28-29; IK campaigns report ``status`` buckets (C-2).
"""

from __future__ import annotations

import os
import tempfile
import weakref
from typing import Any

import numpy as np

from adapters._common import IkAnswer, IkTarget, LibraryModel, make_api, matrix_pose
from adapters._engines import EngineModel, Matrix, quiet_stdio, unsupported
from python_impl.urdf import Urdf
from robot_api.protocol import JointValues
from robot_api.records import IKResult, Pose

with quiet_stdio():  # "pybullet build time: ..." on import
    import pybullet


def _transform(client: int, position: Any, orientation: Any) -> Matrix:
    t = np.eye(4)
    t[:3, :3] = np.asarray(pybullet.getMatrixFromQuaternion(orientation, physicsClientId=client)).reshape(
        3, 3
    )
    t[:3, 3] = position
    return t


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are PyBullet's (see the module docstring)."""

    __slots__ = ("__weakref__", "_base_local", "_client", "_dofs", "_joints", "_links")
    LIBRARY = "PyBullet"

    def _crashes_on(self, document: Urdf) -> str:
        if "" in document.links or "" in document.joints:
            return "pybullet's loadURDF segfaults on an empty link or joint name (F-PYBULLET-2)"
        return ""

    def _load(self, data: bytes) -> Any:
        with quiet_stdio():  # "pybullet build time: ..." on the first connect
            self._client = pybullet.connect(pybullet.DIRECT)
        weakref.finalize(self, pybullet.disconnect, self._client)
        fd, path = tempfile.mkstemp(suffix=".urdf")
        try:
            with os.fdopen(fd, "wb") as handle:
                handle.write(data)
            with quiet_stdio():  # a b3Warning for every link without <inertial>
                body = pybullet.loadURDF(
                    path,
                    useFixedBase=True,
                    flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
                    physicsClientId=self._client,
                )
        finally:
            os.unlink(path)
        if body < 0:
            raise unsupported(self.LIBRARY, "loadURDF failed")
        links: dict[str, int] = {pybullet.getBodyInfo(body, physicsClientId=self._client)[0].decode(): -1}
        joints: dict[str, int] = {}
        movable: list[int] = []  # calculateInverseKinematics answers one value per movable joint, in order
        for j in range(pybullet.getNumJoints(body, physicsClientId=self._client)):
            info = pybullet.getJointInfo(body, j, physicsClientId=self._client)
            joints[info[1].decode()] = j
            links[info[12].decode()] = j
            if info[2] != pybullet.JOINT_FIXED:
                movable.append(j)
        missing = [n for n in self.link_names if n not in links] + [
            n for n in self.joint_names if n not in joints
        ]
        if missing:
            raise unsupported(self.LIBRARY, f"no link or joint named {', '.join(missing)} in the loaded body")
        self._links = tuple(links[n] for n in self.link_names)
        self._joints = tuple(joints[n] for n in self.joint_names)
        self._dofs = tuple(movable.index(j) for j in self._joints)
        info = pybullet.getDynamicsInfo(body, -1, physicsClientId=self._client)
        self._base_local = np.linalg.inv(_transform(self._client, info[3], info[4]))
        return body

    def _frame(self, link: int) -> Matrix:
        index = self._links[link]
        if index < 0:
            pos, orn = pybullet.getBasePositionAndOrientation(self._lib, physicsClientId=self._client)
            return _transform(self._client, pos, orn) @ self._base_local
        state = pybullet.getLinkState(
            self._lib, index, computeForwardKinematics=True, physicsClientId=self._client
        )
        return _transform(self._client, state[4], state[5])

    def _frames(self, values: list[float], links: tuple[int, ...]) -> list[Matrix]:
        for joint, value in zip(self._joints, values, strict=True):
            pybullet.resetJointState(self._lib, joint, value, physicsClientId=self._client)
        return [self._frame(link) for link in links]

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose``, by PyBullet's ``calculateInverseKinematics``.

        Parameters
        ----------
        pose : Pose or (position, orientation)
            Target in the root frame; the quaternion (x, y, z, w) is normalized.
        seed : sequence of float, shape (dof,), optional
            Start of the search (the joint state PyBullet starts from), clamped into
            the limits; ``home_values`` by default.
        link : str, optional
            A link of the chain; the tip by default.

        Returns
        -------
        IKResult
            ``SUCCESS`` when PyBullet's answer meets the contract's criterion (by PyBullet's FK).
        """
        # the shared IK wrapper, past EngineModel's FK-only refusal
        return LibraryModel.inverse_kinematics(self, pose, seed, link)

    def _ik_answer(self, target: IkTarget, q: list[float], index: int, nvars: int) -> IkAnswer:
        """PyBullet's answer from the seed's joint state, to the target in its world; no status."""
        if self._links[index] < 0:
            return q[:nvars], None
        root = self._frames(q, (0,))[0]  # also puts the seed into PyBullet's joint state
        world = root @ target.matrix
        goal = matrix_pose(world)
        answer = pybullet.calculateInverseKinematics(
            self._lib,
            self._links[index],
            goal.position,
            goal.orientation,
            maxNumIterations=IK_ITERATIONS,
            residualThreshold=1e-12,
            physicsClientId=self._client,
        )
        return [float(answer[self._dofs[i]]) for i in range(nvars)], None


IK_ITERATIONS = 200
"""``maxNumIterations`` of ``calculateInverseKinematics`` (PyBullet's default is 20)."""

api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.pybullet_adapter:api``."""
MoveGroup = api.MoveGroup
