"""The ``ardusub_bridge`` node: command/actuators -> ArduSub RC overrides; imu, depth, battery.

A managed node (``autostart``) on the bridges' base (``bridge_node``) over
`uvms_hardware.ardusub_link.ArduSubLink`:

- configure: find ArduSub's HEARTBEAT (``heartbeat_timeout_s``), check its GCS id against
  ``gcs_system_id`` and that no other ground station shares our id (refused naming them),
  refuse thruster outputs an earlier run left in RC passthrough (naming them, the values to
  restore and the command that does it), warn where a lost link is unprotected, listen for
  the autopilot's watchdog script (``autopilot_watchdog``), ask for the telemetry
  (MAV_CMD_SET_MESSAGE_INTERVAL), publish ``imu``, ``depth``, ``battery``.
- activate: script mode changes nothing on the vehicle; passthrough mode journals the thruster
  outputs' functions and sets RCIN passthrough. Then arm and take ``command/actuators``. Any
  failure half-way puts back what was changed (the base's guarantee).
- telemetry stamped when the autopilot sent it (its boot clock mapped into the node clock,
  ``ardusub_stamps``, from the kernel's arrival time of each datagram, ``datagram_arrival``);
  SYS_STATUS, which has no time, at its arrival.
- each period (``override_rate_hz``): thrusts -> PWM (T200 curve at the measured voltage,
  thruster direction) as RC_CHANNELS_OVERRIDE; no command for ``watchdog_timeout_s``: 1500 on
  every thruster until commands return. A vehicle silent for ``link_timeout_s`` is an ERROR on
  /diagnostics at once (a running goal can end on it).
- deactivate, shutdown, SIGINT, SIGTERM, a transition that raised: neutral, disarm, overrides
  released, functions restored and read back, all within ``restore_budget_s``
  (``ArduSubLink.restore``).

Default ``mavlink_url`` ``udpout:127.0.0.1:14550``: the bridge is the client that speaks
first (its 1 Hz HEARTBEAT opens the path), as a GCS does towards a router's server endpoint
(BlueOS's mavlink-router) or the twin listening on 14550, the GCS port of MAVLink. On the
vehicle, the endpoint to use is the router's; that address belongs in the hardware file.

The device is `uvms_hardware.ardusub_component.ArduSubComponent` (no ROS; its decisions in
the pure `uvms_hardware.ardusub_core`); this node turns its lifecycle hooks into the
component's, ``command/actuators`` into ``command``, its period into ``read`` and ``write``
and the component's state and report into messages.
"""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState, Imu
from std_srvs.srv import Trigger
from uvms_common.clock_read import now_ns
from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.parameter_declaration import declare_specs

from uvms_common import direct_topics
from uvms_description.robots import RobotParameter, robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_hardware.ardusub_component import SPECS, ArduSubComponent
from uvms_hardware.ardusub_core import TELEMETRY_REQUEST_PERIOD_S, WATCHDOG_CHOICES
from uvms_hardware.ardusub_link import ArduSubLink
from uvms_hardware.ardusub_stamps import TelemetryStamper
from uvms_hardware.bridge_node import DEVICE_TOPIC_QOS, BridgeNode, run_bridge
from uvms_hardware.component import logger_log
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import hardware_section
from uvms_hardware.t200_curve import T200Curve
from uvms_hardware.watchdog import CommandWatchdog
from uvms_msgs.msg import ActuatorCommand

__all__ = ['SPECS', 'TELEMETRY_REQUEST_PERIOD_S', 'WATCHDOG_CHOICES', 'ArduSubBridgeError',
           'ArduSubBridgeNode', 'main']

LEVELS = (OK, WARN, ERROR)

class ArduSubBridgeError(HardwareError, ValueError):
    """A parameter of the bridge is invalid, or the vehicle cannot be configured."""


class ArduSubBridgeNode(BridgeNode):
    """ArduSub over MAVLink (an `ArduSubComponent`) as the robot side of thrusters and sensors."""

    error_type = ArduSubBridgeError
    diagnostics_task = 'vehicle'

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('ardusub_bridge', **kwargs)
        try:
            source, section = hardware_section(self.robot_name, 'ardusub')
            navigation = {k: p.value for k, p in robot_parameters(self.robot_name,
                                                                  'estimator').items()}
        except (HardwareError, ValueError) as exc:
            raise ArduSubBridgeError(str(exc)) from exc
        depth = section.get('depth', {})
        robot = {name: RobotParameter(value, source) for name, value in (
            ('thruster_channels', section.get('thruster_channels')),
            ('thruster_directions', section.get('thruster_directions')),
            ('surface_pressure_pa', depth.get('surface_pressure_pa')),
            ('water_density_kg_m3', depth.get('water_density_kg_m3'))) if value is not None}
        values = declare_specs(self, SPECS, robot, lambda spec, exc: ArduSubBridgeError(
            f'invalid parameter {spec.name!r}: {exc}'))
        if values['autopilot_watchdog'] not in WATCHDOG_CHOICES:
            raise ArduSubBridgeError(f'autopilot_watchdog = {values["autopilot_watchdog"]!r}'
                                     f': expected one of {", ".join(WATCHDOG_CHOICES)}')
        self.curve = T200Curve.from_section(section['t200'])
        self.component = ArduSubComponent(
            values, self.curve, bm.ImuNoise.from_navigation(navigation),
            float(navigation['navigation.depth.sigma_m']) ** 2
            + float(navigation['navigation.depth.bias_max_m']) ** 2 / 3.0,
            float(depth.get('gravity_m_s2', bm.G_M_S2)), self.get_name(), clock=self.now_s,
            local_clock=self._local_s, log=logger_log(self.get_logger()),
            stop_requested=stop_requested)
        self.start()

    # -- what tests and tools read of the component ------------------------------------
    @property
    def values(self) -> dict[str, Any]:
        """The settings (parameters) of the component."""
        return self.component.values

    @property
    def link(self) -> ArduSubLink | None:
        """The component's MAVLink link (None while unconfigured)."""
        return self.component.link

    @property
    def watchdog(self) -> CommandWatchdog:
        """The command watchdog."""
        return self.component.core.watchdog

    @property
    def stamper(self) -> TelemetryStamper:
        """The telemetry's stamps (the autopilot's clock against the node's)."""
        return self.component.stamper

    @property
    def warnings(self) -> list[str]:
        """What configure warned about."""
        return self.component.warnings

    def _local_s(self) -> float:
        """The node clock (s): what stamps are in (``/clock`` beside the simulator)."""
        return now_ns(self.get_clock()) * 1e-9

    # -- the device hooks --------------------------------------------------------------
    def configure_device(self) -> None:
        """The component's configure; then imu, depth, battery, ~/zero_depth and the period."""
        # On a simulated clock (beside the simulator and the twins) the autopilot's clock can
        # never be mapped into the node's: arrival stamps, as /diagnostics then says.
        self.component.device_time = not self.get_parameter('use_sim_time').value
        self.component.configure()
        self._imu = self.own(self.destroy_publisher, self.create_publisher(
            Imu, 'imu', DEVICE_TOPIC_QOS))
        self._depth = self.own(self.destroy_publisher, self.create_publisher(
            PoseWithCovarianceStamped, 'depth', DEVICE_TOPIC_QOS))
        self._battery = self.own(self.destroy_publisher,
                                 self.create_publisher(BatteryState, 'battery', DEVICE_TOPIC_QOS))
        self.own(self.destroy_service, self.create_service(Trigger, '~/zero_depth', self._zero))
        self.device_timer(1.0 / float(self.values['override_rate_hz']), self._period,
                          then=self._write)
        c = self.component
        assert c.link is not None
        self.get_logger().info(f'ArduSub system {c.link.vehicle.system_id} at '
                               f'{c.link.settings.url}; {c.gcs_param} = {c.gcs_id} as ours; '
                               f'thrusters in {c.link.mode} mode')

    def activate_device(self) -> None:
        """Passthrough mode: journal and set RCIN; then arm and take commands."""
        self.component.activate()
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._command = direct_topics.subscribe(self, ActuatorCommand, 'command/actuators',
                                                self._on_command, qos)

    def put_device_back(self) -> list[str]:
        """Stop taking commands; neutral, disarm, release, functions back (bounded)."""
        if hasattr(self, '_command'):
            destroy, command = self._command
            destroy(command)
            del self._command
        return self.component.put_back()

    def release_device(self) -> None:
        """Close the link."""
        self.component.release()

    def device_report(self) -> Report:
        """The component's report."""
        report = self.component.report(self.now_s())
        return Report(LEVELS[report.level], report.message, dict(report.values))

    # -- the running path --------------------------------------------------------------
    def _on_command(self, msg: ActuatorCommand) -> None:
        problem = self.component.command(list(msg.thrust), self.now_s())
        if problem is not None:
            self.get_logger().error(f'command/actuators rejected: {problem}',
                                    throttle_duration_sec=1.0)

    def _period(self) -> None:
        component = self.component
        component.read(self.now_s())
        state = component.state()
        for s in state.imu:
            self._imu.publish(bm.imu_message(round(s.stamp_s * 1e9), s.quaternion_wxyz,
                                             s.w_rad_s, s.f_m_s2, component.imu_noise))
        for stamp_s, depth_m in state.depth:
            self._depth.publish(bm.depth_message(round(stamp_s * 1e9), depth_m,
                                                 component.depth_variance_m2))
        for stamp_s, voltage_v, current_a, remaining in state.battery:
            self._battery.publish(bm.battery_message(round(stamp_s * 1e9), voltage_v,
                                                     current_a, remaining))
        if state.link_lost_changed:
            self.update_diagnostics()  # at once: the graph may end a running goal on it

    def _write(self) -> None:
        """The period's RC overrides (in the robot loop: after the control step)."""
        self.component.write(self.now_s())

    def _zero(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        done = self.component.zero_depth()
        response.success = done is not None
        response.message = done if done is not None else 'no SCALED_PRESSURE2 received yet'
        return response


def main(args: list[str] | None = None) -> None:
    """Run the ardusub_bridge node until SIGINT/SIGTERM, then put the vehicle back."""
    run_bridge(ArduSubBridgeNode, args, 'ardusub_bridge')


if __name__ == '__main__':
    main()
