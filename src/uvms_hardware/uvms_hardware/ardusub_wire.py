"""ArduSub's MAVLink wire, without ROS and without waiting: messages in, overrides out.

The part of the ardusub_bridge's MAVLink side that a control loop may call every period: it
never blocks. `ArduSubWire.service` sends our 1 Hz HEARTBEAT when due and takes every message
pending (the vehicle's state, its telemetry, other ground stations heard); `send_override`,
`neutral` and `release` write RC_CHANNELS_OVERRIDE. The conversations that wait for an answer
(finding and checking the vehicle, passthrough, arming, the restore) are `ardusub_link`'s.
pymavlink does the framing, CRC and message classes (ardupilotmega dialect, MAVLink 2). Facts
from shared/robots/bluerov2_heavy_alpha5.md ("ArduSub over MAVLink", each with its source).

Answers are taken only from the vehicle: PARAM_VALUE and COMMAND_ACK must come from its system
and component, and a COMMAND_ACK addressed to another system or component (its MAVLink 2
target fields, 0 when not filled) is someone else's (`from_vehicle`, `addressed_to_us`).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from pymavlink import mavutil  # type: ignore[import-untyped]

from uvms_hardware.ardusub_watchdog import ANNOUNCE_NAME, ScriptSettings, toggle_encode
from uvms_hardware.datagram_arrival import DatagramArrival
from uvms_hardware.device_journal import DeviceJournal
from uvms_hardware.t200_curve import T200Curve, clamp_pwm

MAV = mavutil.mavlink
#: SERVOn_FUNCTION of RCIN1 (ArduPilot SRV_Channel.h ``k_rcin1``); RCINk = 50 + k.
K_RCIN1 = 51
#: SERVOn_FUNCTION of Motor1 (``k_motor1``): the firmware's default of output n is 32 + n.
K_MOTOR1 = 33
#: RC_CHANNELS_OVERRIDE values (GCS_Common.cpp): 1-8 ignore / release; 9-18 ignore / release.
IGNORE_1_8, RELEASE_1_8, IGNORE_9_18, RELEASE_9_18 = 65535, 0, 0, 65534
NEUTRAL_US = 1500
#: ArduSub's pilot inputs (1 pitch, 2 roll, 3 throttle, 4 yaw, 5 forward, 6 lateral).
PILOT_CHANNELS = 6
#: The GCS id parameter, then its name before ArduPilot 4.7.
GCS_ID_PARAMS = ('MAV_GCS_SYSID', 'SYSID_MYGCS')
#: Telemetry the bridge asks for: RAW_IMU (ArduPilot sends it scaled, mG and mrad/s, from the
#: first IMU, which every board has; SCALED_IMU2 exists only with a second IMU).
TELEMETRY = {'ATTITUDE_QUATERNION': MAV.MAVLINK_MSG_ID_ATTITUDE_QUATERNION,
             'RAW_IMU': MAV.MAVLINK_MSG_ID_RAW_IMU,
             'SCALED_PRESSURE2': MAV.MAVLINK_MSG_ID_SCALED_PRESSURE2,
             'SYS_STATUS': MAV.MAVLINK_MSG_ID_SYS_STATUS}
PASSTHROUGH, SCRIPT = 'passthrough', 'script'
#: Longest the whole restore may take (s): 3 neutral overrides, disarm, release, then the
#: SERVOn_FUNCTIONs set and read back, all within it (see `ArduSubLink.restore`).
RESTORE_BUDGET_S = 3.0
#: Share of the restore budget the disarm may use; the parameters get the rest.
DISARM_SHARE = 1.0 / 3.0
#: Ground stations send HEARTBEAT at 1 Hz: listening this long hears each at least once (s).
GCS_LISTEN_S = 1.2


def connect(url: str, system_id: int, component_id: int) -> Any:
    """A pymavlink connection speaking MAVLink 2, ardupilotmega dialect."""
    os.environ['MAVLINK20'] = '1'  # read by pymavlink when the dialect is set
    return mavutil.mavlink_connection(url, source_system=system_id,
                                      source_component=component_id, dialect='ardupilotmega')


def servo_function(output: int) -> str:
    """The parameter name of an output's function: ``SERVO<n>_FUNCTION``."""
    return f'SERVO{output}_FUNCTION'


def is_rcin(value: float | None) -> bool:
    """True for RCIN1..RCIN8 passthrough (51..58), what activate's passthrough sets."""
    return value is not None and K_RCIN1 <= value <= K_RCIN1 + 7


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
        restore_budget_s: Longest the whole restore may take (s).
    """

    url: str
    thruster_channels: tuple[int, ...]
    thruster_directions: tuple[int, ...] = ()
    gcs_system_id: int = 255
    gcs_component_id: int = MAV.MAV_COMP_ID_MISSIONPLANNER
    reply_timeout_s: float = 0.5
    retries: int = 3
    silent_after_s: float = 1.0
    restore_budget_s: float = RESTORE_BUDGET_S

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
    #: The watchdog script's announced TIMEOUT_MS (None until heard).
    watchdog_timeout_ms: float | None = None

class ArduSubWire:
    """MAVLink to one ArduSub vehicle as a GCS, never waiting; `clock` gives local seconds."""


    def __init__(self, settings: LinkSettings, curve: T200Curve,
                 clock: Callable[[], float] = time.monotonic,
                 journal: DeviceJournal | None = None) -> None:
        self.settings = settings
        self.curve = curve
        self.clock = clock
        self.vehicle = VehicleState()
        self.conn: Any = None
        #: Where the original SERVOn_FUNCTIONs are kept while changed (passthrough).
        self.journal = journal or DeviceJournal.for_device('ardusub', settings.url)
        #: SERVOn_FUNCTION values before activate changed them: output -> value.
        self.changed_functions: dict[int, float] = {}
        #: PASSTHROUGH or SCRIPT (`use_script`).
        self.mode = PASSTHROUGH
        self.script = ScriptSettings()
        self.overrides_sent = 0
        #: Other ground stations heard: (system, component) -> local time (s) last heard.
        self.other_gcs: dict[tuple[int, int], float] = {}
        self._next_heartbeat_s = -math.inf
        self.opened_s = -math.inf
        #: Telemetry callback: (name, message, the kernel's arrival time of its datagram in s
        #: since the epoch, or None) for each message of TELEMETRY as it is read.
        self.on_telemetry: Callable[[str, Any, float | None], None] | None = None
        self.arrival: DatagramArrival | None = None
        #: True ends any wait at once (SIGINT/SIGTERM of the bridge while it waits).
        self.stop_requested: Callable[[], bool] = lambda: False

    # -- link --------------------------------------------------------------------------
    def open(self) -> None:
        """Open the connection and send our first HEARTBEAT (a udpout peer learns us)."""
        s = self.settings
        self.conn = connect(s.url, s.gcs_system_id, s.gcs_component_id)
        self.arrival = DatagramArrival.attach(self.conn)
        self.opened_s = self.clock()
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

    def from_vehicle(self, msg: Any) -> bool:
        """True when ``msg`` comes from the vehicle's system and component."""
        v = self.vehicle
        return bool(v.system_id) and (msg.get_srcSystem(), msg.get_srcComponent()) == (
            v.system_id, v.component_id)

    def addressed_to_us(self, msg: Any) -> bool:
        """True unless the message's target fields name another system or component (0: none)."""
        s = self.settings
        return (getattr(msg, 'target_system', 0) in (0, s.gcs_system_id)
                and getattr(msg, 'target_component', 0) in (0, s.gcs_component_id))

    def _take(self, msg: Any, now_s: float) -> None:
        kind, v = msg.get_type(), self.vehicle
        if kind == 'HEARTBEAT':
            if msg.type == MAV.MAV_TYPE_SUBMARINE and \
                    msg.autopilot == MAV.MAV_AUTOPILOT_ARDUPILOTMEGA:
                v.system_id, v.component_id = msg.get_srcSystem(), msg.get_srcComponent()
                v.heartbeat_s = now_s
                v.armed = bool(msg.base_mode & MAV.MAV_MODE_FLAG_SAFETY_ARMED)
                v.custom_mode = msg.custom_mode
            elif msg.type == MAV.MAV_TYPE_GCS:
                source = (msg.get_srcSystem(), msg.get_srcComponent())
                if source != (self.settings.gcs_system_id, self.settings.gcs_component_id):
                    self.other_gcs[source] = now_s
            return
        if v.system_id and msg.get_srcSystem() != v.system_id:
            return
        if kind == 'SYS_STATUS' and msg.voltage_battery not in (0, 65535):
            v.voltage_v = msg.voltage_battery / 1000.0
        elif kind == 'ATTITUDE_QUATERNION':
            v.quaternion_wxyz = (msg.q1, msg.q2, msg.q3, msg.q4)
        elif kind == 'NAMED_VALUE_FLOAT' and msg.name == ANNOUNCE_NAME:
            v.watchdog_timeout_ms = float(msg.value)
        if kind in TELEMETRY:
            v.latest[kind] = msg
            if self.on_telemetry is not None:
                self.on_telemetry(kind, msg, self.arrival.last_s if self.arrival else None)

    def use_script(self, script: ScriptSettings) -> None:
        """Drive the thrusters through the watchdog script (RC channels 9-16, nothing changed)."""
        self.mode, self.script = SCRIPT, script

    # -- the running path --------------------------------------------------------------
    def pwm_for(self, thrusts_n: Sequence[float]) -> dict[int, int]:
        """Output -> PWM (µs) of each thruster's thrust (N), direction applied here once.

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

    def send_override(self, pwm_by_output: dict[int, int], others_1_8: int = IGNORE_1_8
                      ) -> None:
        """RC_CHANNELS_OVERRIDE to the vehicle carrying each thruster output's PWM.

        Passthrough: output n's PWM on channel n, ``others_1_8`` on the rest of 1-8, 0
        (ignore) on 9-18. Script: 1500 on the pilot inputs 1-6 (as ArduSub's own
        ``set_neutral_controls`` does: should the script stop while armed, the Motor outputs
        get the mixer's neutral), 65535 (ignore) on 7-8, output n's PWM on the script's
        channel for n (9-16) with the toggle bit of this message, 0 (ignore) elsewhere.
        """
        if self.mode == SCRIPT:
            toggle = self.overrides_sent & 1
            by_channel = {self.script.rc_channel(o): toggle_encode(pwm, toggle)
                          for o, pwm in pwm_by_output.items()}
            values = [NEUTRAL_US] * PILOT_CHANNELS + [IGNORE_1_8] * (8 - PILOT_CHANNELS) + \
                [by_channel.get(k, IGNORE_9_18) for k in range(9, 19)]
        else:
            values = [pwm_by_output.get(k, others_1_8) for k in range(1, 9)] + \
                [IGNORE_9_18] * 10
        v = self.vehicle
        self.conn.mav.rc_channels_override_send(v.system_id, v.component_id, *values)
        self.overrides_sent += 1

    def neutral(self) -> None:
        """1500 µs on every thruster output."""
        self.send_override({c: NEUTRAL_US for c in self.settings.thruster_channels})

    def release(self) -> None:
        """Give our channels back: 0 on 1-8; in script mode 0 on 1-6, 65534 on the script's."""
        if self.mode == SCRIPT:
            values = [RELEASE_1_8] * PILOT_CHANNELS + [IGNORE_1_8] * (8 - PILOT_CHANNELS) + [
                RELEASE_9_18 if k in {self.script.rc_channel(o)
                                      for o in self.settings.thruster_channels}
                else IGNORE_9_18 for k in range(9, 19)]
            v = self.vehicle
            self.conn.mav.rc_channels_override_send(v.system_id, v.component_id, *values)
            self.overrides_sent += 1
            return
        self.send_override({}, RELEASE_1_8)

