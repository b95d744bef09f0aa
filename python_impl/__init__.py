"""The Python twin: the same API as ``native``, written independently.

Pure Python + numpy: URDF via expat under the contract's XML rules, with
urdfdom's rules, kinematics from textbook formulas; no KDL, urdfdom or other
kinematics library. The contract is ``docs/api.md``.
"""

from python_impl.model import RobotModel
from python_impl.move_group import MoveGroup

__all__ = ["MoveGroup", "RobotModel"]
