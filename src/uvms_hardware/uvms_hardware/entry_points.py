"""Console scripts of uvms_hardware's bridge nodes (``ros2 run uvms_hardware ardusub_bridge``)."""

from uvms_common.node_entry import run_node_module


def ardusub_bridge() -> None:
    """The ArduSub bridge node (``uvms_hardware.ardusub_bridge_node``)."""
    run_node_module('uvms_hardware.ardusub_bridge_node')


def dvl_bridge() -> None:
    """The Water Linked DVL bridge node (``uvms_hardware.dvl_bridge_node``)."""
    run_node_module('uvms_hardware.dvl_bridge_node')
