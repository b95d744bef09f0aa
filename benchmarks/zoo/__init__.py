"""The bug zoo: fault-injected variants of the twin, each a real bug class of kinematics stacks.

Every entry names its variant (``benchmarks/zoo/bugs.py``), says in one line
what is wrong, cites a public source of the bug class, and gives the campaign
in which the engine is expected to show it: the op, and a robot with the
feature the bug needs (continuous joints, a mimic joint, URDF defaults...). A
bug counts as *detected* when a campaign of ``native`` against the variant
reports a divergence that is not ``ill_conditioned``, ``known_limitation`` or
``flaky``. The ``control`` entry is the unmodified twin: any detection there is
a false positive. ``CONTROLS`` runs it on every configuration a zoo bug uses,
``fk`` on every known robot and ``ik`` on the default arm.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

ZOO_ROBOT = str(Path(__file__).resolve().parents[1] / "robots" / "zoo_arm.urdf")


@dataclass(frozen=True)
class Bug:
    name: str
    description: str
    source: str
    op: str = "move"
    robot: str = "probot_anno"
    tip_link: str | None = None
    variant: str = ""
    """The variant in ``benchmarks/zoo/bugs.py`` (default: ``name``)."""

    @property
    def target(self) -> str:
        return f"benchmarks.zoo.bugs:{self.variant or self.name}"

    @property
    def is_control(self) -> bool:
        return (self.variant or self.name) == "control"


ZOO: tuple[Bug, ...] = (
    Bug(
        "wrap_positive",
        "continuous joints reported in [0, 2pi) instead of (-pi, pi]",
        "ros/angles angles/include/angles/angles.h: normalize_angle_positive ([0, 2pi)) beside normalize_angle ((-pi, pi]); moveit_commander issue #31 (continuous joint at 15 rad 'out of bounds')",
        robot="kinova",
    ),
    Bug(
        "pi_boundary",
        "a continuous joint at exactly pi reported as -pi ([-pi, pi) instead of (-pi, pi])",
        "https://github.com/ros/angles/pull/19 ('the new implementation will give -3.141592653589793 and the old 3.141592653589793')",
        robot="kinova",
    ),
    Bug(
        "silent_clamp",
        "an out-of-bounds joint target silently clamped instead of rejected",
        "https://github.com/moveit/moveit2_tutorials/pull/96 (a target outside the limits is accepted and clamped with a warning; 'this is more of a bug')",
    ),
    Bug(
        "target_despite_error",
        "a rejected target is set anyway and the arm moves beyond its limits",
        "moveit move_group_interface.h setJointValueTarget: 'If these values are out of bounds then false is returned BUT THE VALUES ARE STILL SET AS THE GOAL'",
    ),
    Bug(
        "missing_lower_unlimited",
        "a <limit> without lower read as unlimited instead of 0",
        "ros/urdfdom urdf_parser/src/joint.cpp parseJointLimits ('no lower, defaults to 0'); https://github.com/dartsim/dart/issues/605",
        robot=ZOO_ROBOT,
    ),
    Bug(
        "axis_not_normalized",
        "a joint axis of length 2 used without normalizing",
        "https://github.com/compas-dev/compas/issues/864 (non-unit axis scales the rotation); pytorch_kinematics commit 453c2fa6 'Fix improper scaling when joint axis not given with unit norm'",
        op="fk",
        robot=ZOO_ROBOT,
    ),
    Bug(
        "missing_axis_z",
        "a joint without <axis> turns about z instead of x",
        "https://github.com/ros/kdl_parser/pull/84 ('The <axis> element is actually optional ... sets the axis to the default value (1,0,0)'); pytorch_kinematics frame.py defaults axis to (0, 0, 1)",
        op="fk",
        robot=ZOO_ROBOT,
    ),
    Bug(
        "quaternion_not_normalized",
        "the IK target quaternion used without normalizing",
        "https://github.com/PilzDE/pilz_industrial_motion/issues/60 ('IK solution not found if quaternion not properly normalised'); https://github.com/moveit/moveit/issues/1458",
        op="ik",
    ),
    Bug(
        "rpy_gimbal_band",
        "orientation through roll-pitch-yaw with a gimbal-lock branch taken 1e-6 too early",
        "orocos_kdl/src/frames.cpp Rotation::GetRPY (gimbal branch at PI/2 - 1e-12); https://github.com/ros/geometry2/issues/504 (wrong roll at pitch -90 deg)",
        op="fk",
    ),
    Bug(
        "float32_integration",
        "execution integrates velocities in float32, ending off the goal",
        "pytorch_kinematics chain.py/frame.py default dtype=torch.float32; https://github.com/tesseract-robotics/tesseract_planning/pull/57 (float trajectories failing bounds by epsilon)",
    ),
    Bug(
        "mimic_ignored",
        "a mimic joint left at 0 instead of following its master",
        "ros/kdl_parser kdl_parser.cpp toKdl() never reads jnt->mimic; https://github.com/ADVRHumanoids/ROSEndEffector/issues/30",
        op="fk",
        robot="panda",
        tip_link="panda_rightfinger",
    ),
    Bug(
        "last_sample_dropped",
        "the trajectory's last sample dropped: the arm stops short of the goal",
        "https://github.com/moveit/moveit2/pull/1274 ('fix a corner case for TOTG where it might not use the last input waypoint')",
    ),
    Bug(
        "ik_status_misread",
        "IK reports success when it did not converge",
        "orocos_kdl solveri.hpp (E_DEGRADED = +1, failures negative) vs trac_ik CartToJnt returning solution counts, callers testing rc >= 0; https://github.com/orocos/orocos_kinematics_dynamics/pull/358",
        op="ik",
    ),
    Bug(
        "off_by_tolerance",
        "a goal tolerance of 1e-5 instead of MoveIt's 1e-4 on bounds checks",
        "moveit move_group_interface.h DEFAULT_GOAL_JOINT_TOLERANCE = 1e-4; satisfiesBounds(margin) in revolute_joint_model.cpp; https://github.com/moveit/moveit2/issues/2090",
    ),
)

CONTROL = Bug("control", "the unmodified twin: no fault", "-")


def _controls() -> tuple[Bug, ...]:
    from robot_api.robots import DEFAULT_ROBOT, known_robots

    configs = {(b.op, b.robot, b.tip_link) for b in ZOO}
    configs |= {("fk", robot, None) for robot in known_robots()}
    configs.add(("ik", DEFAULT_ROBOT, None))
    out = []
    for op, robot, tip in sorted(configs, key=lambda c: (c[0], c[1], c[2] or "")):
        where = Path(robot).stem if robot.endswith(".urdf") else robot
        name = f"control@{op}/{where}" + (f"/{tip}" if tip else "")
        out.append(Bug(name, "the unmodified twin: no fault", "-", op, robot, tip, variant="control"))
    return tuple(out)


CONTROLS: tuple[Bug, ...] = _controls()
"""The control on every op and robot configuration a zoo bug uses, ``fk`` on every known
robot (example-robot-data's included) and ``ik`` on the default arm."""

BY_NAME = {bug.name: bug for bug in (*ZOO, CONTROL, *CONTROLS)}
