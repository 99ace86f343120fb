"""Ask an Alpha 5 device what it is, its mode and its limits; confirm a change by its MODE.

The bridge's configure, activate and put-back and the hardware check share this, over any
link (UDP or serial); never a broadcast request: answers of several devices collide on RS-485.
"""

from __future__ import annotations

from typing import NamedTuple

from uvms_hardware import reach_protocol as rp
from uvms_hardware.alpha5_checks import (
    CONFIRM_TRIES,
    DEFAULT_CONFIRM_TIMEOUT_S,
    IDENTITY_REQUEST,
    LIMITS_REQUEST,
    Setting,
)
from uvms_hardware.hardware_config import Drive
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_hardware.transport import Link, collect


def probe_device(link: Link, splitter: rp.FrameSplitter, drive: Drive, timeout_s: float,
                 tries: int = CONFIRM_TRIES) -> tuple[dict[int, rp.Packet], Mode | None]:
    """Ask one Alpha 5 device for its identity, mode and limits, one request at a time.

    A request whose answers did not all come within ``timeout_s`` is asked again for the
    missing ones, ``tries`` times in all: a datagram lost on UDP, or a bridge or twin late on
    a loaded computer (a twin stand's LIMITS answer missed 0.2 s beside 2 busy loops), is not
    a device that does not answer.

    Returns:
        (packet id -> its answer, the device's mode or None when it did not say).
    """
    answers: dict[int, rp.Packet] = {}

    def feed(chunk: bytes) -> list[int]:
        found = [p for p in splitter.feed(chunk) if p.device_id == drive.device_id]
        answers.update((p.packet_id, p) for p in found)
        return [p.packet_id for p in found]

    for request in (IDENTITY_REQUEST, LIMITS_REQUEST):
        for _ in range(tries):
            missing = tuple(i for i in request if i not in answers)
            if not missing:
                break
            link.send(rp.encode_request(drive.device_id, missing))
            collect(link, feed, missing, timeout_s)
        if PacketId.MODEL not in answers:
            break
    answer = answers.get(PacketId.MODE)
    mode = rp.mode_of(answer.data[0]) if answer is not None and answer.data else None
    return answers, mode


class Confirmation(NamedTuple):
    """How a confirmed setting went: confirmed, the MODE read last (None: none), tries sent."""

    confirmed: bool
    mode: Mode | None
    tries: int


def confirm_setting(link: Link, splitter: rp.FrameSplitter, setting: Setting,
                    tries: int = CONFIRM_TRIES,
                    timeout_s: float = DEFAULT_CONFIRM_TIMEOUT_S) -> Confirmation:
    """Send a setting with a REQUEST MODE behind it until the MODE read back confirms it.

    Each try is one write (one datagram on UDP): the setting's frame, then REQUEST MODE to
    the same device. A MODE answer that does not confirm ends the try at once; silence ends
    it after ``timeout_s``. So one setting takes ``tries * timeout_s`` at most.
    """
    device_id = setting.drive.device_id
    request = rp.encode_request(device_id, (PacketId.MODE,))
    read: list[Mode | None] = []

    def feed(chunk: bytes) -> list[int]:
        found = [p for p in splitter.feed(chunk)
                 if p.device_id == device_id and p.packet_id == PacketId.MODE and p.data]
        read.extend(rp.mode_of(p.data[0]) for p in found)
        return [PacketId.MODE] if found else []

    mode: Mode | None = None
    for attempt in range(1, tries + 1):
        read.clear()
        link.send(setting.frame + request)
        collect(link, feed, (PacketId.MODE,), timeout_s)
        if read:
            mode = read[-1]
            if mode in setting.accepted:
                return Confirmation(True, mode, attempt)
    return Confirmation(False, mode, tries)
