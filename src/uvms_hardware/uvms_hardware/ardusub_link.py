"""The ardusub_bridge's MAVLink side, without ROS: find and check ArduSub, passthrough, override.

pymavlink does the framing, CRC and message classes (ardupilotmega dialect, MAVLink 2, as
ArduSub 4.x speaks it). Facts from shared/robots/bluerov2_heavy_alpha5.md ("ArduSub over
MAVLink", each with its ArduPilot source). The node (``ardusub_bridge_node``) drives it with
its clock; every wait here has a timeout and services the link meanwhile (our HEARTBEAT at
1 Hz, incoming messages)::

    link = ArduSubLink(LinkSettings('udpout:127.0.0.1:14550', (1, 2, 3, 4, 5, 6, 7, 8)))
    link.open(); link.wait_vehicle(5.0); link.check_gcs_id(); warnings = link.failsafe_warnings()
    link.enable_passthrough(); link.arm(True)          # activate
    link.send_override(link.pwm_for(thrusts_n))       # each period, or link.neutral()
    link.restore()                                     # neutral, disarm, functions back, release
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from pymavlink import mavutil  # type: ignore[import-untyped]

from uvms_hardware.errors import DeviceCheckError
from uvms_hardware.t200_curve import T200Curve, clamp_pwm

MAV = mavutil.mavlink
#: SERVOn_FUNCTION of RCIN1 (ArduPilot SRV_Channel.h ``k_rcin1``); RCINk = 50 + k.
K_RCIN1 = 51
#: RC_CHANNELS_OVERRIDE values (GCS_Common.cpp): 1-8 ignore / release; 9-18 ignore.
IGNORE_1_8, RELEASE_1_8, IGNORE_9_18 = 65535, 0, 0
NEUTRAL_US = 1500
#: The GCS id parameter, then its name before ArduPilot 4.7.
GCS_ID_PARAMS = ('MAV_GCS_SYSID', 'SYSID_MYGCS')
#: Telemetry the bridge asks for: RAW_IMU (ArduPilot sends it scaled, mG and mrad/s, from the
#: first IMU, which every board has; SCALED_IMU2 exists only with a second IMU).
TELEMETRY = {'ATTITUDE_QUATERNION': MAV.MAVLINK_MSG_ID_ATTITUDE_QUATERNION,
             'RAW_IMU': MAV.MAVLINK_MSG_ID_RAW_IMU,
             'SCALED_PRESSURE2': MAV.MAVLINK_MSG_ID_SCALED_PRESSURE2,
             'SYS_STATUS': MAV.MAVLINK_MSG_ID_SYS_STATUS}


def connect(url: str, system_id: int, component_id: int) -> Any:
    """A pymavlink connection speaking MAVLink 2, ardupilotmega dialect."""
    os.environ['MAVLINK20'] = '1'  # read by pymavlink when the dialect is set
    return mavutil.mavlink_connection(url, source_system=system_id,
                                      source_component=component_id, dialect='ardupilotmega')


@dataclass(frozen=True)
class LinkSettings:
    """How to reach and drive the vehicle.

    Attributes:
        url: pymavlink URL (``udpout:HOST:PORT``, ``udpin:HOST:PORT``, ``tcp:HOST:PORT``).
        thruster_channels: RC channel / output (1-8) of thruster i.
        thruster_directions: +1/-1 per thruster (our thrust sign -> the T200's).
        gcs_system_id: Our MAVLink system id; the vehicle's GCS id must equal it.
        gcs_component_id: Our component id (MAV_COMP_ID_MISSIONPLANNER, as a GCS).
        reply_timeout_s: Wait for one parameter or command answer (s).
        retries: Tries of a parameter read or command.
        silent_after_s: No vehicle HEARTBEAT this long: restore without waiting for answers.
    """

    url: str
    thruster_channels: tuple[int, ...]
    thruster_directions: tuple[int, ...] = ()
    gcs_system_id: int = 255
    gcs_component_id: int = MAV.MAV_COMP_ID_MISSIONPLANNER
    reply_timeout_s: float = 0.5
    retries: int = 3
    silent_after_s: float = 1.0

    def __post_init__(self) -> None:
        """Check channels 1-8, distinct, and one direction of +-1 per thruster."""
        channels = self.thruster_channels
        if not channels or len(set(channels)) != len(channels) or \
                not all(1 <= c <= 8 for c in channels):
            raise ValueError(f'thruster_channels = {list(channels)}: expected distinct RC '
                             'channels 1-8 (RCIN passthrough 51..58)')
        directions = self.thruster_directions or (1,) * len(channels)
        if len(directions) != len(channels) or any(d not in (1, -1) for d in directions):
            raise ValueError(f'thruster_directions = {list(directions)}: expected +1 or -1 '
                             f'for each of the {len(channels)} thrusters')
        object.__setattr__(self, 'thruster_directions', tuple(directions))


@dataclass
class VehicleState:
    """What the vehicle last said, with the local time (s) of its arrival."""

    system_id: int = 0
    component_id: int = 0
    heartbeat_s: float = -math.inf
    armed: bool = False
    custom_mode: int = -1
    voltage_v: float = math.nan
    quaternion_wxyz: tuple[float, float, float, float] | None = None
    latest: dict[str, Any] = field(default_factory=dict)


class ArduSubLink:
    """MAVLink to one ArduSub vehicle as a GCS; `clock` gives local seconds (monotonic)."""

    def __init__(self, settings: LinkSettings, curve: T200Curve,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.settings = settings
        self.curve = curve
        self.clock = clock
        self.vehicle = VehicleState()
        self.conn: Any = None
        #: SERVOn_FUNCTION values before activate changed them: output -> value.
        self.changed_functions: dict[int, float] = {}
        self.overrides_sent = 0
        self._next_heartbeat_s = -math.inf
        #: Telemetry callback: called with each message of TELEMETRY as it arrives.
        self.on_telemetry: Callable[[str, Any], None] | None = None
        #: True ends any wait at once (SIGINT/SIGTERM of the bridge while it waits).
        self.stop_requested: Callable[[], bool] = lambda: False

    # -- link --------------------------------------------------------------------------
    def open(self) -> None:
        """Open the connection and send our first HEARTBEAT (a udpout peer learns us)."""
        s = self.settings
        self.conn = connect(s.url, s.gcs_system_id, s.gcs_component_id)
        self.service()

    def close(self) -> None:
        """Close the connection."""
        if self.conn is not None:
            self.conn.close()
            self.conn = None

    def link_age_s(self) -> float:
        """Seconds since the vehicle's last HEARTBEAT (inf before the first)."""
        return self.clock() - self.vehicle.heartbeat_s

    def service(self) -> list[Any]:
        """Send our HEARTBEAT when due (1 Hz, as a GCS); take every pending message."""
        now_s = self.clock()
        if now_s >= self._next_heartbeat_s:
            self._next_heartbeat_s = now_s + 1.0
            self.conn.mav.heartbeat_send(MAV.MAV_TYPE_GCS, MAV.MAV_AUTOPILOT_INVALID, 0, 0,
                                         MAV.MAV_STATE_ACTIVE)
        received = []
        while (msg := self.conn.recv_match(blocking=False)) is not None:
            if msg.get_type() != 'BAD_DATA':
                self._take(msg, now_s)
                received.append(msg)
        return received

    def _take(self, msg: Any, now_s: float) -> None:
        kind, v = msg.get_type(), self.vehicle
        if kind == 'HEARTBEAT':
            if msg.type == MAV.MAV_TYPE_SUBMARINE and \
                    msg.autopilot == MAV.MAV_AUTOPILOT_ARDUPILOTMEGA:
                v.system_id, v.component_id = msg.get_srcSystem(), msg.get_srcComponent()
                v.heartbeat_s = now_s
                v.armed = bool(msg.base_mode & MAV.MAV_MODE_FLAG_SAFETY_ARMED)
                v.custom_mode = msg.custom_mode
            return
        if v.system_id and msg.get_srcSystem() != v.system_id:
            return
        if kind == 'SYS_STATUS' and msg.voltage_battery not in (0, 65535):
            v.voltage_v = msg.voltage_battery / 1000.0
        elif kind == 'ATTITUDE_QUATERNION':
            v.quaternion_wxyz = (msg.q1, msg.q2, msg.q3, msg.q4)
        if kind in TELEMETRY:
            v.latest[kind] = msg
            if self.on_telemetry is not None:
                self.on_telemetry(kind, msg)

    def _wait(self, match: Callable[[Any], bool], timeout_s: float,
              interruptible: bool = False) -> Any:
        """The first message that matches, or None after ``timeout_s``.

        ``interruptible``: a stop request ends the wait (finding the vehicle at configure);
        the restore's waits at a stop run to their end.
        """
        end_s = self.clock() + timeout_s
        while self.clock() < end_s:
            if interruptible and self.stop_requested():
                raise DeviceCheckError(f'{self.settings.url}: stopped (a signal) while waiting '
                                       'for the vehicle')
            for msg in self.service():
                if match(msg):
                    return msg
            time.sleep(0.002)
        return None

    # -- configure ---------------------------------------------------------------------
    def wait_vehicle(self, timeout_s: float) -> None:
        """Wait for ArduSub's HEARTBEAT (MAV_TYPE_SUBMARINE, ArduPilot).

        Raises:
            DeviceCheckError: none within ``timeout_s``, naming what answered instead.
        """
        others: set[tuple[int, int, int]] = set()

        def is_sub(msg: Any) -> bool:
            if msg.get_type() == 'HEARTBEAT' and msg.type != MAV.MAV_TYPE_GCS:
                others.add((msg.get_srcSystem(), msg.type, msg.autopilot))
            return bool(msg.get_type() == 'HEARTBEAT' and self.vehicle.system_id and
                        msg.get_srcSystem() == self.vehicle.system_id)

        if self._wait(is_sub, timeout_s, interruptible=True) is None:
            url = self.settings.url
            if others:
                seen = ', '.join(f'system {s} type {t} autopilot {a}' for s, t, a in others)
                raise DeviceCheckError(
                    f'{url}: no ArduSub: heartbeats from {seen}, none of MAV_TYPE_SUBMARINE '
                    f'({MAV.MAV_TYPE_SUBMARINE}) with ArduPilot '
                    f'({MAV.MAV_AUTOPILOT_ARDUPILOTMEGA})')
            raise DeviceCheckError(f'{url}: no vehicle HEARTBEAT within {timeout_s:g} s')

    def read_param(self, name: str) -> float | None:
        """A vehicle parameter by PARAM_REQUEST_READ; None when not answered."""
        v = self.vehicle
        for _ in range(self.settings.retries):
            self.conn.mav.param_request_read_send(v.system_id, v.component_id,
                                                  name.encode(), -1)
            msg = self._wait(lambda m: m.get_type() == 'PARAM_VALUE' and m.param_id == name,
                             self.settings.reply_timeout_s)
            if msg is not None:
                return float(msg.param_value)
        return None

    def set_param(self, name: str, value: float, param_type: int = MAV.MAV_PARAM_TYPE_INT16
                  ) -> float | None:
        """PARAM_SET, then the value read back (None when not answered)."""
        v = self.vehicle
        self.conn.mav.param_set_send(v.system_id, v.component_id, name.encode(), value,
                                     param_type)
        self._wait(lambda m: m.get_type() == 'PARAM_VALUE' and m.param_id == name,
                   self.settings.reply_timeout_s)
        return self.read_param(name)

    def check_gcs_id(self) -> tuple[str, int]:
        """The vehicle's GCS id parameter (``MAV_GCS_SYSID``, else ``SYSID_MYGCS``) equals ours.

        Raises:
            DeviceCheckError: a mismatch (naming both numbers) or neither parameter answered.
        """
        ours = self.settings.gcs_system_id
        for name in GCS_ID_PARAMS:
            value = self.read_param(name)
            if value is None:
                continue
            if int(value) != ours:
                raise DeviceCheckError(
                    f'the vehicle obeys RC overrides only from GCS system id {int(value)} '
                    f'({name}), ours is {ours}: set {name} = {ours} or gcs_system_id = '
                    f'{int(value)}')
            return name, int(value)
        raise DeviceCheckError(f'neither {" nor ".join(GCS_ID_PARAMS)} answered: cannot '
                               'check that the vehicle obeys our RC overrides')

    def failsafe_warnings(self) -> list[str]:
        """Where a lost link is unprotected: FS_GCS_ENABLE, FS_PILOT_INPUT, RC_OVERRIDE_TIME."""
        fs_gcs, fs_pilot = self.read_param('FS_GCS_ENABLE'), self.read_param('FS_PILOT_INPUT')
        override_s = self.read_param('RC_OVERRIDE_TIME')
        warnings = []
        if fs_gcs is None or fs_gcs == 0:
            warnings.append(f'FS_GCS_ENABLE = {fs_gcs}: no GCS failsafe on a lost link')
        if fs_pilot is None or fs_pilot == 0:
            warnings.append(f'FS_PILOT_INPUT = {fs_pilot}: no pilot-input failsafe')
        if override_s is None or override_s < 0:
            warnings.append(f'RC_OVERRIDE_TIME = {override_s}: overrides never expire')
        return warnings

    def request_telemetry(self, rates_hz: dict[str, float], wait: bool = True) -> None:
        """MAV_CMD_SET_MESSAGE_INTERVAL (511) for each message (name -> Hz; 0 stops).

        ``wait`` False sends each once without waiting for its COMMAND_ACK (from a loop that
        must not stall).
        """
        v = self.vehicle
        for name, rate_hz in rates_hz.items():
            interval_us = 1e6 / rate_hz if rate_hz > 0 else -1.0
            if wait:
                self.command(MAV.MAV_CMD_SET_MESSAGE_INTERVAL, TELEMETRY[name], interval_us)
            else:
                self.conn.mav.command_long_send(v.system_id, v.component_id,
                                                MAV.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                                TELEMETRY[name], interval_us, 0, 0, 0, 0, 0)

    def command(self, command: int, *params: float) -> int | None:
        """COMMAND_LONG; the COMMAND_ACK's result (None when not answered)."""
        v, padded = self.vehicle, (list(params) + [0.0] * 7)[:7]
        for confirmation in range(self.settings.retries):
            self.conn.mav.command_long_send(v.system_id, v.component_id, command,
                                            confirmation, *padded)
            ack = self._wait(lambda m: m.get_type() == 'COMMAND_ACK' and m.command == command,
                             self.settings.reply_timeout_s)
            if ack is not None:
                return int(ack.result)
        return None

    # -- activate / deactivate ---------------------------------------------------------
    def enable_passthrough(self) -> None:
        """Remember each thruster output's SERVOn_FUNCTION, set it to RCIN of its channel.

        Raises:
            DeviceCheckError: an output that does not read back as set, naming it.
        """
        for channel in self.settings.thruster_channels:
            name = f'SERVO{channel}_FUNCTION'
            before = self.read_param(name)
            if before is None:
                raise DeviceCheckError(f'{name} not answered: cannot set passthrough')
            wanted = float(K_RCIN1 + channel - 1)
            if before == wanted:
                continue
            self.changed_functions.setdefault(channel, before)
            after = self.set_param(name, wanted)
            if after != wanted:
                raise DeviceCheckError(f'{name} reads {after} after setting it to '
                                       f'{int(wanted)} (RCIN{channel}): channel {channel} is '
                                       'not in passthrough')

    def arm(self, armed: bool) -> None:
        """MAV_CMD_COMPONENT_ARM_DISARM (400), param1 1 or 0.

        Raises:
            DeviceCheckError: refused or not answered.
        """
        result = self.command(MAV.MAV_CMD_COMPONENT_ARM_DISARM, 1.0 if armed else 0.0)
        if result != MAV.MAV_RESULT_ACCEPTED:
            word = 'arm' if armed else 'disarm'
            raise DeviceCheckError(f'{word}: MAV_CMD_COMPONENT_ARM_DISARM answered {result}')

    def restore(self) -> list[str]:
        """Neutral on every thruster, disarm, functions back, release; the problems met.

        Every step is tried even when one fails (a vehicle gone silent); what could not be
        done is returned, one line each, for the node to log.
        """
        problems: list[str] = []
        if self.conn is None:
            return ['no connection']
        if self.link_age_s() > self.settings.silent_after_s:
            return self._restore_blind()
        for _ in range(3):
            self.neutral()
        try:
            self.arm(False)
        except DeviceCheckError as exc:
            problems.append(str(exc))
            if self.link_age_s() > self.settings.silent_after_s:
                return problems + self._restore_blind()
        for channel, value in list(self.changed_functions.items()):
            if self.set_param(f'SERVO{channel}_FUNCTION', value) == value:
                del self.changed_functions[channel]
            else:
                problems.append(f'SERVO{channel}_FUNCTION not restored to {value:g}')
        self.release()
        return problems

    def _restore_blind(self) -> list[str]:
        """Restore without waiting for answers: the vehicle has gone silent."""
        v = self.vehicle
        self.neutral()
        self.conn.mav.command_long_send(v.system_id, v.component_id,
                                        MAV.MAV_CMD_COMPONENT_ARM_DISARM, 0, *[0.0] * 7)
        for channel, value in self.changed_functions.items():
            self.conn.mav.param_set_send(v.system_id, v.component_id,
                                         f'SERVO{channel}_FUNCTION'.encode(), value,
                                         MAV.MAV_PARAM_TYPE_INT16)
        self.release()
        return [f'vehicle silent for {self.link_age_s():.1f} s: neutral, disarm, '
                f'SERVOn_FUNCTION of outputs {sorted(self.changed_functions)} and release '
                'sent without confirmation; check the vehicle']

    # -- the running path --------------------------------------------------------------
    def pwm_for(self, thrusts_n: Sequence[float]) -> dict[int, int]:
        """Channel -> PWM (µs) of each thruster's thrust (N), direction applied here once.

        Raises:
            ValueError: not one thrust per thruster.
        """
        s, voltage_v = self.settings, self.vehicle.voltage_v
        if len(thrusts_n) != len(s.thruster_channels):
            raise ValueError(f'{len(thrusts_n)} thrusts for {len(s.thruster_channels)} '
                             'thrusters')
        return {channel: clamp_pwm(self.curve.pwm_from_thrust(direction * thrust, voltage_v),
                                   self.curve.min_pwm_us, self.curve.max_pwm_us)
                for channel, direction, thrust in zip(
                    s.thruster_channels, s.thruster_directions, thrusts_n, strict=True)}

    def send_override(self, pwm_by_channel: dict[int, int], others_1_8: int = IGNORE_1_8
                      ) -> None:
        """RC_CHANNELS_OVERRIDE to the vehicle: our channels, ``others_1_8`` on 1-8, 0 on 9-18."""
        values = [pwm_by_channel.get(k, others_1_8) for k in range(1, 9)] + [IGNORE_9_18] * 10
        v = self.vehicle
        self.conn.mav.rc_channels_override_send(v.system_id, v.component_id, *values)
        self.overrides_sent += 1

    def neutral(self) -> None:
        """1500 µs on every thruster channel."""
        self.send_override({c: NEUTRAL_US for c in self.settings.thruster_channels})

    def release(self) -> None:
        """Give channels 1-8 back (0 = release)."""
        self.send_override({}, RELEASE_1_8)
