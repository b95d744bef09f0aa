"""The API around placo: link frames from placo's ``RobotWrapper`` (pinocchio underneath).

Use it as ``--targets native,adapters.placo_adapter:api``.

What comes from where
---------------------
* **From placo**: URDF reading (``placo.RobotWrapper`` on a file: placo's loader
  builds a pinocchio model with a floating base), joint placement
  (``RobotWrapper.set_joint``), and frames (``update_kinematics`` then
  ``get_T_world_frame``).
* **From the contract**: everything else (``adapters/_engines.py``); FK only.

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
placo convention                what the adapter does
=============================== =============================================================
floating base                   placo always adds one (at the identity); frames are read
                                relative to the root link's frame (``_engines.relative``)
``RobotWrapper`` reads a file   the (geometry-free) document is written to a private temporary
                                file, loaded with ``Flags.ignore_collisions``, and removed
joint vector                    set joint by joint by name (``set_joint``); continuous joints
                                take the angle (placo stores cos/sin)
geometry                        removed before loading (``_engines.kinematic_urdf``)
=============================== =============================================================

Installation: placo 0.10.2 pins ``pin==3.8.0`` exactly, while the project uses
pinocchio 4.1; it is therefore not in any extra (``third_party.md``). Install it in
a separate environment to run this adapter.
"""

from __future__ import annotations

import os
import tempfile
from typing import Any

import numpy as np
import placo

from adapters._common import make_api
from adapters._engines import EngineModel, Matrix


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are placo's (see the module docstring)."""

    __slots__ = ()
    LIBRARY = "placo"

    def _load(self, data: bytes) -> Any:
        fd, path = tempfile.mkstemp(suffix=".urdf")
        try:
            with os.fdopen(fd, "wb") as handle:
                handle.write(data)
            return placo.RobotWrapper(path, placo.Flags.ignore_collisions)
        finally:
            os.unlink(path)

    def _frames(self, values: list[float], links: tuple[int, ...]) -> list[Matrix]:
        for name, value in zip(self.joint_names, values, strict=True):
            self._lib.set_joint(name, value)
        self._lib.update_kinematics()
        return [np.array(self._lib.get_T_world_frame(self.link_names[i]), dtype=np.float64) for i in links]


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.placo_adapter:api``."""
MoveGroup = api.MoveGroup
