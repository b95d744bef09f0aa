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

from typing import Any

import numpy as np
import pytorch_kinematics as pk
import pytorch_kinematics.urdf_parser_py.xml_reflection.core as _xml_core
import torch
from numpy.typing import NDArray

from adapters._common import IkAnswer, IkTarget, SerialChainModel, make_api
from robot_api.constants import IK_EPS, IK_MAX_ITERATIONS

Matrix = NDArray[np.float64]

DTYPE = torch.float64


class RobotModel(SerialChainModel):
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

    __slots__ = ()
    _LIBRARY = "pytorch-kinematics"
    _NO_MIMIC = "pytorch-kinematics ignores mimic joints"
    _PARSER = _xml_core

    def _build_chain(self, data: bytes, link: str) -> Any:
        return pk.build_serial_chain_from_urdf(data, link).to(dtype=DTYPE)

    def _matrices(self, q: NDArray[np.float64], link: int) -> Matrix:
        """FK of link index ``link`` for q of shape (N, dof), N >= 1: shape (N, 4, 4), in one batch."""
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

    def _ik_answer(self, target: IkTarget, q: list[float], index: int, nvars: int) -> IkAnswer:
        """The library's ``PseudoInverseIK`` from the seed only; its ``converged_any`` is the status."""
        solver = pk.PseudoInverseIK(
            self._chain_to(index),
            retry_configs=torch.tensor([q[:nvars]], dtype=DTYPE),
            pos_tolerance=IK_EPS,
            rot_tolerance=IK_EPS,
            max_iterations=IK_MAX_ITERATIONS,
        )
        solution = solver.solve(pk.Transform3d(matrix=torch.tensor(target.matrix, dtype=DTYPE), dtype=DTYPE))
        return solution.solutions[0, 0].tolist(), bool(solution.converged_any[0])


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.pytorch_kinematics_adapter:api``."""
MoveGroup = api.MoveGroup
