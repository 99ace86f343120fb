"""ROS 2 interface package builtin_interfaces, as the ros2_compat overlay provides it."""
