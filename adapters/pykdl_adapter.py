"""The robot_api contract around PyKDL (Orocos KDL's Python binding), as a fuzzing target.

Use it as ``--targets native,adapters.pykdl_adapter:api``. PyKDL comes from
Debian (``python3-pykdl``, KDL 1.5.1; ``scripts/apt-ensure.sh python3-pykdl``).
It is loaded from ``/usr/lib/python3/dist-packages`` by file
(``importlib.util.spec_from_file_location``) without putting that folder on
``sys.path``; it needs an interpreter with Debian's Python ABI (CPython 3.11),
and :class:`ImportError` says so otherwise. A ``PyKDL`` already importable from
``sys.path`` (a ROS or conda install) is used first.

The adapter normalizes conventions only; every pose and every IK iterate comes
from KDL, so a divergence the fuzzer finds is about KDL (or PyKDL's binding)
or about a convention below. ``native`` also calls KDL (in C++, with urdfdom
and its own chain builder), so against ``native`` a difference points at the
binding, the chain construction or a convention.

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
the KDL chain                              adapter glue: there is no ``kdl_parser`` for Python
                                           here (Debian's ``libkdl-parser1d`` is C++ only), so
                                           the chain is built from ``python_impl``'s parsed
                                           joints as kdl_parser does: per joint on the chain
                                           ``Segment(child, Joint(name, origin.p, origin.M *
                                           axis, RotAxis|TransAxis) or Joint(name, Fixed),
                                           origin)`` with ``origin = Frame(Rotation.RPY(rpy),
                                           Vector(xyz))`` (``kdl_parser_api``: see below)
FK, single and batch                       ``ChainFkSolverPos_recursive.JntToCart(q, frame,
                                           segmentNr)``, one call per row
IK                                         ``ChainIkSolverPos_NR_JL(chain, q_min, q_max,
                                           ChainFkSolverPos_recursive, ChainIkSolverVel_pinv(
                                           chain, IK_PINV_EPS, 150), IK_MAX_ITERATIONS,
                                           IK_EPS)`` on the sub-chain up to the link, after the
                                           contract's seed clamp (KDL does not clamp the seed)
IK with no variable before the link        ``Equal(diff(fk, target), Twist.Zero(), IK_EPS)``
IK errors (distance, angle)                the contract's definitions on KDL's poses (numpy
                                           norm, ``rotation_angle`` of
                                           ``python_impl.transforms``)
=========================================  ====================================================

Two targets: ``api`` builds origins with KDL's ``Rotation.RPY`` (KDL's own
reading of URDF's roll-pitch-yaw); ``kdl_parser_api`` builds them as
kdl_parser does, ``Rotation.Quaternion`` of urdfdom's ``setFromRPY``
quaternion. The two differ by an ulp in some origin entries; ``kdl_parser_api``
then matches ``native`` bit for bit (FK and IK), while with ``api`` Newton-Raphson
amplifies those ulps on ill-conditioned IK queries (status and ~1e-7 value
divergences against ``native``, which ``kdl_parser_api`` does not show).

Not normalized (KDL's semantics): NR_JL's error twist is KDL's ``diff``, whose
rotation part (``Rotation::GetRot`` with ``KDL::epsilon = 1e-6``) is exactly
zero for rotations whose rotation-vector components are all below about
5e-7 rad; the twin and the pinocchio adapter use an exact logarithm, and near
convergence this can decide the IK status.

``ChainIkSolverPos_LMA`` is not used: it is a different algorithm (weighted
Levenberg-Marquardt, no joint limits), not the contract's.

Normalizations (conventions only)
---------------------------------

======================  ==================================  ======================================
convention              KDL                                 what the adapter does
======================  ==================================  ======================================
joint vector            ``JntArray`` of the chain's         our variables -> one entry per
                        movable segments (``nj``), mimic    movable segment, in chain order
                        joints included
mimic joints            no mimic in a ``Chain``             entry = ``multiplier * master +
                                                            offset`` (as ``native``); IK through a
                                                            mimic joint is the contract's
                                                            ``UNSUPPORTED_OPERATION``
continuous joints       ``RotAxis`` with limits ``-inf``/   NR_JL gets ``-inf``/``inf`` limits;
                        ``inf``; values unbounded           results normalized into (-pi, pi]
link selection          ``segmentNr`` = number of           link index ``k`` of ``link_names``
                        segments from the base              -> ``segmentNr = k`` (0: identity)
joint axis              ``Joint`` divides by                axis scaled by its largest component,
                        ``Vector::Norm()``, which is 0      then normalized (the contract's rule,
                        for some tiny axes: ``(1e-7,        as ``native``) before KDL sees it
                        1e-7, 0)`` gives an inf/NaN axis
quaternion order        ``Rotation.Quaternion(x, y, z,      none needed: both ``(x, y, z, w)``
                        w)``, ``GetQuaternion()`` ->
                        ``(x, y, z, w)``
quaternion sign         ``GetQuaternion()``, any sign       normalized, then the contract's sign:
                                                            ``w >= 0``; at ``w == 0`` the first
                                                            non-zero of ``x, y, z`` positive
frames                  ``Frame(M, p)``, row-major          ``M[i, j]``, ``p[i]`` -> 4x4 matrix
                        ``M[i, j]``
IK status               ``CartToJnt`` return code:          ``0`` -> ``SUCCESS``; anything else
                        0 ``E_NOERROR``;                    -> ``NO_SOLUTION`` (as ``native``);
                        -5 ``E_MAX_ITERATIONS_EXCEEDED``    the last iterate is returned either
                        (no convergence); -100              way
                        ``E_IKSOLVERVEL_FAILED`` (the
                        velocity solver failed, e.g. its
                        SVD, -8 ``E_SVD_FAILED``); -101
                        ``E_FKSOLVERPOS_FAILED``; -3 and
                        -4 (not up to date, size
                        mismatch) cannot happen here
FK return code          ``JntToCart``: 0, else -4 (size     a non-zero code is a bug of the
                        mismatch) or -6 (out of range)      adapter: ``RuntimeError``
======================  ==================================  ======================================
"""

from __future__ import annotations

import os
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from adapters._common import LibraryModel, canonical_quaternion, finite_or_seed, ik_result, make_api
from adapters._kdl import KDL, frame_matrix, segment_of
from python_impl.angles import normalize_angle
from python_impl.urdf import is_path_source, load_urdf
from robot_api.constants import IK_EPS, IK_MAX_ITERATIONS, IK_PINV_EPS
from robot_api.protocol import JointValues
from robot_api.records import IKResult, JointType, Pose

__all__ = ["KdlParserRobotModel", "MoveGroup", "RobotModel", "api", "kdl_parser_api"]

IK_SVD_ITERATIONS = 150
"""Sweeps of ``ChainIkSolverVel_pinv``'s SVD (KDL's default, and ``native``'s)."""

E_NOERROR = 0
"""KDL's ``SolverI::E_NOERROR`` (PyKDL does not export the codes)."""


class _IkSolver:
    """KDL's NR_JL solver on the sub-chain up to one link (keeps every KDL object alive)."""

    def __init__(self, segments: list[Any], lower: list[float], upper: list[float]) -> None:
        self.chain = KDL.Chain()
        for segment in segments:
            self.chain.addSegment(segment)
        self.nvars = int(self.chain.getNrOfJoints())
        self.q_min = KDL.JntArray(self.nvars)
        self.q_max = KDL.JntArray(self.nvars)
        for j in range(self.nvars):
            self.q_min[j] = lower[j]
            self.q_max[j] = upper[j]
        self.fk = KDL.ChainFkSolverPos_recursive(self.chain)
        self.vel = KDL.ChainIkSolverVel_pinv(self.chain, IK_PINV_EPS, IK_SVD_ITERATIONS)
        self.pos = KDL.ChainIkSolverPos_NR_JL(
            self.chain, self.q_min, self.q_max, self.fk, self.vel, IK_MAX_ITERATIONS, IK_EPS
        )


class RobotModel(LibraryModel):
    """A kinematic chain from URDF whose kinematics are KDL's, through PyKDL.

    Chain, variables, limits and argument checks follow the contract through
    ``python_impl``; poses come from ``ChainFkSolverPos_recursive`` and IK from
    ``ChainIkSolverPos_NR_JL`` on a ``PyKDL.Chain`` built from the URDF's joints.

    Parameters
    ----------
    urdf : str or os.PathLike
        A URDF file path, or URDF XML text (a string starting with ``<``).
    tip_link : str, optional
        Last link of the chain; by default the contract's tip rule picks it.

    Raises
    ------
    URDFError
        The URDF breaks the contract.
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_fk", "_ik_solvers", "_kdl_chain", "_kdl_joints", "_segments")

    _URDFDOM_ORIGINS: ClassVar[bool] = False
    """Build origins as kdl_parser does (urdfdom's quaternion) instead of ``Rotation.RPY``."""

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        source, is_path = is_path_source(urdf)  # the parent accepted it: a str here
        tree = load_urdf(str(source), is_path)
        index = {name: i for i, name in enumerate(self.joint_names)}
        segments: list[Any] = []
        kdl_joints: list[tuple[int, float, float, bool]] = []  # (variable, multiplier, offset, mimic)
        for link in self.link_names[1:]:
            joint = tree.parent_joint[link]
            segments.append(segment_of(joint, self._URDFDOM_ORIGINS))
            if joint.type == "fixed":
                continue
            if joint.mimic is not None:
                mimic = joint.mimic
                kdl_joints.append((index[mimic.joint], mimic.multiplier, mimic.offset, True))
            else:
                kdl_joints.append((index[joint.name], 1.0, 0.0, False))
        self._segments = segments
        self._kdl_joints = tuple(kdl_joints)
        self._kdl_chain: Any = KDL.Chain()
        for segment in segments:
            self._kdl_chain.addSegment(segment)
        self._fk: Any = KDL.ChainFkSolverPos_recursive(self._kdl_chain)
        self._ik_solvers: dict[int, _IkSolver] = {}

    # -- conventions -----------------------------------------------------------------------

    def _jnt_array(self, values: Any) -> Any:
        """KDL joint values of the chain's movable segments for our variables."""
        q = KDL.JntArray(len(self._kdl_joints))
        for k, (v, multiplier, offset, mimic) in enumerate(self._kdl_joints):
            value = float(values[v])
            q[k] = multiplier * value + offset if mimic else value
        return q

    def _frame(self, values: Any, link: int) -> Any:
        """``PyKDL.Frame`` of link index ``link`` (KDL's segmentNr) in the root frame."""
        frame = KDL.Frame()
        rc = self._fk.JntToCart(self._jnt_array(values), frame, link)
        if rc != E_NOERROR:
            raise RuntimeError(f"KDL's ChainFkSolverPos_recursive returned {rc} for segment {link}")
        return frame

    # -- the API -----------------------------------------------------------------------------

    def pose_of(self, values: list[float], link: int) -> Pose:
        """Pose of link index ``link`` for checked values (KDL's FK)."""
        frame = self._frame(values, link)
        p = frame.p
        return Pose((float(p[0]), float(p[1]), float(p[2])), canonical_quaternion(frame.M.GetQuaternion()))

    def _matrix(self, values: Any, link: int) -> NDArray[np.float64]:
        """The transform (4, 4) of link index ``link`` for checked values (KDL's FK)."""
        return frame_matrix(self._frame(values, link))

    def _ik_solver(self, link: int, nvars: int) -> _IkSolver:
        if link not in self._ik_solvers:
            limits = self.joint_limits[:nvars]
            self._ik_solvers[link] = _IkSolver(
                self._segments[:link], [lim.lower for lim in limits], [lim.upper for lim in limits]
            )
        return self._ik_solvers[link]

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Joint values that put ``link`` at ``pose``: KDL's ``ChainIkSolverPos_NR_JL``.

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
        start = list(q)
        limits = self.joint_limits
        x, y, z, w = orientation
        target = KDL.Frame(KDL.Rotation.Quaternion(x, y, z, w), KDL.Vector(*position))
        if nvars == 0:
            here = self._frame(q, index)
            converged = bool(KDL.Equal(KDL.diff(here, target), KDL.Twist.Zero(), IK_EPS))
        else:
            solver = self._ik_solver(index, nvars)
            q_init, q_out = KDL.JntArray(nvars), KDL.JntArray(nvars)
            for j in range(nvars):
                q_init[j] = q[j]
            rc = solver.pos.CartToJnt(q_init, target, q_out)
            converged = rc == E_NOERROR
            for j in range(nvars):
                v = float(q_out[j])
                q[j] = normalize_angle(v) if limits[j].type == JointType.CONTINUOUS else v
        q, finite = finite_or_seed(q, start)  # a non-finite iterate: the clamped seed, as native
        reached = self._matrix(q, index)
        goal = frame_matrix(target)
        return ik_result(converged and finite, q, reached, goal[:3, 3], goal[:3, :3])


api = make_api(RobotModel, __name__)
"""The implementation object for ``--targets adapters.pykdl_adapter:api``."""
MoveGroup = api.MoveGroup


class KdlParserRobotModel(RobotModel):
    """:class:`RobotModel` whose chain origins follow kdl_parser: urdfdom's quaternion of ``rpy``.

    The chain is then the one ``native`` builds (urdfdom + ``Rotation::Quaternion``),
    so its FK and IK match ``native`` bit for bit: a difference would be PyKDL's.
    """

    __slots__ = ()

    _URDFDOM_ORIGINS: ClassVar[bool] = True


kdl_parser_api = SimpleNamespace(RobotModel=KdlParserRobotModel, MoveGroup=MoveGroup)
"""Variant with kdl_parser's origins: ``--targets adapters.pykdl_adapter:kdl_parser_api``."""
