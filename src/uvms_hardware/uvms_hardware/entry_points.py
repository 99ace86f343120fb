"""Console scripts of uvms_hardware's bridge nodes (``ros2 run uvms_hardware alpha5_bridge``)."""

from uvms_common.node_entry import run_node_module


def alpha5_bridge() -> None:
    """The Reach Alpha 5 bridge (``uvms_hardware.alpha5_bridge_node``)."""
    run_node_module('uvms_hardware.alpha5_bridge_node')


def netft_bridge() -> None:
    """The ATI Net F/T bridge (``uvms_hardware.netft_bridge_node``)."""
    run_node_module('uvms_hardware.netft_bridge_node')
