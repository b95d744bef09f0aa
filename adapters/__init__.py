"""Adapters: the robot_api contract around third-party kinematics libraries, one module per library."""
