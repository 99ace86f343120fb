"""Message classes of rcl_interfaces (ros2_compat), generated on first use."""

from ros2_compat._messages import package_dir, package_getattr

__getattr__ = package_getattr('rcl_interfaces')
__dir__ = package_dir('rcl_interfaces')
