"""The robot_api contract around pinocchio (``pip install pin``), as a fuzzing target.

Use it as ``--targets native,adapters.pinocchio_adapter:api``. The adapter
normalizes conventions only; every pose comes from pinocchio's kinematics, so a
divergence the fuzzer finds is about pinocchio (its URDF parser, its joint
models, its frame placements, its Jacobian) or about a convention below.

What comes from where
---------------------

=========================================  ====================================================
piece                                      source
=========================================  ====================================================
URDF rules, chain selection, variables,    ``python_impl`` (``RobotModel.__init__``:
joint order, limits, home, link names      ``load_urdf`` of ``python_impl.urdf`` and
                                           ``build_chain`` of ``python_impl.chain``), so that
                                           they follow the contract
argument checks and conversions            ``python_impl.convert`` (inherited methods)
MoveGroup semantics                        ``python_impl.MoveGroup`` (subclass); its only
                                           kinematics, ``get_current_pose``, is this FK
kinematic model                            pinocchio's own URDF parser:
                                           ``buildModelFromUrdf``/``buildModelFromXML``
                                           with ``mimic=True``
FK, single and batch                       ``pin.forwardKinematics`` +
                                           ``pin.updateFramePlacement`` (``data.oMf``),
                                           one call per row
IK kinematics                              pinocchio: the same FK, ``pin.computeFrameJacobian``
                                           (``LOCAL_WORLD_ALIGNED``) and ``pin.log3``
IK algorithm                               the contract's (docs/api.md "Inverse kinematics"):
                                           pinocchio has no IK solver in its core, so the
                                           loop (clamped seed, error twist, SVD pseudo-inverse
                                           dropping singular values below ``IK_PINV_EPS``,
                                           step, clamp, ``IK_EPS``, ``IK_MAX_ITERATIONS``) is
                                           written here with numpy, as in pinocchio's CLIK
                                           example
IK errors (distance, angle)                the contract's definitions on pinocchio's poses
                                           (numpy norm, ``rotation_angle`` of
                                           ``python_impl.transforms``)
=========================================  ====================================================

Normalizations (conventions only)
---------------------------------

======================  ==================================  ======================================
convention              pinocchio                           what the adapter does
======================  ==================================  ======================================
joint vector            full ``q`` of size ``nq`` over the  our ``dof`` variables go to their
                        whole URDF tree (other branches     joints' ``idx_q``; every other entry
                        included)                           stays ``pin.neutral`` (it cannot move
                                                            the chain)
continuous joints       ``JointModelRUB*``: ``nq = 2``,     angle ``v`` -> ``(cos v, sin v)``; IK
                        ``q = (cos, sin)``, ``nv = 1``      iterates on the angle (the tangent
                                                            step of ``pin.integrate``) and returns
                                                            it in (-pi, pi] (the contract's form)
mimic joints            ``JointModelMimic`` (``nq = 0``)    nothing: pinocchio applies
                        driven by the master's ``q``        ``multiplier * master + offset``
                                                            itself; the variable is the master
reference frame         poses in the universe (world)       ``oMf[root]^-1 * oMf[link]``, the
                                                            root link being the URDF root; the
                                                            Jacobian's rows are rotated into the
                                                            root's axes
Jacobian layout         ``6 x nv``, rows (linear,           columns picked by each variable's
                        angular), ``LOCAL_WORLD_ALIGNED``   ``idx_v``: the contract's geometric
                        = at the frame origin, world axes   Jacobian at the link origin
link names              ``getFrameId(name)`` searches all   ``FrameType.BODY`` only (a joint may
                        frame types                         share a link's name)
quaternion order        ``pin.Quaternion(w, x, y, z)``      targets built with ``(w, x, y, z)``;
                        (scalars), ``coeffs()`` and the     results read from ``coeffs()`` as
                        4-vector constructor ``(x,y,z,w)``  ``(x, y, z, w)`` (ROS order)
quaternion sign         Eigen's matrix-to-quaternion, any   normalized, then the contract's sign:
                        sign                                ``w >= 0``; at ``w == 0`` the first
                                                            non-zero of ``x, y, z`` positive
URDF errors             pinocchio raises ``ValueError``/    only reached for URDFs the contract
                        ``RuntimeError``                    accepts: ``URDFError``
                                                            (``URDF_UNSUPPORTED``) naming
                                                            pinocchio, so the rejection stays
                                                            visible as a status divergence
IK status               none (no solver)                    the contract's loop decides
                                                            ``SUCCESS`` / ``NO_SOLUTION``
non-finite IK iterates  NaN in, NaN out                     absurd targets (``|p|`` ~ 1e308) give
                                                            inf/NaN steps: ``cos``/``sin`` of a
                                                            non-finite angle and a failed numpy
                                                            SVD become NaN instead of raising, so
                                                            the loop ends non-finite: then
                                                            ``NO_SOLUTION`` with the clamped seed
                                                            (``finite_or_seed``), as ``native``
======================  ==================================  ======================================

Not normalized (semantics left to pinocchio): axis handling of its joint models,
its URDF parser's reading of origins, limits and mimic tags, its trigonometry,
and its rotation logarithm: ``log3`` is exact, while KDL's ``diff`` (hence
``native``'s error twist) returns a zero rotation for rotations whose
rotation-vector components are all below about 5e-7 rad (``Rotation::GetRot``
with ``KDL::epsilon = 1e-6``), which can decide an IK status near convergence.

Known limitation of pinocchio (4.1), seen as ``URDF_UNSUPPORTED`` where the
contract accepts the URDF: ``JointModelMimic`` needs the mimic and master joints
to have configuration spaces of one size, so a continuous joint (``nq = 2``)
mimicking a revolute or prismatic one (``nq = 1``), or the reverse, cannot be
built ("Mimicking and mimicked configuration spaces have different sizes"), even
off the chain, since pinocchio builds the whole tree. And a bug (FINDINGS.md, F-PIN-2):
its URDF parser adds a mimic joint when its walk of the tree reaches it, and refuses
one whose master it has not reached yet ("The parent joint of the mimic joint is not
in the kinematic tree"), such as a sibling whose name sorts first (Romeo's fingers).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from adapters._common import LibraryModel, canonical_quaternion, finite_or_seed, ik_result, make_api
from python_impl.angles import normalize_angle
from python_impl.urdf import is_path_source
from robot_api.constants import IK_EPS, IK_MAX_ITERATIONS, IK_PINV_EPS
from robot_api.errors import ErrorCode, URDFError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, JointType, Pose

Array = NDArray[np.float64]

__all__ = ["MoveGroup", "RobotModel", "api"]


def _pinv_step(jac: Array, twist: Array) -> Array:
    """The contract's ``J^+ twist``: SVD, singular values below ``IK_PINV_EPS`` dropped."""
    try:
        u, s, vt = np.linalg.svd(jac, full_matrices=False)
    except np.linalg.LinAlgError:  # non-finite input (absurd targets): NaN, as KDL's SVD gives
        return np.full(jac.shape[1], math.nan)
    with np.errstate(all="ignore"):
        projected = u.T @ twist
        inv = np.where(np.abs(s) < IK_PINV_EPS, 0.0, projected / np.where(s == 0.0, 1.0, s))
        step: Array = vt.T @ inv
    return step


def _is_small(twist: Array) -> bool:
    """Every component within ``[-IK_EPS, IK_EPS]`` (KDL's ``Equal(twist, Zero, eps)``)."""
    return all(x <= IK_EPS and x + IK_EPS >= 0.0 for x in twist.tolist())


class RobotModel(LibraryModel):
    """A kinematic chain from URDF whose kinematics are pinocchio's.

    Chain, variables, limits and argument checks follow the contract through
    ``python_impl``; poses, Jacobians and rotation logarithms come from a
    pinocchio model built by pinocchio's own URDF parser (``mimic=True``).

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF breaks the contract, or pinocchio cannot build it (``URDF_UNSUPPORTED``).
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_columns", "_data", "_frames", "_neutral", "_pin", "_root_inv", "_velocity_columns")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        source, is_path = is_path_source(urdf)  # the parent accepted it: a str here
        model = self._build(str(source), is_path)
        self._pin: Any = model
        self._data: Any = model.createData()
        self._neutral: Array = np.asarray(pin.neutral(model), dtype=np.float64)
        columns: list[tuple[int, int, int]] = []
        velocity_columns: list[int] = []
        for i, lim in enumerate(self.joint_limits):
            joint = model.joints[self._joint_id(model, lim.name)]
            if joint.nq not in (1, 2) or joint.nv != 1:
                raise URDFError(
                    f"pinocchio models joint '{lim.name}' with nq={joint.nq}, nv={joint.nv}",
                    ErrorCode.URDF_UNSUPPORTED,
                )
            columns.append((i, int(joint.idx_q), int(joint.nq)))
            velocity_columns.append(int(joint.idx_v))
        self._columns = tuple(columns)
        self._velocity_columns = tuple(velocity_columns)
        frames: list[int] = []
        for link in self.link_names:
            if not model.existFrame(link, pin.FrameType.BODY):
                raise URDFError(
                    f"pinocchio's model has no body frame for link '{link}'", ErrorCode.URDF_UNSUPPORTED
                )
            frames.append(int(model.getFrameId(link, pin.FrameType.BODY)))
        self._frames = tuple(frames)
        root = model.frames[frames[0]]
        if int(root.parentJoint) != 0:
            raise URDFError(
                f"pinocchio does not attach the root link '{self.root_link}' to its universe",
                ErrorCode.URDF_UNSUPPORTED,
            )
        # The root link's frame is fixed to pinocchio's universe: its placement is constant.
        self._root_inv: Any = root.placement.inverse()

    @staticmethod
    def _build(source: str, is_path: bool) -> Any:
        try:
            if is_path:
                return pin.buildModelFromUrdf(source, mimic=True)
            return pin.buildModelFromXML(source, mimic=True)
        except Exception as exc:  # noqa: BLE001 - any pinocchio failure is one rejection
            raise URDFError(
                f"pinocchio cannot build a model from this URDF: {type(exc).__name__}: {exc}",
                ErrorCode.URDF_UNSUPPORTED,
            ) from None

    @staticmethod
    def _joint_id(model: Any, name: str) -> int:
        if not model.existJointName(name):
            raise URDFError(f"pinocchio's model has no joint '{name}'", ErrorCode.URDF_UNSUPPORTED)
        return int(model.getJointId(name))

    # -- conventions -----------------------------------------------------------------------

    def _q(self, values: Sequence[float] | Array) -> Array:
        """pinocchio's ``q`` for our variables: ``idx_q`` slots, continuous as (cos, sin)."""
        q = self._neutral.copy()
        for i, idx, nq in self._columns:
            v = float(values[i])
            if nq == 2:
                finite = math.isfinite(v)  # NaN (numpy's answer) rather than math's ValueError
                q[idx] = math.cos(v) if finite else math.nan
                q[idx + 1] = math.sin(v) if finite else math.nan
            else:
                q[idx] = v
        return q

    def _matrix(self, values: Sequence[float] | Array, link: int) -> Array:
        """4x4 pose of link index ``link`` in the root link's frame, by pinocchio."""
        if link == 0:
            return np.eye(4)
        pin.forwardKinematics(self._pin, self._data, self._q(values))
        placement = pin.updateFramePlacement(self._pin, self._data, self._frames[link])
        return np.array(self._root_inv.act(placement).homogeneous, dtype=np.float64)

    def _jacobian(self, values: Sequence[float] | Array, link: int, nvars: int) -> Array:
        """Geometric Jacobian (6, nvars) at the link origin, root axes, by pinocchio."""
        jac = pin.computeFrameJacobian(
            self._pin,
            self._data,
            self._q(values),
            self._frames[link],
            pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
        )
        jac = np.asarray(jac, dtype=np.float64)[:, list(self._velocity_columns[:nvars])]
        r = np.asarray(self._root_inv.rotation, dtype=np.float64)
        out: Array = np.vstack((r @ jac[:3], r @ jac[3:]))
        return out

    @staticmethod
    def _error_twist(current: Array, rotation: Array, position: Array) -> Array:
        """``(p_target - p, R log3(R^T R_target))`` in the root frame (``pin.log3``)."""
        r = current[:3, :3]
        log = np.asarray(pin.log3(r.T @ rotation), dtype=np.float64)
        return np.concatenate([position - current[:3, 3], r @ log])

    # -- the API -----------------------------------------------------------------------------

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values (pinocchio's FK)."""
        t = self._matrix(values, link)
        x, y, z = t[:3, 3].tolist()
        return Pose((x, y, z), canonical_quaternion(pin.Quaternion(t[:3, :3]).coeffs()))

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose``: the contract's NR loop on pinocchio's kinematics.

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
        limits = self.joint_limits
        x, y, z, w = orientation
        target_rotation = np.asarray(pin.Quaternion(w, x, y, z).toRotationMatrix(), dtype=np.float64)
        target_position = np.array(position, dtype=np.float64)

        values = np.array(q, dtype=np.float64)
        converged = False
        if nvars == 0:
            converged = _is_small(
                self._error_twist(self._matrix(values, index), target_rotation, target_position)
            )
        else:
            lower = np.array([lim.lower for lim in limits[:nvars]])
            upper = np.array([lim.upper for lim in limits[:nvars]])
            for _ in range(IK_MAX_ITERATIONS):
                twist = self._error_twist(self._matrix(values, index), target_rotation, target_position)
                if _is_small(twist):
                    converged = True
                    break
                values[:nvars] += _pinv_step(self._jacobian(values, index, nvars), twist)
                values[:nvars] = np.minimum(np.maximum(values[:nvars], lower), upper)
        result = values.tolist()
        for i, lim in enumerate(limits[:nvars]):
            if lim.type == JointType.CONTINUOUS:
                result[i] = normalize_angle(result[i])
        result, finite = finite_or_seed(result, q)
        return ik_result(
            converged and finite, result, self._matrix(result, index), target_position, target_rotation
        )


api = make_api(RobotModel, __name__)
"""The implementation object for ``--targets adapters.pinocchio_adapter:api``."""
MoveGroup = api.MoveGroup
