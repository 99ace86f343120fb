"""``uvms hardware check FILE``: find each device of a hardware file and say what it is.

It changes nothing. The bring-up's first command (docs/hardware.md), and the one to run beside
a launch that misbehaves: it connects to each device the hardware file names, one after the
other, and says as it goes what it checks, how long it waits at most, what it found and what
would stop the bridge (or shows that a running bridge stopped), each such line a PROBLEM, and
how long the device took. The bridges running on the graph (``hardware_check_graph``: their
``/diagnostics``) say what the devices should look like (``hardware_check_status``): an
ERROR of a bridge (a tripped arm, a silent device) is a problem too.

What it sends: MAVLink HEARTBEATs as a GCS and parameter *reads*
(``hardware_check_ardusub``); requests of the Alpha 5's identity, mode, limits, position,
speed and HARDWARE_STATUS (``hardware_check_alpha5``). The DVL is only listened to. The Net
F/T box is asked for records and told to stop again, unless a netft_bridge is active (the
box streams to one requester: the check would take the bridge's stream). No ROS here: plain
sockets through the bridges' own cores.

Each device's waits are the check's own (`CheckBounds`, ``--wait``), not the hardware file's
start-up waits: ``twin.yaml`` gives a launch's bridges 30 s for devices that start with it,
which made a check of absent twins take 65 s (30 s for the vehicle's HEARTBEAT, 30 s of DVL
connection retries).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.address import parse_host_port
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_check_alpha5 import alpha5_bound_s, check_alpha5
from uvms_hardware.hardware_check_ardusub import ardusub_bound_s, check_ardusub
from uvms_hardware.hardware_check_status import BridgeStatus, CheckBounds, Device, Graph, Say
from uvms_hardware.hardware_config import hardware_section, load_alpha5
from uvms_hardware.transport import UdpLink, collect

__all__ = ['CHECKS', 'BridgeStatus', 'CheckBounds', 'check_hardware', 'device_bound_s']

Check = Callable[[str, Mapping[str, Any], Device, CheckBounds, BridgeStatus | None], None]


def check_dvl(robot: str, values: Mapping[str, Any], device: Device, bounds: CheckBounds,
              bridge: BridgeStatus | None) -> None:
    """The DVL: connection, then a velocity report with bottom lock (listening only).

    No bottom lock is a problem: the bridge publishes no velocity without it, so the
    estimator has none. The first locked report within ``wait_s`` ends the listening.
    """
    address = parse_host_port(str(values['address']), 16171, 'dvl_bridge.address')
    link = DvlLink(address, reconnect_period_s=0.2).start()
    try:
        if not link.wait_connected(bounds.wait_s):
            device.problem(f'no connection to {address.host}:{address.port} within '
                           f'{bounds.wait_s:g} s: {link.last_error}')
            return
        end_s = time.monotonic() + bounds.wait_s
        last = None
        while time.monotonic() < end_s:
            reports = link.take()
            if reports:
                last = reports[-1][1]
                if any(report.valid for _, report in reports):
                    last = next(r for _, r in reversed(reports) if r.valid)
                    break
            time.sleep(0.02)
        where = f'{address.host}:{address.port}'
        if last is None:
            device.problem(f'connected to {where}, no velocity report within {bounds.wait_s:g} s')
            return
        device.info(f'{where}: {"bottom lock" if last.valid else "NO bottom lock"}, fom '
                    f'{last.fom:.4f} m/s, altitude {last.altitude_m:.2f} m')
        if not last.valid:
            device.problem(f'no bottom lock in {bounds.wait_s:g} s of reports (velocity_valid '
                           'false): the bridge publishes no dvl without it and the estimator '
                           "has no velocity; the bottom within the DVL's range?")
    finally:
        link.stop()


def check_netft(robot: str, values: Mapping[str, Any], device: Device, bounds: CheckBounds,
                bridge: BridgeStatus | None) -> None:
    """The force sensor: one RDT record (start, then stop again), its status word."""
    host, port = parse_host_port(str(values['address']), rdt.RDT_PORT, 'netft_bridge.address')
    if bridge is not None and bridge.active:
        device.info(f'{host}:{port}: not asked: netft_bridge is active and a start request '
                    'would take its stream; its status word '
                    f'{bridge.values.get("status", "?")}, {bridge.values.get("records", "?")} '
                    'records')
        return
    link = UdpLink(host, port)
    records: list[bytes] = []

    def feed(chunk: bytes) -> list[int]:
        if chunk and not len(chunk) % rdt.RECORD_BYTES:
            records.append(chunk[:rdt.RECORD_BYTES])
            return [1]
        return []

    try:
        link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
        collect(link, feed, [1], bounds.wait_s)
        link.send(rdt.encode_request(rdt.COMMAND_STOP))
    finally:
        link.close()
    if not records:
        device.problem(f'no RDT record from {host}:{port} within {bounds.wait_s:g} s')
        return
    record = rdt.decode_record(records[0])
    device.info(f'{host}:{port}: record {record.rdt_sequence}, status {record.status:#010x}'
                + ('' if record.status == 0 else " (non-zero: see the box's manual)"))
    if record.status != 0:
        device.problem(f'status word {record.status:#010x} is not zero')


CHECKS: dict[str, Check] = {
    'ardusub_bridge': check_ardusub, 'dvl_bridge': check_dvl,
    'alpha5_bridge': check_alpha5, 'netft_bridge': check_netft}


def device_bound_s(robot: str, name: str, bounds: CheckBounds) -> float:
    """The longest the check of bridge ``name``'s device waits for answers (s)."""
    if name == 'ardusub_bridge':
        _, section = hardware_section(robot, 'ardusub')
        return ardusub_bound_s(len(section['thruster_channels']), bounds)
    if name == 'alpha5_bridge':
        return alpha5_bound_s(len(load_alpha5(robot).drives), bounds)
    if name == 'dvl_bridge':
        return 2 * bounds.wait_s
    return bounds.wait_s


def _where(values: Mapping[str, Any]) -> str:
    for key in ('mavlink_url', 'address', 'connection'):
        if key in values:
            return str(values[key])
    return '?'


def check_hardware(robot: str, bridges: Mapping[str, Mapping[str, Any]], say: Say,
                   bounds: CheckBounds | None = None, graph: Graph | None = None,
                   clock: Callable[[], float] = time.monotonic) -> int:
    """Check each bridge's device in turn, saying as it goes; the number of problems (0: ready).

    Args:
        robot: The robot folder whose hardware.yaml describes the devices.
        bridges: Bridge name -> its section of the hardware file.
        say: Where each line goes (printed and flushed at once by the CLI).
        bounds: The check's waits (`CheckBounds()` if None).
        graph: The bridges running now (``hardware_check_graph``); None or empty: none.
        clock: Seconds, for the elapsed times.
    """
    bounds = bounds or CheckBounds()
    graph = graph or {}
    problems = 0
    for name, values in bridges.items():
        short = name.removesuffix('_bridge')
        device = Device(short, say)
        start_s = clock()
        bridge = graph.get(name)
        try:
            device.info(f'checking {_where(values)} (waits at most '
                        f'{device_bound_s(robot, name, bounds):.1f} s for answers)')
            if bridge is not None:
                device.info(f'{bridge.describe()}')
                if bridge.level >= 2:
                    device.problem(f'{name} reports ERROR: {bridge.message}')
            CHECKS[name](robot, values, device, bounds, bridge)
        except (HardwareError, ValueError, OSError) as exc:
            device.problem(str(exc))
        elapsed_s = clock() - start_s
        device.info(f'{device.problems or "no"} problem{"" if device.problems == 1 else "s"}, '
                    f'{elapsed_s:.1f} s')
        problems += device.problems
    return problems
