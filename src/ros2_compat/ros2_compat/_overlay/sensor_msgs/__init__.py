"""ROS 2 interface package sensor_msgs, as the ros2_compat overlay provides it."""
