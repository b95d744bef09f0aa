"""The API around the Robotics Toolbox for Python (``roboticstoolbox``): FK and IK from it.

Use it as ``--targets native,adapters.rtb_adapter:api``.

What comes from where
---------------------
* **From the toolbox**: URDF reading (``roboticstoolbox.models.URDF.URDFRobot.URDF_file``,
  which is what the deprecated ``Robot.URDF`` calls: xacro expansion, the
  toolbox's URDF parser, each joint turned into an elementary transform
  sequence), the ``Robot``, forward kinematics (``Robot.ets(start, end)`` evaluated
  by the compiled ``ETS.eval``/``fkine``) and inverse kinematics (``ETS.ik_LM``,
  the compiled Levenberg-Marquardt solver, Chan's damping; the same call as
  ``Robot.ik_LM(Tep, end, start)``).
* **From the contract** (the twin's non-kinematic code, ``python_impl``): URDF
  validation and errors, chain selection, joint names and order, limits,
  ``home_values``, ``link_names``, argument checks, and ``MoveGroup`` (planning is
  in joint space; its poses come from the toolbox's FK).

Conventions normalized (and nothing else)
-----------------------------------------
============================ ================================================================
toolbox convention           what the adapter does
============================ ================================================================
poses are ``SE3`` / 4x4      the rotation block becomes the contract's quaternion (x, y, z, w),
arrays (``UnitQuaternion``   canonical sign (``w >= 0``), by the twin's matrix-to-quaternion
is (w, x, y, z))             conversion; IK targets go in as 4x4 arrays built from (x, y, z, w)
global ``q`` (length         the adapter uses the *compact* form the toolbox documents for
``robot.n``: every joint of  ``ets(start=root, end=link)``: the joints on the path, root to link,
the tree, by ``jindex``)     which are the contract's first variables in the same order
base and tool transforms     both identity (not set); ``start`` is the URDF root link, so the
                             root frame is the contract's
units                        metres and radians on both sides (nothing to convert)
continuous joints            the toolbox makes them revolute joints; IK answers are normalized
                             into (-pi, pi] (representation only)
IK status                    ``IKSolution.success`` -> ``SUCCESS``, else ``NO_SOLUTION``
IK tolerance                 the toolbox's ``tol`` bounds ``E = 1/2 e^T e`` (e: position and
                             angle-axis error). ``tol = IK_EPS**2 / 2`` makes its success imply
                             the contract's ``|e_i| <= IK_EPS`` (its default 1e-6 would accept
                             errors up to 1.4 mm)
IK iterations and restarts   ``ilimit = IK_MAX_ITERATIONS`` (100) and ``slimit = 1``: one search
                             from the given seed, like the contract. The default (100 searches
                             from random ``rand()`` restarts) ignores the seed after the first
                             search and is not deterministic
IK seed                      the contract's step 1 (clamped into the limits, continuous joints
                             normalized) becomes ``q0``
IK to a link with no         the toolbox cannot solve for zero variables: no solver call, the
variable before it           status is the contract's criterion at the seed (as in the contract)
zero joints (FK of the root  ``ETS.eval(np.zeros(0))`` raises ``TypeError`` (spatialmath's
or of a link before the      ``getmatrix`` refuses an empty 1-D array) while ``eval([])`` works:
first joint)                 single configurations are passed as lists (found by the fuzzer)
batches of one-joint chains  ``ETS.eval(q)`` with ``q`` of shape (N, 1) returns *one* pose, that
                             of ``q[0, 0]``: spatialmath's ``getmatrix`` turns the column into a
                             row, which ``_resolve_q`` takes for a "global" joint vector. The
                             adapter evaluates such batches row by row (found by the tests)
URDF parts that are not      the toolbox loads meshes (``package://`` must resolve, a missing mesh
kinematics                   is an error), checks inertias and transmissions, none of which
                             urdfdom or the contract look at. The adapter hands it the
                             document with only ``<joint>`` elements and *empty* ``<link>``
                             elements (names kept): no visual, collision, inertial,
                             transmission, material or gazebo data. Joints are passed untouched
warnings                     the toolbox's ``warnings`` (deprecations, ...) are silenced
============================ ================================================================

Unsupported, by design
----------------------
* **Mimic joints**: the toolbox ignores ``<mimic>`` (the joint becomes an
  independent variable). A chain with a mimic joint is rejected at load with
  ``URDFError(URDF_UNSUPPORTED)``.
* A URDF the toolbox cannot load (xacro or parser errors on something the
  contract accepts, for instance ``${`` in an attribute, which xacro evaluates)
  is rejected at load with ``URDFError(URDF_UNSUPPORTED)``.

Known library semantics (left visible on purpose)
-------------------------------------------------
* **Joint axes that are not along x, y or z are wrong** (``URDFRobot._links_from_urdf``):
  the toolbox rotates the joint frame by ``angvec2r(|axis|, axis)``, a rotation
  of 1 rad about the axis, and makes the joint turn about the new z. This is not
  a rotation that maps z onto the axis, and it also rotates the child frame: FK
  is off even at q = 0 (by 0.73 on the matrix, axis ``0 0.6 0.8``, in
  ``tests/test_adapters_py_libs.py``).
* IK limits: the toolbox rejects answers outside its ``qlim``, which is the
  URDF's ``lower``/``upper`` even for continuous joints (Kinova: +-2pi), and
  ``[-pi, pi]`` when the URDF gives none (the contract: unbounded for
  continuous joints, ``[0, 0]`` for a revolute joint without ``lower``/``upper``).
  Levenberg-Marquardt does not clamp and does not wrap by 2 pi: PROBOT Anno's
  pose at ``joint_3 = -0.6981`` (its lower limit) is reached as ``5.585085``
  (``-0.6981 + 2 pi``), rejected, and the call fails where the contract succeeds.
* After a rejected or failed search, ``IKSolution.q`` is the *random* start the
  solver drew for the next search (``searches`` = ``slimit + 1``), different on
  every call: failed answers are not reproducible (the status is).
"""

from __future__ import annotations

import io
import os
import warnings
import xml.etree.ElementTree as ET
from typing import Any

import defusedxml.ElementTree as SafeET
import numpy as np
import roboticstoolbox as rtb
from numpy.typing import NDArray
from roboticstoolbox.models.URDF.URDFRobot import URDF_file

from adapters._common import IkAnswer, IkTarget, LibraryModel, make_api, refuse_mimic_joints, urdf_bytes
from robot_api.constants import IK_EPS, IK_MAX_ITERATIONS
from robot_api.errors import ErrorCode, URDFError

Matrix = NDArray[np.float64]

RTB_TOL = IK_EPS * IK_EPS / 2.0
"""The toolbox's ``tol`` (on ``E = 1/2 |e|^2``) that makes its success imply ``|e_i| <= IK_EPS``."""


def _kinematic_document(data: bytes) -> str:
    """The URDF with its joints and (emptied) links only: what the toolbox needs for kinematics."""
    root = SafeET.fromstring(data)
    for child in list(root):
        if child.tag == "link":
            for part in list(child):
                child.remove(part)
        elif child.tag != "joint":
            root.remove(child)
    return ET.tostring(root, encoding="unicode")


class RobotModel(LibraryModel):
    """A chain loaded from URDF whose kinematics are the Robotics Toolbox's (see the module docstring).

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
        mimic joint on the chain, or cannot be loaded by the toolbox (``URDF_UNSUPPORTED``).
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_ets", "_nvars", "_robot")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        refuse_mimic_joints(self, "the Robotics Toolbox ignores mimic joints")
        document = _kinematic_document(urdf_bytes(urdf))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                elinks, name, _ = URDF_file(io.StringIO(document))
                self._robot = rtb.Robot(elinks, name=name)
                ets = [self._robot.ets(start=self.root_link, end=link) for link in self.link_names]
        except Exception as exc:  # noqa: BLE001 - whatever the toolbox raises, it cannot load this URDF
            raise URDFError(
                f"the Robotics Toolbox cannot load this URDF: {type(exc).__name__}: {exc}",
                ErrorCode.URDF_UNSUPPORTED,
            ) from None
        self._ets: tuple[Any, ...] = tuple(ets)
        self._nvars = tuple(self._ik_variables(k) for k in range(len(self.link_names)))
        for k, e in enumerate(self._ets):
            if int(e.n) != self._nvars[k]:
                raise URDFError(
                    f"the Robotics Toolbox sees {e.n} joints on the path to '{self.link_names[k]}', "
                    f"the contract {self._nvars[k]}",
                    ErrorCode.URDF_UNSUPPORTED,
                )

    def _matrix(self, values: list[float] | NDArray[np.float64], link: int) -> Matrix:
        q = [
            float(v) for v in values[: self._nvars[link]]
        ]  # a list: see "zero joints" in the module docstring
        return np.asarray(self._ets[link].eval(q), dtype=np.float64)

    def _matrices(self, q: NDArray[np.float64], link: int) -> Matrix:
        """FK of link index ``link`` for q of shape (N, dof), N >= 1: the toolbox's FK on the whole batch."""
        nvars = self._nvars[link]
        if nvars == 1:  # an (N, 1) batch is misread as one configuration: see the module docstring
            return np.array([self._matrix(row, link) for row in q], dtype=np.float64).reshape(-1, 4, 4)
        out = np.asarray(self._ets[link].eval(q[:, :nvars]), dtype=np.float64)
        return out.reshape(q.shape[0], 4, 4)

    def _ik_answer(self, target: IkTarget, q: list[float], index: int, nvars: int) -> IkAnswer:
        """The toolbox's ``ik_LM``, one search from the seed; its ``success`` is the status."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            solution = self._ets[index].ik_LM(
                target.matrix,
                q0=np.array(q[:nvars]),
                ilimit=IK_MAX_ITERATIONS,
                slimit=1,
                tol=RTB_TOL,
                joint_limits=True,
            )
        return np.asarray(solution.q, dtype=np.float64).tolist(), bool(solution.success)


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.rtb_adapter:api``."""
MoveGroup = api.MoveGroup
