"""ROS 2 interface package tf2_msgs, as the ros2_compat overlay provides it."""
