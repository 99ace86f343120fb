"""Lockstep answers of an unconfigured managed node: zero, stamped like each input.

An unconfigured node has built nothing (ROS 2 lifecycle), yet in lockstep the simulator
steps only when every state is answered. So that a node left unconfigured (``autostart:
false``, waiting for a lifecycle manager) never stalls the exchange, it answers each input
with a zero command of the same stamp, as an inactive node does (docs/interfaces.md). Built
from the input message alone (its stamp and joint names) and the robot's thruster count, so
nothing of the node's configuration is needed. `answer_while_unconfigured` wraps the node's
transition callbacks: the answers stop when configure starts, and resume whenever the node
is unconfigured again (a failed configure, cleanup, error processing). Timer mode (real
time) publishes nothing unconfigured: the simulator holds the initial state until the nodes
are active.

Example (in a managed node's constructor)::

    answer_while_unconfigured(self, lockstep=True, start=not autostarting,
                              make=lambda: controller_zero_answer(self))
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from lifecycle_msgs.msg import State
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from uvms_model.thrusters import ThrusterLayout

from uvms_model import ModelError, UvmsParameters
from uvms_msgs.msg import ActuatorCommand, GeneralizedForce

#: Frame of the zero commands (the vehicle body, as the nodes' own commands).
BASE_LINK_FRD = 'base_link_frd'


def zero_actuator_command(n_thrusters: int) -> Callable[[GeneralizedForce], ActuatorCommand]:
    """Zero thrust on ``n_thrusters`` and zero torque on the command's joints, its stamp."""
    def zero(msg: GeneralizedForce) -> ActuatorCommand:
        names = list(msg.joint_names)
        return ActuatorCommand(header=Header(stamp=msg.header.stamp, frame_id=BASE_LINK_FRD),
                               thrust=[0.0] * n_thrusters, joint_names=names,
                               joint_torques=[0.0] * len(names))
    return zero


def zero_generalized_force(msg: Any) -> GeneralizedForce:
    """Zero vehicle wrench and zero torque on the joints of a JointState, its stamp."""
    names = list(msg.name)
    return GeneralizedForce(header=Header(stamp=msg.header.stamp, frame_id=BASE_LINK_FRD),
                            joint_names=names, joint_torques=[0.0] * len(names))


class ZeroAnswer:
    """A subscription that answers every input with a zero command of the same stamp."""

    def __init__(self, node: Node, in_type: type, in_topic: str, out_type: type,
                 out_topic: str, zero: Callable[[Any], Any]) -> None:
        """Subscribe ``in_topic`` and publish ``zero(input)`` on ``out_topic``."""
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._node = node
        self._zero = zero
        self._publisher: Any = node.create_publisher(out_type, out_topic, qos)
        self._subscription: Any = node.create_subscription(in_type, in_topic, self._on_input,
                                                           qos)
        self.answered = 0
        node.get_logger().info(
            f'unconfigured: answering each {in_topic} with a zero {out_topic} (lockstep)')

    def _on_input(self, msg: Any) -> None:
        try:
            answer = self._zero(msg)
        except Exception as error:  # never let a callback end the node
            self._node.get_logger().error(f'unconfigured: no zero answer: {error}',
                                          throttle_duration_sec=5.0)
            return
        self._publisher.publish(answer)
        self.answered += 1

    def destroy(self) -> None:
        """Drop the subscription and the publisher (the node configures)."""
        self._node.destroy_subscription(self._subscription)
        self._node.destroy_publisher(self._publisher)


def controller_zero_answer(node: Node) -> ZeroAnswer:
    """The controller's: each joint state answered with zero generalized force."""
    return ZeroAnswer(node, JointState, 'joint_states', GeneralizedForce,
                      'command/generalized_force', zero_generalized_force)


def allocator_zero_answer(node: Node, robot: dict[str, Any]) -> ZeroAnswer | None:
    """The allocator's: each command answered with zero thrust; None if the robot is invalid.

    Args:
        node: The allocator.
        robot: Its flat robot parameters (the thruster layout gives the thruster count).
    """
    try:
        thrusters = UvmsParameters.from_flat_dict(robot).thrusters
        count = ThrusterLayout.from_parameters(thrusters).count
    except ModelError as error:
        node.get_logger().error(f'unconfigured: cannot answer lockstep commands: {error}')
        return None
    return ZeroAnswer(node, GeneralizedForce, 'command/generalized_force', ActuatorCommand,
                      'command/actuators', zero_actuator_command(count))


def answer_while_unconfigured(node: LifecycleNode, lockstep: bool, start: bool,
                              make: Callable[[], ZeroAnswer | None]) -> None:
    """Answer lockstep inputs with zeros whenever ``node`` is unconfigured.

    Args:
        node: The managed node, its transition callbacks registered (after its constructor's
            ``super().__init__``).
        lockstep: Its trigger mode is lockstep; otherwise nothing is done.
        start: Answer from now on (the node stays unconfigured: no autostart).
        make: Builds the answer (None: it cannot, and said why).
    """
    if not lockstep:
        return
    held: list[ZeroAnswer] = []

    def answer() -> None:
        if not held:
            built = make()
            held.extend([built] if built is not None else [])

    def drop() -> None:
        while held:
            held.pop().destroy()

    callbacks = node._callbacks  # private: rclpy's table of transition callbacks by state id
    success = TransitionCallbackReturn.SUCCESS

    def wrap(state_id: int, before: bool, after: bool) -> None:
        original = callbacks.get(state_id)

        def wrapped(state: LifecycleState) -> TransitionCallbackReturn:
            if before:
                drop()
            result = original(state) if original is not None else success
            if after and (result == success) == (state_id != State.TRANSITION_STATE_CONFIGURING):
                answer()
            return result
        callbacks[state_id] = wrapped

    wrap(State.TRANSITION_STATE_CONFIGURING, before=True, after=True)  # failed: answer again
    wrap(State.TRANSITION_STATE_CLEANINGUP, before=False, after=True)
    wrap(State.TRANSITION_STATE_ERRORPROCESSING, before=True, after=True)
    wrap(State.TRANSITION_STATE_SHUTTINGDOWN, before=True, after=False)
    if start:
        answer()
