"""The API around Drake: link frames from ``pydrake``'s URDF parser and ``MultibodyPlant``.

Use it as ``--targets native,adapters.drake_adapter:api``.

What comes from where
---------------------
* **From Drake**: URDF reading (``pydrake.multibody.parsing.Parser``, Drake's own
  URDF parser), the ``MultibodyPlant`` it builds, and forward kinematics
  (``MultibodyPlant.CalcRelativeTransform``).
* **From the contract**: everything else (``adapters/_engines.py``); FK only.

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
Drake convention                what the adapter does
=============================== =============================================================
a root link not joined to       the root link's body is welded to the world
``world`` gets a floating       (``MultibodyPlant.WeldFrames``) before ``Finalize``; a URDF
joint at ``Finalize``           root named ``world`` *is* Drake's world body
frames relative to any frame    ``CalcRelativeTransform(context, root_frame, link_frame)``:
                                already the contract's pose
joint vector                    each contract variable is written at its joint's
                                ``position_start()`` in the plant's position vector
continuous joints               Drake makes them ``RevoluteJoint``s without limits (the angle)
geometry                        removed before loading (``_engines.kinematic_urdf``)
crashes                         an empty ``<robot name>`` or a negative velocity limit (both end
                                the process in a ``DRAKE_DEMAND``) is refused with
                                ``URDFError(URDF_UNSUPPORTED)`` before parsing
parser messages                 Drake warns about every dynamics tag it does not model (joint
                                friction, mechanical reductions): the ``drake`` logger is set
                                to ERROR while parsing (restored afterwards)
=============================== =============================================================

Known library semantics (left visible on purpose)
-------------------------------------------------
* ``<mimic>`` becomes a coupler constraint, which FK does not apply: the adapter
  rejects mimic chains. Axes are normalized, ``<link><origin>`` is ignored.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from adapters._common import make_api
from adapters._engines import EngineModel, Matrix
from python_impl.urdf import Urdf


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are Drake's (see the module docstring)."""

    __slots__ = ("_context", "_frames_of", "_q", "_qadr")
    LIBRARY = "Drake"

    def _crashes_on(self, document: Urdf) -> str:
        if not document.name:
            return "Drake's parser aborts the process on an empty <robot name> (F-DRAKE-1)"
        for joint in document.joints.values():
            if joint.limits is not None and joint.type != "fixed" and joint.limits.velocity < 0:
                return f"Drake aborts on the negative velocity limit of '{joint.name}' (F-DRAKE-1)"
        return ""

    def _load(self, data: bytes) -> Any:
        plant = MultibodyPlant(0.0)
        log = logging.getLogger("drake")
        level = log.level
        log.setLevel(logging.ERROR)
        try:
            (instance,) = Parser(plant).AddModelsFromString(data.decode("utf-8"), "urdf")
        finally:
            log.setLevel(level)
        bodies = [
            plant.GetBodyByName(name, instance)
            if plant.HasBodyNamed(name, instance)
            else plant.GetBodyByName(name)  # a URDF link named world is Drake's world body
            for name in self.link_names
        ]
        frames = [body.body_frame() for body in bodies]
        root = bodies[0].index()
        joined = any(plant.get_joint(j).child_body().index() == root for j in plant.GetJointIndices(instance))
        if root != plant.world_body().index() and not joined:
            plant.WeldFrames(plant.world_frame(), frames[0])
        plant.Finalize()
        self._frames_of = tuple(frames)
        self._qadr = np.array(
            [plant.GetJointByName(name, instance).position_start() for name in self.joint_names],
            dtype=np.intp,
        )
        self._context = plant.CreateDefaultContext()
        self._q = np.array(plant.GetPositions(self._context))  # defaults: a free body's unit quaternion
        return plant

    def _matrix(self, values: list[float] | Any, link: int) -> Matrix:
        self._q[self._qadr] = [float(v) for v in values[: self.dof]]
        self._lib.SetPositions(self._context, self._q)
        pose = self._lib.CalcRelativeTransform(self._context, self._frames_of[0], self._frames_of[link])
        return np.array(pose.GetAsMatrix4(), dtype=np.float64)


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.drake_adapter:api``."""
MoveGroup = api.MoveGroup
