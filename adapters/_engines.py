"""The shared part of the FK adapters around simulators and URDF stacks (issue 14).

MuJoCo, PyBullet, Drake, yourdfpy, pytransform3d, Klampt and placo each read
the URDF with their own parser and compute link frames with their own
kinematics. Their adapters (``adapters/<lib>_adapter.py``) only differ in how
they load a document and read one link's frame for a joint vector; everything
else lives here (or in ``adapters._common``) and is the contract's
(``python_impl``): URDF validation and errors, chain selection, joint names and
order, limits, ``home_values``, argument checks, and ``MoveGroup`` (planning in
joint space, poses from the library's FK).

Shared conventions
------------------
* **Root frame**: every library puts the robot in a world of its own (MuJoCo's
  world body, PyBullet's base, Drake's world frame, placo's floating base). The
  adapters always read the root link's frame ``T_w_root`` and the link's frame
  ``T_w_link`` from the library and report ``inv(T_w_root) @ T_w_link``, so where
  the library puts the robot (and whether the base floats) cannot matter.
* **Geometry**: ``<visual>`` and ``<collision>`` elements are removed from the
  document before the library sees it (:func:`kinematic_urdf`): meshes are not
  kinematics, and their ``package://`` files are not resolvable here. Comments go
  too; nothing else changes (``<link><origin>``, odd axes, ``<inertial>`` stay), and
  the contract's parser must read the same kinematic model from both documents.
* **Crashes**: a URDF on which the library is known to kill the process
  (``_crashes_on``: PyBullet segfaults, Drake aborts; ``FINDINGS.md``) is refused
  with ``URDFError(URDF_UNSUPPORTED)`` before the library sees it.
* **Mimic joints** are rejected at load with ``URDFError(URDF_UNSUPPORTED)``: the
  adapters drive each library by joint name and would otherwise leave the mimic
  joint at zero.
* **Inverse kinematics**: these adapters are FK-only unless a module says
  otherwise; ``inverse_kinematics`` raises ``InvalidInputError(UNSUPPORTED_OPERATION)``
  naming the library (campaigns run ``--op fk``).
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
from collections.abc import Iterator
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from adapters._common import LibraryModel, refuse_mimic_joints, urdf_bytes
from python_impl.urdf import Urdf, load_urdf
from robot_api.errors import ErrorCode, InvalidInputError, URDFError
from robot_api.protocol import JointValues
from robot_api.records import IKResult, Pose

Matrix = NDArray[np.float64]

_COMMENT = re.compile(rb"<!--.*?-->", re.S)
_GEOMETRY = re.compile(rb"<(visual|collision)\b[^>]*?/>|<(visual|collision)\b.*?</\2\s*>", re.S)


def kinematic_urdf(data: bytes) -> bytes:
    """The document without comments and ``<visual>``/``<collision>`` elements (module docstring).

    The contract's parser accepted ``data`` first, so it is well-formed and has
    no entity declarations; comments cannot contain ``--``, and these two element
    names cannot nest in URDF. ``EngineModel`` checks that the result has the
    same kinematic model as ``data`` (the contract's parser on both).
    """
    return _GEOMETRY.sub(b"", _COMMENT.sub(b"", data))


@contextlib.contextmanager
def quiet_stdio() -> Iterator[None]:
    """Silence the C-level stdout and stderr (file descriptors 1 and 2) of a chatty library call.

    Bullet's and Klampt's importers print warnings with ``printf`` for every link
    without inertia, which would otherwise interleave with the fuzzer's output.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])


def relative(t_world_root: Matrix, t_world_link: Matrix) -> Matrix:
    """``inv(t_world_root) @ t_world_link`` for rigid transforms (transpose, not inverse)."""
    rot = t_world_root[:3, :3].T
    out = np.eye(4)
    out[:3, :3] = rot @ t_world_link[:3, :3]
    out[:3, 3] = rot @ (t_world_link[:3, 3] - t_world_root[:3, 3])
    return out


def unsupported(library: str, what: str) -> URDFError:
    """The load error of a URDF a library cannot represent."""
    return URDFError(f"{library}: {what}", ErrorCode.URDF_UNSUPPORTED)


class EngineModel(LibraryModel):
    """A chain loaded from URDF whose link frames come from a third-party library.

    Subclasses set ``LIBRARY`` and implement ``_load`` and ``_frames``.

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
        mimic joint on the chain, or the library cannot load it (``URDF_UNSUPPORTED``).
    UnknownNameError
        ``tip_link`` is not a link of the URDF.
    """

    __slots__ = ("_lib",)
    LIBRARY: ClassVar[str] = "?"

    def __init__(self, urdf: str | os.PathLike[str], tip_link: str | None = None) -> None:
        super().__init__(urdf, tip_link)
        refuse_mimic_joints(
            self, f"{self.LIBRARY}: the adapter drives joints by name and has no mimic joints"
        )
        original = urdf_bytes(urdf)
        data = kinematic_urdf(original)
        try:
            document = load_urdf(data.decode("utf-8"), False)
            reference = load_urdf(original.decode("utf-8"), False)
        except UnicodeDecodeError:
            raise unsupported(self.LIBRARY, "the adapters hand libraries UTF-8 documents only") from None
        if (document.name, document.links, document.joints) != (
            reference.name,
            reference.links,
            reference.joints,
        ):
            raise unsupported(self.LIBRARY, "removing <visual>/<collision> would change the kinematic model")
        crash = self._crashes_on(document)
        if crash:
            raise unsupported(self.LIBRARY, f"refused before loading: {crash} (FINDINGS.md)")
        try:
            self._lib = self._load(data)
        except URDFError:
            raise
        except Exception as exc:  # noqa: BLE001 - whatever the library raises, it cannot load this URDF
            raise unsupported(self.LIBRARY, f"cannot load the URDF: {type(exc).__name__}: {exc}") from None

    def _crashes_on(self, document: Urdf) -> str:
        """Why the library would kill the process on this (contract-accepted) URDF, or ``""``."""
        return ""

    def _load(self, data: bytes) -> Any:
        """The library's model of ``data`` (raises anything when it cannot load it)."""
        raise NotImplementedError

    def _frames(self, values: list[float], links: tuple[int, ...]) -> list[Matrix]:
        """Frames of the root link and of ``links`` in the library's world, for the contract's values."""
        raise NotImplementedError

    def _matrix(self, values: list[float] | NDArray[np.float64], link: int) -> Matrix:
        root, frame = self._frames([float(v) for v in values[: self.dof]], (0, link))
        return relative(root, frame)

    def inverse_kinematics(
        self, pose: Pose, seed: JointValues | None = None, link: str | None = None
    ) -> IKResult:
        """Not offered: this adapter is FK-only (see the module docstring).

        Parameters
        ----------
        pose : Pose or (position, orientation)
            Target.
        seed : sequence of float, shape (dof,), optional
            Start of the search.
        link : str, optional
            A link of the chain; the tip by default.

        Raises
        ------
        InvalidInputError
            Always, with ``UNSUPPORTED_OPERATION``, after the contract's argument checks.
        """
        self._ik_start(pose, seed, link)
        raise InvalidInputError(
            f"the {self.LIBRARY} adapter offers forward kinematics only", ErrorCode.UNSUPPORTED_OPERATION
        )
