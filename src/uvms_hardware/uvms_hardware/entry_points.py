"""Console scripts of uvms_hardware's nodes (``ros2 run uvms_hardware ardusub_bridge``)."""

from uvms_common.node_entry import run_node_module


def ardusub_bridge() -> None:
    """The ArduSub bridge node (``uvms_hardware.ardusub_bridge_node``)."""
    run_node_module('uvms_hardware.ardusub_bridge_node')


def dvl_bridge() -> None:
    """The Water Linked DVL bridge node (``uvms_hardware.dvl_bridge_node``)."""
    run_node_module('uvms_hardware.dvl_bridge_node')


def alpha5_bridge() -> None:
    """The Reach Alpha 5 bridge (``uvms_hardware.alpha5_bridge_node``)."""
    run_node_module('uvms_hardware.alpha5_bridge_node')


def netft_bridge() -> None:
    """The ATI Net F/T bridge (``uvms_hardware.netft_bridge_node``)."""
    run_node_module('uvms_hardware.netft_bridge_node')
