"""Test-wide setup: make `import rclpy` resolve to ros2_compat when no ROS 2 is sourced."""

import ros2_compat

# Idempotent, and a no-op in effect under a sourced ROS 2: the fallback finder is asked last.
ros2_compat.activate()
