"""The API around IKPy (``ikpy``): FK and IK from IKPy, everything else from the contract.

Use it as ``--targets native,adapters.ikpy_adapter:api``.

What comes from where
---------------------
* **From IKPy**: URDF reading of the chain's joints (``ikpy.urdf.URDF.get_urdf_parameters``,
  the parser behind ``ikpy.chain.Chain.from_urdf_file``), the ``ikpy.chain.Chain``,
  forward kinematics (``Chain.forward_kinematics``) and inverse kinematics
  (``Chain.inverse_kinematics_frame``, SciPy least squares within IKPy's bounds).
* **From the contract** (the twin's non-kinematic code, ``python_impl``): URDF
  validation and errors, chain selection (root, default tip), joint names and
  order, limits, ``home_values``, ``link_names``, argument checks, and
  ``MoveGroup`` (planning is in joint space; its poses come from IKPy's FK).

Conventions normalized (and nothing else)
-----------------------------------------
============================ ================================================================
IKPy convention              what the adapter does
============================ ================================================================
orientations are 4x4         the rotation block becomes the contract's quaternion (x, y, z, w),
matrices, no quaternion      canonical sign (``w >= 0``), by the twin's matrix-to-quaternion
                             conversion; IK targets go in as 4x4 matrices built from (x, y, z, w)
full joint vector: one entry the adapter scatters the contract's variables into IKPy's active
per IKPy "link" = per URDF   entries (``active_links_mask``: the movable joints) and puts 0 in
joint on the path, plus the  the others (IKPy ignores the value of fixed links); IK answers are
leading ``OriginLink``       read back from the same entries
chain is walked from         ``base_elements`` is the full path ``[root, joint, link, ...,
``base_elements``, first     tip]`` chosen by the contract's tip rule, so IKPy follows exactly
child at branches, and keeps the contract's chain; IKPy's own continuation past the tip is cut
going past the last element  off (the links after the tip are dropped before building the Chain)
frame of link ``k``          ``forward_kinematics(..., full_kinematics=True)[k]``: frame 0 is the
                             ``OriginLink`` (identity = the root link), frame ``k`` the child link
                             of the ``k``-th joint of the path. Same root frame as the contract
units                        metres and radians on both sides (nothing to convert)
continuous joints            IKPy treats them as unbounded revolute joints, as the contract does;
                             IK answers are normalized into (-pi, pi] (representation only)
IK has no status             IKPy returns only a joint vector. The adapter reports ``SUCCESS``
                             exactly when the contract's criterion holds for that vector,
                             evaluated with IKPy's own FK: every component of the error twist
                             ``(p_target - p, R log(R^T R_target))`` within ``IK_EPS`` (1e-6)
IK seed                      the contract's step 1 (seed clamped into the limits, continuous
                             joints normalized) then IKPy's ``initial_position``; IKPy itself
                             then moves the start 1e-3 inside its bounds (its own behaviour)
IK solver parameters         IKPy's defaults (``orientation_mode="all"``, least squares, SciPy's
                             tolerances and budget); nothing tuned
IK to a link with no         IKPy cannot optimize zero variables: no solver call, the status is
variable before it           the contract's criterion at the seed (as in the contract)
warnings                     IKPy's ``warnings`` (fixed joints with an axis, ...) are silenced
============================ ================================================================

Unsupported, by design
----------------------
* **Mimic joints**: IKPy has no mimic support (it would treat the mimic joint as
  an independent joint). A chain with a mimic joint is rejected at load with
  ``URDFError(URDF_UNSUPPORTED)``.
* A URDF that IKPy's own parser cannot read along the chain (for instance a
  floating or planar joint right after the tip, where IKPy keeps walking) is
  rejected at load with ``URDFError(URDF_UNSUPPORTED)``.

Known library semantics (left visible on purpose)
-------------------------------------------------
* IKPy does not normalize joint axes: an axis such as ``0 0 2`` scales the
  rotation matrix (not a rotation any more); urdfdom and the contract normalize.
* IK targets whose solution lies on a joint limit mostly fail: IKPy moves the
  start 1e-3 inside its bounds and SciPy's bounded least squares stops (its
  ``ftol``/``xtol``) about 1e-4 short of the bound. Kinova's own home pose (three
  joints at their lower limits) is not found from the home seed.
* IKPy's cost is position error plus the Frobenius distance of the rotation
  matrices: a local optimizer, it can stop with the position reached and the
  orientation half a turn away where the contract's Newton-Raphson succeeds.
* IKPy reads numbers with Python's ``float`` and splits vectors on any
  whitespace; the adapter only hands it URDFs the contract accepted, so this is
  invisible here.
"""

from __future__ import annotations

import io
import os
import warnings
from typing import Any

import ikpy.chain
import ikpy.link
import ikpy.urdf.URDF
import numpy as np
from numpy.typing import NDArray

from adapters._common import IkAnswer, IkTarget, LibraryModel, make_api, refuse_mimic_joints, urdf_bytes
from python_impl.urdf import is_path_source, load_urdf
from robot_api.errors import ErrorCode, URDFError

Matrix = NDArray[np.float64]


class RobotModel(LibraryModel):
    """A chain loaded from URDF whose kinematics are IKPy's (see the module docstring).

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
        mimic joint on the chain, or cannot be read by IKPy (``URDF_UNSUPPORTED``).
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_chains", "_data", "_joints", "_masks")

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        refuse_mimic_joints(self, "IKPy has no mimic joints")
        source, is_path = is_path_source(urdf)
        assert isinstance(source, str)
        tree = load_urdf(source, is_path)
        self._joints = tuple(tree.parent_joint[link].name for link in self.link_names[1:])
        self._data = urdf_bytes(urdf)
        self._chains: dict[int, Any] = {}
        self._masks: dict[int, NDArray[np.bool_]] = {}
        self._chain_to(len(self.link_names) - 1)

    def _chain_to(self, index: int) -> Any:
        """IKPy's Chain from the root to link ``index`` (built once, by IKPy's URDF parser)."""
        if index in self._chains:
            return self._chains[index]
        elements = [self.root_link]
        for joint, link in zip(self._joints[:index], self.link_names[1 : index + 1], strict=True):
            elements += [joint, link]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                links = ikpy.urdf.URDF.get_urdf_parameters(io.BytesIO(self._data), base_elements=elements)
                links = links[:index]  # IKPy keeps walking past the last element: cut that off
                mask = np.array([False] + [link.joint_type != "fixed" for link in links])
                chain = ikpy.chain.Chain(
                    [ikpy.link.OriginLink(), *links], active_links_mask=mask, name=self.name
                )
        except (ValueError, KeyError, AttributeError) as exc:
            raise URDFError(f"IKPy cannot read the chain: {exc}", ErrorCode.URDF_UNSUPPORTED) from None
        self._chains[index] = chain
        self._masks[index] = mask
        return chain

    def _full(self, values: list[float] | NDArray[np.float64], index: int) -> NDArray[np.float64]:
        """IKPy's full joint vector for the chain to link ``index``."""
        mask = self._masks[index]
        full = np.zeros(mask.shape[0])
        full[mask] = np.asarray(values, dtype=np.float64)[: int(mask.sum())]
        return full

    def _matrix(self, values: list[float] | NDArray[np.float64], link: int) -> Matrix:
        tip = len(self.link_names) - 1
        frames = self._chains[tip].forward_kinematics(self._full(values, tip), full_kinematics=True)
        return np.asarray(frames[link], dtype=np.float64)

    def _ik_answer(self, target: IkTarget, q: list[float], index: int, nvars: int) -> IkAnswer:
        """IKPy's ``inverse_kinematics_frame`` from the seed; no status (the contract's criterion)."""
        chain = self._chain_to(index)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            full = chain.inverse_kinematics_frame(
                target.matrix, initial_position=self._full(q, index), orientation_mode="all"
            )
        return np.asarray(full, dtype=np.float64)[self._masks[index]].tolist(), None


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.ikpy_adapter:api``."""
MoveGroup = api.MoveGroup
