"""Console scripts of uvms_navigation's node (``ros2 run uvms_navigation estimator``), light."""

from uvms_common.node_entry import run_node_module


def estimator() -> None:
    """The estimator node (``uvms_navigation.estimator_node``)."""
    run_node_module('uvms_navigation.estimator_node')
