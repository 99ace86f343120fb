"""ArduSub (MAVLink) as a hardware component: thrusts in; imu, depth and battery out. No ROS.

``ardusub_bridge_node`` wraps it in a managed node. Over `uvms_hardware.ardusub_link`:

- configure: find ArduSub's HEARTBEAT (``heartbeat_timeout_s``), check its GCS id against
  ``gcs_system_id`` and that no other ground station shares our id (refused naming them),
  refuse thruster outputs an earlier run left in RC passthrough (naming them, the values to
  restore and the command that does it), warn where a lost link is unprotected, listen for
  the autopilot's watchdog script (``autopilot_watchdog``, `ardusub_core.choose_mode`), ask
  for the telemetry (MAV_CMD_SET_MESSAGE_INTERVAL). Bounded waits: a lifecycle transition.
- activate: script mode changes nothing on the vehicle; passthrough mode journals the
  thruster outputs' functions and sets RCIN passthrough. Then arm.
- `read` (never waits): our HEARTBEAT when due, every message pending; telemetry stamped when
  the autopilot sent it (``ardusub_stamps``, from the kernel's arrival time of each
  datagram) and kept for `state` (each sample once); intervals asked for again every 20 s.
- `write` (never waits): the period's thrusts -> PWM (T200 curve at the measured voltage,
  thruster direction) as RC_CHANNELS_OVERRIDE; no command for ``watchdog_timeout_s``: 1500 on
  every thruster until commands return (`ardusub_core.ArduSubCore`).
- `put_back`: neutral, disarm, overrides released, functions restored and read back, all
  within ``restore_budget_s`` (``ArduSubLink.restore``); one console line says what.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from uvms_hardware import bridge_messages as bm
from uvms_hardware import latency_probe
from uvms_hardware.ardusub_core import ArduSubCore, choose_mode, put_back_summary
from uvms_hardware.ardusub_link import PASSTHROUGH, SCRIPT, ArduSubLink, LinkSettings
from uvms_hardware.ardusub_restore import find_leftovers, leftovers_refusal
from uvms_hardware.ardusub_stamps import TelemetryStamper
from uvms_hardware.ardusub_watchdog import SCRIPT_NAME, ScriptSettings
from uvms_hardware.component import (
    WARN,
    ComponentReport,
    HardwareComponent,
    LogFn,
    Throttle,
    python_log,
)
from uvms_hardware.device_journal import DeviceJournal
from uvms_hardware.errors import DeviceCheckError
from uvms_hardware.hardware_config import Spec
from uvms_hardware.stop_report import write_stop_report
from uvms_hardware.t200_curve import T200Curve

Vector = tuple[float, float, float]

#: The settings (the bridge node's parameters).
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


@dataclass(frozen=True)
class ImuSample:
    """One IMU sample: ATTITUDE_QUATERNION with RAW_IMU.

    Attributes:
        stamp_s: When the autopilot sent it, on the local clock (s).
        quaternion_wxyz: Orientation of base_link_frd in map_ned.
        w_rad_s: Angular velocity in base_link_frd (rad/s).
        f_m_s2: Specific force in base_link_frd (m/s^2).
    """

    stamp_s: float
    quaternion_wxyz: tuple[float, float, float, float]
    w_rad_s: Vector
    f_m_s2: Vector


@dataclass(frozen=True)
class ArduSubState:
    """What the vehicle gave at the last `ArduSubComponent.read`.

    Attributes:
        imu: IMU samples, oldest first (each once).
        depth: (stamp s, depth m down) of each SCALED_PRESSURE2.
        battery: (stamp s, V, A, fraction 0-1) of each SYS_STATUS.
        fresh: False once the vehicle was silent for ``link_timeout_s``.
        link_lost_changed: The link was lost or came back at this read.
        armed: The vehicle's last HEARTBEAT said armed.
    """

    imu: tuple[ImuSample, ...]
    depth: tuple[tuple[float, float], ...]
    battery: tuple[tuple[float, float, float, float], ...]
    fresh: bool
    link_lost_changed: bool
    armed: bool


class ArduSubComponent(HardwareComponent):
    """ArduSub over MAVLink: thrusters (actuators) and imu, depth, battery (sensors)."""

    def __init__(self, values: Mapping[str, Any], curve: T200Curve, imu_noise: bm.ImuNoise,
                 depth_variance_m2: float, gravity_m_s2: float = bm.G_M_S2,
                 name: str = 'ardusub_bridge', clock: Callable[[], float] = time.monotonic,
                 local_clock: Callable[[], float] | None = None, device_time: bool = True,
                 log: LogFn = python_log,
                 stop_requested: Callable[[], bool] = lambda: False) -> None:
        """A component for the vehicle at ``values['mavlink_url']`` (not contacted yet).

        Args:
            values: Every setting of the bridge (``ardusub_bridge_node.SPECS``) by name.
            curve: The T200's thrust -> PWM curve.
            imu_noise: The imu covariances (kept for the node's messages).
            depth_variance_m2: The depth's variance (m^2).
            gravity_m_s2: g for depth from pressure (m/s^2).
            name: The node's name (stop report).
            clock: The steady clock (s): watchdog, periods, link age.
            local_clock: The clock stamps are in (s; default ``clock``).
            device_time: False: telemetry stamped at arrival (a simulated local clock).
            log: Where messages go.
            stop_requested: True once the process is asked to stop (ends configure's waits).
        """
        super().__init__()
        self.values = dict(values)
        self.curve, self.imu_noise = curve, imu_noise
        self.depth_variance_m2, self.gravity_m_s2 = depth_variance_m2, gravity_m_s2
        self.name, self.clock, self.local_clock = name, clock, local_clock or clock
        self.device_time, self.log, self.stop_requested = device_time, log, stop_requested
        self.link: ArduSubLink | None = None
        self.core = ArduSubCore(len(self.values['thruster_channels']),
                                float(self.values['watchdog_timeout_s']),
                                float(self.values['link_timeout_s']))
        self.stamper = TelemetryStamper(device_time=device_time)
        self.warnings: list[str] = []
        #: The vehicle's GCS id parameter and its value (configure's check).
        self.gcs_param, self.gcs_id = '', 0
        self.telemetry_rates_hz: dict[str, float] = {}
        self.pressure_pa = math.nan
        self._imu: list[ImuSample] = []
        self._depth: list[tuple[float, float]] = []
        self._battery: list[tuple[float, float, float, float]] = []
        self._state = ArduSubState((), (), (), False, False, False)
        self._error_throttle = Throttle(1.0)

    # -- lifecycle ---------------------------------------------------------------------------
    def configure(self) -> None:
        """Find ArduSub, check ids, leftovers and failsafes, pick the mode, ask for telemetry.

        Raises:
            DeviceCheckError: A check failed (named); also JournalError, ValueError.
        """
        v = self.values
        settings = LinkSettings(
            str(v['mavlink_url']), tuple(int(c) for c in v['thruster_channels']),
            tuple(int(d) for d in v['thruster_directions']), int(v['gcs_system_id']),
            reply_timeout_s=float(v['reply_timeout_s']),
            silent_after_s=float(v['link_timeout_s']),
            restore_budget_s=float(v['restore_budget_s']))
        journal = DeviceJournal.for_device('ardusub', settings.url, str(v['journal_dir']))
        self.configured = True
        self.link = link = ArduSubLink(settings, self.curve, journal=journal)
        self.stamper = TelemetryStamper(device_time=self.device_time)
        link.stop_requested = self.stop_requested
        link.open()
        link.wait_vehicle(float(v['heartbeat_timeout_s']))
        self.gcs_param, self.gcs_id = link.check_gcs_id()
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
        self.core.configured(self.clock())
        for warning in self.warnings:
            self.log('warning', warning)
        link.on_telemetry = self._on_telemetry

    def _choose_mode(self, link: ArduSubLink) -> None:
        """Script mode when the autopilot's watchdog script is heard (and wanted)."""
        wanted = str(self.values['autopilot_watchdog'])
        timeout_ms = None if wanted == PASSTHROUGH else link.wait_watchdog_script(
            float(self.values['script_wait_s']))
        script = ScriptSettings.from_source() if timeout_ms is not None else ScriptSettings()
        mode = choose_mode(wanted, timeout_ms, script.outputs, link.settings.thruster_channels,
                           SCRIPT_NAME, float(self.values['script_wait_s']))
        if mode == SCRIPT:
            link.use_script(script)
            clashes = link.rc_input_outputs()
            if clashes:
                self.warnings.append(
                    'outputs ' + ', '.join(f'{o} (SERVO{o}_FUNCTION = {f})' for o, f in
                                           clashes.items())
                    + ' follow RC inputs 9-16, which carry the thrust PWMs in script mode')
            self.log('info', f'{SCRIPT_NAME} heard on the autopilot (timeout {timeout_ms:g} ms):'
                     ' the thrusters return to neutral without this process; no parameter is '
                     'changed')
            return
        self.log('warning', f'thrusters in RC passthrough: only this process stops them (a '
                 f'kill leaves the last PWM on); install {SCRIPT_NAME} on the autopilot '
                 '(docs/hardware.md)')

    def activate(self) -> None:
        """Passthrough mode: journal and set RCIN; then arm (neutral until a command)."""
        assert self.link is not None
        if self.link.mode == PASSTHROUGH:
            self.link.enable_passthrough()
        self.link.arm(True)
        self.core.activated()
        super().activate()

    def put_back(self) -> list[str]:
        """Neutral, disarm, release, functions back (bounded); one line says what."""
        self.active = False
        link = self.link
        if link is None or link.conn is None:
            return []
        changed = dict(link.changed_functions)
        problems = link.restore()
        done = put_back_summary(changed, link.changed_functions, problems, link.mode)
        self.log('info', f'put back: {done}')
        write_stop_report(self.name, done, problems)
        return problems

    def release(self) -> None:
        """Close the link."""
        if self.link is not None:
            self.link.close()
        self.link = None
        super().release()

    # -- the loop ----------------------------------------------------------------------------
    def read(self, now_s: float) -> None:
        """Every message pending (never waits); telemetry asked for again when due."""
        link = self.link
        self._imu, self._depth, self._battery = [], [], []
        if link is None or link.conn is None:
            self._state = ArduSubState((), (), (), False, False, False)
            return
        try:
            link.service()
        except OSError as exc:
            if self._error_throttle(now_s):
                self.log('error', f'MAVLink: {exc}')
        decision = self.core.poll(now_s, link.link_age_s())
        if decision.request_telemetry:
            link.request_telemetry(self.telemetry_rates_hz, wait=False)
        self._state = ArduSubState(tuple(self._imu), tuple(self._depth), tuple(self._battery),
                                   not decision.link_lost, decision.link_lost_changed,
                                   link.vehicle.armed)

    def command(self, thrusts_n: Sequence[float], now_s: float) -> str | None:
        """A new command (N per thruster) for the next writes; None, or why it was refused."""
        return self.core.command(thrusts_n, now_s)

    def write(self, now_s: float, commands: Sequence[float] | None = None) -> None:
        """This period's overrides: the last command, or neutral once the watchdog expired.

        Args:
            now_s: Steady time (s).
            commands: A new command (N per thruster), or None to keep the last one.
        """
        if commands is not None:
            self.command(commands, now_s)
        link = self.link
        if link is None or link.conn is None or not self.active:
            return
        thrusts_n = self.core.output(now_s)
        if thrusts_n is None:
            link.neutral()
        else:
            link.send_override(link.pwm_for(thrusts_n))
            latency_probe.note('rc')

    def state(self) -> ArduSubState:
        """The telemetry of the last read; ``fresh`` False while the vehicle is silent."""
        return self._state

    def zero_depth(self) -> str | None:
        """The present pressure becomes depth 0; what was set, or None (no reading yet)."""
        if not math.isfinite(self.pressure_pa):
            return None
        self.values['surface_pressure_pa'] = self.pressure_pa
        return f'surface pressure {self.pressure_pa:.1f} Pa: depth 0 here'

    def _on_telemetry(self, kind: str, msg: Any, kernel_arrival_s: float | None) -> None:
        arrival_s = self.local_clock()
        if kernel_arrival_s is not None and self.stamper.device_time:
            # When the datagram reached the host (the local clock's epoch when not simulated),
            # not when this period's poll read it.
            arrival_s = min(arrival_s, kernel_arrival_s)
        stamp_s = self.stamper.stamp_s(kind, msg, arrival_s)
        link = self.link
        if kind == 'RAW_IMU' and link is not None and link.vehicle.quaternion_wxyz is not None:
            w, f = bm.imu_from_raw_imu(msg)
            self._imu.append(ImuSample(stamp_s, link.vehicle.quaternion_wxyz,
                                       (w[0], w[1], w[2]), (f[0], f[1], f[2])))
        elif kind == 'SCALED_PRESSURE2':
            self.pressure_pa = msg.press_abs * 100.0
            self._depth.append((stamp_s, bm.depth_from_pressure(
                msg.press_abs, float(self.values['surface_pressure_pa']),
                float(self.values['water_density_kg_m3']), self.gravity_m_s2)))
        elif kind == 'SYS_STATUS':
            self._battery.append((stamp_s, *bm.battery_from_sys_status(msg)))

    def report(self, now_s: float) -> ComponentReport:
        """Link age, armed, mode, voltage, watchdog trips, rejected commands, overrides."""
        link = self.link
        if link is None:
            return ComponentReport(WARN, 'no vehicle', {})
        age_s = link.link_age_s()
        values = {'link_age_s': age_s, 'armed': link.vehicle.armed,
                  'mode': link.vehicle.custom_mode, 'voltage_v': link.vehicle.voltage_v,
                  'thruster_mode': link.mode, 'watchdog_trips': self.core.watchdog.trips,
                  'rejected_commands': self.core.rejected,
                  'overrides_sent': link.overrides_sent, **self.stamper.report()}
        clocks_agree = not self.stamper.device_time or self.stamper.clock.rates_agree
        level, message = self.core.health(now_s, age_s, self.active, self.warnings,
                                          clocks_agree)
        return ComponentReport(level, message, values)
