"""rclpy.validate_namespace: see :func:`rclpy._names.validate_namespace`."""

from rclpy._names import validate_namespace

__all__ = ['validate_namespace']
