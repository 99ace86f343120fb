"""Console scripts of uvms_twins's nodes (``ros2 run uvms_twins hardware_twins``)."""

from uvms_common.node_entry import run_node_module


def hardware_twins() -> None:
    """The protocol twins on the simulator (``uvms_twins.twins_node``)."""
    run_node_module('uvms_twins.twins_node')
