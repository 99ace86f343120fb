"""Implementation details of the compat rclpy (the real one wraps its C extension here)."""
