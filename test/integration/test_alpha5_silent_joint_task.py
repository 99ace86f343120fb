"""A silent Alpha 5 joint ends the controller's running task INPUTS_STALE (issue 46).

The alpha5_bridge on the Alpha 5 twin, the real ControllerNode of bluerov2_alpha5 in timer
mode (as on the robot) and a probe that streams fresh odometry and wrench, on one executor:
when the elbow stops answering, the controller sees its joint states go stale.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from geometry_msgs.msg import Point, Vector3, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.action import ActionClient
from rclpy.parameter import Parameter
from test_alpha5_bridge import ROBOT, Rig
from uvms_control.controller_node import ControllerNode

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ControllerState

CONFIG = Path(__file__).resolve().parents[2] / 'config'
PARAMS = ['--ros-args', '--params-file', str(CONFIG / 'robot.yaml'),
          '--params-file', str(CONFIG / 'controller.yaml')]
#: An arm pose inside every joint's range (rad), joint_1..joint_4.
ARM = [3.0, 0.5, 1.5, 1.5]
Result = ContactTask.Result


class TaskRig(Rig):
    """The bridge's rig plus the controller, fresh odometry and wrench at 100 Hz, a client."""

    def __init__(self) -> None:
        super().__init__()
        self.controller: ControllerNode | None = None
        node = self.probe
        self.odometry = node.create_publisher(Odometry, 'odometry', 10)
        self.wrench = node.create_publisher(WrenchStamped, 'wrench', 10)
        self.controller_states: list[ControllerState] = []
        node.create_subscription(ControllerState, 'controller/state',
                                 self.controller_states.append, 100)
        node.create_timer(0.01, self._publish_vehicle)
        self.client = ActionClient(node, ContactTask, 'controller/contact_task')
        self.results: dict[str, Any] = {}

    def _publish_vehicle(self) -> None:
        stamp = self.probe.get_clock().now().to_msg()
        odometry = Odometry(child_frame_id='base_link_frd')
        odometry.header.stamp, odometry.header.frame_id = stamp, 'map_ned'
        odometry.pose.pose.orientation.w = 1.0
        self.odometry.publish(odometry)
        wrench = WrenchStamped()
        wrench.header.stamp, wrench.header.frame_id = stamp, 'ft_sensor_link'
        self.wrench.publish(wrench)

    def start_controller(self) -> ControllerNode:
        """The controller of bluerov2_alpha5 in timer mode (500 Hz), no allocator watched."""
        overrides = {'robot_name': ROBOT, 'trigger_mode': 'timer',
                     'allocator_node': '', 'watchdog_timeout_s': 0.2}
        self.controller = ControllerNode(
            namespace='uvms', context=self.context, cli_args=PARAMS,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()])
        self.executor.add_node(self.controller)
        return self.controller

    def send_goal(self, name: str, goal: ContactTask.Goal) -> None:
        """Send a goal; wait until it is accepted; keep its result when it comes."""
        self.spin_until(self.client.server_is_ready)
        future = self.client.send_goal_async(goal)
        self.spin_until(future.done)
        handle = future.result()
        assert handle is not None and handle.accepted
        handle.get_result_async().add_done_callback(
            lambda r: self.results.__setitem__(name, r.result().result))

    def close(self) -> None:
        """The controller first, then the bridge's rig."""
        if self.controller is not None:
            self.executor.remove_node(self.controller)
            self.controller.destroy_node()
        super().close()


@pytest.fixture
def rig() -> Iterator[TaskRig]:
    """A fresh twin, bridge rig and controller, closed after the test."""
    made = TaskRig()
    yield made
    made.close()


def motion_goal(start: Point) -> ContactTask.Goal:
    """1 cm down from ``start`` over 5 s, at once, no force."""
    goal = ContactTask.Goal()
    goal.header.frame_id = 'map_ned'
    goal.path = [Point(x=start.x, y=start.y, z=start.z),
                 Point(x=start.x, y=start.y, z=start.z + 0.01)]
    goal.time_from_start_s = [0.0, 5.0]
    goal.normal = Vector3(x=1.0, y=0.0, z=0.0)
    goal.force_ramp_s = 0.5
    return goal


def test_a_silent_joint_ends_the_running_task_inputs_stale(rig: TaskRig) -> None:
    """The elbow goes silent 0.3 s into a 5 s task: the task ends INPUTS_STALE within 0.5 s.

    Before, the bridge republished the elbow's last answer with a new stamp each round; the
    controller's input-age check never saw it, and the task ran on a frozen joint.
    """
    rig.twin.set_joint_state(ARM, [0.0] * 4)
    rig.start_bridge()
    rig.start_controller()
    rig.spin_until(lambda: bool(rig.controller_states), timeout_s=30.0)
    rig.send_goal('running', motion_goal(rig.controller_states[-1].position))
    rig.spin_for(0.3)
    assert 'running' not in rig.results  # running on fresh joint states
    rig.twin.set_silent(0x03)
    silenced_s = time.monotonic()
    rig.spin_until(lambda: 'running' in rig.results, timeout_s=5.0)
    assert rig.results['running'].error_code == Result.INPUTS_STALE
    assert time.monotonic() - silenced_s < 0.5
