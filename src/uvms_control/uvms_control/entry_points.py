"""Console scripts of uvms_control (``ros2 run uvms_control controller``), light to import."""

from uvms_common.node_entry import run_node_module


def controller() -> None:
    """The unified force controller node (``uvms_control.controller_node``)."""
    run_node_module('uvms_control.controller_node')

