"""ROS 2 interface package rcl_interfaces, as the ros2_compat overlay provides it."""
