"""The bug zoo: fault-injected variants of the twin, each a real bug class of kinematics stacks.

Every entry names its variant (``benchmarks/zoo/bugs.py``; the stateful ones, which
need a second call on a live group or a look at a trajectory, ``benchmarks/zoo/stateful.py``
with ``op="scenario"``), says in one line
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
    """The variant in ``benchmarks/zoo/<module>.py`` (default: ``name``)."""
    module: str = "bugs"
    """The module of the variant: ``bugs`` (one call shows them) or ``stateful`` (they need a
    live group: a second call, or a look at a trajectory)."""
    package: str = "benchmarks.zoo"
    """The package of ``module`` (``benchmarks`` for ``UNTUNED``'s ``untuned_bugs``)."""

    @property
    def target(self) -> str:
        return f"{self.package}.{self.module}:{self.variant or self.name}"

    @property
    def is_control(self) -> bool:
        return (self.variant or self.name) == "control"


ONE_CALL: tuple[Bug, ...] = (
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

STATEFUL: tuple[Bug, ...] = (
    Bug(
        "continuous_accumulates",
        "a continuous joint's state accumulates across moves instead of staying in (-pi, pi]",
        "https://github.com/osrf/drcsim/issues/58 (continuous joint 'not limited ... after some time is a value in the 100s'); https://github.com/moveit/moveit_core/pull/174 ('nothing to enforce the continuous joint values to be between -pi and +pi')",
        op="scenario",
        robot="kinova",
        module="stateful",
    ),
    Bug(
        "start_state_home",
        "plans start from the home state instead of the current state; the second go() fails",
        "https://github.com/ros-industrial-consortium/scan_n_plan_workshop/pull/81 ('Fixed error that was always setting start state to zeros'); https://github.com/ros-industrial/stomp_ros/issues/14 ('start point deviates from current robot state' on the second command)",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "cached_pose",
        "get_current_pose() caches the first FK result and never invalidates it after a move",
        "https://github.com/moveit/moveit2/issues/3459 (getCurrentPose() returns the pose before the move); https://github.com/StanfordVL/BEHAVIOR-1K/issues/880 ('kinematic only pose cache ... can output wrong values if the scene is moved')",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "cartesian_ignores_scaling",
        "compute_cartesian_path times its path at full speed, ignoring the scaling factors",
        "https://github.com/moveit/moveit/issues/1065 ('set_max_{velocity,acceleration}_scaling_factor not working in compute_cartesian_path'); https://github.com/moveit/moveit2/issues/1967",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "acceleration_scaling_ignored",
        "the acceleration scaling factor is checked but not applied: same end point, too fast",
        "https://github.com/tesseract-robotics/tesseract_planning/issues/118 (TOTG's scaling factors unused); https://github.com/moveit/moveit2/issues/3779 ('max_acceleration_scaling_factor not honored by TOTG')",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "duplicate_start_point",
        "plan() repeats the start point at time 0: time_from_start not strictly increasing",
        "https://github.com/shadow-robot/sr_interface/pull/363 ('waypoints that are not strictly increasing in time ... the initial two waypoints in the plan being the same, both having a time_from_start of 0')",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "execute_stops_short",
        "execute(plan) leaves the arm at the plan's second-to-last point",
        "https://github.com/ros-industrial/staubli_val3_driver/issues/16 ('Last point of trajectory skipped')",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "remember_aliases_state",
        "remember_joint_values() stores the live state list, so the remembered state follows the arm",
        "https://github.com/pollen-robotics/reachy_mini/issues/68 ('get_current_joints() misses a .copy()': callers alias the live joint state)",
        op="scenario",
        module="stateful",
    ),
    Bug(
        "pose_goal_scaled_twice",
        "a plan to a pose or position goal applies the velocity scaling twice: same end, within every limit, too slow",
        "https://github.com/NVlabs/curobo/issues/251 ('velocity_scale is applied twice reducing the velocity limits by a factor of (velocity_scale)^2'); https://github.com/IvoD1998/Staubli_ROS2/issues/8 ('Velocity scaling performed twice', seen in pose tracking)",
        op="scenario",
        robot="xarm7",
        module="stateful",
    ),
)
"""Bugs that need a live group: a second call, or a look at a planned or executed trajectory.
``--op move`` (one call on a fresh group) is expected to miss them; ``--op scenario`` to find them."""

ZOO: tuple[Bug, ...] = (*ONE_CALL, *STATEFUL)
"""Every zoo bug: those one call shows, then the stateful ones."""

DEEP: tuple[Bug, ...] = (
    Bug(
        "narrow_band",
        "FK wrong (1 mm) only for joint_2 in a band 0.1% wide of its range, at 61.73% of it",
        "https://github.com/pollen-robotics/reachy2_symbolic_ik/issues/34 (within a tolerance band around a singularity the solver deliberately gives 'a slightly false result'); https://github.com/bourumir-wyngs/rs-opw-kinematics/issues/56 (behaviour decided by a 0.125 um shift band)",
        op="fk",
        module="deep",
    ),
    Bug(
        "joint_relation",
        "FK wrong only when joint_1 - joint_3 is within 1e-3 of sqrt(2) - 1 (two joints in a relation)",
        "https://github.com/Sarrasor/RoboticManipulators/issues/1 (Fanuc FK wrong because of the J2/J3 coupling: 'J3 = J3+J2')",
        op="fk",
        module="deep",
    ),
    Bug(
        "computed_branch",
        "FK wrong only when the computed tool x position lies in [0.1234, 0.1244) m (a branch on a computed float)",
        "https://github.com/Jgocunha/universal-robots-kinematics/issues/17 and pull 52 (a branch on the computed theta5: exact equality missed values near zero that came from rounding in acos)",
        op="fk",
        module="deep",
    ),
    Bug(
        "atan2_quadrant",
        "the tool position mirrored only when its azimuth atan2(y, x) lies in (2.0, 2.01) rad",
        "https://github.com/MethodicalAcceleratorDesign/MAD-NG/issues/415 (atan2 incorrect in quadrants 2 and 3); https://github.com/rdiankov/openrave/issues/278 (ikfast: atan2(py, px) case not considered)",
        op="fk",
        module="deep",
    ),
    Bug(
        "calibration_entry",
        "one wrong entry of a per-joint calibration table: joint_3 off by 1 mrad when round(100 q) == 137",
        "https://github.com/robotology/mesh-support/issues/308 ('a bug in the calibration xls file: the sign of the zero of joint 2 had a wrong sign')",
        op="fk",
        module="deep",
    ),
    Bug(
        "small_angle_wrist",
        "a near-singular wrist: joint_5 within 2e-3 rad of 0 (but not 0) treated as 0",
        "https://github.com/Jgocunha/universal-robots-kinematics/issues/17 (IK 'silent failure at theta5 ~ 0': theta6 set to 0 in the singular case); https://github.com/bourumir-wyngs/rs-opw-kinematics/issues/58 (J4/J6 wrong within the singularity zone of J5)",
        op="fk",
        module="deep",
    ),
    Bug(
        "narrower_band",
        "FK wrong (1 mm) only for joint_2 in a band 1e-5 of its range wide, at 38.29% of it",
        "https://github.com/bourumir-wyngs/rs-opw-kinematics/issues/56 (behaviour decided by a 0.125 um shift band: far narrower than 0.1%); https://github.com/pollen-robotics/reachy2_symbolic_ik/issues/34",
        op="fk",
        module="deep",
    ),
    Bug(
        "tight_relation",
        "FK wrong only when joint_2 + joint_4 is within 2e-5 of 1/e (a thin slab of two joints)",
        "https://github.com/Sarrasor/RoboticManipulators/issues/1 (a J2/J3 coupling error in Fanuc FK)",
        op="fk",
        module="deep",
    ),
    Bug(
        "amplified_error",
        "the tool's z off by 1e-11 / |joint_5 - 0.6583| m: a difference above rounding almost everywhere, above 1e-6 m only within 1e-5 rad",
        "https://github.com/Jgocunha/universal-robots-kinematics/issues/17 (error blowing up near theta5 ~ 0); https://github.com/bourumir-wyngs/rs-opw-kinematics/issues/58 (J4/J6 wrong within the singularity zone of J5)",
        op="fk",
        module="deep",
    ),
    Bug(
        "wrap_past_pi",
        "a revolute joint target in [4.0, 4.05) rad (limits +-2pi) wrapped into (-pi, pi]",
        "https://github.com/Kinovarobotics/kinova-ros/pull/20 ('removed angle normalization of joints 1,4,5,6 to allow full rotations'); https://github.com/moveit/moveit_commander/issues/31 (targets normalized into [-pi, pi])",
        robot="ur5",
        module="deep",
    ),
    Bug(
        "per_joint_band",
        "a move target's joint in [0.86131, 0.86133) rad moved by 1 mrad, the band tested per joint inside a list comprehension (a per-joint correction)",
        "https://github.com/robotology/mesh-support/issues/308 (a wrong per-joint calibration entry); https://github.com/Kinovarobotics/kinova-ros/pull/20 (a per-joint change of targets: 'removed angle normalization of joints 1,4,5,6')",
        module="deep",
    ),
    Bug(
        "ik_seed_band",
        "IK reports its seed as a success when the seed's joint_1 lies in [0.3, 0.31) rad (only from certain seeds)",
        "https://github.com/tesseract-robotics/tesseract_planning/pull/763 (a seed-dependent IK gives a wrong branch from some seeds); https://github.com/TAMS-Group/bio_ik/issues/48 ('returned state may differ from input pose and doesn't respect success criteria')",
        op="scenario",
        module="deep",
    ),
    Bug(
        "execute_skips_start_check",
        "execute(plan) runs a plan made before the arm moved from the plan's own start (no check of the start against the current state): it takes /plan, a move, then /execute",
        "https://github.com/moveit/moveit/pull/63 ('validate trajectory before execution': the start point against the current state, allowed_start_tolerance); https://github.com/personalrobotics/aikido/issues/272 ('TrajectoryExecutors should check that the trajectory starts at the right place')",
        op="scenario",
        module="deep",
    ),
    Bug(
        "plan_start_band",
        "a plan starts 1 mrad off when the current joint_2 lies in a band 0.1% of its range wide (at 68.21% of it): the arm must be moved into the band before a /plan",
        "https://github.com/robotology/mesh-support/issues/308 (a wrong entry of a per-joint calibration table); https://github.com/ros-industrial-consortium/scan_n_plan_workshop/pull/81 (the planner's start state read wrong)",
        op="scenario",
        module="deep",
    ),
    Bug(
        "profile_switch_band",
        "a move just past the switch from the triangular to the trapezoidal velocity profile (A / v^2 of the path's bounds in (1, 1.001), a float computed from the move and both scaling factors) timed as a triangle: up to 0.05% over the velocity limit",
        "https://github.com/nameofuser1/py-scurve/issues/3 ('wrong profile when max velocity can not be reached': the duration jumps at the switch between the profiles); https://github.com/orocos/orocos_kinematics_dynamics/pull/39 ('Check that the maxvel is obtainable in a half trapezoidal velocity profile')",
        op="scenario",
        module="deep",
    ),
)
"""Deep bugs (issue 11, ``benchmarks/zoo/deep.py``): faults confined to narrow regions of
the input space, for ``benchmarks.bench_deep``; not part of ``ZOO``'s runs."""

CONTROL = Bug("control", "the unmodified twin: no fault", "-")
SCENARIO_UR5 = ("scenario", "ur5", None)
"""A scenario control on UR5 besides the zoo's arms: joint limits of +-2 pi and a singular home
make its IK steps the hardest to judge (where a false positive was found, docs/engine.md
"Ill-conditioning")."""
IK_UR5 = ("ik", "ur5", None)
"""An ``ik`` control on UR5 for the same reason (single IK calls from its singular home)."""
IK_ARMS = (("ik", "panda", None), ("ik", "kinova", None), ("ik", "xarm7", None))
"""``ik`` controls on the other seven- and six-axis arms: a redundant arm (Panda, xArm7) and
continuous joints (Kinova) give Newton-Raphson other ways to part."""


def _controls() -> tuple[Bug, ...]:
    from robot_api.robots import DEFAULT_ROBOT, known_robots

    configs = {(b.op, b.robot, b.tip_link) for b in ZOO}
    configs |= {("fk", robot, None) for robot in known_robots()}
    configs.add(("ik", DEFAULT_ROBOT, None))
    configs |= {SCENARIO_UR5, IK_UR5, *IK_ARMS}
    out = []
    for op, robot, tip in sorted(configs, key=lambda c: (c[0], c[1], c[2] or "")):
        where = Path(robot).stem if robot.endswith(".urdf") else robot
        name = f"control@{op}/{where}" + (f"/{tip}" if tip else "")
        out.append(Bug(name, "the unmodified twin: no fault", "-", op, robot, tip, variant="control"))
    return tuple(out)


CONTROLS: tuple[Bug, ...] = _controls()
"""The control on every op and robot configuration a zoo bug uses, ``fk`` on every known
robot (example-robot-data's included), ``ik`` on the default arm, UR5, Panda, Kinova and
xArm7, and ``scenario`` on UR5."""

UNTUNED: tuple[Bug, ...] = tuple(
    Bug(name, description, source, op, package="benchmarks", module="untuned_bugs")
    for name, description, source, op in (
        (
            "gated_band",
            "joint_4 offset (1 mrad) in a band 0.2% of its range wide at e/10 of it, only with joint_2 < 0",
            "a per-direction compensation table with one bad cell (helper's own class, sixty-third session)",
            "move",
        ),
        (
            "sum_band_orient",
            "flange roll wrong (1 mrad) when joint_1 + joint_6 is within 3.4e-3 rad of pi/7",
            "a 'tool yaw' shortcut combining base and flange angles (helper's own class)",
            "fk",
        ),
        (
            "floor_clamp",
            "the tool point's z clamped to -0.098683 m inside FK (a workspace floor)",
            "a table height applied inside forward kinematics (helper's own class)",
            "fk",
        ),
        (
            "second_go_sign",
            "joint_4's goal negated on a group's second go() only",
            "a direction flag toggled per move instead of per joint (helper's own class)",
            "scenario",
        ),
        (
            "ik_ball",
            "IK reports NO_SOLUTION for goals within 2.54 cm of a point inside the workspace",
            "a spurious singularity guard around one workspace point (helper's own class)",
            "ik",
        ),
        (
            "folded_corner",
            "FK 1 mm high with joint_3 > 3.6 and joint_5 > 3.7 rad (both past pi)",
            "a wrong 'folded' branch past pi on two joints (helper's own class)",
            "move",
        ),
    )
)
"""The six bugs a helper planted without having seen the engine (``benchmarks/untuned_bugs.py``;
BENCHMARKS.md, "Bugs the engine was not tuned on"), on the default arm; ``bench_ab`` races
engines on them by name like the zoo's."""

BY_NAME = {bug.name: bug for bug in (*ZOO, CONTROL, *CONTROLS)}
