"""The API around yourdfpy: link frames from yourdfpy's URDF model and scene graph.

Use it as ``--targets native,adapters.yourdfpy_adapter:api``.

What comes from where
---------------------
* **From yourdfpy**: URDF reading (``yourdfpy.URDF.load``, its own lxml parser
  and data classes), joint placement (``URDF.update_cfg``) and the frames of the
  trimesh scene graph it maintains (``URDF.get_transform(link, root)``).
* **From the contract**: everything else (``adapters/_engines.py``); FK only.

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
yourdfpy convention             what the adapter does
=============================== =============================================================
``update_cfg`` takes a dict or  a dict from the contract's joint names to its values
a vector of actuated joints
root frame                      ``get_transform(link, root_link)`` is already in the root frame
meshes                          not loaded (``load_meshes=False``,
                                ``load_collision_meshes=False``, no collision scene graph)
geometry                        removed before loading (``_engines.kinematic_urdf``)
=============================== =============================================================

Known library semantics (left visible on purpose, ``FINDINGS.md``)
-----------------------------------------------------------------
* A prismatic axis that is not unit length (not URDF) moves ``q * axis``; revolute
  axes are normalized.
* yourdfpy applies ``<mimic>`` in ``update_cfg``; the adapter still rejects mimic
  chains (shared rule of ``adapters/_engines.py``).
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np
import yourdfpy

from adapters._common import make_api
from adapters._engines import EngineModel, Matrix


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are yourdfpy's (see the module docstring)."""

    __slots__ = ()
    LIBRARY = "yourdfpy"

    def _load(self, data: bytes) -> Any:
        return yourdfpy.URDF.load(
            io.BytesIO(data),
            build_scene_graph=True,
            build_collision_scene_graph=False,
            load_meshes=False,
            load_collision_meshes=False,
        )

    def _matrix(self, values: list[float] | Any, link: int) -> Matrix:
        self._lib.update_cfg(dict(zip(self.joint_names, (float(v) for v in values[: self.dof]), strict=True)))
        return np.array(self._lib.get_transform(self.link_names[link], self.root_link), dtype=np.float64)


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.yourdfpy_adapter:api``."""
MoveGroup = api.MoveGroup
