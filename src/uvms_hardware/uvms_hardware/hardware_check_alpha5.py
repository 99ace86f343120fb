"""``uvms hardware check``'s arm: each Alpha 5 joint's device, limits, mode, fault and speed.

What the alpha5_bridge needs of each device (``alpha5_bridge_node``): it answers; its limits are
the URDF's and hardware.yaml's; before a launch it rests (Standby, Disable or Passive: the
bridge puts Standby at activate and the resting mode back at its stop); while the bridge is
active it is in Current mode, driven (Velocity there is the bridge's VELOCITY 0 hold: its trip
or its watchdog); no HARDWARE_STATUS error; and no joint faster than the bridge's trip speed
(``overspeed_factor`` x the URDF's limit), or the bridge trips again the moment it is
activated. Asked one device at a time (answers collide on RS-485), nothing changed.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from uvms_hardware import reach_protocol as rp
from uvms_hardware.alpha5_checks import check_device, describe
from uvms_hardware.alpha5_core import DEFAULT_OVERSPEED_FACTOR, FEEDBACK_REQUEST, RESTING_MODES
from uvms_hardware.alpha5_probe import probe_device
from uvms_hardware.hardware_check_status import BridgeStatus, CheckBounds, Device
from uvms_hardware.hardware_config import Drive, load_alpha5
from uvms_hardware.reach_protocol import FrameSplitter, Mode, PacketId
from uvms_hardware.transport import Link, collect, open_link, parse_connection

#: Asked of each device after its identity and limits.
STATE_REQUEST = (*FEEDBACK_REQUEST, PacketId.HARDWARE_STATUS)


def alpha5_bound_s(drives: int, bounds: CheckBounds) -> float:
    """The longest the arm's check takes (s).

    Per device: its identity and its limits requests, each tried ``retries`` times, then its
    state request, each try ``reply_s``.
    """
    return drives * (2 * bounds.retries + 1) * bounds.reply_s


def check_alpha5(robot: str, values: Mapping[str, Any], device: Device, bounds: CheckBounds,
                 bridge: BridgeStatus | None) -> None:
    """Every joint's device against what the bridge needs, given whether a bridge is active."""
    arm = load_alpha5(robot)
    link = open_link(parse_connection(str(values['connection']), arm.udp_port,
                                      'alpha5_bridge.connection'))
    factor = float(values.get('overspeed_factor', DEFAULT_OVERSPEED_FACTOR))
    active = bridge is not None and bridge.active
    try:
        for drive in arm.drives:
            splitter = FrameSplitter()
            answers, mode = probe_device(link, splitter, drive, bounds.reply_s, bounds.retries)
            errors = check_device(drive, answers, bounds.reply_s)
            for error in errors:
                device.problem(error)
            if PacketId.MODEL not in answers:
                continue
            state = _ask_state(link, splitter, drive, bounds.reply_s)
            _judge(drive, mode, state, factor, active, device, limits_ok=not errors)
    finally:
        link.close()


def _ask_state(link: Link, splitter: FrameSplitter, drive: Drive, timeout_s: float
               ) -> dict[int, rp.Packet]:
    """The device's position, velocity and HARDWARE_STATUS (those it answered)."""
    answers: dict[int, rp.Packet] = {}

    def feed(chunk: bytes) -> list[int]:
        found = [p for p in splitter.feed(chunk) if p.device_id == drive.device_id]
        answers.update((p.packet_id, p) for p in found)
        return [p.packet_id for p in found]

    link.send(rp.encode_request(drive.device_id, STATE_REQUEST))
    collect(link, feed, STATE_REQUEST, timeout_s)
    return answers


def _judge(drive: Drive, mode: Mode | None, state: Mapping[int, rp.Packet], factor: float,
           active: bool, device: Device, limits_ok: bool) -> None:
    """One joint's line, and its problems: mode, fault, speed."""
    name = describe(drive)
    mode_text = mode.name.capitalize() if mode is not None else 'mode unknown'
    speed = _value(state.get(PacketId.VELOCITY))
    position = _value(state.get(PacketId.POSITION))
    unit = 'm' if rp.is_length_packet(drive.device_id, PacketId.POSITION) else 'rad'
    shown = ', '.join(part for part in (
        f'at {position:.3f} {unit}' if position is not None else '',
        f'{speed:.3f} {unit}/s' if speed is not None else '') if part)
    device.info(f'{name}: {mode_text}' + (f', {shown}' if shown else '')
                + (', limits as the URDF' if limits_ok else ''))
    status = state.get(PacketId.HARDWARE_STATUS)
    if status is not None and any(status.data):
        device.problem(f'{name}: HARDWARE_STATUS {status.data.hex()}: the device reports a '
                       "fault (its layout is not in Reach's documents; see the arm's manual)")
    limit = factor * drive.velocity_limit
    if speed is not None and abs(speed) > limit:
        device.problem(f'{name}: moving at {speed:.3g} {unit}/s, over {factor:g} x its limit '
                       f'{drive.velocity_limit:g} {unit}/s: the bridge trips on it (activated '
                       'now, it would trip at once)')
    if mode is None:
        return
    if active and mode == Mode.VELOCITY:
        device.problem(f"{name}: Velocity mode while alpha5_bridge is active: the bridge's "
                       'VELOCITY 0 hold (its overspeed trip, or its watchdog: no command for '
                       '0.1 s); it drives in Current mode')
    elif not active and mode not in RESTING_MODES:
        device.problem(f'{name}: {mode_text} mode and no alpha5_bridge active: left so by a '
                       'bridge that did not end cleanly, or another host drives it; the bridge '
                       'expects a resting mode (Standby, Disable, Passive)')


def _value(packet: rp.Packet | None) -> float | None:
    """A feedback packet's value in SI (None when absent or malformed)."""
    if packet is None or len(packet.data) != 4:
        return None
    return float(rp.packet_values_si(packet)[0])
