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

from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu, JointState
from uvms_common.cdr_codecs import Decoded, MalformedPayloadError, RawDecoder
from uvms_common.diagnostics import DiagnosticsPublisher
from uvms_common.hot_messages import joint_state_codec, wrench_codec
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.robot_parameters import declare_robot_name
from uvms_hardware.device_clock import DeviceClock
from uvms_hardware.errors import HardwareError
from uvms_thrusters.raw_conversions import ActuatorCommandWriter

from uvms_msgs.msg import ActuatorCommand
from uvms_twins.twin_stand import (
    CONTROL_MODES,
    STAND_PARAMETERS,
    TwinStand,
    ardusub_listen_address,
)

__all__ = ['CONTROL_MODES', 'PARAMETERS', 'TwinsNode', 'ardusub_listen_address', 'main']

#: Parameters: name -> (default, description).
PARAMETERS: dict[str, tuple[Any, str]] = {
    'plant_namespace': ('/plant', 'Where the simulator publishes its device-side topics'),
    'rate_hz': (500.0, 'Rate of the actuator command to the simulator (Hz, steady clock)'),
    **STAND_PARAMETERS,
}


class TwinsNode(Node):
    """Serves the four twins and moves the plant's measurements and commands over /plant."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('hardware_twins', **kwargs)
        robot = declare_robot_name(self)
        v = {name: self.declare_parameter(name, default).value
             for name, (default, _) in PARAMETERS.items()}
        self.stand = TwinStand(robot, v, self._plant_s, self.get_logger().info)
        # Kept by their old names: the tests and tools reach the twins through the node.
        self.ardusub, self.dvl, self.arm = self.stand.ardusub, self.stand.dvl, self.stand.arm
        self.netft = self.stand.netft
        self._joints = self.stand.joints
        self._command_writer = ActuatorCommandWriter(len(self.stand.thrusters.channels),
                                                     self._joints)
        self._device_clock = DeviceClock(self)
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
        self._diagnostics.add('twins', self.stand.report)
        self.get_logger().info(f'twins of {robot}: {self.stand.summary()}')

    def _plant_s(self) -> float:
        """The plant's time (s): the node's clock, /clock beside the simulator."""
        return self.get_clock().now().nanoseconds * 1e-9

    def _on_joints(self, data: bytes) -> None:
        decoded = self._decoded(self._joint_decoder, data)
        if decoded is None:
            return
        if decoded.view is not None:
            at, fields = self._joint_fields
            values = fields.unpack_from(decoded.view, at)
            n = len(self._joints)
            self.stand.set_joint_state(values[:n], values[n:])
            return
        msg = decoded.message
        state = dict(zip(msg.name, zip(msg.position, msg.velocity, strict=False), strict=False))
        if all(j in state for j in self._joints):
            self.stand.set_joint_state([state[j][0] for j in self._joints],
                                       [state[j][1] for j in self._joints])

    def _on_wrench(self, data: bytes) -> None:
        decoded = self._decoded(self._wrench_decoder, data)
        if decoded is None:
            return
        if decoded.view is not None:
            at, fields = self._wrench_fields
            wrench = fields.unpack_from(decoded.view, at)
        else:
            f, t = decoded.message.wrench.force, decoded.message.wrench.torque
            wrench = (f.x, f.y, f.z, t.x, t.y, t.z)
        self.stand.set_wrench(wrench[:3], wrench[3:])

    def _decoded(self, decoder: RawDecoder, data: bytes) -> Decoded | None:
        try:
            return decoder.decode(data)
        except MalformedPayloadError as exc:
            self.get_logger().error(f'malformed plant payload: {exc}', throttle_duration_sec=5.0)
            return None

    def _on_imu(self, msg: Imu) -> None:
        q, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
        self.stand.set_imu((q.w, q.x, q.y, q.z), (w.x, w.y, w.z), (a.x, a.y, a.z))

    def _on_depth(self, msg: PoseWithCovarianceStamped) -> None:
        self.stand.set_depth(msg.pose.pose.position.z)

    def _on_dvl(self, msg: TwistWithCovarianceStamped) -> None:
        v = msg.twist.twist.linear
        stamp = msg.header.stamp
        self.stand.dvl_reading((v.x, v.y, v.z), math.sqrt(msg.twist.covariance[0]),
                               stamp.sec + stamp.nanosec * 1e-9, self._device_clock.now_s())

    def _on_tick(self) -> None:
        plant_ns = self.get_clock().now().nanoseconds
        command = self.stand.command(plant_ns, self._device_clock.now_s())
        if command is not None:
            thrust, torques = command
            self._command_pub.publish(self._command_writer.payload(plant_ns, thrust, torques))

    def destroy_node(self) -> None:
        """Stop the twins, then destroy the node."""
        self.stand.stop()
        self._diagnostics.destroy()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Run the twins until SIGINT/SIGTERM."""
    sys.exit(run_node(TwinsNode, args, 'hardware_twins', (HardwareError, ValueError, OSError)))


if __name__ == '__main__':
    main()
