"""Test-wide setup: the project's ROS 2 defaults (loopback-only Fast DDS profile) for rclpy."""

from uvms_common.ros_environment import ros_environment_defaults

# Before any test creates a DDS participant; a user's own settings win (see the module).
ros_environment_defaults()
