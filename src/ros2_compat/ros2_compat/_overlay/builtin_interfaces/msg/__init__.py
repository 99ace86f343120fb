"""Message classes of builtin_interfaces (ros2_compat), generated on first use."""

from ros2_compat._messages import package_dir, package_getattr

__getattr__ = package_getattr('builtin_interfaces')
__dir__ = package_dir('builtin_interfaces')
