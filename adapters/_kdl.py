"""PyKDL for the adapter (:mod:`adapters.pykdl_adapter`): loading Debian's build, and the
chain pieces built as kdl_parser builds them (segments, urdfdom's quaternion, frames and the
contract's quaternion sign)."""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from python_impl.transforms import unit
from python_impl.urdf import Joint

DEBIAN_DIST_PACKAGES = Path("/usr/lib/python3/dist-packages")
"""Where Debian's ``python3-pykdl`` installs ``PyKDL.<abi>.so``."""


def load_pykdl() -> ModuleType:
    """Import PyKDL: from ``sys.path`` if there, else Debian's build by file.

    Raises
    ------
    ImportError
        If no PyKDL matching this interpreter's ABI can be loaded.
    """
    if "PyKDL" in sys.modules:
        return sys.modules["PyKDL"]
    if importlib.util.find_spec("PyKDL") is not None:
        return importlib.import_module("PyKDL")
    suffixes = importlib.machinery.EXTENSION_SUFFIXES
    candidates = [DEBIAN_DIST_PACKAGES / f"PyKDL{suffix}" for suffix in suffixes]
    path = next((p for p in candidates if p.is_file()), None)
    if path is None:
        found = sorted(p.name for p in DEBIAN_DIST_PACKAGES.glob("PyKDL*.so"))
        raise ImportError(
            "PyKDL is not available for this interpreter "
            f"(Python {sys.version_info.major}.{sys.version_info.minor}, extension suffixes "
            f"{importlib.machinery.EXTENSION_SUFFIXES}); found in {DEBIAN_DIST_PACKAGES}: "
            f"{found or 'nothing'}. Install Debian's python3-pykdl (scripts/apt-ensure.sh python3-pykdl) "
            "and run with a CPython of Debian's python3 version."
        )
    spec = importlib.util.spec_from_file_location("PyKDL", path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load PyKDL from {path}")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:
        raise ImportError(f"cannot load PyKDL from {path}: {type(exc).__name__}: {exc}") from exc
    sys.modules["PyKDL"] = module
    return module


KDL: Any = load_pykdl()


def frame_matrix(frame: Any) -> NDArray[np.float64]:
    """4x4 homogeneous matrix of a ``PyKDL.Frame``."""
    m = np.eye(4)
    rotation, position = frame.M, frame.p
    for r in range(3):
        m[r, 0] = rotation[r, 0]
        m[r, 1] = rotation[r, 1]
        m[r, 2] = rotation[r, 2]
        m[r, 3] = position[r]
    return m


def urdfdom_quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """urdfdom's ``Rotation::setFromRPY`` (then ``normalize()``): the quaternion kdl_parser reads."""
    phi, the, psi = roll / 2.0, pitch / 2.0, yaw / 2.0
    sphi, cphi = math.sin(phi), math.cos(phi)
    sthe, cthe = math.sin(the), math.cos(the)
    spsi, cpsi = math.sin(psi), math.cos(psi)
    x = sphi * cthe * cpsi - cphi * sthe * spsi
    y = cphi * sthe * cpsi + sphi * cthe * spsi
    z = cphi * cthe * spsi - sphi * sthe * cpsi
    w = cphi * cthe * cpsi + sphi * sthe * spsi
    s = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / s, y / s, z / s, w / s)


def segment_of(joint: Joint, urdfdom_origins: bool = False) -> Any:
    """A ``PyKDL.Segment`` for a URDF joint and its child link, as kdl_parser builds it.

    The origin's rotation is ``Rotation.RPY(rpy)``, or with ``urdfdom_origins``
    ``Rotation.Quaternion`` of urdfdom's quaternion of ``rpy`` (kdl_parser's path).
    """
    rotation = (
        KDL.Rotation.Quaternion(*urdfdom_quaternion(*joint.rpy))
        if urdfdom_origins
        else KDL.Rotation.RPY(*joint.rpy)
    )
    origin = KDL.Frame(rotation, KDL.Vector(*joint.xyz))
    if joint.type in ("revolute", "continuous", "prismatic"):
        a = unit(joint.axis)  # the contract's axis rule (non-zero: the chain rules checked it)
        axis = origin.M * KDL.Vector(float(a[0]), float(a[1]), float(a[2]))
        kind = KDL.Joint.TransAxis if joint.type == "prismatic" else KDL.Joint.RotAxis
        return KDL.Segment(joint.child, KDL.Joint(joint.name, origin.p, axis, kind), origin)
    return KDL.Segment(joint.child, KDL.Joint(joint.name, KDL.Joint.Fixed), origin)
