"""The ``hardware_twins`` node: the robot's four devices as protocol twins, on the simulator.

``uvms launch --hardware twin`` runs the simulator with its device-side topics under
``/plant`` (``uvms_bringup.hardware_plan``); this node serves the twins where the bridges
connect (``<bridge>.connection``: the bridge's own connection string) and moves the physics
between them and the simulator:

- ``/plant/joint_states`` -> the Alpha 5 twin's joint positions and rates;
- ``/plant/wrench`` (ft_sensor_link) -> the Net F/T twin, in the sensor's axes;
- ``/plant/imu``, ``/plant/depth`` -> the ArduSub twin's attitude, rates, specific force and
  pressure; ``/plant/dvl`` -> one DVL twin velocity report per reading, sent at once (no
  reading for ``dvl_lost_s``: ``velocity_valid`` false at ``dvl_idle_rate_hz``, as a DVL that
  lost the bottom);
- at ``rate_hz`` on the steady clock: the ArduSub twin's servo outputs (PWM) -> thrusts through
  the T200 curve and the thrusters' dynamics, the arm twin's modes and setpoints -> joint
  torques (``uvms_twins.plant_side``: Current mode's I Kt N eta, Velocity mode's servo),
  published as ``/plant/command/actuators``.

Real devices need no such node; it is the test stand. Everything binds where the hardware
file says (127.0.0.1 in ``config/hardware/twin.yaml``).
"""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu, JointState
from uvms_common.cdr_codecs import Decoded, MalformedPayloadError, RawDecoder
from uvms_common.diagnostics import OK, WARN, DiagnosticsPublisher, Report
from uvms_common.hot_messages import joint_state_codec, wrench_codec
from uvms_common.node_main import run_node
from uvms_common.robot_parameters import declare_robot_name
from uvms_hardware.address import parse_host_port
from uvms_hardware.device_clock import DeviceClock
from uvms_hardware.errors import AddressError, HardwareError
from uvms_hardware.hardware_config import hardware_section, load_alpha5, load_netft
from uvms_hardware.netft_core import DEFAULT_ROT_LINK_FROM_SENSOR
from uvms_hardware.reach_protocol import Mode
from uvms_hardware.transport import parse_connection
from uvms_thrusters.raw_conversions import ActuatorCommandWriter

from uvms_msgs.msg import ActuatorCommand
from uvms_twins.alpha5_twin import Alpha5Twin
from uvms_twins.ardusub_twin import ArduSubTwin
from uvms_twins.dvl_twin import DvlTwin
from uvms_twins.netft_twin import NetFtTwin
from uvms_twins.plant_side import (
    SERVO_BANDWIDTH_RAD_S,
    ArmServo,
    JointInertia,
    ThrusterTwin,
    effort_limits_n_m,
    joint_torques,
)

#: Arm modes in which a bridge drives a joint (Standby, Disable, Passive: not driven).
CONTROL_MODES = (Mode.CURRENT, Mode.VELOCITY, Mode.POSITION)
#: Parameters: name -> (default, description).
PARAMETERS: dict[str, tuple[Any, str]] = {
    'plant_namespace': ('/plant', 'Where the simulator publishes its device-side topics'),
    'rate_hz': (500.0, 'Rate of the actuator command to the simulator (Hz, steady clock)'),
    'battery_voltage_v': (16.0, 'Battery voltage the ArduSub twin reports and the T200 curve '
                                'is read at (V)'),
    'netft_rate_hz': (500.0, 'Records per second the Net F/T twin streams (Hz): the '
                             "simulator's wrench rate; more would repeat its values"),
    'dvl_lost_s': (0.5, 'No DVL reading from the simulator for this long: no bottom lock (s)'),
    'dvl_idle_rate_hz': (2.0, 'Reports per second of the DVL twin while no reading comes (Hz; '
                              'assumed: a DVL without lock still answers its pings)'),
    'arm_servo_bandwidth_rad_s': (SERVO_BANDWIDTH_RAD_S, "Bandwidth of the arm devices' own "
                                  'speed loop in Velocity mode (rad/s; plant_side.ArmServo)'),
    'dvl_altitude_m': (1.85, 'Altitude the DVL twin reports (m; the simulated reading has '
                              'none)'),
    'ardusub_bridge.connection': ('udpout:127.0.0.1:14551', 'Where the ArduSub bridge '
                                  'connects (the twin listens there)'),
    'dvl_bridge.connection': ('127.0.0.1:16171', 'Where the DVL bridge connects'),
    'alpha5_bridge.connection': ('udp:127.0.0.1:6789', 'Where the Alpha 5 bridge connects'),
    'netft_bridge.connection': ('127.0.0.1:49152', 'Where the Net F/T bridge connects'),
}


def ardusub_listen_address(url: str) -> tuple[str, int]:
    """The address the twin listens on for a bridge's ``udpout:HOST:PORT``.

    Raises:
        AddressError: Another kind of URL (the twin serves UDP only).
    """
    kind, _, rest = url.partition(':')
    if kind != 'udpout':
        raise AddressError(f'ardusub_bridge.mavlink_url = {url!r}: the ArduSub twin serves a '
                           'bridge on udpout:HOST:PORT only')
    host, port = parse_host_port(rest, 14550, 'ardusub_bridge.mavlink_url')
    return host, port


class TwinsNode(Node):
    """Serves the four twins and moves the plant's measurements and commands."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('hardware_twins', **kwargs)
        robot = declare_robot_name(self)
        v = {name: self.declare_parameter(name, default).value
             for name, (default, _) in PARAMETERS.items()}
        self._voltage_v = float(v['battery_voltage_v'])
        self._dvl_lost_s = float(v['dvl_lost_s'])
        self._altitude_m = float(v['dvl_altitude_m'])
        _, ardusub = hardware_section(robot, 'ardusub')
        self._rho = float(ardusub['depth']['water_density_kg_m3'])
        self._surface_pa = float(ardusub['depth']['surface_pressure_pa'])
        host, port = ardusub_listen_address(str(v['ardusub_bridge.connection']))
        # The autopilot runs our watchdog script, as a deployed vehicle should (docs/hardware.md):
        # the stand's bridge then drives the thrusters through it, changing no parameter.
        self.ardusub = ArduSubTwin(port=port, host=host, watchdog_script=True)
        host, port = parse_host_port(str(v['dvl_bridge.connection']), 16171)
        # The DVL's clock is the plant's (as a real one is NTP-synchronised to the vehicle's):
        # its time_of_validity is when the plant measured, whatever the real-time factor.
        self.dvl = DvlTwin(host=host, port=port, rate_hz=float(v['dvl_idle_rate_hz']),
                           clock=lambda: self.get_clock().now().nanoseconds * 1e-9)
        arm = load_alpha5(robot)
        link = parse_connection(str(v['alpha5_bridge.connection']), 6789,
                                'alpha5_bridge.connection')
        if link.kind != 'udp':
            raise AddressError(f'alpha5_bridge.connection = {link}: the Alpha 5 twin serves '
                               'UDP only (a serial bridge needs the real arm)')
        # The jaws, which the plant does not have, move on the plant's clock as the joints do.
        self.arm = Alpha5Twin(arm, host=link.target, port=link.number,
                              clock=lambda: self.get_clock().now().nanoseconds * 1e-9)
        host, port = parse_host_port(str(v['netft_bridge.connection']), load_netft(robot).port)
        self.netft = NetFtTwin(host=host, port=port, rate_hz=float(v['netft_rate_hz']))
        # A device always has a state, so a twin serves only once the plant has given it one:
        # before, the bridges would configure on zeros and the estimator start from them.
        self._waiting_for = {'joint_states', 'imu'}
        # And the plant hears from the devices only once the bridges drive them: the simulator
        # holds its first state until an actuator command comes, and one sent before the arm
        # is driven would start physics with the arm limp (its light links fall at ~60 rad/s^2).
        self._driven = False
        self._joints = tuple(d.joint_name for d in arm.drives)
        self._effort = effort_limits_n_m(robot)
        self._servo = ArmServo(JointInertia(robot), self._effort,
                               float(v['arm_servo_bandwidth_rad_s']))
        self._thrusters = ThrusterTwin.for_robot(robot)
        self._rot_sensor_from_link = np.array(DEFAULT_ROT_LINK_FROM_SENSOR).reshape(3, 3).T
        self._command_writer = ActuatorCommandWriter(len(self._thrusters.channels), self._joints)
        self._device_clock = DeviceClock(self)
        self._last_plant_ns: int | None = None
        self._last_dvl_s = -float('inf')
        self._ticks = 0
        plant = str(v['plant_namespace']).rstrip('/')
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        # The two fast topics raw, through the layouts the simulator publishes, as the control
        # loop takes them (typed in another layout, they still read).
        self._joint_decoder = RawDecoder(joint_state_codec(self._joints))
        self._joint_fields = self._joint_decoder.codec.struct(['position', 'velocity'])
        self._wrench_decoder = RawDecoder(wrench_codec())
        self._wrench_fields = self._wrench_decoder.codec.struct(['wrench.force', 'wrench.torque'])
        self.create_subscription(JointState, f'{plant}/joint_states', self._on_joints, qos,
                                 raw=True)
        self.create_subscription(WrenchStamped, f'{plant}/wrench', self._on_wrench, qos,
                                 raw=True)
        self.create_subscription(Imu, f'{plant}/imu', self._on_imu, qos)
        self.create_subscription(PoseWithCovarianceStamped, f'{plant}/depth', self._on_depth, qos)
        self.create_subscription(TwistWithCovarianceStamped, f'{plant}/dvl', self._on_dvl, qos)
        self._command_pub = self.create_publisher(ActuatorCommand, f'{plant}/command/actuators',
                                                  qos)
        self._device_clock.timer(1.0 / float(v['rate_hz']), self._on_tick)
        self._diagnostics = DiagnosticsPublisher(self, robot)
        self._diagnostics.add('twins', self._report)
        self.get_logger().info(
            f'twins of {robot}: ArduSub udpin:{self.ardusub.address[0]}:'
            f'{self.ardusub.address[1]}, DVL {v["dvl_bridge.connection"]}, Alpha 5 '
            f'{v["alpha5_bridge.connection"]}, Net F/T {v["netft_bridge.connection"]}')

    def _heard(self, topic: str) -> None:
        """The plant's first ``topic``: once joint states and IMU came, the twins serve."""
        if not self._waiting_for:
            return
        self._waiting_for.discard(topic)
        if not self._waiting_for:
            for twin in (self.ardusub, self.dvl, self.arm, self.netft):
                twin.start()
            self.get_logger().info('the plant has a state: the twins serve')

    def _on_joints(self, data: bytes) -> None:
        decoded = self._decoded(self._joint_decoder, data)
        if decoded is None:
            return
        if decoded.view is not None:
            at, fields = self._joint_fields
            values = fields.unpack_from(decoded.view, at)
            n = len(self._joints)
            self.arm.set_joint_state(values[:n], values[n:])
            self._heard('joint_states')
            return
        msg = decoded.message
        state = dict(zip(msg.name, zip(msg.position, msg.velocity, strict=False), strict=False))
        if all(j in state for j in self._joints):
            self.arm.set_joint_state([state[j][0] for j in self._joints],
                                     [state[j][1] for j in self._joints])
            self._heard('joint_states')

    def _on_wrench(self, data: bytes) -> None:
        decoded = self._decoded(self._wrench_decoder, data)
        if decoded is None:
            return
        if decoded.view is not None:
            at, fields = self._wrench_fields
            wrench = np.array(fields.unpack_from(decoded.view, at))
        else:
            f, t = decoded.message.wrench.force, decoded.message.wrench.torque
            wrench = np.array([f.x, f.y, f.z, t.x, t.y, t.z])
        force = self._rot_sensor_from_link @ wrench[:3]
        torque = self._rot_sensor_from_link @ wrench[3:]
        self.netft.set_wrench(tuple(force.tolist()), tuple(torque.tolist()))

    def _decoded(self, decoder: RawDecoder, data: bytes) -> Decoded | None:
        try:
            return decoder.decode(data)
        except MalformedPayloadError as exc:
            self.get_logger().error(f'malformed plant payload: {exc}', throttle_duration_sec=5.0)
            return None

    def _on_imu(self, msg: Imu) -> None:
        q, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
        self.ardusub.set_plant_state(quaternion_wxyz=(q.w, q.x, q.y, q.z),
                                     rates_rad_s=(w.x, w.y, w.z),
                                     specific_force_m_s2=(a.x, a.y, a.z),
                                     voltage_v=self._voltage_v)
        self._heard('imu')

    def _on_depth(self, msg: PoseWithCovarianceStamped) -> None:
        depth_m = msg.pose.pose.position.z
        self.ardusub.set_plant_state(pressure_pa=self._surface_pa + self._rho * 9.80665 * depth_m)

    def _on_dvl(self, msg: TwistWithCovarianceStamped) -> None:
        v = msg.twist.twist.linear
        self._last_dvl_s = self._device_clock.now_s()
        # The simulated reading's sigma as the figure of merit (the bridge's variance: fom^2).
        stamp = msg.header.stamp
        self.dvl.report((v.x, v.y, v.z), True, math.sqrt(msg.twist.covariance[0]),
                        self._altitude_m, time_of_validity_s=stamp.sec + stamp.nanosec * 1e-9)

    def _on_tick(self) -> None:
        if self._device_clock.now_s() - self._last_dvl_s > self._dvl_lost_s:
            self.dvl.set_velocity((0.0, 0.0, 0.0), False, 10.0, -1.0)
        # The propellers turn in the plant's time (the node's clock: /clock beside the
        # simulator), not the wall's: at --real-time-factor 0.5 they would spin up twice as fast.
        plant_ns = self.get_clock().now().nanoseconds
        last_ns = plant_ns if self._last_plant_ns is None else self._last_plant_ns
        dt_s = min(max((plant_ns - last_ns) * 1e-9, 0.0), 0.1)
        self._last_plant_ns = plant_ns
        thrust = self._thrusters.step(self.ardusub.servo_outputs_us(), self._voltage_v, dt_s)
        commands = self.arm.joint_commands()
        if not self._driven:
            self._driven = self.ardusub.armed and bool(self.ardusub.overrides()) and all(
                mode in CONTROL_MODES for mode, _ in commands.values())
            if not self._driven:
                return
            self.get_logger().info('the bridges drive the arm and the vehicle: actuator '
                                   'commands to the plant')
        positions, velocities = self.arm.joint_state()
        servo = self._servo.torques(commands, positions, velocities, dt_s)
        torques = joint_torques(commands, self.arm.joint_torques_n_m(), self._effort, servo)
        self._command_pub.publish(self._command_writer.payload(
            plant_ns, thrust, [torques[j] for j in self._joints]))
        self._ticks += 1

    def _report(self) -> Report:
        if self._waiting_for:
            return Report(WARN, f'waiting for the plant\'s {", ".join(sorted(self._waiting_for))}',
                          {'ticks': self._ticks})
        if not self._driven:
            return Report(WARN, 'waiting for the bridges to drive the arm and the vehicle',
                          {'armed': self.ardusub.armed})
        return Report(OK, 'serving', {'ticks': self._ticks, 'armed': self.ardusub.armed})

    def destroy_node(self) -> None:
        """Stop the twins, then destroy the node."""
        for twin in (self.ardusub, self.dvl, self.arm, self.netft):
            twin.stop()
        self._diagnostics.destroy()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Run the twins until SIGINT/SIGTERM."""
    sys.exit(run_node(TwinsNode, args, 'hardware_twins', (HardwareError, ValueError, OSError)))


if __name__ == '__main__':
    main()
