"""The API around Klampt: link frames from Klampt's URDF importer and ``RobotModel``.

Use it as ``--targets native,adapters.klampt_adapter:api``.

What comes from where
---------------------
* **From Klampt**: URDF reading (``WorldModel.loadRobot``, Klampt's own URDF
  parser and converter to its robot format), configurations
  (``RobotModel.setConfig``) and link frames (``RobotModelLink.getTransform``).
* **From the contract**: everything else (``adapters/_engines.py``); FK only.

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
Klampt convention               what the adapter does
=============================== =============================================================
a configuration holds one entry the contract's variable of joint J goes to the entry of J's
per *link* (fixed ones too),    child link (found by name); every other entry (the six virtual
with a 6-DoF virtual floating   base links ``base0``...``base4``, fixed links) stays 0
base in front
frames relative to Klampt's     read relative to the root link's frame (``_engines.relative``);
world                           a URDF root named ``world`` is Klampt's world frame (identity)
``getTransform`` is (R, t),     R is read column-major into a 3x3 matrix
R a column-major 9-list
``loadRobot`` reads a file      the (geometry-free) document is written to a private temporary
                                file, loaded, and the file removed
importer messages               Klampt prints its progress: C-level stdout/stderr are silenced
                                while loading
geometry                        removed before loading (``_engines.kinematic_urdf``)
=============================== =============================================================

Known library semantics (left visible on purpose, ``FINDINGS.md``)
-----------------------------------------------------------------
* Axes that are not unit length (not URDF) are used as given: a revolute axis
  ``0 0 2`` turns twice as far, a prismatic ``0 3 0`` moves three times as far.
* ``<mimic>`` becomes an affine *driver*; ``setConfig`` sets links, not drivers
  (the adapter rejects mimic chains).
"""

from __future__ import annotations

import os
import tempfile
from typing import Any

import klampt
import numpy as np

from adapters._common import make_api
from adapters._engines import EngineModel, Matrix, quiet_stdio, unsupported


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are Klampt's (see the module docstring)."""

    __slots__ = ("_config", "_links", "_robot", "_slots")
    LIBRARY = "Klampt"

    def _load(self, data: bytes) -> Any:
        world = klampt.WorldModel()
        fd, path = tempfile.mkstemp(suffix=".urdf")
        try:
            with os.fdopen(fd, "wb") as handle:
                handle.write(data)
            with quiet_stdio():
                ok = world.loadRobot(path)
        finally:
            os.unlink(path)
        if not ok or world.numRobots() != 1:
            raise unsupported(self.LIBRARY, "loadRobot failed")
        robot = world.robot(0)
        names = {robot.link(i).getName(): i for i in range(robot.numLinks())}
        if self.root_link == "world" and "world" not in names:
            names["world"] = -1  # Klampt's importer makes a URDF link named world its world frame
        missing = [n for n in self.link_names if n not in names]
        if missing:
            raise unsupported(self.LIBRARY, f"no link named {', '.join(missing)} in the loaded robot")
        self._links = tuple(names[n] for n in self.link_names)
        slots = [0] * self.dof  # no mimic joints: variable v moves exactly one segment
        for segment, variable in enumerate(self.chain.variable.tolist()):
            if variable >= 0:
                slots[variable] = names[self.link_names[segment + 1]]
        self._slots = np.array(slots, dtype=np.intp)
        self._config = np.zeros(robot.numLinks())
        self._robot = robot
        return world  # the robot lives as long as its world

    def _frames(self, values: list[float], links: tuple[int, ...]) -> list[Matrix]:
        self._config[self._slots] = values
        self._robot.setConfig(self._config.tolist())
        out = []
        for link in links:
            t = np.eye(4)
            if self._links[link] < 0:
                out.append(t)
                continue
            rot, pos = self._robot.link(self._links[link]).getTransform()
            t[:3, :3] = np.asarray(rot, dtype=np.float64).reshape(3, 3).T
            t[:3, 3] = pos
            out.append(t)
        return out


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.klampt_adapter:api``."""
MoveGroup = api.MoveGroup
