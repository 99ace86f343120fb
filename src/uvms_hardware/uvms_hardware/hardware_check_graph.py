"""The bridges running on the ROS graph, for ``uvms hardware check``: their ``/diagnostics``.

Each bridge publishes its status once a period of its clock (``bridge_node``: the lifecycle
state among the values). The check listens for at most ``listen_s``: it stops as soon as every
bridge seen on the graph has reported, or after ``discovery_s`` with no bridge on the graph
at all (nothing runs: the usual case before a launch)::

    graph = running_bridges(('alpha5_bridge', 'dvl_bridge'), listen_s=3.0)
    graph['alpha5_bridge'].state, graph['alpha5_bridge'].message   # 'active', 'tripped: ...'
"""

from __future__ import annotations

import time
from collections.abc import Collection

from uvms_hardware.hardware_check_status import BridgeStatus

#: With no bridge node on the graph after this long, nothing runs (s).
DISCOVERY_S = 1.0


def _level(value: bytes | int) -> int:
    return value[0] if isinstance(value, bytes) else int(value)


def running_bridges(names: Collection[str], listen_s: float = 3.0,
                    discovery_s: float = DISCOVERY_S) -> dict[str, BridgeStatus]:
    """Bridge name -> its last status, for the bridges of ``names`` heard within ``listen_s``."""
    import rclpy
    import rclpy.executors
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from uvms_common.ros_environment import ros_environment_defaults

    ros_environment_defaults()
    heard: dict[str, BridgeStatus] = {}

    def on_diagnostics(msg: DiagnosticArray) -> None:
        for status in msg.status:
            node, _, _ = status.name.partition(': ')
            values = {kv.key: kv.value for kv in status.values}
            if node in names and 'lifecycle_state' in values:  # the device's, not the process's
                heard[node] = BridgeStatus(node, values.get('lifecycle_state', '?'),
                                           _level(status.level), status.message, values)

    context = rclpy.Context()
    rclpy.init(args=[], context=context)
    node = Node('uvms_hardware_check', context=context)
    try:
        node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics,
                                 QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE))
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        start_s = time.monotonic()
        while (elapsed_s := time.monotonic() - start_s) < listen_s:
            executor.spin_once(timeout_sec=0.05)
            on_graph = {n for n, _ in node.get_node_names_and_namespaces()} & set(names)
            if elapsed_s >= discovery_s and on_graph <= set(heard):
                break
        return heard
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
