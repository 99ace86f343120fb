"""ROS 2 interface package nav_msgs, as the ros2_compat overlay provides it."""
