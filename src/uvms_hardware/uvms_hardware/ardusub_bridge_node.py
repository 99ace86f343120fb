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
"""

from __future__ import annotations

import math
from typing import Any

from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState, Imu
from std_srvs.srv import Trigger
from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.parameter_declaration import declare_specs

from uvms_description.robots import RobotParameter, robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_hardware.ardusub_link import PASSTHROUGH, SCRIPT, ArduSubLink, LinkSettings
from uvms_hardware.ardusub_restore import find_leftovers, leftovers_refusal
from uvms_hardware.ardusub_stamps import TelemetryStamper
from uvms_hardware.ardusub_watchdog import SCRIPT_NAME, ScriptSettings
from uvms_hardware.bridge_node import BridgeNode, run_bridge
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.device_journal import DeviceJournal
from uvms_hardware.errors import DeviceCheckError, HardwareError
from uvms_hardware.hardware_config import Spec, hardware_section
from uvms_hardware.stop_report import write_stop_report
from uvms_hardware.t200_curve import T200Curve
from uvms_hardware.watchdog import CommandWatchdog
from uvms_msgs.msg import ActuatorCommand

#: Telemetry intervals are asked for again this often (s), as RDML's ardusub_manager does.
TELEMETRY_REQUEST_PERIOD_S = 20.0
WATCHDOG_CHOICES = ('auto', SCRIPT, PASSTHROUGH)

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
    Spec('autopilot_watchdog', 'auto', f'{SCRIPT_NAME} on the autopilot: auto (script mode '
         'when heard at configure, else passthrough), script (refuse without it), passthrough '
         '(never use it)'),
    Spec('script_wait_s', 1.5, 'Listen this long at configure for the watchdog script (s); it '
         'announces itself once a second', 0.0, 10.0),
    Spec('restore_budget_s', 3.0, 'Longest the restore at a stop may take (s): neutral, '
         'disarm, release, functions read back', 0.5, 8.0),
    Spec('journal_dir', '', 'Folder of the journal of original values ("": UVMS_JOURNAL_DIR, '
         'else $XDG_STATE_HOME/uvms/journal, else ~/.local/state/uvms/journal)'),
)


class ArduSubBridgeError(HardwareError, ValueError):
    """A parameter of the bridge is invalid, or the vehicle cannot be configured."""


class ArduSubBridgeNode(BridgeNode):
    """ArduSub over MAVLink as the robot side of the graph's thrusters and sensors."""

    error_type = ArduSubBridgeError
    diagnostics_task = 'vehicle'

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
        self.values = declare_specs(self, SPECS, robot, lambda spec, exc: ArduSubBridgeError(
            f'invalid parameter {spec.name!r}: {exc}'))
        if self.values['autopilot_watchdog'] not in WATCHDOG_CHOICES:
            raise ArduSubBridgeError(f'autopilot_watchdog = {self.values["autopilot_watchdog"]!r}'
                                     f': expected one of {", ".join(WATCHDOG_CHOICES)}')
        self.curve = T200Curve.from_section(section['t200'])
        self.imu_noise = bm.ImuNoise.from_navigation(navigation)
        self.depth_variance = float(navigation['navigation.depth.sigma_m']) ** 2 + \
            float(navigation['navigation.depth.bias_max_m']) ** 2 / 3.0
        self.gravity = float(depth.get('gravity_m_s2', bm.G_M_S2))
        self.link: ArduSubLink | None = None
        self.watchdog = CommandWatchdog(float(self.values['watchdog_timeout_s']))
        self.thrusts: list[float] | None = None
        self.rejected = 0
        self.warnings: list[str] = []
        self._link_lost = False
        self._pressure_pa = math.nan
        self.stamper = TelemetryStamper()
        self.telemetry_rates_hz: dict[str, float] = {}
        self._next_request_s = math.inf
        self.start()

    # -- the device hooks --------------------------------------------------------------
    def configure_device(self) -> None:
        """Find ArduSub, check ids, leftovers and failsafes, pick the mode, ask for telemetry."""
        v = self.values
        settings = LinkSettings(
            str(v['mavlink_url']), tuple(int(c) for c in v['thruster_channels']),
            tuple(int(d) for d in v['thruster_directions']), int(v['gcs_system_id']),
            reply_timeout_s=float(v['reply_timeout_s']),
            silent_after_s=float(v['link_timeout_s']),
            restore_budget_s=float(v['restore_budget_s']))
        journal = DeviceJournal.for_device('ardusub', settings.url, str(v['journal_dir']))
        self.link = link = ArduSubLink(settings, self.curve, journal=journal)
        # On a simulated clock (beside the simulator and the twins) the autopilot's clock can
        # never be mapped into the node's: arrival stamps, as /diagnostics then says.
        self.stamper = TelemetryStamper(
            device_time=not self.get_parameter('use_sim_time').value)
        link.stop_requested = stop_requested
        link.open()
        link.wait_vehicle(float(v['heartbeat_timeout_s']))
        name, gcs_id = link.check_gcs_id()
        leftovers = find_leftovers(link)
        if leftovers is not None:
            raise DeviceCheckError(leftovers_refusal(leftovers, settings.url,
                                                     str(v['journal_dir'])))
        journal.remove()  # a journal whose values the vehicle has again: nothing left changed
        self.warnings = link.failsafe_warnings()
        self._choose_mode(link)
        self.warnings += link.check_other_gcs()
        imu_hz = float(v['imu_rate_hz'])
        self.telemetry_rates_hz = {
            'ATTITUDE_QUATERNION': imu_hz, 'RAW_IMU': imu_hz,
            'SCALED_PRESSURE2': float(v['depth_rate_hz']),
            'SYS_STATUS': float(v['battery_rate_hz'])}
        link.request_telemetry(self.telemetry_rates_hz)
        self._next_request_s = self.now_s() + TELEMETRY_REQUEST_PERIOD_S
        for warning in self.warnings:
            self.get_logger().warning(warning)
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._imu = self.own(self.destroy_publisher, self.create_publisher(Imu, 'imu', qos))
        self._depth = self.own(self.destroy_publisher, self.create_publisher(
            PoseWithCovarianceStamped, 'depth', qos))
        self._battery = self.own(self.destroy_publisher,
                                 self.create_publisher(BatteryState, 'battery', qos))
        link.on_telemetry = self._on_telemetry
        self.own(self.destroy_service, self.create_service(Trigger, '~/zero_depth', self._zero))
        self.device_timer(1.0 / float(v['override_rate_hz']), self._period)
        self.get_logger().info(f'ArduSub system {link.vehicle.system_id} at {settings.url}; '
                               f'{name} = {gcs_id} as ours; thrusters in {link.mode} mode')

    def _choose_mode(self, link: ArduSubLink) -> None:
        """Script mode when the autopilot's watchdog script is heard (and wanted)."""
        wanted = str(self.values['autopilot_watchdog'])
        timeout_ms = None if wanted == PASSTHROUGH else link.wait_watchdog_script(
            float(self.values['script_wait_s']))
        if timeout_ms is not None:
            script = ScriptSettings.from_source()
            if set(script.outputs) != set(link.settings.thruster_channels):
                raise DeviceCheckError(
                    f'{SCRIPT_NAME} drives outputs {list(script.outputs)}, thruster_channels '
                    f'are {list(link.settings.thruster_channels)}: make them the same')
            link.use_script(script)
            clashes = link.rc_input_outputs()
            if clashes:
                self.warnings.append(
                    'outputs ' + ', '.join(f'{o} (SERVO{o}_FUNCTION = {f})' for o, f in
                                           clashes.items())
                    + ' follow RC inputs 9-16, which carry the thrust PWMs in script mode')
            self.get_logger().info(
                f'{SCRIPT_NAME} heard on the autopilot (timeout {timeout_ms:g} ms): the '
                'thrusters return to neutral without this process; no parameter is changed')
            return
        if wanted == SCRIPT:
            raise DeviceCheckError(f'{SCRIPT_NAME} not heard from the autopilot within '
                                   f'{float(self.values["script_wait_s"]):g} s and '
                                   'autopilot_watchdog = script: install it (docs/hardware.md)')
        self.get_logger().warning(
            f'thrusters in RC passthrough: only this process stops them (a kill leaves the '
            f'last PWM on); install {SCRIPT_NAME} on the autopilot (docs/hardware.md)')

    def activate_device(self) -> None:
        """Passthrough mode: journal and set RCIN; then arm and take commands."""
        assert self.link is not None
        if self.link.mode == PASSTHROUGH:
            self.link.enable_passthrough()
        self.link.arm(True)
        self.thrusts = None
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._command = self.create_subscription(ActuatorCommand, 'command/actuators',
                                                 self._on_command, qos)

    def put_device_back(self) -> list[str]:
        """Stop taking commands; neutral, disarm, release, functions back (bounded)."""
        if hasattr(self, '_command'):
            self.destroy_subscription(self._command)
            del self._command
        if self.link is None or self.link.conn is None:
            return []
        link = self.link
        changed = {c: v for c, v in link.changed_functions.items()}
        problems = link.restore()
        self._say_put_back(link, changed, problems)
        return problems

    def _say_put_back(self, link: ArduSubLink, changed: dict[int, float],
                      problems: list[str]) -> None:
        """One console line of what the stop put back (and the launcher's report)."""
        if any('sent without confirmation' in p for p in problems):
            done = ("vehicle silent: neutral, disarm, overrides released and the outputs' "
                    'functions SENT, none confirmed')
        else:
            disarm = ('disarm NOT confirmed' if any(p.startswith(('disarm', 'arm:'))
                                                     for p in problems) else 'disarmed')
            done = f'thrusters neutral (1500 us), {disarm}, RC overrides released'
            restored = {c: v for c, v in changed.items() if c not in link.changed_functions}
            if restored:
                done += ', SERVOn_FUNCTION restored and read back (' + ', '.join(
                    f'{c}={v:g}' for c, v in sorted(restored.items())) + ')'
            if link.changed_functions:
                done += ', NOT read back: ' + ', '.join(
                    f'SERVO{c}_FUNCTION' for c in sorted(link.changed_functions)) + \
                    ' (journal kept: uvms hardware restore ardusub)'
            if not changed:
                done += f'; no parameter had been changed ({link.mode} mode)'
        self.get_logger().info(f'put back: {done}')
        write_stop_report(self.get_name(), done, problems)

    def release_device(self) -> None:
        """Close the link."""
        if self.link is not None:
            self.link.close()
        self.link = None

    def device_report(self) -> Report:
        """Link age, armed, mode, voltage, watchdog trips, rejected commands, overrides."""
        link = self.link
        if link is None:
            return Report(WARN, 'no vehicle', {})
        age_s = link.link_age_s()
        values = {'link_age_s': age_s, 'armed': link.vehicle.armed,
                  'mode': link.vehicle.custom_mode, 'voltage_v': link.vehicle.voltage_v,
                  'thruster_mode': link.mode, 'watchdog_trips': self.watchdog.trips,
                  'rejected_commands': self.rejected, 'overrides_sent': link.overrides_sent,
                  **self.stamper.report()}
        if age_s > float(self.values['link_timeout_s']):
            return Report(ERROR, f'vehicle silent for {age_s:.1f} s', values)
        if self.stamper.device_time and not self.stamper.clock.rates_agree:
            return Report(WARN, "the autopilot's clock does not run at the node clock's rate "
                          "(beside a simulator, the twin must run on the plant's time): "
                          'telemetry stamped at arrival', values)
        if self.device_active and self.watchdog.expired(self.now_s()):
            return Report(WARN, 'no command: thrusters neutral', values)
        return Report(WARN if self.warnings else OK, self.warnings[0] if self.warnings
                      else 'running', values)

    # -- the running path --------------------------------------------------------------
    def _on_command(self, msg: ActuatorCommand) -> None:
        thrusts = list(msg.thrust)
        expected = len(self.values['thruster_channels'])
        if len(thrusts) != expected or not all(math.isfinite(t) for t in thrusts):
            self.rejected += 1
            self.get_logger().error(f'command/actuators rejected: {len(thrusts)} thrusts '
                                    f'(expected {expected} finite)', throttle_duration_sec=1.0)
            return
        self.thrusts = thrusts
        self.watchdog.feed(self.now_s())

    def _period(self) -> None:
        link = self.link
        if link is None or link.conn is None:
            return
        try:
            link.service()
        except OSError as exc:
            self.get_logger().error(f'MAVLink: {exc}', throttle_duration_sec=1.0)
        if self.now_s() >= self._next_request_s:
            # A rebooted autopilot forgets the intervals: asked again, without waiting.
            self._next_request_s = self.now_s() + TELEMETRY_REQUEST_PERIOD_S
            link.request_telemetry(self.telemetry_rates_hz, wait=False)
        lost = link.link_age_s() > float(self.values['link_timeout_s'])
        if lost != self._link_lost:
            self._link_lost = lost
            self.update_diagnostics()  # at once: the graph may end a running goal on it
        if not self.device_active:
            return
        if self.thrusts is None or self.watchdog.expired(self.now_s()):
            link.neutral()
        else:
            link.send_override(link.pwm_for(self.thrusts))

    def _on_telemetry(self, kind: str, msg: Any, kernel_arrival_s: float | None) -> None:
        arrival_s = self.get_clock().now().nanoseconds * 1e-9
        if kernel_arrival_s is not None and self.stamper.device_time:
            # When the datagram reached the host (the node clock's epoch when not simulated),
            # not when this period's poll read it.
            arrival_s = min(arrival_s, kernel_arrival_s)
        t_ns = round(self.stamper.stamp_s(kind, msg, arrival_s) * 1e9)
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


def main(args: list[str] | None = None) -> None:
    """Run the ardusub_bridge node until SIGINT/SIGTERM, then put the vehicle back."""
    run_bridge(ArduSubBridgeNode, args, 'ardusub_bridge')


if __name__ == '__main__':
    main()
