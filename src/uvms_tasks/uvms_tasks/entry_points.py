"""Console scripts of uvms_tasks's nodes (``ros2 run uvms_tasks mission``), light."""

from uvms_common.node_entry import run_node_module


def mission() -> None:
    """The mission node (``uvms_tasks.mission_node``)."""
    run_node_module('uvms_tasks.mission_node')
