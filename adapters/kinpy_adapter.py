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

from typing import Any

import kinpy
import kinpy.urdf_parser_py.xml_reflection.core as _xml_core
import numpy as np
from numpy.typing import NDArray

from adapters._common import IkAnswer, IkTarget, SerialChainModel, make_api

Matrix = NDArray[np.float64]


class RobotModel(SerialChainModel):
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

    __slots__ = ()
    _LIBRARY = "kinpy"
    _NO_MIMIC = "kinpy has no mimic joints"
    _PARSER = _xml_core

    def _build_chain(self, data: bytes, link: str) -> Any:
        return kinpy.build_serial_chain_from_urdf(data, link)

    def _matrix(self, values: list[float] | NDArray[np.float64], link: int) -> Matrix:
        frames = self._chains[self._tip].forward_kinematics(
            [float(v) for v in values[: self.dof]], end_only=False
        )
        return np.asarray(frames[self.link_names[link]].matrix(), dtype=np.float64)

    def _ik_answer(self, target: IkTarget, q: list[float], index: int, nvars: int) -> IkAnswer:
        """kinpy's ``inverse_kinematics`` (BFGS) from the seed; no status (the contract's criterion)."""
        x, y, z, w = target.orientation
        goal = kinpy.Transform(rot=[w, x, y, z], pos=np.array(target.position))
        answer = self._chain_to(index).inverse_kinematics(goal, np.array(q[:nvars]))
        return np.asarray(answer, dtype=np.float64).tolist(), None


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.kinpy_adapter:api``."""
MoveGroup = api.MoveGroup
