"""ROS 2 interface package uvms_msgs, as the ros2_compat overlay provides it."""
