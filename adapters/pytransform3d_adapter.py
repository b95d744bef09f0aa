"""The API around pytransform3d: link frames from its ``UrdfTransformManager``.

Use it as ``--targets native,adapters.pytransform3d_adapter:api``.

What comes from where
---------------------
* **From pytransform3d**: URDF reading (``UrdfTransformManager.load_urdf``, its
  own BeautifulSoup-based parser), joint placement (``set_joint``) and the
  transform graph's path composition (``get_transform(link, root)``).
* **From the contract**: everything else (``adapters/_engines.py``); FK only.

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
pytransform3d convention        what the adapter does
=============================== =============================================================
``get_transform(A, B)`` is the  ``get_transform(link, root_link)``: already the contract's pose
frame A expressed in B
joint vector                    set joint by joint by name (``set_joint``)
geometry                        removed before loading (``_engines.kinematic_urdf``); no
                                ``mesh_path`` is given
=============================== =============================================================

Known library semantics (left visible on purpose, ``FINDINGS.md``)
-----------------------------------------------------------------
* **Clipping**: ``set_joint`` clips every value to the joint's ``<limit>`` (documented);
  the contract's FK does not enforce limits, so values beyond them diverge.
* **Continuous joints are clipped too** (F-PT3D-1, a bug): a continuous joint with a
  ``<limit lower upper>`` element (example-robot-data's double pendulum: ``0 0``)
  is clamped to it, although a continuous joint has no limits.
* ``<mimic>`` is not read: the mimic joint stays at 0 (the adapter rejects mimic chains).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pytransform3d.urdf import UrdfTransformManager

from adapters._common import make_api
from adapters._engines import EngineModel, Matrix


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are pytransform3d's (see the module docstring)."""

    __slots__ = ()
    LIBRARY = "pytransform3d"

    def _load(self, data: bytes) -> Any:
        manager = UrdfTransformManager(check=False)
        manager.load_urdf(data.decode("utf-8"))
        return manager

    def _matrix(self, values: list[float] | Any, link: int) -> Matrix:
        for name, value in zip(self.joint_names, values[: self.dof], strict=True):
            self._lib.set_joint(name, float(value))
        return np.array(self._lib.get_transform(self.link_names[link], self.root_link), dtype=np.float64)


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.pytransform3d_adapter:api``."""
MoveGroup = api.MoveGroup
