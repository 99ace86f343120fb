"""Message classes of rosgraph_msgs (ros2_compat), generated on first use."""

from ros2_compat._messages import package_dir, package_getattr

__getattr__ = package_getattr('rosgraph_msgs')
__dir__ = package_dir('rosgraph_msgs')
