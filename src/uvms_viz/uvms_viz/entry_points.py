"""Console scripts of uvms_viz's nodes (``ros2 run uvms_viz visualizer``), light."""

from uvms_common.node_entry import run_node_module


def visualizer() -> None:
    """The marker node (``uvms_viz.visualizer_node``)."""
    run_node_module('uvms_viz.visualizer_node')


def foxglove_server() -> None:
    """The Foxglove live view node (``uvms_viz.foxglove_server_node``)."""
    run_node_module('uvms_viz.foxglove_server_node')
