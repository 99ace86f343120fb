"""Protocol twins of the robot's devices (no ROS): what the bridges are tested against."""
