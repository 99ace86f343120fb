"""Protocol twins of the robot's devices: plain-Python servers of vendor protocols, no ROS."""
