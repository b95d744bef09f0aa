#!/usr/bin/env bash
# Installs ROS 1 (Noetic's core, as Debian 12 ships it) when it is missing. Only the ROS
# features and their tests need it (--transport ros, the ros_tf target, bags, view):
#   scripts/ros-ensure.sh          core: master, rospy, roscpp (C++ node), rosbag, tf2,
#                                  robot_state_publisher
#   scripts/ros-ensure.sh --viz    core + RViz and Xvfb (fuzz_diff.py view)
set -euo pipefail
cd "$(dirname "$0")/.."

ROS_PACKAGES=(
  ros-core python3-rosmaster python3-rospy python3-rosbag python3-roslaunch rosbash
  python3-tf2-ros ros-robot-state-publisher
  python3-sensor-msgs python3-geometry-msgs python3-std-msgs
  libroscpp-dev libstd-msgs-dev nlohmann-json3-dev  # the C++ target node (ros/cpp)
  cmake g++ libeigen3-dev liborocos-kdl-dev liburdfdom-dev libconsole-bridge-dev libexpat1-dev
)
VIZ_PACKAGES=(rviz xvfb x11-apps imagemagick)

case "$#:${1:-}" in
  0:) scripts/apt-ensure.sh "${ROS_PACKAGES[@]}" ;;
  1:--viz) scripts/apt-ensure.sh "${ROS_PACKAGES[@]}" "${VIZ_PACKAGES[@]}" ;;
  1:-h | 1:--help) sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//' ;;
  *)
    echo "scripts/ros-ensure.sh: unknown argument(s): $*; usage: scripts/ros-ensure.sh [--viz | --help]" >&2
    exit 2
    ;;
esac
