"""Scenario files: the format of ``config/scenarios/*.yaml``, loaded and checked (no rclpy)."""
