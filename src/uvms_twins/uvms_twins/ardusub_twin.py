"""An ArduSub twin: speaks MAVLink (pymavlink, ardupilotmega dialect) as ArduSub does.

No ROS. It follows ArduPilot's sources and docs for what a companion computer uses, not our
bridge; each behaviour names its source:

- HEARTBEAT at 1 Hz: MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_MODE_FLAG_SAFETY_ARMED
  while armed, custom_mode 19 = MANUAL (``ArduSub/mode.h``, ``GCS_MAVLink_Sub.cpp``).
- PARAM_REQUEST_READ / PARAM_SET answered with PARAM_VALUE; an unknown name is not answered
  (``GCS_Param.cpp``). The GCS id parameter is ``MAV_GCS_SYSID`` or, for older firmware,
  ``SYSID_MYGCS`` (``gcs_param``), default 255; FS_GCS_ENABLE 2, FS_PILOT_INPUT 2,
  RC_OVERRIDE_TIME 3.0, SERVOn_FUNCTION 33..40 (Motor1..8) on outputs 1..8
  (``ArduSub/Parameters.cpp``, ``RC_Channels_VarInfo.h``, ``SRV_Channel.h``).
- COMMAND_LONG MAV_CMD_COMPONENT_ARM_DISARM (param1 1/0) and MAV_CMD_SET_MESSAGE_INTERVAL
  (param1 message id, param2 interval µs; -1 stops) answered with COMMAND_ACK addressed to the
  sender (target system and component = the command's source, ``GCS_Common.cpp``
  handle_command_long).
- RC_CHANNELS_OVERRIDE obeyed only from the GCS system id (``GCS_Common.cpp``): channels 1-8,
  65535 ignore (the old override stays), 0 release; 9-18, 0 or 65535 ignore, 65534 release.
  Each channel's override expires ``RC_OVERRIDE_TIME`` s after it was last set (-1 never;
  0 disables overrides).
- RC inputs read at 50 Hz: ArduSub's ``fifty_hz_loop`` calls ``rc().read_input()`` (the
  scheduler table of ``ArduSub/ArduSub.cpp``), which takes each channel's override in force
  into its input (``RC_Channel::update``); an output that follows an RC input, and the
  script's ``rc:get_pwm``, change only at those reads, whatever rate the overrides come at.
- Outputs: SERVOn_FUNCTION 51..66 (RCIN1..16, ``k_rcin1`` = 51) outputs RC channel k; 1
  (RCPassThru) channel n; 33..40 (Motor1..8) neutral 1500 (no pilot input is modelled);
  0 no pulse (0). A passthrough output follows its RC channel's input, which keeps the last
  override once it expired or was released when no receiver is fitted (``RC_Channel::update``
  sets ``radio_in`` only from an override or a receiver): the twin keeps the last value.
  Before any override it outputs 0.
- ``watchdog_script=True``: ``uvms_thruster_watchdog.lua`` installed and running, modelled by
  ``uvms_hardware.ardusub_watchdog.WatchdogScript`` with the settings read from the script:
  every PERIOD_MS it may set outputs with ``set_output_pwm_chan_timeout`` (forced over a
  Motor function until the timeout; a passthrough output ignores it, as ``SRV_Channel::
  output_ch`` overwrites it from the RC input), and it announces NAMED_VALUE_FLOAT 'UVMS_WD'
  once a second. ``stop_script()`` makes it die (its overrides then expire).
- Telemetry at the requested intervals, from the plant, timed on the twin's boot clock as
  ArduPilot's (``time_boot_ms``; RAW_IMU ``time_usec`` in µs): ATTITUDE_QUATERNION (body FRD
  in NED), RAW_IMU (ArduPilot fills it scaled: mG, mrad/s; ``GCS_Common.cpp`` send_raw_imu),
  SCALED_PRESSURE2 (the Bar30 is ArduSub's second barometer; hPa), SYS_STATUS (mV).

Not modelled: failsafes (FS_GCS, FS_PILOT), arming checks, modes other than MANUAL, stream
rates by SRx_ parameters. Listens on ``udpin:127.0.0.1:PORT`` (0: a free port).
"""

from __future__ import annotations

import argparse
import math
import os
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from pymavlink import mavutil  # type: ignore[import-untyped]
from uvms_hardware.address import LOOPBACK
from uvms_hardware.ardusub_watchdog import ANNOUNCE_NAME, ScriptSettings, WatchdogScript

from uvms_twins.periodic_task import next_run_s

MAV = mavutil.mavlink
#: ArduSub's custom_mode of MANUAL (ArduSub/mode.h).
MODE_MANUAL = 19
#: SERVOn_FUNCTION of RCIN1 (ArduPilot SRV_Channel.h ``k_rcin1``); RCIN16 is 66.
K_RCIN1 = 51
#: SERVOn_FUNCTION of Motor1 (``k_motor1``); Motor8 is 40.
K_MOTOR1 = 33
#: Rate at which ArduSub reads its RC inputs, overrides included (Hz): ``fifty_hz_loop`` ->
#: ``rc().read_input()``, scheduled at 50 Hz in ``ArduSub/ArduSub.cpp``.
RC_READ_HZ = 50.0
#: MAV_PARAM_TYPE of each kind of parameter, as ArduPilot declares them.
INT8, INT16, REAL32 = MAV.MAV_PARAM_TYPE_INT8, MAV.MAV_PARAM_TYPE_INT16, MAV.MAV_PARAM_TYPE_REAL32
TELEMETRY_IDS = (MAV.MAVLINK_MSG_ID_ATTITUDE_QUATERNION, MAV.MAVLINK_MSG_ID_RAW_IMU,
                 MAV.MAVLINK_MSG_ID_SCALED_PRESSURE2, MAV.MAVLINK_MSG_ID_SYS_STATUS)


def default_parameters(gcs_param: str = 'MAV_GCS_SYSID') -> dict[str, tuple[float, int]]:
    """ArduSub's defaults of the parameters the twin knows: name -> (value, MAV_PARAM_TYPE)."""
    table: dict[str, tuple[float, int]] = {
        gcs_param: (255.0, INT16), 'FS_GCS_ENABLE': (2.0, INT8), 'FS_GCS_TIMEOUT': (5.0, REAL32),
        'FS_PILOT_INPUT': (2.0, INT8), 'FS_PILOT_TIMEOUT': (3.0, REAL32),
        'RC_OVERRIDE_TIME': (3.0, REAL32)}
    for n in range(1, 17):
        table[f'SERVO{n}_FUNCTION'] = (float(K_MOTOR1 + n - 1) if n <= 8 else 0.0, INT16)
    return table


@dataclass
class Plant:
    """What the sensors measure: attitude, rates, specific force, pressure, battery."""

    quaternion_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    rates_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    specific_force_m_s2: tuple[float, float, float] = (0.0, 0.0, -9.80665)
    pressure_pa: float = 101325.0
    voltage_v: float = 16.0


@dataclass
class OverrideRecord:
    """One RC_CHANNELS_OVERRIDE as received (decoded by pymavlink), for the tests."""

    t_s: float
    src_system: int
    src_component: int
    target_system: int
    target_component: int
    channels: tuple[int, ...]
    obeyed: bool


@dataclass
class _Channel:
    value_us: int = 0
    set_s: float = -math.inf
    #: The RC input (``radio_in``) as of the last RC read: the override in force then, else
    #: the last one (no receiver fitted): what a passthrough output keeps (unknown, unsafe).
    last_us: int = 0


@dataclass
class TwinState:
    """Everything the twin's thread changes, under one lock."""

    armed: bool = False
    channels: dict[int, _Channel] = field(default_factory=lambda: {k: _Channel()
                                                                    for k in range(1, 19)})
    intervals_s: dict[int, float] = field(default_factory=dict)
    due_s: dict[int, float] = field(default_factory=dict)
    overrides: deque[OverrideRecord] = field(default_factory=lambda: deque(maxlen=20000))
    param_sets: list[tuple[str, float]] = field(default_factory=list)
    commands: list[tuple[int, tuple[float, ...]]] = field(default_factory=list)
    #: The watchdog script's output overrides: output -> (PWM, local time it expires, s).
    script_overrides: dict[int, tuple[int, float]] = field(default_factory=dict)
    #: When the RC inputs were read (monotonic s), the latest last.
    rc_reads: deque[float] = field(default_factory=lambda: deque(maxlen=2000))
    #: Telemetry sent: (message name, wall time of its time field, s since the epoch).
    sent: deque[tuple[str, float]] = field(default_factory=lambda: deque(maxlen=20000))


class ArduSubTwin:
    """The twin: a thread serving MAVLink on ``udpin:host:port``; plant API in plain Python."""

    def __init__(self, port: int = 0, host: str = LOOPBACK, system_id: int = 1,
                 component_id: int = 1, gcs_param: str = 'MAV_GCS_SYSID',
                 parameters: dict[str, float] | None = None,
                 watchdog_script: bool = False, rc_read_hz: float = RC_READ_HZ) -> None:
        self.gcs_param = gcs_param
        self.params = default_parameters(gcs_param)
        for name, value in (parameters or {}).items():
            self.params[name] = (float(value), self.params.get(name, (0.0, REAL32))[1])
        os.environ['MAVLINK20'] = '1'  # ArduSub 4.x speaks MAVLink 2; read with the dialect
        self.conn: Any = mavutil.mavlink_connection(
            f'udpin:{host}:{port}', source_system=system_id, source_component=component_id,
            dialect='ardupilotmega')
        self.address: tuple[str, int] = self.conn.port.getsockname()[:2]
        self.system_id, self.component_id = system_id, component_id
        self.plant = Plant()
        self.state = TwinState()
        #: True: the twin neither answers nor sends (a vehicle that stopped answering).
        self.silent = False
        #: The watchdog script (None: not installed); it runs while ``script_running``.
        self.script = WatchdogScript(ScriptSettings.from_source()) if watchdog_script else None
        self.script_running = watchdog_script
        self._next_script_s = 0.0
        self._rc_period_s = 1.0 / rc_read_hz
        self._next_rc_s = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._boot_s = time.monotonic()
        self._thread = threading.Thread(target=self._run, name='ardusub twin', daemon=True)

    def start(self) -> ArduSubTwin:
        """Start serving; returns self."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread and close the socket."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.conn.close()

    def __enter__(self) -> ArduSubTwin:
        """Start."""
        return self.start()

    def __exit__(self, *exc: object) -> None:
        """Stop."""
        self.stop()

    @property
    def url(self) -> str:
        """The pymavlink URL a bridge uses to reach the twin."""
        return f'udpout:{self.address[0]}:{self.address[1]}'

    # -- plant API ---------------------------------------------------------------------
    def set_plant_state(self, quaternion_wxyz: tuple[float, float, float, float] | None = None,
                        rates_rad_s: tuple[float, float, float] | None = None,
                        specific_force_m_s2: tuple[float, float, float] | None = None,
                        pressure_pa: float | None = None, depth_m: float | None = None,
                        voltage_v: float | None = None, water_density_kg_m3: float = 1000.0
                        ) -> None:
        """Set what the sensors measure (None keeps a value); depth_m sets the pressure."""
        with self._lock:
            p = self.plant
            p.quaternion_wxyz = quaternion_wxyz or p.quaternion_wxyz
            p.rates_rad_s = rates_rad_s or p.rates_rad_s
            p.specific_force_m_s2 = specific_force_m_s2 or p.specific_force_m_s2
            if depth_m is not None:
                p.pressure_pa = 101325.0 + water_density_kg_m3 * 9.80665 * depth_m
            if pressure_pa is not None:
                p.pressure_pa = pressure_pa
            if voltage_v is not None:
                p.voltage_v = voltage_v

    def servo_outputs_us(self) -> list[int]:
        """PWM (µs) of outputs 1..16 as the module description says (0: no pulse)."""
        with self._lock:
            return [self._output(n) for n in range(1, 17)]

    def param(self, name: str) -> float:
        """A parameter's value now."""
        with self._lock:
            return self.params[name][0]

    def overrides(self) -> list[OverrideRecord]:
        """RC_CHANNELS_OVERRIDE messages received so far (oldest first)."""
        with self._lock:
            return list(self.state.overrides)

    def rc_read_times(self) -> list[float]:
        """When the RC inputs were read (monotonic s), oldest first (at most the last 2000)."""
        with self._lock:
            return list(self.state.rc_reads)

    @property
    def armed(self) -> bool:
        """The vehicle's armed state."""
        with self._lock:
            return self.state.armed

    def stop_script(self) -> None:
        """The watchdog script dies (an error, SCR_ENABLE 0): its overrides run out."""
        with self._lock:
            self.script_running = False

    def _output(self, n: int, now_s: float | None = None) -> int:
        function = int(self.params[f'SERVO{n}_FUNCTION'][0])
        if K_RCIN1 <= function <= K_RCIN1 + 15:
            return self.state.channels[function - K_RCIN1 + 1].last_us
        if function == 1:
            return self.state.channels[n].last_us
        now_s = time.monotonic() if now_s is None else now_s
        forced = self.state.script_overrides.get(n)
        if forced is not None and now_s < forced[1]:
            return forced[0]
        if K_MOTOR1 <= function <= K_MOTOR1 + 7:
            return 1500  # disarmed: AP_Motors6DOF neutral; armed: no pilot input modelled
        return 0

    def active_override_us(self, channel: int, now_s: float | None = None) -> int:
        """The override in force on RC channel ``channel`` (0: none, expired or released)."""
        now_s = time.monotonic() if now_s is None else now_s
        with self._lock:
            ch = self.state.channels[channel]
            timeout_s = self.params['RC_OVERRIDE_TIME'][0]
            if ch.value_us == 0 or timeout_s == 0.0:
                return 0
            if timeout_s > 0.0 and now_s - ch.set_s > timeout_s:
                return 0
            return ch.value_us

    # -- the MAVLink side --------------------------------------------------------------
    def _run(self) -> None:
        next_heartbeat_s = 0.0
        while not self._stop.is_set():
            msg = self.conn.recv_match(blocking=True, timeout=0.002)
            now_s = time.monotonic()
            if self.silent:
                continue
            if msg is not None and msg.get_type() != 'BAD_DATA':
                self._handle(msg, now_s)
            if now_s >= self._next_rc_s:
                self._next_rc_s = next_run_s(self._next_rc_s, now_s, self._rc_period_s)
                self._read_rc(now_s)
            if now_s >= next_heartbeat_s:
                next_heartbeat_s = now_s + 1.0
                self._heartbeat()
            self._telemetry(now_s)
            self._run_script(now_s)

    def _read_rc(self, now_s: float) -> None:
        """ArduSub's RC read: each channel's override in force becomes its input."""
        with self._lock:
            timeout_s = self.params['RC_OVERRIDE_TIME'][0]
            for ch in self.state.channels.values():
                expired = timeout_s > 0.0 and now_s - ch.set_s > timeout_s
                if ch.value_us != 0 and timeout_s != 0.0 and not expired:
                    ch.last_us = ch.value_us
            self.state.rc_reads.append(now_s)

    def _run_script(self, now_s: float) -> None:
        script = self.script
        if script is None or now_s < self._next_script_s:
            return
        with self._lock:
            if not self.script_running:
                return
            settings = script.settings
            self._next_script_s = now_s + settings.period_ms * 1e-3
            now_ms = (now_s - self._boot_s) * 1000.0
            rc_pwm = {k: ch.last_us for k, ch in self.state.channels.items()}
            for output, pwm in script.update(now_ms, self.state.armed, rc_pwm).items():
                self.state.script_overrides[output] = (pwm, now_s + settings.timeout_ms * 1e-3)
            announce = script.announce_due(now_ms)
        if announce:
            self.conn.mav.named_value_float_send(int(now_ms) & 0xFFFFFFFF,
                                                 ANNOUNCE_NAME.encode(),
                                                 float(settings.timeout_ms))

    def _heartbeat(self) -> None:
        with self._lock:
            armed = self.state.armed
        base_mode = MAV.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
            MAV.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
        self.conn.mav.heartbeat_send(
            MAV.MAV_TYPE_SUBMARINE, MAV.MAV_AUTOPILOT_ARDUPILOTMEGA, base_mode, MODE_MANUAL,
            MAV.MAV_STATE_ACTIVE if armed else MAV.MAV_STATE_STANDBY)

    def _handle(self, msg: Any, now_s: float) -> None:
        kind = msg.get_type()
        if kind == 'PARAM_REQUEST_READ':
            self._send_param(msg.param_id)
        elif kind == 'PARAM_SET':
            with self._lock:
                known = msg.param_id in self.params
                if known:
                    self.params[msg.param_id] = (float(msg.param_value),
                                                 self.params[msg.param_id][1])
                    self.state.param_sets.append((msg.param_id, float(msg.param_value)))
            if known:
                self._send_param(msg.param_id)
        elif kind == 'COMMAND_LONG':
            self._command(msg)
        elif kind == 'RC_CHANNELS_OVERRIDE':
            self._override(msg, now_s)

    def _send_param(self, name: str) -> None:
        with self._lock:
            if name not in self.params:
                return  # ArduPilot does not answer a name it does not know
            value, kind = self.params[name]
            index, count = list(self.params).index(name), len(self.params)
        self.conn.mav.param_value_send(name.encode(), value, kind, count, index)

    def _command(self, msg: Any) -> None:
        result = MAV.MAV_RESULT_ACCEPTED
        with self._lock:
            self.state.commands.append((msg.command, (msg.param1, msg.param2)))
            if msg.command == MAV.MAV_CMD_COMPONENT_ARM_DISARM:
                self.state.armed = msg.param1 == 1.0
            elif msg.command == MAV.MAV_CMD_SET_MESSAGE_INTERVAL:
                message_id, interval_us = int(msg.param1), msg.param2
                if interval_us < 0:
                    self.state.intervals_s.pop(message_id, None)
                elif message_id in TELEMETRY_IDS:
                    self.state.intervals_s[message_id] = max(interval_us, 1000.0) * 1e-6
                else:
                    result = MAV.MAV_RESULT_UNSUPPORTED
            else:
                result = MAV.MAV_RESULT_UNSUPPORTED
        self.conn.mav.command_ack_send(msg.command, result, 0, 0, msg.get_srcSystem(),
                                       msg.get_srcComponent())

    def _override(self, msg: Any, now_s: float) -> None:
        values = tuple(int(getattr(msg, f'chan{k}_raw')) for k in range(1, 19))
        with self._lock:
            gcs_id = int(self.params[self.gcs_param][0])
            obeyed = (msg.get_srcSystem() == gcs_id and msg.target_system == self.system_id
                      and self.params['RC_OVERRIDE_TIME'][0] != 0.0)
            self.state.overrides.append(OverrideRecord(
                now_s, msg.get_srcSystem(), msg.get_srcComponent(), msg.target_system,
                msg.target_component, values, obeyed))
            if not obeyed:
                return
            for k, value in enumerate(values, start=1):
                ch = self.state.channels[k]
                if value == 65535 or (k > 8 and value == 0):
                    continue  # ignore: the old override stays
                if value == 0 or (k > 8 and value == 65534):
                    ch.value_us = 0  # release (a passthrough output keeps last_us: unknown)
                    continue
                ch.value_us, ch.set_s = value, now_s  # the input takes it at the RC read

    def _telemetry(self, now_s: float) -> None:
        with self._lock:
            due = [m for m, interval in self.state.intervals_s.items()
                   if now_s >= self.state.due_s.get(m, 0.0)]
            for m in due:
                self.state.due_s[m] = now_s + self.state.intervals_s[m]
            plant = Plant(**vars(self.plant))
        # The messages' time and its wall time read together: what a test compares stamps with.
        wall_s, boot_us = time.time(), int((time.monotonic() - self._boot_s) * 1e6)
        boot_ms = (boot_us // 1000) & 0xFFFFFFFF
        mav = self.conn.mav
        for m in due:
            if m == MAV.MAVLINK_MSG_ID_ATTITUDE_QUATERNION:
                mav.attitude_quaternion_send(boot_ms, *plant.quaternion_wxyz, *plant.rates_rad_s)
            elif m == MAV.MAVLINK_MSG_ID_RAW_IMU:
                acc = [round(a / 9.80665 * 1000.0) for a in plant.specific_force_m_s2]
                gyro = [round(w * 1000.0) for w in plant.rates_rad_s]
                mav.raw_imu_send(boot_us, *acc, *gyro, 0, 0, 0)  # AP_HAL::micros64()
            elif m == MAV.MAVLINK_MSG_ID_SCALED_PRESSURE2:
                mav.scaled_pressure2_send(boot_ms, plant.pressure_pa / 100.0, 0.0, 1500)
            elif m == MAV.MAVLINK_MSG_ID_SYS_STATUS:
                mav.sys_status_send(0, 0, 0, 0, int(plant.voltage_v * 1000.0), -1, -1,
                                    0, 0, 0, 0, 0, 0)
            with self._lock:
                self.state.sent.append((MAV.mavlink_map[m].msgname, wall_s))

    def sent_times(self, name: str) -> list[float]:
        """Wall times (s since the epoch) of the times in each message ``name`` sent."""
        with self._lock:
            return [t for kind, t in self.state.sent if kind == name]


def main(argv: list[str] | None = None) -> None:
    """Run the twin on 127.0.0.1 until interrupted: ``python -m ...ardusub_twin --port N``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--port', type=int, default=14550)
    parser.add_argument('--gcs-param', default='MAV_GCS_SYSID')
    parser.add_argument('--watchdog-script', action='store_true',
                        help='model uvms_thruster_watchdog.lua installed on the autopilot')
    args = parser.parse_args(argv)
    with ArduSubTwin(port=args.port, gcs_param=args.gcs_param,
                     watchdog_script=args.watchdog_script) as twin:
        print(f'ardusub twin on udpin:{twin.address[0]}:{twin.address[1]}', flush=True)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass


if __name__ == '__main__':
    main()
