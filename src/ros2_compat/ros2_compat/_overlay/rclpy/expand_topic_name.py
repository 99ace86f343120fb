"""rclpy.expand_topic_name: see :func:`rclpy._names.expand_topic_name`."""

from rclpy._names import expand_topic_name

__all__ = ['expand_topic_name']
