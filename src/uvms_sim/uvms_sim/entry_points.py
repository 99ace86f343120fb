"""Console scripts of uvms_sim (``ros2 run uvms_sim simulator``), light to import."""

from uvms_common.node_entry import run_node_module


def simulator() -> None:
    """The simulator node (``uvms_sim.simulator_node``)."""
    run_node_module('uvms_sim.simulator_node')
