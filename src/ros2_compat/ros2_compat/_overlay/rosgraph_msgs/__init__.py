"""ROS 2 interface package rosgraph_msgs, as the ros2_compat overlay provides it."""
