"""Ask an Alpha 5 device what it is, its mode and its limits, one device at a time.

The bridge's configure and the hardware check share this, over any link (UDP or serial);
never a broadcast request: answers of several devices collide on RS-485.
"""

from __future__ import annotations

from uvms_hardware import reach_protocol as rp
from uvms_hardware.alpha5_core import IDENTITY_REQUEST, LIMITS_REQUEST
from uvms_hardware.hardware_config import Drive
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_hardware.transport import Link, collect


def probe_device(link: Link, splitter: rp.FrameSplitter, drive: Drive, timeout_s: float
                 ) -> tuple[dict[int, rp.Packet], Mode | None]:
    """Ask one Alpha 5 device for its identity, mode and limits, one request at a time.

    Returns:
        (packet id -> its answer, the device's mode or None when it did not say).
    """
    answers: dict[int, rp.Packet] = {}

    def feed(chunk: bytes) -> list[int]:
        found = [p for p in splitter.feed(chunk) if p.device_id == drive.device_id]
        answers.update((p.packet_id, p) for p in found)
        return [p.packet_id for p in found]

    for request in (IDENTITY_REQUEST, LIMITS_REQUEST):
        link.send(rp.encode_request(drive.device_id, request))
        collect(link, feed, request, timeout_s)
        if PacketId.MODEL not in answers:
            break
    answer = answers.get(PacketId.MODE)
    mode = rp.mode_of(answer.data[0]) if answer is not None and answer.data else None
    return answers, mode
