"""The API around MuJoCo: link frames from MuJoCo's URDF compiler and ``mj_kinematics``.

Use it as ``--targets native,adapters.mujoco_adapter:api``.

What comes from where
---------------------
* **From MuJoCo**: URDF reading and compilation (``mujoco.MjSpec.from_string``,
  MuJoCo's own URDF importer), and the body frames (``mujoco.mj_kinematics``:
  ``data.xpos``/``data.xmat``).
* **From the contract**: everything else (``adapters/_engines.py``); FK only.

Conventions normalized (and nothing else)
-----------------------------------------
=============================== =============================================================
MuJoCo convention               what the adapter does
=============================== =============================================================
fixed joints are merged         ``compiler.fusestatic`` is set to false before compiling, so
(``fusestatic`` defaults to     every URDF link stays a body of its own name
true for URDF)
the root link hangs from        frames are read relative to the root link's body
MuJoCo's world body             (``_engines.relative``); a URDF root named ``world`` *is*
                                MuJoCo's world body (identity)
body frame vs inertial frame    ``xpos``/``xmat`` are the body (URDF link) frame; the inertial
                                frame (``xipos``) is never read
a moving body needs mass and    ``compiler.boundmass`` and ``boundinertia`` are set to 1e-9:
inertia above ``mjMINVAL``      a link without ``<inertial>`` (legal URDF) compiles; masses do
                                not enter ``mj_kinematics``
joint vector                    each contract variable is written to ``qpos[jnt_qposadr]`` of
                                the MuJoCo joint of the same name (hinge or slide)
geometry                        removed before loading (``_engines.kinematic_urdf``)
warnings                        MuJoCo appends its warnings (e.g. "equal lower and upper
                                limits, limit ignored") to ``MUJOCO_LOG.TXT`` in the working
                                directory: while loading, a ``mju_user_warning`` handler turns
                                them into Python ``RuntimeWarning``s instead
=============================== =============================================================

Known library semantics (left visible on purpose)
-------------------------------------------------
* ``<mimic>`` becomes an equality constraint, which ``mj_kinematics`` does not
  apply (only the simulation does): the adapter rejects mimic chains.
* Axes are normalized and ``<link><origin>`` is ignored, as in urdfdom/KDL.
"""

from __future__ import annotations

import warnings
from typing import Any

import mujoco
import numpy as np

from adapters._common import make_api
from adapters._engines import EngineModel, Matrix, unsupported


def _warn(message: str) -> None:
    """MuJoCo's warning handler while the adapter loads (instead of MUJOCO_LOG.TXT)."""
    warnings.warn(f"MuJoCo: {message}", RuntimeWarning, stacklevel=2)


class RobotModel(EngineModel):
    """A chain loaded from URDF whose link frames are MuJoCo's (see the module docstring)."""

    __slots__ = ("_bodies", "_data", "_qadr")
    LIBRARY = "MuJoCo"

    def _load(self, data: bytes) -> Any:
        previous = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(_warn)
        try:
            spec = mujoco.MjSpec.from_string(data.decode("utf-8"))
            spec.compiler.fusestatic = False
            spec.compiler.boundmass = 1e-9
            spec.compiler.boundinertia = 1e-9
            model = spec.compile()
        finally:
            mujoco.set_mju_user_warning(previous)
        self._data = mujoco.MjData(model)
        self._data.qpos[:] = 0.0
        bodies = []
        for name in self.link_names:
            bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            if bid < 0 and name == self.root_link:
                bid = 0  # the URDF root became MuJoCo's world body
            if bid < 0:
                raise unsupported(self.LIBRARY, f"link '{name}' is not a body of the compiled model")
            bodies.append(bid)
        self._bodies = tuple(bodies)
        qadr = []
        for name in self.joint_names:
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if jid < 0:
                raise unsupported(self.LIBRARY, f"joint '{name}' is not a joint of the compiled model")
            qadr.append(int(model.jnt_qposadr[jid]))
        self._qadr = np.array(qadr, dtype=np.intp)
        return model

    def _frames(self, values: list[float], links: tuple[int, ...]) -> list[Matrix]:
        self._data.qpos[self._qadr] = values
        mujoco.mj_kinematics(self._lib, self._data)
        out = []
        for link in links:
            t = np.eye(4)
            body = self._bodies[link]
            t[:3, :3] = self._data.xmat[body].reshape(3, 3)
            t[:3, 3] = self._data.xpos[body]
            out.append(t)
        return out


api = make_api(RobotModel, __name__)
"""The implementation to plug in: ``--targets native,adapters.mujoco_adapter:api``."""
MoveGroup = api.MoveGroup
