"""The ardusub_bridge's MAVLink conversations, without ROS: find and check ArduSub, restore it.

pymavlink does the framing, CRC and message classes (ardupilotmega dialect, MAVLink 2, as
ArduSub 4.x speaks it). Facts from shared/robots/bluerov2_heavy_alpha5.md ("ArduSub over
MAVLink", each with its ArduPilot source). The node (``ardusub_bridge_node``) drives it with
its clock; every wait here has a timeout and services the link meanwhile (our HEARTBEAT at
1 Hz, incoming messages)::

    link = ArduSubLink(LinkSettings('udpout:127.0.0.1:14550', (1, 2, 3, 4, 5, 6, 7, 8)))
    link.open(); link.wait_vehicle(5.0); link.check_gcs_id(); warnings = link.failsafe_warnings()
    link.wait_watchdog_script(1.5)                     # script mode if the autopilot has it
    link.enable_passthrough(); link.arm(True)          # activate (passthrough: journal first)
    link.send_override(link.pwm_for(thrusts_n))       # each period, or link.neutral()
    link.restore()                                     # neutral, disarm, release, functions back

Two ways to drive the thrusters:

- **script** (``uvms_thruster_watchdog.lua`` heard at configure, ``ardusub_watchdog``): the
  PWMs go on RC channels 9-16 with the toggle bit; the script on the autopilot puts them on
  the Motor outputs and returns them to neutral on its own when they stop. Nothing on the
  vehicle is changed.
- **passthrough**: each thruster output's SERVOn_FUNCTION becomes RCIN1..8 (journalled before
  the first change, ``device_journal``), the PWMs go on RC channels 1-8; only this process
  stops them.

`ArduSubLink` is the wire (``ardusub_wire``: never waits, what the running path calls) plus the
exchanges that wait for the vehicle's answer, each bounded by a timeout: configure, activate,
deactivate and the restore.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from typing import Any

from uvms_hardware.ardusub_core import Exchange
from uvms_hardware.ardusub_wire import (
    DISARM_SHARE,
    GCS_ID_PARAMS,
    GCS_LISTEN_S,
    IGNORE_1_8,
    K_MOTOR1,
    K_RCIN1,
    MAV,
    NEUTRAL_US,
    PASSTHROUGH,
    RELEASE_1_8,
    SCRIPT,
    TELEMETRY,
    ArduSubWire,
    LinkSettings,
    VehicleState,
    connect,
    is_rcin,
    servo_function,
)
from uvms_hardware.errors import DeviceCheckError

__all__ = ['IGNORE_1_8', 'K_MOTOR1', 'K_RCIN1', 'NEUTRAL_US', 'PASSTHROUGH', 'RELEASE_1_8',
           'SCRIPT', 'TELEMETRY', 'ArduSubLink', 'LinkSettings', 'VehicleState', 'connect',
           'is_rcin', 'servo_function']


class ArduSubLink(ArduSubWire):
    """The wire plus the exchanges that wait for the vehicle's answers (each bounded)."""

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

    def _ask(self, send: Callable[[int], None], match: Callable[[Any], bool],
             exchange: Exchange) -> Any:
        """The answer that matches, sending the request when ``exchange`` says; None when over.

        ``send(confirmation)`` gets the try's index (MAVLink's confirmation field counts them).
        """
        while True:
            now_s = self.clock()
            if exchange.due(now_s):
                send(exchange.sent - 1)
            elif exchange.over(now_s):
                return None
            for msg in self.service():
                if match(msg):
                    return msg
            time.sleep(0.002)

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

    def _is_param(self, msg: Any, name: str) -> bool:
        return (msg.get_type() == 'PARAM_VALUE' and msg.param_id == name
                and self.from_vehicle(msg))

    def read_param(self, name: str) -> float | None:
        """A vehicle parameter by PARAM_REQUEST_READ; None when not answered."""
        v = self.vehicle
        msg = self._ask(lambda confirmation: self.conn.mav.param_request_read_send(
            v.system_id, v.component_id, name.encode(), -1),
            lambda m: self._is_param(m, name), Exchange(self.settings.retries,
                                                       self.settings.reply_timeout_s))
        return None if msg is None else float(msg.param_value)

    def set_param(self, name: str, value: float, param_type: int = MAV.MAV_PARAM_TYPE_INT16
                  ) -> float | None:
        """PARAM_SET, then the value read back (None when not answered)."""
        v = self.vehicle
        self.conn.mav.param_set_send(v.system_id, v.component_id, name.encode(), value,
                                     param_type)
        self._wait(lambda m: self._is_param(m, name), self.settings.reply_timeout_s)
        return self.read_param(name)

    def set_params_until(self, values: Mapping[str, float], end_s: float) -> dict[str, float]:
        """PARAM_SET of every value at once, resent until each is read back or ``end_s``.

        ArduPilot answers a PARAM_SET with the parameter's PARAM_VALUE (``GCS_Param.cpp``);
        each PARAM_SET is followed by a PARAM_REQUEST_READ of the same name (a vehicle that
        ignores the set, the value being already right, still answers that). A PARAM_VALUE from
        the vehicle equal to the value is the read-back. Bounded by ``end_s`` (local seconds)
        whatever the vehicle does.

        Returns:
            What was not read back: name -> the value it should have.
        """
        v, pending = self.vehicle, dict(values)
        while pending and self.clock() < end_s:
            for name, value in pending.items():
                self.conn.mav.param_set_send(v.system_id, v.component_id, name.encode(), value,
                                             MAV.MAV_PARAM_TYPE_INT16)
                self.conn.mav.param_request_read_send(v.system_id, v.component_id,
                                                      name.encode(), -1)
            round_end_s = min(end_s, self.clock() + self.settings.reply_timeout_s)
            while pending and self.clock() < round_end_s:
                for msg in self.service():
                    if (msg.get_type() == 'PARAM_VALUE' and self.from_vehicle(msg)
                            and pending.get(msg.param_id) == float(msg.param_value)):
                        del pending[msg.param_id]
                time.sleep(0.002)
        return pending

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

    def check_other_gcs(self) -> list[str]:
        """Other ground stations heard on the link (HEARTBEAT of MAV_TYPE_GCS), as warnings.

        The vehicle cannot tell a ground station with our system id from us: it obeys its
        RC overrides and releases alike, and its heartbeats keep the vehicle's GCS failsafe
        and the watchdog script's GCS from ever looking lost.

        Raises:
            DeviceCheckError: a ground station with our system id (another component).
        """
        self._wait(lambda m: False, self.opened_s + GCS_LISTEN_S - self.clock(),
                   interruptible=True)  # every ground station heard at least once
        ours = self.settings.gcs_system_id
        same = sorted(c for s, c in self.other_gcs if s == ours)
        if same:
            raise DeviceCheckError(
                f'another ground station with our system id {ours} is on the link (component'
                f'{"s" if len(same) > 1 else ""} {", ".join(map(str, same))}, e.g. '
                'QGroundControl, whose default id is 255): the vehicle obeys its RC overrides '
                'and releases as ours; close it, or give it another MAVLink system id')
        return [f'another ground station on the link: system {s} component {c} (the vehicle '
                'ignores its RC overrides, but it can arm, disarm, change modes and parameters)'
                for s, c in sorted(self.other_gcs)]

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

    def wait_watchdog_script(self, timeout_s: float) -> float | None:
        """Listen for the watchdog script's announcement; its TIMEOUT_MS, or None (not heard)."""
        if self.vehicle.watchdog_timeout_ms is None:
            self._wait(lambda m: self.vehicle.watchdog_timeout_ms is not None, timeout_s,
                       interruptible=True)
        return self.vehicle.watchdog_timeout_ms

    def rc_input_outputs(self) -> dict[int, int]:
        """Outputs 1-16 whose SERVOn_FUNCTION is RCIN9..RCIN16 (59..66): output -> function.

        In script mode those would follow our thrust values (lights, a camera tilt).
        """
        found = {}
        for output in range(1, 17):
            value = self.read_param(servo_function(output))
            if value is not None and K_RCIN1 + 8 <= value <= K_RCIN1 + 15:
                found[output] = int(value)
        return found

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

    def _is_ack(self, msg: Any, command: int) -> bool:
        return (msg.get_type() == 'COMMAND_ACK' and msg.command == command
                and self.from_vehicle(msg) and self.addressed_to_us(msg))

    def command(self, command: int, *params: float, end_s: float = math.inf) -> int | None:
        """COMMAND_LONG; the COMMAND_ACK's result (None when not answered).

        Sent up to ``retries`` times (MAVLink's confirmation field counting them), never
        waiting past ``end_s`` (local seconds).
        """
        v, padded = self.vehicle, (list(params) + [0.0] * 7)[:7]
        ack = self._ask(lambda confirmation: self.conn.mav.command_long_send(
            v.system_id, v.component_id, command, confirmation, *padded),
            lambda m: self._is_ack(m, command),
            Exchange(self.settings.retries, self.settings.reply_timeout_s, end_s))
        return None if ack is None else int(ack.result)

    # -- activate / deactivate ---------------------------------------------------------
    def enable_passthrough(self) -> None:
        """Journal each thruster output's SERVOn_FUNCTION, then set it to RCIN of its channel.

        Every original is read and written to the journal (fsync'd) before the first change.

        Raises:
            DeviceCheckError: an output not answered or not read back as set, naming it.
            JournalError: the journal cannot be written (nothing is changed then).
        """
        originals: dict[int, float] = {}
        for channel in self.settings.thruster_channels:
            before = self.read_param(servo_function(channel))
            if before is None:
                raise DeviceCheckError(f'{servo_function(channel)} not answered: cannot set '
                                       'passthrough')
            if before != float(K_RCIN1 + channel - 1):
                originals[channel] = before
        self.journal.record({servo_function(c): value for c, value in originals.items()})
        for channel, before in originals.items():
            wanted = float(K_RCIN1 + channel - 1)
            self.changed_functions.setdefault(channel, before)
            after = self.set_param(servo_function(channel), wanted)
            if after != wanted:
                raise DeviceCheckError(f'{servo_function(channel)} reads {after} after setting '
                                       f'it to {int(wanted)} (RCIN{channel}): channel {channel} '
                                       'is not in passthrough')

    def arm(self, armed: bool, end_s: float = math.inf) -> None:
        """MAV_CMD_COMPONENT_ARM_DISARM (400), param1 1 or 0.

        Raises:
            DeviceCheckError: refused or not answered.
        """
        result = self.command(MAV.MAV_CMD_COMPONENT_ARM_DISARM, 1.0 if armed else 0.0,
                              end_s=end_s)
        if result != MAV.MAV_RESULT_ACCEPTED:
            word = 'arm' if armed else 'disarm'
            raise DeviceCheckError(f'{word}: MAV_CMD_COMPONENT_ARM_DISARM answered {result}')

    def restore(self) -> list[str]:
        """Neutral, disarm, release, functions back and read back; the problems met.

        In this order, all within ``restore_budget_s``: three neutral overrides; the disarm
        (up to a third of the budget); the overrides released (before any parameter, so that
        nothing of ours drives an output whose function goes back); every changed
        SERVOn_FUNCTION set at once and resent until read back or the budget is spent. The
        journal is removed once everything was read back; otherwise it stays, for the next
        configure and ``uvms hardware restore``. Every step is tried even when one fails.
        """
        problems: list[str] = []
        if self.conn is None:
            return ['no connection']
        start_s = self.clock()
        budget_s = self.settings.restore_budget_s
        if self.link_age_s() > self.settings.silent_after_s:
            return self._restore_blind()
        for _ in range(3):
            self.neutral()
        try:
            self.arm(False, end_s=start_s + budget_s * DISARM_SHARE)
        except DeviceCheckError as exc:
            if self.vehicle.armed:  # ArduPilot refuses to disarm a vehicle already disarmed
                problems.append(str(exc))
        except Exception as exc:  # whatever failed, the functions must still go back
            problems.append(f'disarm: {type(exc).__name__}: {exc}')
        self.release()
        problems += self.restore_functions(start_s + budget_s)
        return problems

    def restore_functions(self, end_s: float) -> list[str]:
        """Every changed SERVOn_FUNCTION back by ``end_s``; journal removed when all read back."""
        pending = self.set_params_until({servo_function(c): value for c, value in
                                         self.changed_functions.items()}, end_s)
        for channel in list(self.changed_functions):
            if servo_function(channel) not in pending:
                del self.changed_functions[channel]
        if pending:
            return [f'{name} not read back as {value:g} in time; the journal '
                    f'{self.journal.path} keeps it' for name, value in pending.items()]
        self.journal.remove()
        return []

    def _restore_blind(self) -> list[str]:
        """Restore without waiting for answers: the vehicle has gone silent; journal kept."""
        v = self.vehicle
        self.neutral()
        self.conn.mav.command_long_send(v.system_id, v.component_id,
                                        MAV.MAV_CMD_COMPONENT_ARM_DISARM, 0, *[0.0] * 7)
        self.release()
        for channel, value in self.changed_functions.items():
            self.conn.mav.param_set_send(v.system_id, v.component_id,
                                         servo_function(channel).encode(), value,
                                         MAV.MAV_PARAM_TYPE_INT16)
        kept = f'; the journal {self.journal.path} keeps them' if self.changed_functions else ''
        return [f'vehicle silent for {self.link_age_s():.1f} s: neutral, disarm, release and '
                f'SERVOn_FUNCTION of outputs {sorted(self.changed_functions)} sent without '
                f'confirmation{kept}; check the vehicle']
