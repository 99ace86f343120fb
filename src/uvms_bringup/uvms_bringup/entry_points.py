"""Console scripts of uvms_bringup's nodes (``ros2 run uvms_bringup recorder``), light."""

from uvms_common.node_entry import run_node_module


def recorder() -> None:
    """The MCAP recorder node (``uvms_bringup.recorder_node``)."""
    run_node_module('uvms_bringup.recorder_node')


def visualizer() -> None:
    """The marker node (``uvms_bringup.visualizer_node``)."""
    run_node_module('uvms_bringup.visualizer_node')


def foxglove_server() -> None:
    """The Foxglove live view node (``uvms_bringup.foxglove_server_node``)."""
    run_node_module('uvms_bringup.foxglove_server_node')
