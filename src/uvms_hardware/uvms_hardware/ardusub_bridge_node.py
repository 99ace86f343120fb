"""The ``ardusub_bridge`` node: command/actuators -> ArduSub RC overrides; imu, depth, battery.

A managed node (``autostart``) over `uvms_hardware.ardusub_link.ArduSubLink`:

- configure: find ArduSub's HEARTBEAT (``heartbeat_timeout_s``), check its GCS id against
  ``gcs_system_id`` (refused naming both), warn where a lost link is unprotected, ask for the
  telemetry (MAV_CMD_SET_MESSAGE_INTERVAL), publish ``imu``, ``depth``, ``battery``.
- activate: thruster outputs to RCIN passthrough (remembered), arm, take ``command/actuators``.
- each period (``override_rate_hz``): thrusts -> PWM (T200 curve at the measured voltage,
  thruster direction) as RC_CHANNELS_OVERRIDE; no command for ``watchdog_timeout_s``: 1500 on
  every thruster channel until commands return. A vehicle silent for ``link_timeout_s`` is an
  ERROR on /diagnostics at once (a running goal can end on it).
- deactivate, shutdown, SIGINT, SIGTERM: neutral, disarm, functions restored, override
  released (``ArduSubLink.restore``).

Default ``mavlink_url`` ``udpout:127.0.0.1:14550``: the bridge is the client that speaks
first (its 1 Hz HEARTBEAT opens the path), as a GCS does towards a router's server endpoint
(BlueOS's mavlink-router) or the twin listening on 14550, the GCS port of MAVLink. On the
vehicle, the endpoint to use is the router's; that address belongs in the hardware file.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState, Imu
from std_srvs.srv import Trigger
from uvms_common.diagnostics import ERROR, OK, WARN, DiagnosticsPublisher, Report
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_main import run_node
from uvms_common.parameter_declaration import declare_specs
from uvms_common.robot_parameters import declare_robot_name

from uvms_description.robots import RobotParameter, robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_hardware.ardusub_link import ArduSubLink, LinkSettings
from uvms_hardware.device_clock import DeviceClock, stop_requested
from uvms_hardware.errors import DeviceCheckError, HardwareError
from uvms_hardware.hardware_config import Spec, hardware_section
from uvms_hardware.t200_curve import T200Curve
from uvms_hardware.watchdog import CommandWatchdog
from uvms_msgs.msg import ActuatorCommand

SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE
#: Telemetry intervals are asked for again this often (s), as RDML's ardusub_manager does.
TELEMETRY_REQUEST_PERIOD_S = 20.0


SPECS = (
    Spec('mavlink_url', 'udpout:127.0.0.1:14550', 'pymavlink URL of the vehicle: '
         'udpout:HOST:PORT, udpin:HOST:PORT or tcp:HOST:PORT'),
    Spec('gcs_system_id', 255, 'Our MAVLink system id; must equal MAV_GCS_SYSID', 1, 255),
    Spec('heartbeat_timeout_s', 10.0, 'Wait for the vehicle at configure (s): it may come up '
         'after the bridge (launch order)', 0.1, 120.0),
    Spec('reply_timeout_s', 0.5, 'Wait for a parameter or command answer (s)', 0.05, 10.0),
    Spec('link_timeout_s', 1.0, 'Vehicle silent this long: ERROR on /diagnostics (s)', 0.1, 30.0),
    Spec('watchdog_timeout_s', 0.1, 'No command this long: thrusters neutral (s)', 0.01, 1.0),
    Spec('override_rate_hz', 60.0, 'RC_CHANNELS_OVERRIDE rate (Hz); 60 keeps >= 50 under '
         'jitter', 50.0, 400.0),
    Spec('imu_rate_hz', 50.0, 'ATTITUDE_QUATERNION and RAW_IMU rate asked for (Hz)', 1.0, 400.0),
    Spec('depth_rate_hz', 20.0, 'SCALED_PRESSURE2 rate asked for (Hz)', 1.0, 100.0),
    Spec('battery_rate_hz', 2.0, 'SYS_STATUS rate asked for (Hz)', 0.1, 50.0),
    Spec('thruster_channels', [1, 2, 3, 4, 5, 6, 7, 8], 'RC channel (1-8) of thruster i'),
    Spec('thruster_directions', [1, 1, 1, 1, 1, 1, 1, 1], '+1/-1: thruster i on the frame'),
    Spec('surface_pressure_pa', 101325.0, 'Pressure at zero depth (Pa); ~/zero_depth sets it'),
    Spec('water_density_kg_m3', 1000.0, 'Water density for depth (kg/m^3)', 900.0, 1100.0),
)


class ArduSubBridgeError(HardwareError, ValueError):
    """A parameter of the bridge is invalid."""


class ArduSubBridgeNode(LifecycleNode):
    """ArduSub over MAVLink as the robot side of the graph's thrusters and sensors."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('ardusub_bridge', **kwargs)
        self._device_clock = DeviceClock(self)
        self.robot_name = declare_robot_name(self)
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
        self.values = declare_specs(self, SPECS, robot, lambda spec, exc: ArduSubBridgeError(
            f'invalid parameter {spec.name!r}: {exc}'))
        self.curve = T200Curve.from_section(section['t200'])
        self.imu_noise = bm.ImuNoise.from_navigation(navigation)
        self.depth_variance = float(navigation['navigation.depth.sigma_m']) ** 2 + \
            float(navigation['navigation.depth.bias_max_m']) ** 2 / 3.0
        self.gravity = float(depth.get('gravity_m_s2', bm.G_M_S2))
        starting = declare_autostart(self)
        guard_change_state(self)
        self.link: ArduSubLink | None = None
        self.watchdog = CommandWatchdog(float(self.values['watchdog_timeout_s']))
        self.thrusts: list[float] | None = None
        self.rejected = 0
        self.warnings: list[str] = []
        self._active = False
        self._dirty = False  # activate changed the vehicle: put it back once
        self._link_lost = False
        self._pressure_pa = math.nan
        self.telemetry_rates_hz: dict[str, float] = {}
        self._next_request_s = math.inf
        self._entities: list[Any] = []
        self._diagnostics = DiagnosticsPublisher(self, self.robot_name)
        self._diagnostics.add('vehicle', self._report)
        if starting and not autostart(self):
            self.destroy_node()
            raise DeviceCheckError('ardusub_bridge: cannot configure and activate (logged)')

    def _now_s(self) -> float:
        """The steady clock (s): the link's times (``uvms_hardware.device_clock``)."""
        return self._device_clock.now_s()

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Find ArduSub, check its GCS id and failsafes, ask for telemetry, make publishers."""
        v = self.values
        try:
            settings = LinkSettings(
                str(v['mavlink_url']), tuple(int(c) for c in v['thruster_channels']),
                tuple(int(d) for d in v['thruster_directions']), int(v['gcs_system_id']),
                reply_timeout_s=float(v['reply_timeout_s']),
                silent_after_s=float(v['link_timeout_s']))
            self.link = ArduSubLink(settings, self.curve)
            self.link.stop_requested = stop_requested
            self.link.open()
            self.link.wait_vehicle(float(v['heartbeat_timeout_s']))
            name, gcs_id = self.link.check_gcs_id()
            self.warnings = self.link.failsafe_warnings()
            imu_hz = float(v['imu_rate_hz'])
            self.telemetry_rates_hz = {
                'ATTITUDE_QUATERNION': imu_hz, 'RAW_IMU': imu_hz,
                'SCALED_PRESSURE2': float(v['depth_rate_hz']),
                'SYS_STATUS': float(v['battery_rate_hz'])}
            self.link.request_telemetry(self.telemetry_rates_hz)
            self._next_request_s = self._now_s() + TELEMETRY_REQUEST_PERIOD_S
        except (DeviceCheckError, ValueError, OSError) as exc:
            self.get_logger().error(f'configure failed: {exc}')
            self._close_link()
            return FAILURE
        for warning in self.warnings:
            self.get_logger().warning(warning)
        self.get_logger().info(
            'in RC passthrough a failsafe disarm does not stop the thrusters and what an '
            "output does once its override expires is unknown: this bridge's watchdog "
            f'(neutral after {self.watchdog.timeout_s:g} s) is what protects them')
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._imu = self.create_publisher(Imu, 'imu', qos)
        self._depth = self.create_publisher(PoseWithCovarianceStamped, 'depth', qos)
        self._battery = self.create_publisher(BatteryState, 'battery', qos)
        self.link.on_telemetry = self._on_telemetry
        self._entities = [(self.destroy_publisher, p) for p in (self._imu, self._depth,
                                                                self._battery)]
        self._entities += [
            (self.destroy_service, self.create_service(Trigger, '~/zero_depth', self._zero)),
            (self.destroy_timer, self._device_clock.timer(1.0 / float(v['override_rate_hz']),
                                                          self._period))]
        self.get_logger().info(f'ArduSub system {self.link.vehicle.system_id} at '
                               f'{settings.url}; {name} = {gcs_id} as ours')
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Thruster outputs to RCIN passthrough, arm, take commands."""
        assert self.link is not None
        self._dirty = True
        try:
            self.link.enable_passthrough()
            self.link.arm(True)
        except DeviceCheckError as exc:
            self.get_logger().error(f'activate refused: {exc}')
            self._put_back()
            return FAILURE
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._command = self.create_subscription(ActuatorCommand, 'command/actuators',
                                                 self._on_command, qos)
        self.thrusts = None
        self._active = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Neutral, disarm, functions restored, override released."""
        self._put_back()
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Drop publishers, timer and the link."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """From any state: put the vehicle back as found, release everything."""
        self._put_back()
        self._release()
        return super().on_shutdown(state)

    def destroy_node(self) -> None:
        """Shut down as rclcpp's lifecycle node does, then destroy."""
        if state_label(self) not in ('finalized', 'unknown') and self.context.ok():
            self.trigger_shutdown()
        self._diagnostics.destroy()
        super().destroy_node()

    def put_vehicle_back(self) -> None:
        """The process's last word to the vehicle (run_node's close_output, before teardown)."""
        self._put_back()

    def _put_back(self) -> None:
        if self._active and hasattr(self, '_command'):
            self.destroy_subscription(self._command)
        self._active = False
        if not self._dirty:
            return
        self._dirty = False
        if self.link is not None and self.link.conn is not None:
            for problem in self.link.restore():
                self.get_logger().error(f'putting the vehicle back: {problem}')

    def _release(self) -> None:
        for destroy, entity in reversed(self._entities):
            destroy(entity)
        self._entities = []
        self._close_link()

    def _close_link(self) -> None:
        if self.link is not None:
            self.link.close()
        self.link = None

    def _on_command(self, msg: ActuatorCommand) -> None:
        thrusts = list(msg.thrust)
        expected = len(self.values['thruster_channels'])
        if len(thrusts) != expected or not all(math.isfinite(t) for t in thrusts):
            self.rejected += 1
            self.get_logger().error(f'command/actuators rejected: {len(thrusts)} thrusts '
                                    f'(expected {expected} finite)', throttle_duration_sec=1.0)
            return
        self.thrusts = thrusts
        self.watchdog.feed(self._now_s())

    def _period(self) -> None:
        link = self.link
        if link is None:
            return
        try:
            link.service()
        except OSError as exc:
            self.get_logger().error(f'MAVLink: {exc}', throttle_duration_sec=1.0)
        if self._now_s() >= self._next_request_s:
            # A rebooted autopilot forgets the intervals: asked again, without waiting.
            self._next_request_s = self._now_s() + TELEMETRY_REQUEST_PERIOD_S
            link.request_telemetry(self.telemetry_rates_hz, wait=False)
        lost = link.link_age_s() > float(self.values['link_timeout_s'])
        if lost != self._link_lost:
            self._link_lost = lost
            self._diagnostics.update()  # at once: the graph may end a running goal on it
        if not self._active:
            return
        if self.thrusts is None or self.watchdog.expired(self._now_s()):
            link.neutral()
        else:
            link.send_override(link.pwm_for(self.thrusts))

    def _on_telemetry(self, kind: str, msg: Any) -> None:
        t_ns = self.get_clock().now().nanoseconds
        link = self.link
        if kind == 'RAW_IMU' and link is not None and link.vehicle.quaternion_wxyz is not None:
            w, f = bm.imu_from_raw_imu(msg)
            self._imu.publish(bm.imu_message(t_ns, link.vehicle.quaternion_wxyz, w, f,
                                             self.imu_noise))
        elif kind == 'SCALED_PRESSURE2':
            self._pressure_pa = msg.press_abs * 100.0
            depth_m = bm.depth_from_pressure(
                msg.press_abs, float(self.values['surface_pressure_pa']),
                float(self.values['water_density_kg_m3']), self.gravity)
            self._depth.publish(bm.depth_message(t_ns, depth_m, self.depth_variance))
        elif kind == 'SYS_STATUS':
            self._battery.publish(bm.battery_message(t_ns, *bm.battery_from_sys_status(msg)))

    def _zero(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success = math.isfinite(self._pressure_pa)
        if response.success:
            self.values['surface_pressure_pa'] = self._pressure_pa
            response.message = f'surface pressure {self._pressure_pa:.1f} Pa: depth 0 here'
        else:
            response.message = 'no SCALED_PRESSURE2 received yet'
        return response

    def _report(self) -> Report:
        state, link = state_label(self), self.link
        if link is None:
            return Report(WARN, f'{state}: no vehicle', {'lifecycle_state': state})
        age_s = link.link_age_s()
        values = {'lifecycle_state': state, 'link_age_s': age_s, 'armed': link.vehicle.armed,
                  'mode': link.vehicle.custom_mode, 'voltage_v': link.vehicle.voltage_v,
                  'watchdog_trips': self.watchdog.trips, 'rejected_commands': self.rejected,
                  'overrides_sent': link.overrides_sent}
        if age_s > float(self.values['link_timeout_s']):
            return Report(ERROR, f'vehicle silent for {age_s:.1f} s', values)
        if self._active and self.watchdog.expired(self._now_s()):
            return Report(WARN, 'no command: thrusters neutral', values)
        return Report(WARN if self.warnings else OK, self.warnings[0] if self.warnings
                      else 'running', values)


def main(args: list[str] | None = None) -> None:
    """Run the ardusub_bridge node until SIGINT/SIGTERM, then put the vehicle back."""
    sys.exit(run_node(ArduSubBridgeNode, args, 'ardusub_bridge',
                      (ArduSubBridgeError, DeviceCheckError, ParameterException),
                      close_output=lambda node: node.put_vehicle_back()))


if __name__ == '__main__':
    main()
