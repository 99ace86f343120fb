"""Unit constants shared by the rclpy modules."""

#: Nanoseconds per second.
S_TO_NS = 1000 * 1000 * 1000
