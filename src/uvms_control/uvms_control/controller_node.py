"""The ``controller`` node: the unified force controller (paper sec. 4) as a ROS 2 node.

Subscribes ``joint_states``, ``odometry`` and ``wrench``; publishes
``command/generalized_force`` and ``controller/state`` (relative names: run it in ``/uvms``).
``trigger_mode: lockstep`` computes once the three inputs with one stamp have arrived and
stamps the command alike (a repeated stamp re-sends the same command); inputs are gathered
per stamp, so inputs with other stamps (another publisher, a flood of bad messages) cannot
stall the exchange. ``timer`` computes at ``control_rate_hz`` of the steady (wall) clock on
the latest inputs and stamps with the node clock (``/clock`` time under ``use_sim_time``). A
rejected input (NaN/Inf, wrong size or frame) is logged; at the stamp of a running lockstep
exchange the last safe command is held; stale inputs (older than
``watchdog_timeout_s``: by stamp in lockstep, by node-clock arrival time in timer mode) give a
zero command, logged once.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from uvms_common.node_main import run_node

from uvms_control import conversions
from uvms_control.core.errors import ControlInputError, ControlParameterError
from uvms_control.core.parameter_specs import (
    CONTROLLER_NODE_PARAMETER_SPECS,
    CONTROLLER_PARAMETER_SPECS,
)
from uvms_control.core.parameters import ControllerParameters, validate_node_parameters
from uvms_control.core.unified_controller import UnifiedForceController
from uvms_control.ros_parameters import declare_parameters
from uvms_model import PARAMETER_SPECS, ModelError, UvmsModel, UvmsParameters
from uvms_msgs.msg import ControllerState, GeneralizedForce

TOPICS = ('joint_states', 'odometry', 'wrench')


class _Input(NamedTuple):
    stamp_ns: int
    arrival_ns: int
    value: Any  # None when the message was rejected


@dataclass
class _PendingEntry:
    """The inputs of one stamp that have arrived (None: arrived but rejected)."""

    values: dict[str, Any] = field(default_factory=dict)
    valid: int = 0
    complete: bool = False


class PendingStamps:
    """Lockstep inputs gathered per stamp, so that inputs of other stamps cannot disturb one.

    A stamp is complete when every topic has arrived for it and at least one of them was
    valid: a rejected input at the stamp of the running exchange is then answered with the
    last safe command, while rejected inputs of stamps nothing valid asked for never complete
    and never evict an entry that holds valid inputs. At most ``capacity`` stamps are kept.
    """

    def __init__(self, topics: tuple[str, ...], capacity: int = 16) -> None:
        self._topics = topics
        self._capacity = capacity
        self._entries: dict[int, _PendingEntry] = {}

    def arrive(self, stamp_ns: int, topic: str, value: Any) -> _PendingEntry:
        """Record one input (None if it was rejected); return the entry of its stamp."""
        entry = self._entries.get(stamp_ns)
        if entry is None:
            if len(self._entries) >= self._capacity:
                self._evict()
            entry = self._entries[stamp_ns] = _PendingEntry()
        if value is not None and entry.values.get(topic) is None:
            entry.valid += 1
        if value is not None or topic not in entry.values:
            entry.values[topic] = value
        entry.complete = entry.valid > 0 and len(entry.values) == len(self._topics)
        return entry

    def finish(self, stamp_ns: int) -> None:
        """Forget a computed stamp and every older one (the exchange has moved past them)."""
        for stamp in [s for s in self._entries if s <= stamp_ns]:
            del self._entries[stamp]

    def _evict(self) -> None:
        """Drop the oldest entry without a valid input, else the oldest entry."""
        invalid = [s for s, e in self._entries.items() if e.valid == 0]
        del self._entries[invalid[0] if invalid else next(iter(self._entries))]


class ControllerNode(Node):
    """Unified force controller: sensor topics in, generalized force and state out."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('controller', **kwargs)
        robot = declare_parameters(self, PARAMETER_SPECS)
        node = validate_node_parameters(
            CONTROLLER_NODE_PARAMETER_SPECS,
            declare_parameters(self, CONTROLLER_NODE_PARAMETER_SPECS),
        )
        gains = ControllerParameters.from_flat_dict(
            declare_parameters(self, CONTROLLER_PARAMETER_SPECS)
        )
        try:
            model = UvmsModel(UvmsParameters.from_flat_dict(robot))
        except ModelError as error:
            raise ControlParameterError(
                'robot parameters', str(error), 'config/robot.yaml'
            ) from error
        self.core = UnifiedForceController(gains, model)
        self._joint_names = model.joint_names
        self._lockstep = node['trigger_mode'] == 'lockstep'
        self._watchdog_ns = round(float(node['watchdog_timeout_s']) * 1e9)
        self._inputs: dict[str, _Input | None] = dict.fromkeys(TOPICS)
        self._pending = PendingStamps(TOPICS)
        self._last_tau_b = np.zeros(model.n_dof)
        self._last_stamp_ns = -1
        self._first_stamp_ns: int | None = None
        self._zeroed_stamp_ns = -1
        self._stale = False
        # Refilled for each publication (rclpy serializes at publish).
        self._command_msg: GeneralizedForce | None = None
        self._state_msg: ControllerState | None = None

        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._command_pub = self.create_publisher(
            GeneralizedForce, 'command/generalized_force', qos
        )
        self._state_pub = self.create_publisher(ControllerState, 'controller/state', qos)
        readers: dict[str, tuple[type, Callable[[Any], Any]]] = {
            'joint_states': (
                JointState,
                lambda m: conversions.joint_state_arrays(m, self._joint_names),
            ),
            'odometry': (Odometry, conversions.odometry_arrays),
            'wrench': (WrenchStamped, conversions.wrench_force),
        }
        for topic, (msg_type, read) in readers.items():
            self.create_subscription(
                msg_type, topic, lambda msg, t=topic, r=read: self._on_input(t, r, msg), qos
            )
        if not self._lockstep:
            # The period runs on the steady clock: a timer on /clock time fires once per
            # /clock message at most, so a burst of /clock drops control periods.
            self.create_timer(1.0 / float(node['control_rate_hz']), self._on_timer,
                              clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'unified force controller, {node["trigger_mode"]} trigger, '
            f'null space {"on" if gains.null_space_enabled else "off"}, W mode {gains.switch_mode}'
        )

    def _on_input(self, topic: str, read: Callable[[Any], Any], msg: Any) -> None:
        """Convert and keep one input; in lockstep, compute once a stamp is complete."""
        stamp = conversions.stamp_ns(msg.header.stamp)
        try:
            value = read(msg)
        except ControlInputError as error:
            self.get_logger().error(f'rejected {topic}: {error}', throttle_duration_sec=1.0)
            value = None
        if not self._lockstep:
            if value is not None:  # timer mode computes on the last valid input
                self._inputs[topic] = _Input(stamp, self.get_clock().now().nanoseconds, value)
            return
        entry = self._pending.arrive(stamp, topic, value)
        if value is not None:
            self._inputs[topic] = _Input(stamp, 0, value)
            if self._first_stamp_ns is None:
                self._first_stamp_ns = stamp
        if entry.complete:
            self._pending.finish(stamp)
            inputs = [_Input(stamp, 0, entry.values[name]) for name in TOPICS]
            self._compute(stamp, inputs)
            return
        if value is None or self._first_stamp_ns is None:
            return  # only valid inputs move the lockstep exchange on
        oldest = min(self._first_stamp_ns if i is None else i.stamp_ns
                     for i in self._inputs.values())
        if stamp - oldest > self._watchdog_ns and stamp != self._zeroed_stamp_ns:
            self._zeroed_stamp_ns = stamp  # answer the stamp once, so the simulation goes on
            self._zero(stamp, 'an input is older than watchdog_timeout_s')

    def _on_timer(self) -> None:
        """Timer mode: compute on the latest inputs, or zero the command when they are stale."""
        now = self.get_clock().now().nanoseconds
        inputs = [self._inputs[name] for name in TOPICS]
        if any(i is None for i in inputs):
            self.get_logger().info('waiting for joint_states, odometry and wrench', once=True)
            return
        if any(now - i.arrival_ns > self._watchdog_ns for i in inputs if i is not None):
            self._zero(now, 'inputs older than watchdog_timeout_s')
            return
        self._compute(now, inputs)

    def _compute(self, t_ns: int, inputs: list[_Input | None]) -> None:
        if any(i is None or i.value is None for i in inputs):
            self._publish_command(t_ns, self._last_tau_b)  # hold the last safe command
            return
        if self._stale:
            self._stale = False
            self.get_logger().info('fresh inputs: control resumed')
        if t_ns == self._last_stamp_ns:
            self._publish_command(t_ns, self._last_tau_b)  # a re-published state: same answer
            return
        (positions, velocities), (eta, nu), force = (i.value for i in inputs if i is not None)
        q = np.concatenate((eta, positions))
        w = np.concatenate((nu, velocities))
        try:
            result = self.core.step_from_sensors(t_ns * 1e-9, q, w, force)
        except ControlInputError as error:
            self.get_logger().error(
                f'control step failed, holding: {error}', throttle_duration_sec=1.0
            )
            self._publish_command(t_ns, self._last_tau_b)
            return
        self._last_tau_b = result.tau_b
        self._last_stamp_ns = t_ns
        self._publish_command(t_ns, result.tau_b)
        self._state_msg = conversions.controller_state_message(t_ns, result, self._state_msg)
        self._state_pub.publish(self._state_msg)

    def _zero(self, t_ns: int, reason: str) -> None:
        if not self._stale:
            self._stale = True
            self.get_logger().warn(f'{reason}: publishing zero generalized force')
        self._last_tau_b = np.zeros_like(self._last_tau_b)
        self._publish_command(t_ns, self._last_tau_b)

    def _publish_command(self, t_ns: int, tau_b: np.ndarray) -> None:
        self._command_msg = conversions.generalized_force_message(
            t_ns, tau_b, self._joint_names, self._command_msg
        )
        self._command_pub.publish(self._command_msg)


def main(args: list[str] | None = None) -> None:
    """Run the controller node until SIGINT/SIGTERM."""
    sys.exit(run_node(ControllerNode, args, 'controller',
                      (ControlParameterError, ParameterException)))

if __name__ == '__main__':
    main()
