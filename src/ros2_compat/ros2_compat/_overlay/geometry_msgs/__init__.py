"""ROS 2 interface package geometry_msgs, as the ros2_compat overlay provides it."""
