"""Console scripts of uvms_twins's nodes (``ros2 run uvms_twins hardware_twins``)."""

from uvms_common.node_entry import run_node_module


def hardware_twins() -> None:
    """The protocol twins on the simulator (``uvms_twins.twins_node``)."""
    run_node_module('uvms_twins.twins_node')


def simulator_with_twins() -> None:
    """The simulator with the twins in its process (``uvms_twins.simulator_with_twins``)."""
    run_node_module('uvms_twins.simulator_with_twins')
