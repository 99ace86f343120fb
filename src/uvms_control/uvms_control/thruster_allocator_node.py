"""The ``thruster_allocator`` node: allocation (paper eq. 10) and thruster dynamics (eq. 11-15).

Subscribes ``command/generalized_force``; publishes ``command/actuators`` (actual thrusts
after the thruster dynamics, motor torques) and ``thrusters/state``. ``trigger_mode:
lockstep`` answers every command with its stamp, integrating the thrusters over the time
between command stamps; ``timer`` steps at ``rate_hz`` of the steady clock on the latest
command, stamped with the node clock. A rejected command (NaN/Inf, wrong size, frame or
joints) is logged and the last safe command is held;
in timer mode a command older than ``watchdog_timeout_s`` (node clock) is replaced by zero,
so the thrusters spin down and the motors go limp.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_common.node_main import run_node
from uvms_model.thrusters import ThrusterLayout

from uvms_control import conversions
from uvms_control.core.allocation import AllocatorParameters, ThrusterAllocator
from uvms_control.core.errors import ControlInputError, ControlParameterError
from uvms_control.core.parameter_specs import ALLOCATOR_PARAMETER_SPECS
from uvms_control.core.parameters import (
    thruster_parameters_from_flat_dict,
    validate_node_parameters,
)
from uvms_control.ros_parameters import declare_parameters
from uvms_model import PARAMETER_SPECS, ModelError, UvmsParameters, load_description
from uvms_msgs.msg import ActuatorCommand, GeneralizedForce, ThrusterState


class ThrusterAllocatorNode(Node):
    """Generalized force command in, thrusts and motor torques out."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('thruster_allocator', **kwargs)
        robot = declare_parameters(self, PARAMETER_SPECS)
        values = validate_node_parameters(
            ALLOCATOR_PARAMETER_SPECS, declare_parameters(self, ALLOCATOR_PARAMETER_SPECS)
        )
        try:
            uvms = UvmsParameters.from_flat_dict(robot)
            layout = ThrusterLayout.from_parameters(uvms.thrusters)
            joint_names = load_description(
                uvms.description.urdf_path, uvms.description.hydrodynamics_path
            ).joint_names
        except ModelError as error:
            raise ControlParameterError(
                'robot parameters', str(error), 'valid values (config/robot.yaml)'
            ) from error
        thruster = thruster_parameters_from_flat_dict(
            {k: v for k, v in values.items() if k.startswith('thruster.')},
            uvms.hydrodynamics.water_density_kg_m3,
        )
        torque_limits = np.asarray(values['allocator.max_joint_torque_n_m'], dtype=float)
        if torque_limits.size != len(joint_names):
            raise ControlParameterError(
                'allocator.max_joint_torque_n_m',
                torque_limits.tolist(),
                f'{len(joint_names)} values, one per arm joint',
            )
        limits = AllocatorParameters(
            layout.thrust_matrix(), layout.max_thrust_n, torque_limits, thruster
        )
        self.core = ThrusterAllocator(limits)
        self._joint_names = joint_names
        self._lockstep = values['trigger_mode'] == 'lockstep'
        self._watchdog_ns = round(float(values['watchdog_timeout_s']) * 1e9)
        self._max_step_ns = round(float(values['max_step_s']) * 1e9)
        self._period_s = 1.0 / float(values['rate_hz'])
        self._safe_tau_b = np.zeros(6 + len(self._joint_names))
        self._last_stamp_ns: int | None = None
        self._arrival_ns: int | None = None
        self._stale = False
        # Refilled for each publication (rclpy serializes at publish).
        self._actuator_msg: ActuatorCommand | None = None
        self._state_msg: ThrusterState | None = None

        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._actuator_pub = self.create_publisher(ActuatorCommand, 'command/actuators', qos)
        self._state_pub = self.create_publisher(ThrusterState, 'thrusters/state', qos)
        self.create_subscription(
            GeneralizedForce, 'command/generalized_force', self._on_command, qos
        )
        if not self._lockstep:
            # On the steady clock, as the controller's: /clock bursts must not drop periods.
            self.create_timer(self._period_s, self._on_timer,
                              clock=Clock(clock_type=ClockType.STEADY_TIME))
        c = self.core.thrusters.calibration
        self.get_logger().info(
            f'{layout.count} thrusters, {values["trigger_mode"]} trigger; calibrated blade area '
            f'{c.blade_area:.4g} m^2, reverse lift factor {c.reverse_lift_factor:.3f}, '
            f'integration step <= {c.max_step * 1e3:.3g} ms'
        )

    def _on_command(self, msg: GeneralizedForce) -> None:
        """Keep a valid command; in lockstep answer it at once with its own stamp."""
        stamp = conversions.stamp_ns(msg.header.stamp)
        try:
            _, tau_b = conversions.generalized_force_arrays(msg, self._joint_names)
        except ControlInputError as error:
            self.get_logger().error(
                f'rejected generalized force, holding the last safe command: {error}',
                throttle_duration_sec=1.0,
            )
            tau_b = None
        if tau_b is not None:
            self._safe_tau_b = tau_b
            self._arrival_ns = self.get_clock().now().nanoseconds
        if not self._lockstep:
            return
        if self._last_stamp_ns is not None and stamp < self._last_stamp_ns:
            return  # an old command: the thrusters are already past it
        ahead_ns = stamp - self.get_clock().now().nanoseconds
        if ahead_ns > self._max_step_ns:
            # Stamped beyond simulated time: no state asked for it (another publisher). It
            # must not move the thruster time ahead, or the real commands would look old.
            self.get_logger().warn(
                f'ignored generalized force stamped {ahead_ns * 1e-9:.3f} s ahead of the clock',
                throttle_duration_sec=1.0,
            )
            return
        dt_ns = 0 if self._last_stamp_ns is None else stamp - self._last_stamp_ns
        if dt_ns > self._max_step_ns:
            self.get_logger().warn(
                f'{dt_ns * 1e-9:.3f} s between commands exceeds max_step_s: thrusters restarted'
            )
            self.core.reset()
            dt_ns = 0
        self._last_stamp_ns = stamp
        self._step(stamp, self._safe_tau_b, dt_ns * 1e-9)

    def _on_timer(self) -> None:
        """Timer mode: step on the latest command, or on zero once it is stale."""
        now = self.get_clock().now().nanoseconds
        tau_b = self._safe_tau_b
        if self._arrival_ns is None or now - self._arrival_ns > self._watchdog_ns:
            if not self._stale and self._arrival_ns is not None:
                self.get_logger().warn(
                    'generalized force command is stale: thrusters and motors set to zero'
                )
            self._stale = self._arrival_ns is not None
            tau_b = np.zeros_like(tau_b)
        elif self._stale:
            self._stale = False
            self.get_logger().info('fresh generalized force commands: resumed')
        self._step(now, tau_b, self._period_s)

    def _step(self, t_ns: int, tau_b: np.ndarray, dt: float) -> None:
        output = self.core.step(tau_b, dt)
        self._actuator_msg = conversions.actuator_command_message(
            t_ns, output.thrust, self._joint_names, output.joint_torques, self._actuator_msg
        )
        self._actuator_pub.publish(self._actuator_msg)
        self._state_msg = conversions.thruster_state_message(t_ns, output, self._state_msg)
        self._state_pub.publish(self._state_msg)


def main(args: list[str] | None = None) -> None:
    """Run the thruster allocator node until SIGINT/SIGTERM."""
    sys.exit(run_node(ThrusterAllocatorNode, args, 'thruster_allocator',
                      (ControlParameterError, ParameterException)))

if __name__ == '__main__':
    main()
