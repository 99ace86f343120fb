"""``uvms hardware check FILE``: find each device of a hardware file and say what it is.

It changes nothing. The bring-up's first command (docs/hardware.md): before any bridge
changes a parameter or arms anything, it connects to each device the hardware file names,
prints what it found and what would stop the bridge from activating, and returns the number
of problems. What it sends: MAVLink HEARTBEATs as a GCS and parameter *reads*, nothing the
vehicle keeps; requests of the Alpha 5's identity, mode and limits. The DVL is only listened
to. The Net F/T box is asked for records and told to stop again. No ROS: plain sockets
through the bridges' own cores.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from typing import Any

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.address import parse_host_port
from uvms_hardware.alpha5_core import check_device
from uvms_hardware.alpha5_probe import probe_device
from uvms_hardware.ardusub_link import ArduSubLink, LinkSettings
from uvms_hardware.ardusub_restore import find_leftovers, leftovers_refusal
from uvms_hardware.ardusub_watchdog import SCRIPT_NAME
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import hardware_section, load_alpha5
from uvms_hardware.reach_protocol import FrameSplitter
from uvms_hardware.t200_curve import T200Curve
from uvms_hardware.transport import UdpLink, collect, open_link, parse_connection

#: Seconds to listen for a device's first words.
LISTEN_S = 3.0

Say = Callable[[str], None]


def check_ardusub(robot: str, values: Mapping[str, Any], say: Say) -> int:
    """The vehicle: heartbeat, GCS id, failsafes, thruster outputs (leftovers), script, battery."""
    _, section = hardware_section(robot, 'ardusub')
    settings = LinkSettings(str(values['mavlink_url']),
                            tuple(int(c) for c in section['thruster_channels']),
                            tuple(int(d) for d in section['thruster_directions']),
                            int(values.get('gcs_system_id', 255)))
    link = ArduSubLink(settings, T200Curve.from_section(section['t200']))
    problems = 0
    try:
        link.open()
        link.wait_vehicle(float(values.get('heartbeat_timeout_s', LISTEN_S)))
        v = link.vehicle
        say(f'ardusub: system {v.system_id} component {v.component_id}, '
            f'{"armed" if v.armed else "disarmed"}, custom mode {v.custom_mode}')
        try:
            name, gcs_id = link.check_gcs_id()
            say(f'ardusub: {name} = {gcs_id}: our RC overrides will be obeyed')
        except HardwareError as exc:
            problems += 1
            say(f'ardusub: PROBLEM: {exc}')
        for warning in link.failsafe_warnings():
            say(f'ardusub: warning: {warning}')
        try:
            for warning in link.check_other_gcs():
                say(f'ardusub: warning: {warning}')
        except HardwareError as exc:
            problems += 1
            say(f'ardusub: PROBLEM: {exc}')
        functions = {c: link.read_param(f'SERVO{c}_FUNCTION') for c in settings.thruster_channels}
        say('ardusub: thruster outputs SERVOn_FUNCTION: ' + ', '.join(
            f'{c}={"?" if f is None else int(f)}' for c, f in functions.items())
            + ' (passthrough mode sets RCIN 51..58 and puts these back)')
        leftovers = find_leftovers(link)
        if leftovers is not None:
            problems += 1
            say(f'ardusub: PROBLEM: {leftovers_refusal(leftovers, settings.url)}')
        script_ms = link.wait_watchdog_script(1.5)
        say(f'ardusub: {SCRIPT_NAME} heard (timeout {script_ms:g} ms): the thrusters stop '
            'without the bridge' if script_ms is not None else
            f'ardusub: warning: {SCRIPT_NAME} not heard: the bridge will use RC passthrough, '
            'and only its process stops the thrusters (docs/hardware.md)')
        end_s = time.monotonic() + 1.5
        while math.isnan(v.voltage_v) and time.monotonic() < end_s:
            link.service()
            time.sleep(0.01)
        say(f'ardusub: battery {v.voltage_v:.2f} V' if math.isfinite(v.voltage_v) else
            'ardusub: battery: no SYS_STATUS heard (the bridge asks for it when it runs)')
    except HardwareError as exc:
        problems += 1
        say(f'ardusub: PROBLEM: {exc}')
    finally:
        link.close()
    return problems


def check_dvl(robot: str, values: Mapping[str, Any], say: Say) -> int:
    """The DVL: connection, a velocity report, bottom lock (listening only)."""
    address = parse_host_port(str(values['address']), 16171, 'dvl_bridge.address')
    link = DvlLink(address).start()
    try:
        if not link.wait_connected(float(values.get('connect_timeout_s', LISTEN_S))):
            say(f'dvl: PROBLEM: no connection to {address.host}:{address.port}: '
                f'{link.last_error}')
            return 1
        end_s = time.monotonic() + LISTEN_S
        reports = []
        while not reports and time.monotonic() < end_s:
            reports = link.take()
            time.sleep(0.02)
        if not reports:
            say(f'dvl: PROBLEM: connected to {address.host}:{address.port}, no velocity report '
                f'within {LISTEN_S:g} s')
            return 1
        _, report = reports[-1]
        lock = 'bottom lock' if report.valid else 'NO bottom lock'
        say(f'dvl: {address.host}:{address.port}: {lock}, fom {report.fom:.4f} m/s, '
            f'altitude {report.altitude_m:.2f} m')
        return 0
    finally:
        link.stop()


def check_alpha5(robot: str, values: Mapping[str, Any], say: Say) -> int:
    """The arm: every joint's device, its mode and its limits against the URDF's."""
    arm = load_alpha5(robot)
    link = open_link(parse_connection(str(values['connection']), arm.udp_port,
                                      'alpha5_bridge.connection'))
    timeout_s = float(values.get('answer_timeout_s', 0.2))
    problems = 0
    try:
        for drive in arm.drives:
            answers, mode = probe_device(link, FrameSplitter(), drive, timeout_s)
            errors = check_device(drive, answers, timeout_s)
            problems += len(errors)
            for error in errors:
                say(f'alpha5: PROBLEM: {error}')
            if not errors:
                say(f'alpha5: {drive.joint_name} (device {drive.device_id:#04x}): '
                    f'{mode.name if mode is not None else "mode unknown"}, limits as the URDF')
    finally:
        link.close()
    return problems


def check_netft(robot: str, values: Mapping[str, Any], say: Say) -> int:
    """The force sensor: one RDT record (start, then stop again), its status word."""
    host, port = parse_host_port(str(values['address']), rdt.RDT_PORT, 'netft_bridge.address')
    link = UdpLink(host, port)
    records: list[bytes] = []

    def feed(chunk: bytes) -> list[int]:
        if chunk and not len(chunk) % rdt.RECORD_BYTES:
            records.append(chunk[:rdt.RECORD_BYTES])
            return [1]
        return []

    try:
        link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
        collect(link, feed, [1], LISTEN_S)
        link.send(rdt.encode_request(rdt.COMMAND_STOP))
    finally:
        link.close()
    if not records:
        say(f'netft: PROBLEM: no RDT record from {host}:{port} within {LISTEN_S:g} s')
        return 1
    record = rdt.decode_record(records[0])
    say(f'netft: {host}:{port}: record {record.rdt_sequence}, status {record.status:#010x}'
        + ('' if record.status == 0 else " (non-zero: see the box's manual)"))
    return int(record.status != 0)


CHECKS: dict[str, Callable[[str, Mapping[str, Any], Say], int]] = {
    'ardusub_bridge': check_ardusub, 'dvl_bridge': check_dvl,
    'alpha5_bridge': check_alpha5, 'netft_bridge': check_netft}


def check_hardware(robot: str, bridges: Mapping[str, Mapping[str, Any]], say: Say) -> int:
    """Check each bridge's device in turn; the number of problems found (0: ready)."""
    problems = 0
    for name, values in bridges.items():
        try:
            problems += CHECKS[name](robot, values, say)
        except (HardwareError, ValueError, OSError) as exc:
            problems += 1
            say(f'{name.removesuffix("_bridge")}: PROBLEM: {exc}')
    return problems
