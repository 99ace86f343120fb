"""ROS 2 interface package std_msgs, as the ros2_compat overlay provides it."""
