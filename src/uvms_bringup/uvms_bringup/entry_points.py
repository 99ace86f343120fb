"""Console scripts of uvms_bringup's nodes (``ros2 run uvms_bringup recorder``), light."""

from uvms_common.node_entry import run_node_module


def recorder() -> None:
    """The MCAP recorder node (``uvms_bringup.recorder_node``)."""
    run_node_module('uvms_bringup.recorder_node')
