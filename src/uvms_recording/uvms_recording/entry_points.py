"""Console scripts of uvms_recording's nodes (``ros2 run uvms_recording recorder``), light."""

from uvms_common.node_entry import run_node_module


def recorder() -> None:
    """The MCAP recorder node (``uvms_recording.recorder_node``)."""
    run_node_module('uvms_recording.recorder_node')
