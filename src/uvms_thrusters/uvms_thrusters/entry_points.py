"""Console scripts of uvms_thrusters (``ros2 run uvms_thrusters thruster_allocator``)."""

from uvms_common.node_entry import run_node_module


def thruster_allocator() -> None:
    """The thruster allocator node (``uvms_thrusters.thruster_allocator_node``)."""
    run_node_module('uvms_thrusters.thruster_allocator_node')
