"""rclpy.validate_node_name: see :func:`rclpy._names.validate_node_name`."""

from rclpy._names import validate_node_name

__all__ = ['validate_node_name']
