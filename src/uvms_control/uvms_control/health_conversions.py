"""The controller's reading of thruster health: a goal ends when actuation is lost.

The allocator publishes ``thrusters/health`` (``uvms_thrusters.health_conversions``, the one
import of uvms_thrusters in this package); `ActuationWatch` subscribes it for the
controller's action server.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_thrusters.health_conversions import HEALTH_TOPIC

from uvms_control.core.task.contact_task import TaskCode
from uvms_control.core.task.task_supervisor import TaskEvent, TaskSupervisor
from uvms_msgs.msg import ThrusterHealth


class ActuationWatch:
    """The controller's side: a goal ends ACTUATION_LOST once the thrusters are not enough.

    Subscribes ``thrusters/health``; on the first message that says ``fully_actuated``
    false, and on every later one while a goal runs (a goal sent while actuation is lost), it
    ends the running task with ``TaskCode.ACTUATION_LOST`` through the supervisor
    (which holds where X_d was, with what the vehicle still controls) and hands the events
    to ``finish`` (the action server's). Created by the controller's ``ContactTaskServer``.

    Args:
        node: The controller node.
        supervisor: Returns the running ``TaskSupervisor``, or None while the node is inactive.
        finish: Delivers task events (results) to the action clients.
    """

    def __init__(self, node: Node, supervisor: Callable[[], TaskSupervisor | None],
                 finish: Callable[[Iterable[TaskEvent]], None]) -> None:
        self._node = node
        self._supervisor = supervisor
        self._finish = finish
        self.lost = False
        node.create_subscription(ThrusterHealth, HEALTH_TOPIC, self.on_health,
                                 QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))

    def on_health(self, msg: ThrusterHealth) -> None:
        """End the running goal when actuation is lost, and any goal started while it is."""
        lost = not msg.fully_actuated
        supervisor = self._supervisor()
        if lost and supervisor is not None and (not self.lost or supervisor.goal_id is not None):
            reason = f'actuation lost: thruster allocation rank {msg.rank} < 6 (thrusters/health)'
            self._node.get_logger().error(f'{reason}: ending the running goal and holding')
            self._finish(supervisor.abort_all(TaskCode.ACTUATION_LOST, reason))
        self.lost = lost
