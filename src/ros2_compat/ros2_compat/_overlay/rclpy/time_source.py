"""Time source of a node: drives its ROS clock from /clock while ``use_sim_time`` is true."""

from __future__ import annotations

import weakref
from typing import TYPE_CHECKING, Any

from rclpy.clock import ROSClock
from rclpy.clock_type import ClockType
from rclpy.constants import S_TO_NS
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.subscription import Subscription

CLOCK_TOPIC = '/clock'
USE_SIM_TIME_NAME = 'use_sim_time'


class TimeSource:
    """Keeps the ROS clocks attached to it on simulated time from /clock when enabled.

    As in rclpy: attaching a node declares ``use_sim_time`` (False) if needed and watches it;
    while it is true, the node subscribes to /clock (rosgraph_msgs/Clock, best effort, depth 1)
    and every attached clock reports the last time received (0 until the first message).
    """

    def __init__(self, *, node: Node | None = None) -> None:
        self._clock_sub: Subscription[Any] | None = None
        self._node_weak_ref: weakref.ref[Node] | None = None
        self._associated_clocks: set[ROSClock] = set()
        self._last_time_set = Time(clock_type=ClockType.ROS_TIME)
        self._ros_time_is_active = False
        if node is not None:
            self.attach_node(node)

    @property
    def ros_time_is_active(self) -> bool:
        """Whether attached clocks follow /clock."""
        return self._ros_time_is_active

    @ros_time_is_active.setter
    def ros_time_is_active(self, enabled: bool) -> None:
        if self._ros_time_is_active == enabled:
            return
        self._ros_time_is_active = enabled
        for clock in self._associated_clocks:
            clock._set_ros_time_is_active(enabled)
        if enabled:
            self._subscribe_to_clock_topic()
        elif self._clock_sub is not None:
            node = self._get_node()
            if node is not None:
                node.destroy_subscription(self._clock_sub)
                self._clock_sub = None

    def _subscribe_to_clock_topic(self) -> None:
        if self._clock_sub is None:
            node = self._get_node()
            if node is not None:
                from rosgraph_msgs.msg import Clock as ClockMsg

                self._clock_sub = node.create_subscription(
                    ClockMsg,
                    CLOCK_TOPIC,
                    self.clock_callback,
                    QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT),
                )

    def attach_node(self, node: Node) -> None:
        """Use ``node`` for the /clock subscription and its ``use_sim_time`` parameter.

        Raises:
            TypeError: If ``node`` is not a Node.
        """
        from rclpy.node import Node

        if not isinstance(node, Node):
            raise TypeError('Node must be of type rclpy.node.Node')
        if self._node_weak_ref is not None:
            self.detach_node()
        self._node_weak_ref = weakref.ref(node)
        if not node.has_parameter(USE_SIM_TIME_NAME):
            node.declare_parameter(USE_SIM_TIME_NAME, False)
        use_sim_time_param = node.get_parameter(USE_SIM_TIME_NAME)
        if use_sim_time_param.type_ != Parameter.Type.NOT_SET:
            if use_sim_time_param.type_ == Parameter.Type.BOOL:
                self.ros_time_is_active = use_sim_time_param.value
            else:
                node.get_logger().error(
                    f"Invalid type for parameter '{USE_SIM_TIME_NAME}' "
                    f'{use_sim_time_param.type_!r} should be bool'
                )
        else:
            node.get_logger().debug(
                f"'{USE_SIM_TIME_NAME}' parameter not set, using wall time by default"
            )
        node.add_on_set_parameters_callback(self._on_parameter_event)

    def detach_node(self) -> None:
        """Stop using the attached node."""
        if self._clock_sub is not None:
            node = self._get_node()
            if node is None:
                raise RuntimeError('Unable to destroy previously created clock subscription')
            node.destroy_subscription(self._clock_sub)
        self._clock_sub = None
        self._node_weak_ref = None

    def attach_clock(self, clock: ROSClock) -> None:
        """Drive ``clock`` from this time source.

        Raises:
            ValueError: If ``clock`` is not a ROS clock.
        """
        if not isinstance(clock, ROSClock):
            raise ValueError('Only clocks with type ROS_TIME can be attached.')
        clock.set_ros_time_override(self._last_time_set)
        clock._set_ros_time_is_active(self.ros_time_is_active)
        self._associated_clocks.add(clock)

    def clock_callback(self, msg: Any) -> None:
        """Set every attached clock to the time of a /clock message."""
        stamp = msg.clock
        nanoseconds = stamp.sec * S_TO_NS + stamp.nanosec
        if type(nanoseconds) is int and 0 <= nanoseconds < 2**63:
            time_from_msg = Time._from_ns(nanoseconds, ClockType.ROS_TIME)  # the common case
        else:
            time_from_msg = Time.from_msg(stamp)  # raises what rclpy raises
        self._last_time_set = time_from_msg
        for clock in self._associated_clocks:
            clock.set_ros_time_override(time_from_msg)

    def _on_parameter_event(self, parameter_list: list[Parameter]) -> Any:
        from rcl_interfaces.msg import SetParametersResult

        successful = True
        reason = ''
        for parameter in parameter_list:
            if parameter.name == USE_SIM_TIME_NAME:
                if parameter.type_ == Parameter.Type.BOOL:
                    self.ros_time_is_active = parameter.value
                else:
                    successful = False
                    reason = f'{USE_SIM_TIME_NAME} parameter set to something besides a bool'
                    node = self._get_node()
                    if node:
                        node.get_logger().error(reason)
                break
        return SetParametersResult(successful=successful, reason=reason)

    def _get_node(self) -> Node | None:
        if self._node_weak_ref is not None:
            return self._node_weak_ref()
        return None
